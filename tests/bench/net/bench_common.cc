#include "bench_common.h"

#include "telegrasp/idl/cli.h"
#include "telegrasp/idl/profiles.h"
#include "telegrasp/idl/telegraspPubSubTypes.h"
#include "telegrasp/idl/topics.h"

#include <fastdds/dds/core/status/PublicationMatchedStatus.hpp>
#include <fastdds/dds/core/status/SubscriptionMatchedStatus.hpp>
#include <fastdds/dds/subscriber/SampleInfo.hpp>
#include <fastrtps/attributes/LibrarySettingsAttributes.h>
#include <fastrtps/xmlparser/XMLProfileManager.h>

#include <algorithm>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <deque>
#include <fcntl.h>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <numbers>
#include <set>
#include <sstream>
#include <sys/prctl.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <thread>
#include <unistd.h>

namespace telegrasp::bench {

std::int64_t now_ns() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(Clock::now().time_since_epoch()).count();
}

// ---------------------------------------------------------------------------------------------

namespace {
std::atomic<bool> g_stop{false};
extern "C" void on_stop_signal(int) { g_stop = true; }

// Running children, for the watchdog.
}  // namespace

void install_signal_handlers() {
  std::signal(SIGINT, on_stop_signal);
  std::signal(SIGTERM, on_stop_signal);
}

bool stop_requested() { return g_stop.load(); }

bool sleep_unless_stopped(double seconds) {
  const auto end = Clock::now() + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(seconds));
  while (Clock::now() < end) {
    if (stop_requested()) return false;
    std::this_thread::sleep_for(std::min<Clock::duration>(std::chrono::milliseconds(20), end - Clock::now()));
  }
  return !stop_requested();
}

Watchdog::Watchdog(double seconds) {
  thread_ = std::thread([this, seconds] {
    const auto start = Clock::now();
    std::optional<Clock::time_point> stop_seen;
    while (!done_) {
      std::this_thread::sleep_for(std::chrono::milliseconds(100));
      const auto now = Clock::now();
      if (stop_requested() && !stop_seen) stop_seen = now;
      const bool overdue = std::chrono::duration<double>(now - start).count() > seconds;
      const bool stuck = stop_seen && now - *stop_seen > std::chrono::seconds(15);
      if (!overdue && !stuck) continue;
      std::fprintf(stderr, "telegrasp-bench: watchdog: %s; killing the children and exiting\n",
                   overdue ? "the run exceeded its time limit (a hang, e.g. inside Fast DDS)"
                           : "no clean stop 15 s after the signal");
      const std::vector<int> children = ChildProcess::live_pids();
      for (int pid : children) ::kill(pid, SIGTERM);
      std::this_thread::sleep_for(std::chrono::seconds(3));
      for (int pid : children) ::kill(pid, SIGKILL);
      ::_exit(1);
    }
  });
}

Watchdog::~Watchdog() {
  done_ = true;
  thread_.join();
}

std::string self_exe() { return std::filesystem::read_symlink("/proc/self/exe").string(); }

std::string default_server_path() {
  return (std::filesystem::path(self_exe()).parent_path() / "telegrasp-server").string();
}

// ---------------------------------------------------------------------------------------------

namespace {
std::int64_t stat_cpu_us(const std::string& path) {
  std::ifstream in(path);
  std::string text;
  if (!std::getline(in, text)) return -1;
  const auto close = text.rfind(')');
  if (close == std::string::npos) return -1;
  std::istringstream fields(text.substr(close + 2));  // from field 3 (state) on
  std::string f;
  long long utime = -1, stime = -1;
  for (int field = 3; field <= 15 && fields >> f; ++field) {
    if (field == 14) utime = std::stoll(f);
    if (field == 15) stime = std::stoll(f);
  }
  if (utime < 0 || stime < 0) return -1;
  static const long ticks = ::sysconf(_SC_CLK_TCK);
  return (utime + stime) * 1000000LL / ticks;
}
}  // namespace

std::int64_t process_cpu_us(pid_t pid) { return stat_cpu_us("/proc/" + std::to_string(pid) + "/stat"); }

std::int64_t thread_cpu_us(pid_t pid, pid_t tid) {
  return stat_cpu_us("/proc/" + std::to_string(pid) + "/task/" + std::to_string(tid) + "/stat");
}

std::map<pid_t, std::int64_t> threads_cpu_us(pid_t pid) {
  std::map<pid_t, std::int64_t> out;
  std::error_code ec;
  for (const auto& entry : std::filesystem::directory_iterator("/proc/" + std::to_string(pid) + "/task", ec)) {
    const pid_t tid = static_cast<pid_t>(std::stol(entry.path().filename().string()));
    if (const std::int64_t us = thread_cpu_us(pid, tid); us >= 0) out[tid] = us;
  }
  return out;
}

std::int64_t self_cpu_us() {
  rusage u{};
  ::getrusage(RUSAGE_SELF, &u);
  return (u.ru_utime.tv_sec + u.ru_stime.tv_sec) * 1000000LL + u.ru_utime.tv_usec + u.ru_stime.tv_usec;
}

std::int64_t machine_busy_us() {
  std::ifstream in("/proc/stat");
  std::string cpu;
  long long user = 0, nice = 0, system = 0, idle = 0, iowait = 0, irq = 0, softirq = 0, steal = 0;
  if (!(in >> cpu >> user >> nice >> system >> idle >> iowait >> irq >> softirq >> steal) || cpu != "cpu") return -1;
  static const long ticks = ::sysconf(_SC_CLK_TCK);
  return (user + nice + system + irq + softirq + steal) * 1000000LL / ticks;
}

InterfaceCounters loopback_counters() {
  std::ifstream in("/proc/net/dev");
  std::string line;
  while (std::getline(in, line)) {
    const auto colon = line.find(':');
    if (colon == std::string::npos) continue;
    std::string name = line.substr(0, colon);
    name.erase(0, name.find_first_not_of(' '));
    if (name != "lo") continue;
    std::istringstream fields(line.substr(colon + 1));
    InterfaceCounters c;
    if (fields >> c.bytes >> c.packets) return c;
  }
  return {};
}

// ---------------------------------------------------------------------------------------------

void load_profiles(const std::string& file, const std::string& participant_profile) {
  idl::load_profiles(file, participant_profile);
  eprosima::fastrtps::LibrarySettingsAttributes settings;
  settings.intraprocess_delivery = eprosima::fastrtps::INTRAPROCESS_OFF;
  eprosima::fastrtps::xmlparser::XMLProfileManager::library_settings(settings);
}

int matched_readers(dds::DataWriter* writer) {
  dds::PublicationMatchedStatus s;
  writer->get_publication_matched_status(s);
  return s.current_count;
}

int matched_writers(dds::DataReader* reader) {
  dds::SubscriptionMatchedStatus s;
  reader->get_subscription_matched_status(s);
  return s.current_count;
}

bool wait_until(const std::function<bool()>& ready, double timeout_s) {
  const auto end = Clock::now() + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(timeout_s));
  while (!ready()) {
    if (Clock::now() >= end || stop_requested()) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  return true;
}

// ---------------------------------------------------------------------------------------------

ServerOptions server_options(const CommonOptions& o) {
  ServerOptions so;
  so.path = o.server;
  so.domain = o.domain;
  so.profile = o.profile;
  so.profiles_file = o.profiles_file;
  so.late_latch = o.late_latch;
  so.tick_hz = o.tick_hz;
  so.extra = o.server_args;
  return so;
}

std::vector<std::string> server_argv(const ServerOptions& o) {
  // The benchmarks drive many hands from one participant at any rate: the per-client limits are lifted.
  std::vector<std::string> a{o.path,      "--domain",         std::to_string(o.domain),
                             "--profile", o.profile,          "--max-hands-per-participant",
                             "4096",      "--max-input-rate", "1000000"};
  if (o.empty_scene) a.insert(a.begin() + 5, "--empty-scene");
  if (!o.profiles_file.empty()) a.insert(a.end(), {"--profiles", o.profiles_file});
  if (!o.late_latch) a.push_back("--no-late-latch");
  if (o.tick_hz > 0) a.insert(a.end(), {"--tick-hz", cli::format_number(o.tick_hz)});
  a.insert(a.end(), o.extra.begin(), o.extra.end());
  return a;
}

void StatusCollector::on_data_available(dds::DataReader* reader) {
  Record r;
  dds::SampleInfo info;
  while (reader->take_next_sample(&r.status, &info) == ReturnCode_t::RETCODE_OK) {
    if (!info.valid_data) continue;
    r.received_ns = now_ns();
    const pid_t pid = server_pid_.load();
    if (pid > 0) {
      const auto& prefix = info.sample_identity.writer_guid().guidPrefix.value;
      const unsigned writer_pid16 = static_cast<unsigned>(prefix[4]) | static_cast<unsigned>(prefix[5]) << 8;
      if (writer_pid16 != (static_cast<unsigned>(pid) & 0xFFFFu)) {
        ++foreign_;
        continue;
      }
    } else {
      ++foreign_;  // no server of ours yet: whoever this is, it is not ours
      continue;
    }
    r.server_cpu_us = process_cpu_us(pid);
    r.sim_thread_cpu_us = thread_cpu_us(pid, pid);
    r.self_cpu_us = self_cpu_us();
    r.machine_busy_us = machine_busy_us();
    r.lo = loopback_counters();
    std::lock_guard lock(mutex_);
    records_.push_back(r);
    cv_.notify_all();
  }
}

std::size_t StatusCollector::count() const {
  std::lock_guard lock(mutex_);
  return records_.size();
}

std::optional<StatusCollector::Record> StatusCollector::latest() const {
  std::lock_guard lock(mutex_);
  if (records_.empty()) return std::nullopt;
  return records_.back();
}

std::vector<StatusCollector::Record> StatusCollector::since(std::int64_t t_ns) const {
  std::lock_guard lock(mutex_);
  std::vector<Record> out;
  for (const auto& r : records_)
    if (r.received_ns >= t_ns) out.push_back(r);
  return out;
}

std::optional<StatusCollector::Record> StatusCollector::wait_for(
    std::int64_t after_ns, double timeout_s, const std::function<bool(const msg::ServerStatus&)>& pred) {
  const auto end = Clock::now() + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(timeout_s));
  std::unique_lock lock(mutex_);
  std::size_t checked = 0;
  while (true) {
    for (; checked < records_.size(); ++checked) {
      const Record& r = records_[checked];
      if (r.received_ns >= after_ns && (!pred || pred(r.status))) return r;
    }
    if (Clock::now() >= end || stop_requested()) return std::nullopt;
    cv_.wait_for(lock, std::chrono::milliseconds(50));
  }
}

void start_server(ChildProcess& child, const ServerOptions& o, StatusCollector& collector, double timeout_s) {
  if (::access(o.path.c_str(), X_OK) != 0)
    throw std::runtime_error("--server: " + o.path +
                             " is not an executable file (build the telegrasp-server target, or pass --server PATH)");
  const auto argv = server_argv(o);
  // A server already on the domain would mix its inputs and outputs with ours.
  wait_until([&] { return collector.foreign() > 0; }, 1.5);
  if (collector.foreign() > 0)
    throw std::runtime_error("another telegrasp-server already publishes ServerStatus on domain " +
                             std::to_string(o.domain) + "; pick a free one with --domain");
  child.start(argv, o.log_path);
  collector.set_server_pid(child.pid());
  const auto end = Clock::now() + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(timeout_s));
  while (collector.count() == 0) {
    if (!child.running())
      throw std::runtime_error("telegrasp-server exited (" + child.exit_description() +
                               ") before sending a ServerStatus; command: " + join_command(argv) + "\n  log " +
                               o.log_path + ":\n" + child.log_tail());
    if (stop_requested()) throw std::runtime_error("interrupted while waiting for telegrasp-server");
    if (Clock::now() >= end)
      throw std::runtime_error("telegrasp-server sent no ServerStatus within " +
                               std::to_string(static_cast<int>(timeout_s)) + " s on domain " +
                               std::to_string(o.domain) + "; command: " + join_command(argv) + "\n  log " + o.log_path +
                               ":\n" + child.log_tail());
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
}

// ---------------------------------------------------------------------------------------------

Summary summarize(std::vector<double> v) {
  Summary s;
  s.count = v.size();
  if (v.empty()) return s;
  std::sort(v.begin(), v.end());
  auto rank = [&](double p) {
    const auto k = static_cast<std::size_t>(std::ceil(p * static_cast<double>(v.size())));
    return v[std::clamp<std::size_t>(k, 1, v.size()) - 1];
  };
  s.p50 = rank(0.50);
  s.p90 = rank(0.90);
  s.p99 = rank(0.99);
  s.max = v.back();
  double sum = 0;
  for (double x : v) sum += x;
  s.mean = sum / static_cast<double>(v.size());
  return s;
}

msg::Quat wobble_quaternion(double angle) {
  const double n = std::sqrt(1.0 + 4.0 + 9.0);
  const double s = std::sin(angle / 2);
  msg::Quat q;
  q.w(std::cos(angle / 2));
  q.x(s * 1.0 / n);
  q.y(s * 2.0 / n);
  q.z(s * 3.0 / n);
  return q;
}

msg::ControllerState controller_sample(const std::string& client_id, int client, int side, std::uint64_t seq,
                                       double t) {
  constexpr double kTwoPi = 2 * std::numbers::pi;
  const double phase = 0.37 * client + 1.3 * side;
  msg::ControllerState s;
  s.client_id(client_id);
  s.hand_side(static_cast<std::uint8_t>(side));
  s.sequence_number(seq);
  msg::Pose3 palm;
  msg::Vec3 p;
  p.x(-1.85 + 0.11 * (client % 16) + 0.05 * std::sin(kTwoPi * 0.3 * t + phase));
  p.y(-1.75 + 0.45 * (client / 16 % 8) + (side == idl::kHandLeft ? -0.1 : 0.1) +
      0.05 * std::cos(kTwoPi * 0.4 * t + phase));
  p.z(0.45 + 0.1 * std::sin(kTwoPi * 0.5 * t + phase));
  palm.position(p);
  palm.orientation(wobble_quaternion(0.6 * std::sin(kTwoPi * 0.25 * t + phase)));
  s.palm(palm);
  s.trigger(std::clamp(0.5 - 0.5 * std::cos(kTwoPi * 0.5 * t + phase), 0.0, 1.0));
  s.buttons(0);
  s.tracking_valid(true);
  return s;
}

std::string join_command(const std::vector<std::string>& argv) {
  std::string out;
  for (const auto& a : argv) {
    if (!out.empty()) out += ' ';
    if (a.find_first_of(" \t\"'$\\") == std::string::npos && !a.empty())
      out += a;
    else
      out += "'" + a + "'";
  }
  return out;
}

}  // namespace telegrasp::bench
