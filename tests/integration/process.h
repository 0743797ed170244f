// Process: a child program started for a test and killed (SIGTERM, then SIGKILL) when it goes.
#pragma once

#include <chrono>
#include <string>
#include <vector>

namespace telegrasp::testing {

class Process {
 public:
  /// Starts `program` (a path) with `args`; stdout and stderr go to `log_path` if not empty.
  Process(const std::string& program, const std::vector<std::string>& args, const std::string& log_path = "");
  ~Process();
  Process(const Process&) = delete;
  Process& operator=(const Process&) = delete;

  int pid() const { return pid_; }
  /// Sends a signal (e.g. SIGKILL) without waiting.
  void signal(int sig);
  /// Waits up to `timeout` for the process to end; its exit code (128 + signal if killed), or -1
  /// if it is still running.
  int wait(std::chrono::milliseconds timeout);
  bool running();

 private:
  int pid_ = -1;
  int status_ = -1;
  bool reaped_ = false;
};

/// Full path of a program built into build/bin.
std::string bin(const std::string& name);

}  // namespace telegrasp::testing
