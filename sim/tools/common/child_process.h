// ChildProcess: a program started by a tool, a test or a benchmark, stopped (SIGTERM, then
// SIGKILL) when it goes. The one place that forks, execs and waits.
#pragma once

#include <chrono>
#include <string>
#include <vector>

namespace telegrasp::tools {

class ChildProcess {
 public:
  /// Starts the program at path argv[0] with arguments argv[1..]. If `log_path` is not empty,
  /// stdout and stderr go to that file (truncated); with `pipe_stdout`, stdout goes instead to a
  /// pipe read through stdout_fd() (non-blocking). Throws std::runtime_error when it cannot fork
  /// or make the pipe; a program that cannot be run exits with status 127.
  explicit ChildProcess(const std::vector<std::string>& argv, const std::string& log_path = "", bool pipe_stdout = false);
  /// Stops the child if it still runs (stop()).
  ~ChildProcess();
  ChildProcess(ChildProcess&& other) noexcept;
  ChildProcess& operator=(ChildProcess&& other) noexcept;
  ChildProcess(const ChildProcess&) = delete;
  ChildProcess& operator=(const ChildProcess&) = delete;

  int pid() const { return pid_; }
  /// The read end of the child's stdout pipe, or -1 without `pipe_stdout`.
  int stdout_fd() const { return out_fd_; }
  /// Sends `sig` (e.g. SIGKILL) without waiting; nothing once the child is reaped.
  void signal(int sig);
  /// Whether the child still runs; reaps it, without blocking, when it has ended.
  bool running();
  /// Waits up to `timeout` for the child to end: its exit status (128 + the signal's number if a
  /// signal ended it), or -1 if it still runs.
  int wait(std::chrono::milliseconds timeout);
  /// SIGTERM, then SIGKILL after `grace`: the exit status as wait() gives it.
  int stop(std::chrono::milliseconds grace = std::chrono::seconds(5));

 private:
  void release();

  int pid_ = -1;
  int out_fd_ = -1;
  int status_ = -1;
  bool reaped_ = false;
};

}  // namespace telegrasp::tools
