#pragma once
// Every benchmark run happens in a forked child: its peak memory is its own, and a crash, a hang or an
// exception is a result to report, not the end of the benchmark.
#include <malloc.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <csignal>
#include <cstdlib>
#include <exception>
#include <fstream>
#include <functional>
#include <new>
#include <string>
#include <tbb/global_control.h>
#include <vector>

namespace lodkit::bench {

struct ChildRun {
  enum class End { Exited, Crashed, TimedOut };
  End end = End::Crashed;
  int exit_code = 0;
  /// The most memory the run held: the child's peak resident set (VmHWM, reset when it starts) less
  /// what it started with, once the heap its parent had freed is handed back. A forked child starts
  /// with its parent's resident pages (the parent's meshes, and heap a previous measurement freed but
  /// kept), and wait4's ru_maxrss counts them: on the 1M-face igea that was 1.1 GB for a run that
  /// takes 0.36 GB alone.
  double peak_mib = 0;
  std::vector<double> reply;  ///< what `work` returned, empty unless all of it arrived

  /// Exited with status 0 after sending its whole reply.
  bool ok() const { return end == End::Exited && exit_code == 0; }
};

/// A line of /proc/self/status in KiB ("VmRSS", "VmHWM"), or -1 where /proc does not say.
inline double status_kib(const std::string& key) {
  std::ifstream status("/proc/self/status");
  for (std::string line; std::getline(status, line);)
    if (line.rfind(key + ":", 0) == 0) return std::stod(line.substr(key.size() + 1));
  return -1.0;
}

/// Starts a measurement of this process's peak memory from here: hands back the heap it had freed but
/// kept, and resets the kernel's high-water mark (Linux 4.0+). Returns the resident set it starts
/// from, or -1 where that cannot be done.
inline double start_peak_measurement() {
  malloc_trim(0);
  std::ofstream clear("/proc/self/clear_refs");
  if (!(clear << "5" << std::flush)) return -1.0;
  return status_kib("VmRSS");
}

/// Runs `work` in a child process, with a time limit in seconds (0: none). `work` returns
/// `reply_size` numbers, which come back through a pipe; an exception in the child ends it with exit
/// code 3.
inline ChildRun run_in_child(const std::function<std::vector<double>()>& work, std::size_t reply_size,
                             int limit_seconds = 0) {
  int fds[2];
  if (pipe(fds) != 0) std::exit(1);
  {
    // A forked child inherits TBB's state but not its worker threads, and then runs every parallel
    // loop on one thread. Ending the parent's workers first lets the child start TBB afresh.
    tbb::task_scheduler_handle handle{tbb::attach{}};
    (void)tbb::finalize(handle, std::nothrow);
  }
  const pid_t pid = fork();
  if (pid == 0) {
    close(fds[0]);
    if (limit_seconds > 0) alarm(static_cast<unsigned>(limit_seconds));
    // (Without handing back the heap the parent freed, the run's allocations would reuse those resident
    // pages unseen: bunny -> 1 % with hoppe read 2 MiB after a run on the horse.)
    const double start_kib = start_peak_measurement();
    std::vector<double> reply;
    try {
      reply = work();
    } catch (const std::exception&) {
      _exit(3);
    }
    reply.resize(reply_size);
    const double peak_kib = status_kib("VmHWM");
    reply.push_back(start_kib >= 0 && peak_kib >= 0 ? peak_kib - start_kib : -1.0);  // last, for the parent
    const auto bytes = static_cast<ssize_t>(reply.size() * sizeof(double));
    if (write(fds[1], reply.data(), static_cast<std::size_t>(bytes)) != bytes) _exit(4);
    _exit(0);
  }
  close(fds[1]);
  ChildRun run;
  std::vector<double> reply(reply_size + 1);
  const auto bytes = static_cast<ssize_t>(reply.size() * sizeof(double));
  const bool replied = read(fds[0], reply.data(), static_cast<std::size_t>(bytes)) == bytes;
  close(fds[0]);
  int status = 0;
  rusage usage{};
  wait4(pid, &status, 0, &usage);
  // The child's own measure; wait4's (which counts the parent's pages too) where it has none.
  const double own_kib = replied ? reply.back() : -1.0;
  run.peak_mib = (own_kib >= 0 ? own_kib : static_cast<double>(usage.ru_maxrss)) / 1024.0;
  reply.pop_back();
  if (WIFSIGNALED(status)) {
    run.end = WTERMSIG(status) == SIGALRM ? ChildRun::End::TimedOut : ChildRun::End::Crashed;
    return run;
  }
  run.end = ChildRun::End::Exited;
  run.exit_code = WEXITSTATUS(status);
  if (replied && run.exit_code == 0) run.reply = std::move(reply);
  return run;
}

}  // namespace lodkit::bench
