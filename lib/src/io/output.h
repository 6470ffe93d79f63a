#pragma once
// Buffered output for the writers: text numbers formatted with std::to_chars (shortest form that reads
// back to the same double), raw bytes for binary formats, and an atomic file commit.
#include <charconv>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <functional>
#include <string>
#include <string_view>

namespace lodkit::detail {

class Output {
 public:
  /// Collects everything in memory (see `str()`).
  Output() = default;
  /// Streams to `file`, flushing every megabyte.
  explicit Output(std::FILE* file) : file_(file) { buffer_.reserve(kFlushAt + 4096); }

  void put(std::string_view s) {
    buffer_.append(s);
    maybe_flush();
  }
  void put(char c) {
    buffer_.push_back(c);
    maybe_flush();
  }
  void put_bytes(const void* data, std::size_t n) {
    buffer_.append(static_cast<const char*>(data), n);
    maybe_flush();
  }
  template <typename T>
  void put_number(T value) {
    char tmp[64];
    const auto res = std::to_chars(tmp, tmp + sizeof tmp, value);
    buffer_.append(tmp, res.ptr);
    maybe_flush();
  }

  /// Writes what is buffered to the file; returns false on an I/O error.
  bool flush();
  std::string& str() { return buffer_; }

 private:
  static constexpr std::size_t kFlushAt = 1 << 20;
  void maybe_flush() {
    if (file_ && buffer_.size() >= kFlushAt) flush();
  }
  std::FILE* file_ = nullptr;
  std::string buffer_;
  bool failed_ = false;
};

/// \throw Error "<path>: is a directory" where `path` names one. Checked before anything else about a
/// file named to be written or read (its format, its temporary file), so that this is what the user hears.
void refuse_directory(const std::filesystem::path& path);

/// Runs `write` against a temporary file in the target's directory, then renames it over `path`.
/// On any failure (an exception from `write` or an I/O error) the temporary file is removed and the
/// target is left untouched. \throw Error "<path>: <reason>".
void write_file_atomically(const std::filesystem::path& path,
                           const std::function<void(Output&)>& write);

}  // namespace lodkit::detail
