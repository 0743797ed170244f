#include "child_process.h"

#include <cerrno>
#include <csignal>
#include <cstring>
#include <deque>
#include <fstream>
#include <mutex>
#include <set>
#include <stdexcept>
#include <thread>
#include <utility>

#include <fcntl.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

namespace telegrasp::tools {
namespace {

std::mutex g_live_mutex;
std::set<int> g_live;

void set_live(int pid, bool live) {
  std::lock_guard lock(g_live_mutex);
  if (live)
    g_live.insert(pid);
  else
    g_live.erase(pid);
}

void write_stderr(const char* s) { (void)!::write(STDERR_FILENO, s, std::strlen(s)); }

}  // namespace

ChildProcess::ChildProcess(const std::vector<std::string>& argv, const std::string& log_path, bool pipe_stdout) {
  start(argv, log_path, pipe_stdout);
}

ChildProcess::~ChildProcess() { release(); }

ChildProcess::ChildProcess(ChildProcess&& other) noexcept { *this = std::move(other); }

ChildProcess& ChildProcess::operator=(ChildProcess&& other) noexcept {
  if (this != &other) {
    release();
    pid_ = std::exchange(other.pid_, -1);
    out_fd_ = std::exchange(other.out_fd_, -1);
    status_ = other.status_;
    log_path_ = std::move(other.log_path_);
    exit_description_ = std::move(other.exit_description_);
  }
  return *this;
}

void ChildProcess::release() {
  stop();
  if (out_fd_ >= 0) ::close(out_fd_);
  out_fd_ = -1;
}

void ChildProcess::start(const std::vector<std::string>& argv, const std::string& log_path, bool pipe_stdout) {
  if (pid_ > 0) throw std::logic_error("ChildProcess::start: a child already runs");
  if (argv.empty()) throw std::logic_error("ChildProcess::start: no program given");
  if (out_fd_ >= 0) ::close(out_fd_);
  out_fd_ = -1;
  status_ = -1;
  log_path_ = log_path;
  exit_description_.clear();
  const int log = log_path.empty() ? -1 : ::open(log_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (!log_path.empty() && log < 0)
    throw std::runtime_error("cannot write the log file " + log_path + ": " + std::strerror(errno));
  int fds[2] = {-1, -1};
  if (pipe_stdout && ::pipe(fds) != 0) {
    const int error = errno;
    if (log >= 0) ::close(log);
    throw std::runtime_error(std::string("pipe: ") + std::strerror(error));
  }
  // Everything the child needs is built before fork: after it, only async-signal-safe calls.
  std::vector<char*> args;
  for (const std::string& a : argv) args.push_back(const_cast<char*>(a.c_str()));
  args.push_back(nullptr);
  const pid_t parent = ::getpid();
  const pid_t pid = ::fork();
  if (pid < 0) {
    const int error = errno;
    for (int fd : {fds[0], fds[1], log})
      if (fd >= 0) ::close(fd);
    throw std::runtime_error(std::string("fork: ") + std::strerror(error));
  }
  if (pid == 0) {
    // The kernel sends SIGTERM when the parent dies, so no child outlives a crashed parent.
    ::prctl(PR_SET_PDEATHSIG, SIGTERM);
    if (::getppid() != parent) ::_exit(126);  // the parent died before prctl
    if (log >= 0) {
      ::dup2(log, STDERR_FILENO);
      if (!pipe_stdout) ::dup2(log, STDOUT_FILENO);
    }
    if (pipe_stdout) {
      ::dup2(fds[1], STDOUT_FILENO);
      ::close(fds[0]);
      ::close(fds[1]);
    }
    ::execv(args[0], args.data());
    const char* why = std::strerror(errno);
    write_stderr("cannot run ");
    write_stderr(args[0]);
    write_stderr(": ");
    write_stderr(why);
    write_stderr("\n");
    ::_exit(127);
  }
  if (log >= 0) ::close(log);
  if (pipe_stdout) {
    ::close(fds[1]);
    out_fd_ = fds[0];
    ::fcntl(out_fd_, F_SETFL, O_NONBLOCK);
  }
  pid_ = pid;
  set_live(pid, true);
}

void ChildProcess::reaped(int status) {
  set_live(pid_, false);
  if (WIFEXITED(status)) {
    status_ = WEXITSTATUS(status);
    exit_description_ = "exit status " + std::to_string(status_);
  } else if (WIFSIGNALED(status)) {
    status_ = 128 + WTERMSIG(status);
    exit_description_ = std::string("killed by signal ") + strsignal(WTERMSIG(status));
  } else {
    status_ = 128;
    exit_description_ = "status " + std::to_string(status);
  }
  pid_ = -1;
}

void ChildProcess::signal(int sig) {
  if (pid_ > 0) ::kill(pid_, sig);
}

bool ChildProcess::running() {
  if (pid_ <= 0) return false;
  int status = 0;
  if (::waitpid(pid_, &status, WNOHANG) == pid_) reaped(status);
  return pid_ > 0;
}

int ChildProcess::wait(std::chrono::milliseconds timeout) {
  const auto end = std::chrono::steady_clock::now() + timeout;
  while (running()) {
    if (std::chrono::steady_clock::now() >= end) return -1;
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  return status_;
}

int ChildProcess::stop(std::chrono::milliseconds grace) {
  if (!running()) return status_;
  signal(SIGTERM);
  if (wait(grace) >= 0) return status_;
  signal(SIGKILL);
  int status = 0;
  while (::waitpid(pid_, &status, 0) < 0 && errno == EINTR) {}
  reaped(status);
  exit_description_ += " (did not stop within " + std::to_string(grace.count()) + " ms of SIGTERM: SIGKILLed)";
  return status_;
}

std::string ChildProcess::log_tail(int lines) const {
  std::ifstream in(log_path_);
  std::deque<std::string> tail;
  for (std::string line; std::getline(in, line);) {
    tail.push_back(line);
    if (static_cast<int>(tail.size()) > lines) tail.pop_front();
  }
  std::string out;
  for (const std::string& line : tail) out += "    " + line + "\n";
  return out;
}

std::vector<int> ChildProcess::live_pids() {
  std::lock_guard lock(g_live_mutex);
  return {g_live.begin(), g_live.end()};
}

}  // namespace telegrasp::tools
