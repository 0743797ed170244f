#include "fault_env.h"

#include <sched.h>
#include <sys/wait.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <sstream>

namespace telegrasp::testing {
namespace {

bool g_private = false;
std::string g_failure = "enter_private_network was not called";

// Runs a shell command; its exit status, with stdout and stderr in `out`.
int run(const std::string& command, std::string& out) {
  out.clear();
  std::FILE* p = ::popen((command + " 2>&1").c_str(), "r");
  if (!p) return -1;
  std::array<char, 256> buf;
  while (std::fgets(buf.data(), buf.size(), p)) out += buf.data();
  const int status = ::pclose(p);
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

}  // namespace

bool enter_private_network(std::string& why) {
  if (::unshare(CLONE_NEWNET) != 0) {
    why = std::string("unshare(CLONE_NEWNET) failed: ") + std::strerror(errno) + " (the fault tests need root)";
    g_failure = why;
    return false;
  }
  std::string out;
  if (run("ip link set lo up", out) != 0) {
    why = "`ip link set lo up` failed in the new network namespace: " + out;
    g_failure = why;
    return false;
  }
  g_private = true;
  g_failure.clear();
  return true;
}

bool in_private_network() { return g_private; }
const std::string& private_network_failure() { return g_failure; }

std::string drop_loopback_packets(double p) {
  // An earlier test of this process may have added a rule: start from none.
  std::string flushed;
  if (run("iptables -F INPUT", flushed) != 0) return "`iptables -F INPUT` failed: " + flushed;
  if (p <= 0) return "";
  std::ostringstream cmd;
  cmd << "iptables -A INPUT -i lo -m statistic --mode random --probability " << p << " -j DROP";
  std::string out;
  if (run(cmd.str(), out) == 0) return "";
  return "`" + cmd.str() + "` failed: " + out;
}

std::vector<nlohmann::json> read_json_lines(const std::string& path) {
  std::vector<nlohmann::json> out;
  std::ifstream in(path);
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] != '{') continue;
    nlohmann::json j = nlohmann::json::parse(line, nullptr, false);
    if (j.is_object()) out.push_back(std::move(j));
  }
  return out;
}

EventIds check_event_ids(std::vector<std::uint64_t> ids) {
  EventIds e;
  std::sort(ids.begin(), ids.end());
  for (std::size_t i = 1; i < ids.size(); ++i) {
    if (ids[i] == ids[i - 1] && (e.duplicates.empty() || e.duplicates.back() != ids[i])) e.duplicates.push_back(ids[i]);
    for (std::uint64_t m = ids[i - 1] + 1; m < ids[i]; ++m) e.missing.push_back(m);
  }
  e.ids = std::move(ids);
  return e;
}

std::string EventIds::describe() const {
  std::ostringstream s;
  s << ids.size() << " events";
  if (!ids.empty()) s << " (ids " << ids.front() << ".." << ids.back() << ")";
  s << ", missing:";
  for (std::uint64_t m : missing) s << " " << m;
  s << ", duplicated:";
  for (std::uint64_t d : duplicates) s << " " << d;
  return s.str();
}

}  // namespace telegrasp::testing
