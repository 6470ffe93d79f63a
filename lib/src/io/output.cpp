#include "io/output.h"

#include <lodkit/error.h>
#include <lodkit/io.h>

#include <atomic>
#include <cerrno>
#include <csignal>
#include <cstring>
#include <fcntl.h>
#include <fmt/format.h>
#include <optional>
#include <pthread.h>
#include <random>
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

// Creates `base` + a random suffix, new, for writing. (mkstemp would make it 0600, and a chmod after it
// cannot know the umask without changing it, which races with other threads; opened here with 0666,
// the file gets the umask's permissions, as every program's output does.)
int create_temporary(const std::string& base, std::string& name) {
  static constexpr char kLetters[] = "abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789";
  thread_local std::mt19937_64 random{std::random_device{}()};
  for (int attempt = 0; attempt < 100; ++attempt) {
    name = base;
    for (int i = 0; i < 6; ++i) name += kLetters[random() % (sizeof kLetters - 1)];
    const int fd = ::open(name.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0666);
    if (fd >= 0 || errno != EEXIST) return fd;
  }
  return -1;
}

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

void refuse_directory(const std::filesystem::path& path) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) throw Error(fmt::format("{}: is a directory", path.string()));
}

void write_file_atomically(const std::filesystem::path& path,
                           const std::function<void(Output&)>& write) {
  namespace fs = std::filesystem;
  const std::string name = path.string();
  refuse_directory(path);
  const fs::path dir = path.has_parent_path() ? path.parent_path() : fs::path(".");
  std::string hidden_name(".");  // appended piecewise: GCC 12 warns falsely on "." + string
  hidden_name += path.filename().string();
  hidden_name += ".tmp-";
  std::string tmpl;
  // Created and tracked with the stopping signals held back: one that came between the two would find
  // the file untracked and leave it behind (CI caught that once). A signal held back meanwhile arrives
  // once the file is tracked.
  sigset_t stopping, before;
  sigemptyset(&stopping);
  for (const int signal : {SIGINT, SIGTERM, SIGHUP}) sigaddset(&stopping, signal);
  pthread_sigmask(SIG_BLOCK, &stopping, &before);
  const int fd = create_temporary((dir / hidden_name).string(), tmpl);
  const int created_errno = errno;
  std::optional<UnfinishedOutput> tracked;
  if (fd >= 0) tracked.emplace(tmpl.c_str());
  pthread_sigmask(SIG_SETMASK, &before, nullptr);
  if (fd < 0) throw Error(fmt::format("{}: cannot create a file there: {}", name, std::strerror(created_errno)));
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
