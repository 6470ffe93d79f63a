#include "io/output.h"

#include <lodkit/error.h>

#include <lodkit/io.h>

#include <atomic>
#include <cerrno>
#include <cstring>
#include <fmt/format.h>
#include <sys/stat.h>
#include <unistd.h>

namespace lodkit {
namespace {

// The temporary files being written, for remove_unfinished_outputs(): a fixed table of pointers to
// their names, because a signal handler may neither lock nor allocate. (A write that finds the table
// full is not tracked; 32 writes at once is more than lodkit ever runs.)
constexpr int kTrackedWrites = 32;
std::atomic<const char*> g_unfinished[kTrackedWrites];
static_assert(std::atomic<const char*>::is_always_lock_free);

// Tracks `path` while it lives; the name must outlive it.
class UnfinishedOutput {
 public:
  explicit UnfinishedOutput(const char* path) {
    for (auto& slot : g_unfinished) {
      const char* empty = nullptr;
      if (slot.compare_exchange_strong(empty, path)) {
        slot_ = &slot;
        return;
      }
    }
  }
  ~UnfinishedOutput() {
    if (slot_) slot_->store(nullptr);
  }
  UnfinishedOutput(const UnfinishedOutput&) = delete;
  UnfinishedOutput& operator=(const UnfinishedOutput&) = delete;

 private:
  std::atomic<const char*>* slot_ = nullptr;
};

}  // namespace

void remove_unfinished_outputs() noexcept {
  for (auto& slot : g_unfinished)
    if (const char* path = slot.load()) ::unlink(path);  // (after the rename, its old name is gone: no-op)
}

}  // namespace lodkit

namespace lodkit::detail {

bool Output::flush() {
  if (!file_ || buffer_.empty()) return !failed_;
  if (std::fwrite(buffer_.data(), 1, buffer_.size(), file_) != buffer_.size()) failed_ = true;
  buffer_.clear();
  return !failed_;
}

void write_file_atomically(const std::filesystem::path& path,
                           const std::function<void(Output&)>& write) {
  namespace fs = std::filesystem;
  const std::string name = path.string();
  if (fs::is_directory(path)) throw Error(fmt::format("{}: is a directory", name));
  const fs::path dir = path.has_parent_path() ? path.parent_path() : fs::path(".");
  std::string hidden_name(".");  // appended piecewise: GCC 12 warns falsely on "." + string
  hidden_name += path.filename().string();
  hidden_name += ".tmp-XXXXXX";
  std::string tmpl = (dir / hidden_name).string();
  const int fd = ::mkstemp(tmpl.data());
  if (fd < 0) throw Error(fmt::format("{}: cannot create a file there: {}", name, std::strerror(errno)));
  const UnfinishedOutput tracked(tmpl.c_str());
  ::fchmod(fd, 0644);
  std::FILE* file = ::fdopen(fd, "wb");
  if (!file) {
    ::close(fd);
    ::unlink(tmpl.c_str());
    throw Error(fmt::format("{}: cannot open for writing", name));
  }
  auto discard = [&] {
    std::fclose(file);
    ::unlink(tmpl.c_str());
  };
  bool flushed = false;
  try {
    Output out(file);
    write(out);
    flushed = out.flush() && std::fflush(file) == 0;
  } catch (...) {
    // The temporary file is incomplete: remove it so no partial output is ever left behind.
    discard();
    throw;
  }
  if (!flushed) {
    const int err = errno;
    discard();
    throw Error(fmt::format("{}: write failed: {}", name, std::strerror(err)));
  }
  if (std::fclose(file) != 0) {
    const int err = errno;
    ::unlink(tmpl.c_str());
    throw Error(fmt::format("{}: write failed: {}", name, std::strerror(err)));
  }
  if (::rename(tmpl.c_str(), name.c_str()) != 0) {
    const int err = errno;
    ::unlink(tmpl.c_str());
    throw Error(fmt::format("{}: cannot rename the finished file into place: {}", name,
                            std::strerror(err)));
  }
}

}  // namespace lodkit::detail
