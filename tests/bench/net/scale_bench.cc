// telegrasp-bench-scale: how many hands telegrasp-server sustains at its tick rate without
// missing a tick, and what each costs in server CPU.
#include "bench_common.h"
#include "cli.h"
#include "test_domain.h"

#include "telegrasp/idl/telegraspPubSubTypes.h"
#include "telegrasp/idl/topics.h"

#include <fastdds/dds/publisher/DataWriter.hpp>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <optional>
#include <thread>
#include <unistd.h>

namespace {

namespace msg = telegrasp::msg;
namespace idl = telegrasp::idl;
using namespace telegrasp::bench;
namespace cli = telegrasp::cli;
namespace dds = eprosima::fastdds::dds;  // also a global namespace dds in the Fast DDS headers

constexpr const char* kUsage = R"(Usage: telegrasp-bench-scale [options]

Starts telegrasp-server (--empty-scene, private domain, max_hands raised to --max through a
temporary --config file) as a child process, then publishes ControllerState for a growing number
of hands from publisher threads of this process (one DomainParticipant each; client ids
"scale-<i>", 2 hands each, smooth motion in the air, oscillating trigger), adding --step hands per
level. Each level is measured over --seconds-per-step between two ServerStatus samples: missed
ticks, tick work p50/max, hands, accepted inputs, and the CPU time (utime+stime, /proc) of the
server, of its simulation thread and of this publisher process. A level is sustained when no tick
was missed, the server reports every hand, the publishers kept --sample-hz and the server accepted at
least 90% of what they wrote. The first level that is not sustained is measured once more (a
one-off hiccup does not count); if it fails again, or at --max, the run stops. Level 0 (idle
server) is measured first as the baseline.

Fast DDS intraprocess delivery is off in this process (several participants in one process
deadlock Fast DDS 2.9.1's liveliness protocol, eProsima/Fast-DDS#3115), so its participants talk
through the transport as separate processes would. The run stops with an error if another
telegrasp-server already answers on --domain; a watchdog kills the children if anything hangs.
Reported: hands_sustained and cpu_us_per_hand_tick (server CPU, all threads, per hand per tick) at
that level; also the largest level at which the machine was not saturated (< 80% of all cores
busy; the publishers share them) with its cost per hand, the marginal cost (least squares over
the unsaturated levels), and the largest level at which <= 1% of the inputs were lost. Past
saturation the server's cost per hand falls (samples batch up per wake-up, some are dropped), so
that figure is the honest one for the server itself.

Options:
  --sample-hz HZ         controller sample rate per hand (default 90; --hz, its old name, still
                         works for one release)
  --tick-hz HZ           the server's tick rate (default: the server's, 90)
  --step N               hands added per level, even (default 8)
  --max N                last level (default 512)
  --seconds-per-step S   measured seconds per level (default 3)
  --publishers N         publisher threads/participants in this process (default 2)
  --json FILE            also write the results as JSON
  --profile NAME         Fast DDS participant profile (default loopback)
  --profiles FILE        Fast DDS XML profiles file (default: the telegrasp one)
  --domain D             DDS domain of this run, 0..232 (default: a free one, leased as the
                         tests lease theirs: tests/common/test_domain.h)
  --server PATH          telegrasp-server executable (default: the one next to this program)
  --server-arg ARG       one more argument for the server (repeatable)
  --server-log FILE      server output (default: a temporary file, removed after a clean run)
  --no-late-latch        start the server with --no-late-latch
  -h, --help             this text

Exit status: 0 done, 1 a runtime failure (the server could not be started or never answered, an
output could not be written), 2 a usage error (a bad or missing option or value).
)";

struct Options : CommonOptions {
  int step = 8;
  int max = 512;
  double seconds_per_step = 3;
  int publishers = 2;
};

constexpr const char* kTool = "telegrasp-bench-scale";

[[noreturn]] void usage_error(const std::string& what) { cli::usage_exit(kTool, what); }

Options parse(int argc, char** argv) {
  Options o;
  cli::for_each_option(argc, argv, kUsage, usage_error, [&](const std::string& f, const auto& value) {
    if (parse_common_option(kTool, f, value, o, usage_error)) return true;
    if (f == "--step")
      o.step = static_cast<int>(cli::parse_whole(f, value(), 2, 4096, usage_error));
    else if (f == "--max")
      o.max = static_cast<int>(cli::parse_whole(f, value(), 2, 4096, usage_error));
    else if (f == "--seconds-per-step")
      o.seconds_per_step = cli::parse_number(f, value(), 1, 600, usage_error);
    else if (f == "--publishers")
      o.publishers = static_cast<int>(cli::parse_whole(f, value(), 1, 64, usage_error));
    else
      return false;
    return true;
  });
  if (o.step % 2 != 0)
    usage_error("--step expects an even number of hands (2 per client id), got " + std::to_string(o.step));
  if (o.max % 2 != 0)
    usage_error("--max expects an even number of hands (2 per client id), got " + std::to_string(o.max));
  if (o.server.empty()) o.server = default_server_path();
  return o;
}

/// Publisher threads: thread p owns client ids c with c % P == p and publishes both hands of
/// each of them once per period while 2c < hands(). Clients are spread over 8 slots per period so
/// the server sees a steady stream rather than one burst per period.
class Publishers {
 public:
  Publishers(int count, int domain, const std::string& profile, const std::string& profiles_file, double hz,
             int max_hands)
      : hz_(hz) {
    for (int p = 0; p < count; ++p) {
      participants_.push_back(std::make_unique<idl::DdsParticipant>(domain, profile, profiles_file));
      writers_.push_back(participants_.back()->writer<msg::ControllerStatePubSubType>(idl::kControllerStateTopic));
    }
    for (int c = 0; c < max_hands / 2; ++c) ids_.push_back("scale-" + std::to_string(c));
  }
  ~Publishers() { stop(); }

  bool matched(double timeout_s) {
    return wait_until(
        [&] {
          for (auto* w : writers_)
            if (matched_readers(w) == 0) return false;
          return true;
        },
        timeout_s);
  }
  void start() {
    t0_ = Clock::now();
    for (int p = 0; p < static_cast<int>(writers_.size()); ++p) threads_.emplace_back([this, p] { run(p); });
  }
  void stop() {
    stop_ = true;
    for (auto& t : threads_) t.join();
    threads_.clear();
  }
  void set_hands(int hands) { hands_ = hands; }
  std::uint64_t written() const { return written_.load(); }
  std::uint64_t skipped_periods() const { return skipped_.load(); }

 private:
  static constexpr int kSlots = 8;
  void run(int p) {
    const int threads = static_cast<int>(writers_.size());
    const auto period = std::chrono::duration<double>(1.0 / hz_);
    std::vector<std::uint64_t> seq(ids_.size() * 2, 0);
    std::uint64_t k = 0;
    while (!stop_ && !stop_requested()) {
      for (int slot = 0; slot < kSlots && !stop_; ++slot) {
        const double offset = (slot + static_cast<double>(p) / threads) / kSlots;
        const auto due = t0_ + std::chrono::duration_cast<Clock::duration>(period * (static_cast<double>(k) + offset));
        std::this_thread::sleep_until(due);
        const int hands = hands_.load();
        const double t = std::chrono::duration<double>(Clock::now() - t0_).count();
        for (int c = p + threads * slot; 2 * c < hands; c += threads * kSlots) {
          for (int side = 0; side < 2; ++side) {
            msg::ControllerState s = controller_sample(ids_[c], c, side, ++seq[2 * c + side], t);
            s.client_time_ns(now_ns());
            writers_[p]->write(&s);
            ++written_;
          }
        }
      }
      ++k;
      // Far behind (starved of CPU): skip the lost periods rather than burst to catch up.
      const auto behind = std::chrono::duration<double>(Clock::now() - t0_).count() * hz_ - static_cast<double>(k);
      if (behind > 1) {
        skipped_ += static_cast<std::uint64_t>(behind);
        k += static_cast<std::uint64_t>(behind);
      }
    }
  }

  double hz_;
  std::vector<std::unique_ptr<idl::DdsParticipant>> participants_;
  std::vector<dds::DataWriter*> writers_;
  std::vector<std::string> ids_;
  std::vector<std::thread> threads_;
  Clock::time_point t0_;
  std::atomic<bool> stop_{false};
  std::atomic<int> hands_{0};
  std::atomic<std::uint64_t> written_{0}, skipped_{0};
};

struct Step {
  int hands = 0;
  int attempt = 1;
  bool sustained = false;
  std::string why;  // what failed, if not sustained
  double window_s = 0;
  std::uint64_t ticks = 0, missed = 0;
  int hands_min = 0, hands_max = 0;
  double tick_us_p50 = 0, tick_us_max = 0;
  double server_cpu_us = 0, sim_cpu_us = 0, pub_cpu_us = 0, other_cpu_us = 0, machine_cpu_us = 0;
  double published_per_hand_hz = 0, accepted_per_hand_hz = 0;
  std::uint64_t rejected = 0, skipped_periods = 0;
  std::vector<std::pair<pid_t, double>> threads_cpu_pct;  // the server's busiest threads

  double server_cpu_pct() const { return server_cpu_us / (window_s * 1e6) * 100; }
  double sim_cpu_pct() const { return sim_cpu_us / (window_s * 1e6) * 100; }
  double pub_cpu_pct() const { return pub_cpu_us / (window_s * 1e6) * 100; }
  double other_cpu_pct() const { return other_cpu_us / (window_s * 1e6) * 100; }
  double machine_cpu_pct() const { return machine_cpu_us / (window_s * 1e6) * 100; }
  /// The machine's cores were >= 80% busy: the server competes for CPU and its cost per hand
  /// falls (samples batch up per wake-up, inputs get dropped), so such levels say little about it.
  bool saturated() const { return machine_cpu_pct() >= 80.0 * std::thread::hardware_concurrency(); }
  /// Inputs the publishers wrote that the server never accepted, %.
  double input_loss_pct() const {
    return published_per_hand_hz > 0 ? 100 * (1 - accepted_per_hand_hz / published_per_hand_hz) : 0;
  }
  double cpu_us_per_tick() const { return ticks ? server_cpu_us / static_cast<double>(ticks) : 0; }
  double cpu_us_per_hand_tick() const {
    return hands && ticks ? server_cpu_us / (static_cast<double>(hands) * static_cast<double>(ticks)) : 0;
  }
};

/// Measures the current level between two ServerStatus samples about `seconds` apart.
Step measure(int hands, int attempt, const Options& o, StatusCollector& status, Publishers& pubs, pid_t server) {
  Step st;
  st.hands = hands;
  st.attempt = attempt;
  const std::int64_t t_set = now_ns();
  // The window opens at the first status that reports every hand of the level.
  const auto start = status.wait_for(t_set, 6, [&](const msg::ServerStatus& s) { return s.hands() == hands; });
  if (!start) {
    const auto last = status.latest();
    st.why = "the server did not report " + std::to_string(hands) +
             " hands within 6 s (last status: " + (last ? std::to_string(last->status.hands()) : std::string("none")) +
             ")";
    return st;
  }
  const std::uint64_t written0 = pubs.written(), skipped0 = pubs.skipped_periods();
  const auto threads0 = threads_cpu_us(server);
  const std::int64_t threads_t0 = now_ns();
  const auto end = status.wait_for(start->received_ns + static_cast<std::int64_t>((o.seconds_per_step - 0.5) * 1e9),
                                   o.seconds_per_step + 5);
  if (!end) {
    st.why = stop_requested()
                 ? "interrupted"
                 : "no ServerStatus for " + std::to_string(static_cast<int>(o.seconds_per_step + 5)) + " s";
    return st;
  }
  const std::uint64_t written1 = pubs.written(), skipped1 = pubs.skipped_periods();
  const auto threads1 = threads_cpu_us(server);
  const double threads_s = static_cast<double>(now_ns() - threads_t0) * 1e-9;
  for (const auto& [tid, us] : threads1) {
    const auto it = threads0.find(tid);
    const double d = static_cast<double>(us - (it == threads0.end() ? 0 : it->second));
    if (d > 0) st.threads_cpu_pct.emplace_back(tid, d / (threads_s * 1e6) * 100);
  }
  std::sort(st.threads_cpu_pct.begin(), st.threads_cpu_pct.end(),
            [](const auto& a, const auto& b) { return a.second > b.second; });
  st.window_s = static_cast<double>(end->received_ns - start->received_ns) * 1e-9;
  st.ticks = end->status.tick() - start->status.tick();
  st.missed = end->status.missed_ticks() - start->status.missed_ticks();
  st.hands_min = st.hands_max = start->status.hands();
  std::vector<double> p50s;
  for (const auto& r : status.since(start->received_ns + 1)) {
    if (r.received_ns > end->received_ns) break;
    st.hands_min = std::min(st.hands_min, r.status.hands());
    st.hands_max = std::max(st.hands_max, r.status.hands());
    st.tick_us_max = std::max(st.tick_us_max, r.status.tick_us_max());
    p50s.push_back(r.status.tick_us_p50());
  }
  st.tick_us_p50 = summarize(p50s).p50;
  st.server_cpu_us = static_cast<double>(end->server_cpu_us - start->server_cpu_us);
  st.sim_cpu_us = static_cast<double>(end->sim_thread_cpu_us - start->sim_thread_cpu_us);
  st.pub_cpu_us = static_cast<double>(end->self_cpu_us - start->self_cpu_us);
  st.machine_cpu_us = static_cast<double>(end->machine_busy_us - start->machine_busy_us);
  st.other_cpu_us = st.machine_cpu_us - st.server_cpu_us - st.pub_cpu_us;
  st.rejected = end->status.inputs_rejected() - start->status.inputs_rejected();
  st.skipped_periods = skipped1 - skipped0;
  if (hands > 0) {
    st.published_per_hand_hz = static_cast<double>(written1 - written0) / (hands * st.window_s);
    st.accepted_per_hand_hz =
        static_cast<double>(end->status.inputs_accepted() - start->status.inputs_accepted()) / (hands * st.window_s);
  }
  std::vector<std::string> why;
  if (st.missed > 0) why.push_back(std::to_string(st.missed) + " ticks missed");
  if (st.hands_min != hands || st.hands_max != hands)
    why.push_back("server reported " + std::to_string(st.hands_min) + ".." + std::to_string(st.hands_max) + " hands");
  if (hands > 0 && st.published_per_hand_hz < 0.9 * o.sample_hz)
    why.push_back("publishers reached only " + cli::format_number(std::round(st.published_per_hand_hz * 10) / 10) +
                  " Hz per hand");
  if (hands > 0 && st.accepted_per_hand_hz < 0.9 * st.published_per_hand_hz)
    why.push_back("server accepted only " + cli::format_number(std::round(st.accepted_per_hand_hz * 10) / 10) +
                  " Hz per hand");
  if (st.rejected > 0) why.push_back(std::to_string(st.rejected) + " inputs rejected");
  st.sustained = why.empty();
  for (const auto& w : why) st.why += (st.why.empty() ? "" : "; ") + w;
  return st;
}

void print_header() {
  std::cout << std::right << std::setw(6) << "hands" << std::setw(4) << "try" << std::setw(7) << "ticks" << std::setw(7)
            << "missed" << std::setw(10) << "tick p50" << std::setw(10) << "tick max" << std::setw(9) << "srv cpu"
            << std::setw(9) << "sim thr" << std::setw(9) << "pub cpu" << std::setw(8) << "others" << std::setw(11)
            << "us/tick" << std::setw(13) << "us/hand/tick" << std::setw(9) << "pub Hz" << std::setw(9) << "acc Hz"
            << std::setw(9) << "machine"
            << "  result\n";
}

void print_step(const Step& s) {
  std::cout << std::right << std::fixed << std::setw(6) << s.hands << std::setw(4) << s.attempt << std::setw(7)
            << s.ticks << std::setw(7) << s.missed << std::setprecision(0) << std::setw(10) << s.tick_us_p50
            << std::setw(10) << s.tick_us_max << std::setprecision(1) << std::setw(8)
            << (s.window_s > 0 ? s.server_cpu_pct() : 0) << "%" << std::setw(8)
            << (s.window_s > 0 ? s.sim_cpu_pct() : 0) << "%" << std::setw(8) << (s.window_s > 0 ? s.pub_cpu_pct() : 0)
            << "%" << std::setw(7) << (s.window_s > 0 ? s.other_cpu_pct() : 0) << "%" << std::setprecision(0)
            << std::setw(11) << s.cpu_us_per_tick() << std::setprecision(2) << std::setw(13) << s.cpu_us_per_hand_tick()
            << std::setprecision(1) << std::setw(9) << s.published_per_hand_hz << std::setw(9) << s.accepted_per_hand_hz
            << std::setw(8) << (s.window_s > 0 ? s.machine_cpu_pct() : 0) << (s.saturated() ? "*" : "%") << "  "
            << (s.sustained ? "sustained" : "NOT sustained: " + s.why) << "\n";
  std::cout.flush();
  std::cerr << "  server threads (tid: % of one core):";
  for (std::size_t i = 0; i < s.threads_cpu_pct.size() && i < 6; ++i)
    std::cerr << " " << s.threads_cpu_pct[i].first << ": " << std::fixed << std::setprecision(1)
              << s.threads_cpu_pct[i].second;
  std::cerr << "\n";
}

nlohmann::ordered_json to_json(const Step& s) {
  auto r = [](double x, double unit) { return std::round(x / unit) * unit; };
  return {{"hands", s.hands},
          {"attempt", s.attempt},
          {"sustained", s.sustained},
          {"why_not", s.why},
          {"window_s", r(s.window_s, 0.001)},
          {"ticks", s.ticks},
          {"missed_ticks", s.missed},
          {"server_hands_min", s.hands_min},
          {"server_hands_max", s.hands_max},
          {"tick_us_p50", r(s.tick_us_p50, 0.1)},
          {"tick_us_max", r(s.tick_us_max, 0.1)},
          {"server_cpu_pct", r(s.window_s > 0 ? s.server_cpu_pct() : 0, 0.1)},
          {"server_sim_thread_cpu_pct", r(s.window_s > 0 ? s.sim_cpu_pct() : 0, 0.1)},
          {"publisher_process_cpu_pct", r(s.window_s > 0 ? s.pub_cpu_pct() : 0, 0.1)},
          {"other_processes_cpu_pct", r(s.window_s > 0 ? s.other_cpu_pct() : 0, 0.1)},
          {"machine_cpu_pct", r(s.window_s > 0 ? s.machine_cpu_pct() : 0, 0.1)},
          {"machine_saturated", s.window_s > 0 && s.saturated()},
          {"input_loss_pct", r(s.input_loss_pct(), 0.01)},
          {"server_cpu_us_per_tick", r(s.cpu_us_per_tick(), 0.1)},
          {"server_cpu_us_per_hand_tick", r(s.cpu_us_per_hand_tick(), 0.001)},
          {"published_hz_per_hand", r(s.published_per_hand_hz, 0.01)},
          {"accepted_hz_per_hand", r(s.accepted_per_hand_hz, 0.01)},
          {"inputs_rejected", s.rejected},
          {"publisher_skipped_periods", s.skipped_periods},
          {"server_threads_cpu_pct", [&] {
             auto a = nlohmann::ordered_json::array();
             for (const auto& [tid, pct] : s.threads_cpu_pct) a.push_back({{"tid", tid}, {"cpu_pct", r(pct, 0.1)}});
             return a;
           }()}};
}

int run(const Options& o) {
  install_signal_handlers();
  // Start-up and matching waits, then at most two attempts per level with their waits.
  const Watchdog watchdog(120 + 2.0 * (o.max / o.step + 2) * (o.seconds_per_step + 12));
  load_profiles(o.profiles_file, o.profile);
  std::string loadavg;
  std::getline(std::ifstream("/proc/loadavg"), loadavg);
  const std::string tmp =
      std::filesystem::temp_directory_path() / ("telegrasp-bench-scale-" + std::to_string(::getpid()));
  const bool own_server_log = o.server_log.empty();
  const std::string config = tmp + "-server.conf";
  struct RemoveOnExit {
    std::string path;
    ~RemoveOnExit() { std::filesystem::remove(path); }
  } remove_config{config};
  {
    std::ofstream c(config);
    c << "# written by telegrasp-bench-scale: room for every hand of the run\nmax_hands: " << std::max(o.max, 256)
      << "\n";
    if (!c) throw std::runtime_error("cannot write " + config);
  }
  ServerOptions so = server_options(o);
  so.extra = {"--config", config};
  so.extra.insert(so.extra.end(), o.server_args.begin(), o.server_args.end());
  so.log_path = own_server_log ? tmp + "-server.log" : o.server_log;

  StatusCollector status;
  ChildProcess server;
  idl::DdsParticipant main_participant(o.domain, o.profile, o.profiles_file);
  main_participant.reader<msg::ServerStatusPubSubType>(idl::kServerStatusTopic, &status);
  std::cerr << "telegrasp-bench-scale: starting " << join_command(server_argv(so)) << " (log " << so.log_path << ")\n";
  start_server(server, so, status, 20);
  const pid_t server_pid = server.pid();
  std::cerr << "telegrasp-bench-scale: server pid " << server_pid << " answered\n";

  std::vector<Step> steps;
  int hands_sustained = 0;
  std::optional<std::size_t> at_sustained;  // index into steps
  std::string stop_reason;
  {
    Publishers pubs(o.publishers, o.domain, o.profile, o.profiles_file, o.sample_hz, o.max);
    if (!pubs.matched(15))
      throw std::runtime_error(
          "the publisher participants did not match the server's ControllerState reader within 15 s");
    pubs.start();
    std::cout << "telegrasp-bench-scale: " << o.publishers << " publisher threads at " << o.sample_hz << " Hz, +"
              << o.step << " hands per " << o.seconds_per_step << " s level, up to " << o.max << "; late latching "
              << (o.late_latch ? "on" : "off") << "; CPU in % of one core\n";
    print_header();
    for (int hands = 0;; hands = std::min(hands + o.step, o.max)) {
      pubs.set_hands(hands);
      Step s = measure(hands, 1, o, status, pubs, server_pid);
      print_step(s);
      steps.push_back(s);
      if (!s.sustained && !stop_requested()) {  // confirm: one re-measurement of the same level
        s = measure(hands, 2, o, status, pubs, server_pid);
        print_step(s);
        steps.push_back(s);
      }
      if (stop_requested()) {
        stop_reason = "interrupted";
        break;
      }
      if (!s.sustained) {
        stop_reason = std::to_string(hands) + " hands not sustained twice: " + s.why;
        break;
      }
      if (hands > 0) {
        hands_sustained = hands;
        at_sustained = steps.size() - 1;
      }
      if (hands >= o.max) {
        stop_reason = "reached --max " + std::to_string(o.max);
        break;
      }
    }
    pubs.stop();
  }
  if (stop_requested()) throw std::runtime_error("interrupted");
  server.stop();
  const std::string server_exit = server.exit_description();

  // The last sustained level before the stop whose inputs all (>= 99%) reached the server, and
  // the last one the machine ran unsaturated: there the per-hand cost is the server's own.
  int hands_lossless = 0, hands_unsaturated = 0;
  std::optional<std::size_t> at_unsaturated;
  for (std::size_t i = 0; i < steps.size(); ++i) {
    const Step& s = steps[i];
    if (!s.sustained || s.hands == 0) continue;
    if (s.input_loss_pct() <= 1.0) hands_lossless = std::max(hands_lossless, s.hands);
    if (!s.saturated() && s.hands >= hands_unsaturated) {
      hands_unsaturated = s.hands;
      at_unsaturated = i;
    }
  }
  // Marginal cost: least-squares slope of server CPU per tick over hands, across the sustained,
  // unsaturated levels.
  double sx = 0, sy = 0, sxx = 0, sxy = 0;
  int n = 0;
  for (const Step& s : steps)
    if (s.sustained && !s.saturated() && s.ticks > 0) {
      const double x = s.hands, y = s.cpu_us_per_tick();
      sx += x, sy += y, sxx += x * x, sxy += x * y, ++n;
    }
  const double denom = n * sxx - sx * sx;
  const double slope = n >= 2 && denom > 0 ? (n * sxy - sx * sy) / denom : 0;
  const double intercept = n >= 2 ? (sy - slope * sx) / n : 0;
  const double per_hand_tick = at_sustained ? steps[*at_sustained].cpu_us_per_hand_tick() : 0;
  const double per_hand_tick_unsaturated = at_unsaturated ? steps[*at_unsaturated].cpu_us_per_hand_tick() : 0;

  std::cout << "hands sustained at " << o.sample_hz << " Hz with no missed tick: " << hands_sustained
            << " (stop: " << stop_reason << ")\n"
            << std::setprecision(2) << "server CPU per hand per tick at that level: " << per_hand_tick
            << " us (all threads, fixed cost included); marginal " << slope << " us/hand/tick over a fixed "
            << std::setprecision(0) << intercept << " us/tick (least squares over the sustained, unsaturated levels)\n"
            << std::setprecision(2)
            << "largest unsaturated level (machine < 80% busy; * marks saturated levels): " << hands_unsaturated
            << " hands, " << per_hand_tick_unsaturated
            << " us/hand/tick; largest sustained level with <= 1% inputs lost: " << hands_lossless << " hands\n"
            << "target >= 128 hands: " << (hands_sustained >= 128 ? "met" : "NOT met") << "\n";

  if (!o.json.empty()) {
    nlohmann::ordered_json j;
    j["hands_sustained"] = hands_sustained;
    j["cpu_us_per_hand_tick"] = std::round(per_hand_tick * 1000) / 1000;
    j["cpu_us_per_hand_tick_marginal"] = std::round(slope * 1000) / 1000;
    j["cpu_us_per_tick_fixed"] = std::round(intercept * 10) / 10;
    j["hands_unsaturated"] = hands_unsaturated;
    j["cpu_us_per_hand_tick_unsaturated"] = std::round(per_hand_tick_unsaturated * 1000) / 1000;
    j["hands_sustained_lossless"] = hands_lossless;
    j["sample_hz"] = o.sample_hz;
    // null: the server's default
    j["tick_hz"] = o.tick_hz > 0 ? nlohmann::ordered_json(o.tick_hz) : nlohmann::ordered_json();
    j["step"] = o.step;
    j["max"] = o.max;
    j["seconds_per_step"] = o.seconds_per_step;
    j["publishers"] = o.publishers;
    j["late_latch"] = o.late_latch;
    j["profile"] = o.profile;
    j["cpus"] = std::thread::hardware_concurrency();
    j["loadavg_at_start"] = loadavg;
    j["stop_reason"] = stop_reason;
    j["note"] = "CPU percentages are of one core; the publisher process shares the machine's cores with the server";
    j["server_command"] = join_command(server_argv(so));
    j["server_exit"] = server_exit;
    j["steps"] = nlohmann::ordered_json::array();
    for (const Step& s : steps) j["steps"].push_back(to_json(s));
    std::ofstream out(o.json);
    out << j.dump(2) << "\n";
    if (!out) throw std::runtime_error("--json: cannot write " + o.json);
    std::cerr << "telegrasp-bench-scale: wrote " << o.json << "\n";
  }
  if (own_server_log) std::filesystem::remove(so.log_path);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  Options o = parse(argc, argv);
  return run_on_domain(kTool, o, run);
}
