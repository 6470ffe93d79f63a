#pragma once
// A whole input file in memory, memory-mapped where possible (reading is then limited by parsing, not
// by copies). Read-only; the mapping lives as long as the buffer.
#include <filesystem>
#include <string>
#include <string_view>

namespace lodkit::detail {

class FileBuffer {
 public:
  /// \throw Error "<path>: <reason>" if the file is missing, a directory or unreadable.
  explicit FileBuffer(const std::filesystem::path& path);
  ~FileBuffer();
  FileBuffer(const FileBuffer&) = delete;
  FileBuffer& operator=(const FileBuffer&) = delete;

  std::string_view bytes() const { return {data_, size_}; }

 private:
  const char* data_ = nullptr;
  std::size_t size_ = 0;
  bool mapped_ = false;
  std::string fallback_;  // used when mmap is not possible (pipes, empty files)
};

}  // namespace lodkit::detail
