// telegrasp-soak: a long run of many hands grasping continuously against one server, watching the
// server's memory (VmRSS and heap in use), tick time and missed ticks for growth. Starts the server (or watches one
// already running), runs telegrasp-bot processes (two hands each) and restarts each bot when it
// ends, samples every --sample-s seconds and prints the samples and a verdict as JSON.
#include "client_options.h"
#include "child_process.h"
#include "telegrasp/idl/cli.h"
#include "telegrasp/client/client.h"
#include "telegrasp/idl/network_flags.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <csignal>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <memory>
#include <mutex>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include <unistd.h>

namespace {

namespace fs = std::filesystem;
namespace client = telegrasp::client;
using telegrasp::tools::ChildProcess;
using json = nlohmann::ordered_json;
using Clock = std::chrono::steady_clock;

using telegrasp::cli::kExitInterrupted;
using telegrasp::cli::kExitMemoryGrew;
using telegrasp::cli::kExitTooFewGrasps;

constexpr const char* kUsage = R"(Usage: telegrasp-soak --hands N --duration-s S [options]

Soak test: N hands grasp continuously for S seconds against one telegrasp server while the
server's resident memory (VmRSS from /proc/PID/status), heap in use, tick time and missed ticks
(from its ServerStatus) are sampled every --sample-s seconds. The hands are telegrasp-bot
processes with two hands each (one right hand for an odd N), each grasping every object of the
scene over and over (--trials 10000) and restarted with a new seed and client id when it ends (a
bot gives an object up after 10 s without a chance at it, and may then finish). By default the
soak starts its own telegrasp-server (the 30 stand-ins, or --server-config) and stops it at the
end.

At the end it prints one JSON object on stdout: the settings, every sample
  {"t_s", "rss_kib", "heap_kib" (the lowest of the period's statuses: what stays allocated),
   "tick_us_p50", "tick_us_max" (the worst 1 s status in the sample period),
   "missed_ticks" (in the period), "missed_ticks_total", "server_hands", "server_clients",
   "grasps", "releases" (events in the period), "bot_restarts" (in the period)}
and a verdict: memory is flat when the heap in use grew by less than --max-growth-pct (no leak)
and the RSS by less than --max-rss-growth-pct over the samples after the warm-up, each measured
two ways (last sample against the first after warm-up, and a least-squares line through them
over the same span); all must stay under their limits. The RSS has the looser limit because it
keeps the heap's high-water mark: a rare large grasp-quality hull raises it for good, with no
leak. A server that reports no heap (an older one, or a sanitizer build, whose RSS grows anyway
as freed memory waits in quarantine) is judged on its RSS with --max-growth-pct.

Options:
  --hands N           hands grasping at once, 1..1024 (required)
  --duration-s S      how long to run, in seconds, > 0 (required; e.g. 1800 for 30 minutes)
  --sample-s S        seconds between samples (default 10)
  --warmup-s S        samples before this are not judged (default: 60, at most a third of the run)
  --max-growth-pct P  the verdict's limit on the growth of the server's heap in use after
                      warm-up, a leak (default 1; on the RSS when the server reports no heap)
  --max-rss-growth-pct P
                      the verdict's limit on RSS growth after warm-up (default 5): the RSS also
                      keeps the heap's high-water mark, so it grows a little with no leak
  --domain N          DDS domain, 0..232 (default 0)
  --profile NAME      Fast DDS participant profile for the server, bots and the soak (default
                      loopback)
  --profiles FILE     Fast DDS XML profiles (default: $TELEGRASP_PROFILES, else the shipped file)
  --scene NAME        the scene of the server and bots (default $TELEGRASP_SCENE, else default)
  --discovery-server HOST[:PORT]
                      a Fast DDS discovery server; repeat in id order (telegrasp-server --help)
  --server-pid PID    watch this already running server instead of starting one (it must be on
                      --domain with --profile; its RSS is read from /proc/PID/status)
  --server-config F   the started server's --config file (default: none, the 30 stand-ins)
  --bot-nice N        run the bots at this nice value, 0..19 (default 10): the server, the
                      program under test, gets the CPU first when the bots' planning saturates it
  --skill NAME        the bots' skill: perfect | experienced | inexperienced (default experienced)
  --log-dir DIR       where the server's and bots' logs go (default: a new folder in $TMPDIR,
                      printed on stderr)
  --min-grasps N      fail (exit 8) when fewer grasp events than N arrived over the run
                      (default 0): the hands were not grasping
  --json FILE         also write the JSON result to FILE
  -h, --help          this text

Progress goes to stderr, one line per sample. The programs telegrasp-server and telegrasp-bot are
taken from the folder of this executable.

Exit status: 0 the run completed and memory was flat, 7 the run completed but memory grew past
a limit, 8 memory was flat but fewer than --min-grasps grasps happened, 1 a
runtime failure (a program missing, the server did not start or died, no ServerStatus,
/proc/PID/status unreadable), 2 a usage error, 130 stopped by SIGINT or SIGTERM (the samples so
far are printed).
)";

[[noreturn]] void usage_error(const std::string& what) { telegrasp::cli::usage_exit("telegrasp-soak", what); }

struct Options {
  int hands = 0;
  double duration_s = 0, sample_s = 10, warmup_s = -1, max_growth_pct = 1, max_rss_growth_pct = 5;
  int domain = 0;
  std::string scene;  // "": $TELEGRASP_SCENE, else default
  std::vector<std::string> discovery_servers;
  std::string profile = "loopback", profiles_file, server_config, skill = "experienced", log_dir, json_path;
  int server_pid = 0;
  int bot_nice = 10;
  long min_grasps = 0;
};

Options parse(int argc, char** argv) {
  Options o;
  telegrasp::cli::for_each_option(argc, argv, kUsage, usage_error, [&](const std::string& a, const auto& value) {
    if (a == "--hands")
      o.hands = static_cast<int>(telegrasp::cli::parse_whole(a, value(), 1, 1024, usage_error));
    else if (a == "--duration-s")
      o.duration_s = telegrasp::cli::parse_number(a, value(), 0.06, 7 * 24 * 3600, usage_error);
    else if (a == "--minutes") {  // the old spelling, in minutes
      telegrasp::cli::warn_renamed("telegrasp-soak", a, "--duration-s (in seconds)");
      o.duration_s = 60 * telegrasp::cli::parse_number(a, value(), 1e-3, 7 * 24 * 60, usage_error);
    } else if (a == "--sample-s")
      o.sample_s = telegrasp::cli::parse_number(a, value(), 1, 3600, usage_error);
    else if (a == "--warmup-s")
      o.warmup_s = telegrasp::cli::parse_number(a, value(), 0, 7 * 24 * 3600, usage_error);
    else if (a == "--max-growth-pct")
      o.max_growth_pct = telegrasp::cli::parse_number(a, value(), 0, 1000, usage_error);
    else if (a == "--max-rss-growth-pct")
      o.max_rss_growth_pct = telegrasp::cli::parse_number(a, value(), 0, 1000, usage_error);
    else if (telegrasp::idl::parse_network_flag(a, value, o, usage_error))
      ;
    else if (a == "--server-pid")
      o.server_pid = static_cast<int>(telegrasp::cli::parse_whole(a, value(), 1, 1L << 30, usage_error));
    else if (a == "--bot-nice")
      o.bot_nice = static_cast<int>(telegrasp::cli::parse_whole(a, value(), 0, 19, usage_error));
    else if (telegrasp::cli::text_flag(
                 a, value, {{"--server-config", &o.server_config}, {"--log-dir", &o.log_dir}, {"--json", &o.json_path}}))
      ;
    else if (a == "--skill") {
      o.skill = value();
      if (o.skill != "perfect" && o.skill != "experienced" && o.skill != "inexperienced")
        usage_error("--skill expects perfect, experienced or inexperienced, got '" + o.skill + "'");
    } else if (a == "--min-grasps")
      o.min_grasps = telegrasp::cli::parse_whole(a, value(), 0, 1L << 40, usage_error);
    else
      return false;
    return true;
  });
  if (o.hands == 0) usage_error("--hands N is required");
  if (o.duration_s == 0) usage_error("--duration-s S is required");
  const double run_s = o.duration_s;
  if (o.warmup_s < 0) o.warmup_s = std::min(60.0, run_s / 3);
  if (o.warmup_s >= run_s) usage_error("--warmup-s must be shorter than the run (--duration-s)");
  if (o.sample_s > run_s) usage_error("--sample-s must not be longer than the run (--duration-s)");
  if (!o.server_config.empty() && o.server_pid)
    usage_error("--server-config is for a started server; --server-pid watches a running one");
  if (!o.server_config.empty() && !fs::is_regular_file(o.server_config))
    usage_error("--server-config " + o.server_config + ": no such file");
  return o;
}

std::atomic<bool> g_stop{false};
extern "C" void on_signal(int) { g_stop = true; }

std::string self_dir() {
  std::error_code ec;
  const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  return ec ? std::string(".") : exe.parent_path().string();
}

// VmRSS of `pid` in KiB, or nothing if the process is gone or the line is missing.
std::optional<long> rss_kib(int pid) {
  std::ifstream in("/proc/" + std::to_string(pid) + "/status");
  std::string line;
  while (std::getline(in, line))
    if (line.rfind("VmRSS:", 0) == 0) return std::strtol(line.c_str() + 6, nullptr, 10);
  return std::nullopt;
}

// What the ServerStatus and GraspEvent callbacks gather between two samples.
struct Window {
  std::mutex mu;
  std::optional<client::ServerStatus> latest;
  double tick_us_max = 0;
  std::vector<double> tick_us_p50;
  std::optional<std::uint64_t> heap_kib_min;  // the lowest heap in use of the period's statuses
  int grasps = 0, releases = 0;
};

// One bot slot: its process and how often it was (re)started.
struct Slot {
  ChildProcess bot;
  bool both = true;
  int starts = 0;
};

double median(std::vector<double> v) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

// Least-squares slope of y over x.
double slope(const std::vector<double>& x, const std::vector<double>& y) {
  const double n = static_cast<double>(x.size());
  double sx = 0, sy = 0, sxx = 0, sxy = 0;
  for (std::size_t i = 0; i < x.size(); ++i) sx += x[i], sy += y[i], sxx += x[i] * x[i], sxy += x[i] * y[i];
  const double d = n * sxx - sx * sx;
  return d > 0 ? (n * sxy - sx * sy) / d : 0;
}

// How a memory series grew over the judged samples: the last against the first, and a
// least-squares line through all of them over the same span, both in % of the first.
json growth(const std::vector<double>& t, const std::vector<double>& kib, double limit_pct) {
  const double base = kib.front();
  const double last = 100 * (kib.back() - base) / base;
  const double fit = 100 * slope(t, kib) * (t.back() - t.front()) / base;
  return {{"first_kib", base},
          {"last_kib", kib.back()},
          {"max_kib", *std::max_element(kib.begin(), kib.end())},
          {"growth_last_pct", last},
          {"growth_fit_pct", fit},
          {"limit_pct", limit_pct},
          {"flat", last < limit_pct && fit < limit_pct}};
}

// A failure before the run: its message, then exit 1.
struct Failure : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// The programs this soak starts, beside its own executable.
void check_programs(const std::string& bin, const Options& opt) {
  for (const char* tool : {"telegrasp-server", "telegrasp-bot"})
    if ((tool != std::string("telegrasp-server") || !opt.server_pid) && access((bin + "/" + tool).c_str(), X_OK) != 0)
      throw Failure(bin + "/" + tool + ": not found or not executable");
}

// Where the server's and bots' logs go: --log-dir, or a new folder in $TMPDIR.
std::string make_log_dir(const Options& opt) {
  std::string log_dir = opt.log_dir;
  std::error_code ec;
  if (log_dir.empty()) {
    std::string pattern = (fs::temp_directory_path(ec) / "telegrasp_soak.XXXXXX").string();
    if (!mkdtemp(pattern.data())) throw Failure("cannot make a log folder " + pattern);
    log_dir = pattern;
  } else if (fs::create_directories(log_dir, ec); ec) {
    throw Failure("--log-dir " + log_dir + ": " + ec.message());
  }
  std::cerr << "telegrasp-soak: logs in " << log_dir << "\n";
  return log_dir;
}

// What the run is made of: the programs' folder, the network flags every process gets, the logs,
// the server (started here and stopped at the end, or one already running) and its pid.
struct Setup {
  std::string bin, log_dir;
  std::vector<std::string> dds;
  ChildProcess server;
  int server_pid = 0;
  bool server_ended(const Options& opt) { return !opt.server_pid && !server.running(); }
};

void start_server(const Options& opt, Setup& setup) {
  setup.server_pid = opt.server_pid;
  if (!setup.server_pid) {
    std::vector<std::string> argv = {setup.bin + "/telegrasp-server"};
    argv.insert(argv.end(), setup.dds.begin(), setup.dds.end());
    if (!opt.server_config.empty()) argv.insert(argv.end(), {"--config", opt.server_config});
    try {
      setup.server.start(argv, setup.log_dir + "/server.log");
    } catch (const std::exception& e) {
      throw Failure(std::string("cannot start the server: ") + e.what());
    }
    setup.server_pid = setup.server.pid();
  }
  if (!rss_kib(setup.server_pid))
    throw Failure("cannot read /proc/" + std::to_string(setup.server_pid) + "/status (no such server process)");
}

// The soak's own subscriber (server status and grasp events only, gathered into `window`),
// returned once the server's first status has arrived.
std::unique_ptr<client::Client> subscribe(const Options& opt, Setup& setup, Window& window) {
  std::unique_ptr<client::Client> c;
  try {
    c = std::make_unique<client::Client>(telegrasp::tools::client_options(
        opt, "soak-" + std::to_string(getpid()), client::kServerStatuses | client::kGraspEvents));
  } catch (const std::exception& e) {
    throw Failure(e.what());
  }
  c->on_server_status([&window](const client::ServerStatus& s) {
    std::lock_guard lock(window.mu);
    window.latest = s;
    window.tick_us_max = std::max(window.tick_us_max, s.tick_us_max);
    window.tick_us_p50.push_back(s.tick_us_p50);
    if (s.heap_kib > 0) window.heap_kib_min = std::min(window.heap_kib_min.value_or(s.heap_kib), s.heap_kib);
  });
  c->on_grasp_event([&window](const client::GraspEvent& e) {
    std::lock_guard lock(window.mu);
    (e.kind == client::GraspEvent::Kind::kGrasp ? window.grasps : window.releases)++;
  });
  const auto found_deadline = Clock::now() + std::chrono::seconds(60);
  while (!g_stop && !c->latest_server_status()) {
    if (Clock::now() > found_deadline || setup.server_ended(opt))
      throw Failure("no ServerStatus from the server (pid " + std::to_string(setup.server_pid) + ") on domain " +
                    std::to_string(opt.domain) + " with profile " + opt.profile + " within 60 s; see " + setup.log_dir +
                    "/server.log");
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  return c;
}

// The bots: two hands each (one right hand in the last slot for an odd count); slot k's n-th
// start is client soak<pid>-k-n with seed 1000 n + k.
class Bots {
 public:
  Bots(const Options& opt, const Setup& setup) : opt_(opt), setup_(setup), slots_((opt.hands + 1) / 2) {
    if (opt.hands % 2) slots_.back().both = false;
  }
  std::size_t size() const { return slots_.size(); }
  void start_all() {
    try {
      for (std::size_t k = 0; k < slots_.size() && !g_stop; ++k) {
        start(k);
        std::this_thread::sleep_for(std::chrono::milliseconds(20));  // spread the discovery bursts
      }
    } catch (const std::exception& e) {
      throw Failure(std::string("cannot start a bot: ") + e.what());
    }
  }
  // Restarts every bot that ended (a bot that cannot run at all would spin: counted, and the
  // run goes on); returns how many, and sets `failure` if one could not be started.
  int restart_ended(std::string& failure) {
    int restarts = 0;
    for (std::size_t k = 0; k < slots_.size(); ++k)
      if (!slots_[k].bot.running()) {
        try {
          start(k);
        } catch (const std::exception& e) {
          failure = std::string("cannot restart a bot: ") + e.what();
        }
        ++restarts;
      }
    return restarts;
  }
  void stop() {
    for (Slot& s : slots_) s.bot.signal(SIGTERM);
    for (Slot& s : slots_) s.bot.stop(std::chrono::seconds(10));
  }

 private:
  void start(std::size_t k) {
    Slot& s = slots_[k];
    const std::string id = "soak" + std::to_string(getpid()) + "-" + std::to_string(k) + "-" + std::to_string(s.starts);
    std::vector<std::string> argv = {"/usr/bin/nice",
                                     "-n",
                                     std::to_string(opt_.bot_nice),
                                     setup_.bin + "/telegrasp-bot",
                                     "--client-id",
                                     id,
                                     "--hands",
                                     s.both ? "both" : "right",
                                     "--trials",
                                     "10000",
                                     "--skill",
                                     opt_.skill,
                                     "--seed",
                                     std::to_string(1000 * s.starts + k + 1),
                                     "--timeout-s",
                                     "60"};
    argv.insert(argv.end(), setup_.dds.begin(), setup_.dds.end());
    s.bot.start(argv, setup_.log_dir + "/bot" + std::to_string(k) + ".log");
    ++s.starts;
  }
  const Options& opt_;
  const Setup& setup_;
  std::vector<Slot> slots_;
};

// The samples of a run, those judged (after the warm-up), and how it ended.
struct Run {
  json samples = json::array();
  std::vector<double> t_judged, rss_judged;
  std::vector<double> t_heap, heap_judged;  // the samples whose period had a status with the heap
  int total_restarts = 0;
  std::string failure;  // "" when the run lasted until its end or a signal
};

// Samples every --sample-s seconds until the end of the run, a signal or a failure, restarting
// the bots that end. Missed ticks are counted from the first status on (a starting server may
// miss some while it loads).
Run sample_until_end(const Options& opt, Setup& setup, Bots& bots, Window& window, std::uint64_t missed_before) {
  Run run;
  const auto t0 = Clock::now();
  const auto end = t0 + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(opt.duration_s));
  auto next_sample = t0;
  int restarts = 0;
  while (!g_stop) {
    const int restarted = bots.restart_ended(run.failure);
    restarts += restarted, run.total_restarts += restarted;
    if (!run.failure.empty()) break;
    if (setup.server_ended(opt)) {
      run.failure = "the server ended (" + setup.server.exit_description() + "); see " + setup.log_dir + "/server.log";
      break;
    }
    const auto now = Clock::now();
    if (now >= next_sample + std::chrono::duration<double>(opt.sample_s) || now >= end) {
      next_sample = now;
      const double t = std::chrono::duration<double>(now - t0).count();
      const std::optional<long> rss = rss_kib(setup.server_pid);
      if (!rss) {
        run.failure = "cannot read /proc/" + std::to_string(setup.server_pid) + "/status: the server is gone";
        break;
      }
      json s;
      {
        std::lock_guard lock(window.mu);
        const std::uint64_t missed_total = window.latest ? window.latest->missed_ticks : 0;
        s = {{"t_s", std::round(t * 10) / 10},
             {"rss_kib", *rss},
             {"heap_kib", window.heap_kib_min ? json(*window.heap_kib_min) : json(nullptr)},
             {"tick_us_p50", median(window.tick_us_p50)},
             {"tick_us_max", window.tick_us_max},
             {"missed_ticks", missed_total - missed_before},
             {"missed_ticks_total", missed_total},
             {"server_hands", window.latest ? window.latest->hands : 0},
             {"server_clients", window.latest ? window.latest->clients : 0},
             {"grasps", window.grasps},
             {"releases", window.releases},
             {"bot_restarts", restarts}};
        missed_before = missed_total;
        window.tick_us_max = 0;
        window.tick_us_p50.clear();
        window.heap_kib_min.reset();
        window.grasps = window.releases = 0;
      }
      restarts = 0;
      std::cerr << "telegrasp-soak: " << s.dump() << "\n";
      if (t >= opt.warmup_s) {
        if (s["heap_kib"].is_number()) run.t_heap.push_back(t), run.heap_judged.push_back(s["heap_kib"].get<double>());
        run.t_judged.push_back(t), run.rss_judged.push_back(static_cast<double>(*rss));
      }
      run.samples.push_back(std::move(s));
      if (now >= end) break;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  return run;
}

// The verdict over the samples after warm-up. A leak shows in the heap in use. The resident set
// also keeps the heap's high-water mark (pages the allocator cannot give back), so it is held to
// the looser --max-rss-growth-pct; it has the tighter limit only when the server does not report
// its heap. A sample whose period brought no status (a stalled server, lost samples) has no heap
// figure: skipped.
json judge(const Options& opt, const Run& run) {
  json verdict;
  if (run.rss_judged.size() >= 2) {
    const bool heap = run.heap_judged.size() >= 2;
    verdict = {{"judged_samples", run.rss_judged.size()},
               {"judged_from_s", run.t_judged.front()},
               {"judged_on", heap ? "heap and rss" : "rss (the server reported no heap)"},
               {"heap_samples_missing", run.t_judged.size() - run.heap_judged.size()},
               {"heap", heap ? growth(run.t_heap, run.heap_judged, opt.max_growth_pct) : json(nullptr)},
               {"rss", growth(run.t_judged, run.rss_judged, heap ? opt.max_rss_growth_pct : opt.max_growth_pct)}};
    verdict["flat_memory"] = verdict["rss"]["flat"].get<bool>() && (!heap || verdict["heap"]["flat"].get<bool>());
  } else {
    verdict = {{"flat_memory", nullptr},
               {"why", "fewer than 2 samples after the warm-up: lengthen --duration-s or shorten --warmup-s"}};
  }
  int grasps = 0;
  std::uint64_t missed = 0;
  for (const json& s : run.samples) grasps += s["grasps"].get<int>(), missed += s["missed_ticks"].get<std::uint64_t>();
  verdict["grasps"] = grasps;
  verdict["missed_ticks"] = missed;
  verdict["bot_restarts"] = run.total_restarts;
  return verdict;
}

// The result on stdout (and in --json), the verdict on stderr, and the exit status.
int report(const Options& opt, const json& result, bool interrupted) {
  std::cout << result.dump(1) << "\n" << std::flush;
  if (!opt.json_path.empty()) {
    std::ofstream out(opt.json_path);
    out << result.dump(1) << "\n";
    if (!out.flush()) {
      std::cerr << "telegrasp-soak: cannot write --json file " << opt.json_path << "\n";
      return telegrasp::cli::kExitFailure;
    }
  }
  if (!result["failure"].is_null()) {
    std::cerr << "telegrasp-soak: " << result["failure"].get<std::string>() << "\n";
    return telegrasp::cli::kExitFailure;
  }
  if (interrupted) return kExitInterrupted;
  const json& verdict = result["verdict"];
  if (verdict["flat_memory"].is_null()) {
    std::cerr << "telegrasp-soak: no verdict: " << verdict["why"].get<std::string>() << "\n";
    return telegrasp::cli::kExitFailure;
  }
  const bool flat = verdict["flat_memory"].get<bool>();
  std::cerr << "telegrasp-soak: " << (flat ? "flat memory" : "memory grew") << ":";
  for (const char* series : {"heap", "rss"}) {
    const json& g = verdict[series];
    if (g.is_null()) continue;
    std::cerr << " " << (series == std::string("heap") ? "heap in use" : "RSS") << " "
              << g["growth_last_pct"].get<double>() << " % (last against first after warm-up), "
              << g["growth_fit_pct"].get<double>() << " % (fitted line), limit " << g["limit_pct"].get<double>() << " %"
              << (g["flat"].get<bool>() ? ";" : " EXCEEDED;");
  }
  const int grasps = verdict["grasps"].get<int>();
  std::cerr << " " << grasps << " grasps, " << verdict["missed_ticks"].get<std::uint64_t>() << " missed ticks\n";
  if (!flat) return kExitMemoryGrew;
  if (grasps < opt.min_grasps) {
    std::cerr << "telegrasp-soak: only " << grasps << " grasps, --min-grasps " << opt.min_grasps << "\n";
    return kExitTooFewGrasps;
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  const Options opt = parse(argc, argv);
  std::signal(SIGINT, on_signal);
  std::signal(SIGTERM, on_signal);

  Setup setup;
  Window window;
  std::unique_ptr<client::Client> c;
  std::optional<Bots> bots;
  try {
    setup.bin = self_dir();
    check_programs(setup.bin, opt);
    setup.log_dir = make_log_dir(opt);
    setup.dds = telegrasp::idl::network_args(opt);
    start_server(opt, setup);
    c = subscribe(opt, setup, window);
    bots.emplace(opt, setup);
    bots->start_all();
  } catch (const Failure& e) {
    std::cerr << "telegrasp-soak: " << e.what() << "\n";
    return telegrasp::cli::kExitFailure;
  }
  std::cerr << "telegrasp-soak: " << opt.hands << " hands in " << bots->size() << " bots against server pid "
            << setup.server_pid << ", " << opt.duration_s << " s, a sample every " << opt.sample_s << " s\n";

  const auto first_status = c->latest_server_status();  // none only when a signal came first
  const Run run = sample_until_end(opt, setup, *bots, window, first_status ? first_status->missed_ticks : 0);
  const bool interrupted = g_stop;

  // Stop the bots first (their hands leave), then the server we started.
  bots->stop();
  c.reset();
  const int server_status = opt.server_pid ? 0 : setup.server.stop(std::chrono::seconds(10));

  const json result = {{"hands", opt.hands},
                       {"bots", bots->size()},
                       {"duration_s", opt.duration_s},
                       {"minutes", opt.duration_s / 60},  // the old name of the setting, for one release
                       {"sample_s", opt.sample_s},
                       {"warmup_s", opt.warmup_s},
                       {"profile", opt.profile},
                       {"bot_nice", opt.bot_nice},
                       {"server_pid", setup.server_pid},
                       {"server_exit", opt.server_pid ? json(nullptr) : json(server_status)},
                       {"log_dir", setup.log_dir},
                       {"samples", run.samples},
                       {"verdict", judge(opt, run)},
                       {"completed", run.failure.empty() && !interrupted},
                       {"failure", run.failure.empty() ? json(nullptr) : json(run.failure)}};
  return report(opt, result, interrupted);
}
