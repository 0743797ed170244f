// ChildProcess: a program started by a tool, a test or a benchmark, stopped (SIGTERM, then
// SIGKILL) when it goes, and sent SIGTERM by the kernel if its parent dies first. The one place
// that forks, execs and waits.
#pragma once

#include <chrono>
#include <string>
#include <vector>

namespace telegrasp::tools {

class ChildProcess {
 public:
  /// Nothing running yet; see start().
  ChildProcess() = default;
  /// start(argv, log_path, pipe_stdout).
  explicit ChildProcess(const std::vector<std::string>& argv, const std::string& log_path = "",
                        bool pipe_stdout = false);
  /// Stops the child if it still runs (stop()).
  ~ChildProcess();
  ChildProcess(ChildProcess&& other) noexcept;
  ChildProcess& operator=(ChildProcess&& other) noexcept;
  ChildProcess(const ChildProcess&) = delete;
  ChildProcess& operator=(const ChildProcess&) = delete;

  /// Starts the program at path argv[0] with arguments argv[1..]. If `log_path` is not empty,
  /// stdout and stderr go to that file (truncated); with `pipe_stdout`, stdout goes instead to a
  /// pipe read through stdout_fd() (non-blocking). Throws std::runtime_error naming what failed
  /// (the log file, the pipe, fork) and std::logic_error if a child already runs; a program that
  /// cannot be run exits with status 127.
  void start(const std::vector<std::string>& argv, const std::string& log_path = "", bool pipe_stdout = false);

  int pid() const { return pid_; }
  /// The read end of the child's stdout pipe, or -1 without `pipe_stdout`.
  int stdout_fd() const { return out_fd_; }
  const std::string& log_path() const { return log_path_; }
  /// Sends `sig` (e.g. SIGKILL) without waiting; nothing once the child is reaped.
  void signal(int sig);
  /// Whether the child still runs; reaps it, without blocking, when it has ended.
  bool running();
  /// Waits up to `timeout` for the child to end: its exit status (128 + the signal's number if a
  /// signal ended it), or -1 if it still runs.
  int wait(std::chrono::milliseconds timeout);
  /// SIGTERM, then SIGKILL after `grace`: the exit status as wait() gives it.
  int stop(std::chrono::milliseconds grace = std::chrono::seconds(5));
  /// How it ended, for messages ("exit status 1", "killed by signal Killed", plus a note when
  /// stop() had to SIGKILL it); "" while it runs.
  const std::string& exit_description() const { return exit_description_; }
  /// The last `lines` lines of the log file, for error messages.
  std::string log_tail(int lines = 15) const;

  /// The process ids of every child started and not yet reaped, in this process: for a watchdog
  /// that must stop them all before it exits. Thread-safe.
  static std::vector<int> live_pids();

 private:
  void reaped(int status);
  void release();

  int pid_ = -1;
  int out_fd_ = -1;
  int status_ = -1;
  std::string log_path_, exit_description_;
};

}  // namespace telegrasp::tools
