// telegrasp-bench-latency: end-to-end latency through telegrasp-server (controller sample
// published -> first HandSkeleton reflecting it), and, in the same run, the raw Fast DDS round
// trip of an echo process with the same transport and QoS.
#include "bench_common.h"
#include "telegrasp/idl/cli.h"
#include "test_domain.h"

#include "telegrasp/idl/telegraspPubSubTypes.h"
#include "telegrasp/idl/topics.h"

#include <fastdds/dds/publisher/DataWriter.hpp>
#include <fastdds/dds/subscriber/DataReader.hpp>
#include <fastdds/dds/subscriber/SampleInfo.hpp>

#include <nlohmann/json.hpp>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <numbers>
#include <optional>
#include <thread>
#include <unistd.h>

namespace {

namespace msg = telegrasp::msg;
namespace idl = telegrasp::idl;
namespace cli = telegrasp::cli;
using namespace telegrasp::bench;
namespace dds = eprosima::fastdds::dds;  // also a global namespace dds in the Fast DDS headers

constexpr const char* kUsage = R"(Usage: telegrasp-bench-latency [options]

Starts telegrasp-server (--empty-scene, private domain) as a child process and measures, in one run:
  raw round trip  N*2 ControllerState streams to an echo process (this program re-executed with
                  --echo-role) on topic bench/Ping and back on bench/Pong, with the ControllerState
                  writer/reader and HandSkeleton writer/reader QoS profiles: the transport alone;
  end to end      N client participants ("lat-<i>", 2 hands each, smooth motion in the air above
                  the table, oscillating trigger) publish ControllerState at --sample-hz; one observer
                  participant takes HandSkeleton. Latency of sample s = first skeleton of that hand
                  with input_sequence >= s minus the publication of s (each sample counted once);
                  e2e_tick_us counts only tick skeletons (late_latched false).
Fast DDS intraprocess delivery is off in this process (several participants in one process
deadlock Fast DDS 2.9.1's liveliness protocol, eProsima/Fast-DDS#3115), so its participants talk
through the transport as separate processes would. The run stops with an error if another
telegrasp-server already answers on --domain; a watchdog kills the children if anything hangs.
With --secure DIR the raw round trip runs a second time, right after the first, with the `secure`
participant profile (DDS Security: PKI-DH, access control, AES-GCM) on the topics it encrypts:
pings on telegrasp/ControllerState as identity "bench", echoed on telegrasp/HandSkeleton (same
ControllerState samples: access control checks topic names, not types) as identity "server";
DIR is made by `deploy/security/make-certs.sh DIR bench`. The table then adds its row and the
difference: the cost of security against --profile (loopback by default, the same transports as
`secure`: shared memory and UDP on 127.0.0.1).
The first --warmup-s seconds of each phase are excluded. A table goes to stdout, progress to stderr.

Options:
  --clients N         client participants, 2 hands each (default 16)
  --sample-hz HZ      controller sample rate per hand (default 90; --hz, its old name, still works
                      for one release)
  --tick-hz HZ        the server's tick rate (default: the server's, 90)
  --duration-s S      measured seconds per phase, after the warm-up (default 10)
  --warmup-s S        warm-up seconds per phase, not measured (default 1)
  --json FILE         also write the results as JSON
  --profile NAME      Fast DDS participant profile for everyone (default loopback)
  --profiles FILE     Fast DDS XML profiles file (default: the telegrasp one)
  --secure DIR        also measure the raw round trip with the secure profile, identities from DIR
                      (made by deploy/security/make-certs.sh DIR bench)
  --domain D          DDS domain of this run, 0..232 (default: a free one, leased as the
                      tests lease theirs: tests/common/test_domain.h)
  --server PATH       telegrasp-server executable (default: the one next to this program)
  --server-arg ARG    one more argument for the server (repeatable)
  --server-log FILE   server output (default: a temporary file, removed after a clean run)
  --no-late-latch     start the server with --no-late-latch (skeletons only at ticks)
  --phase P           spread (default): client i publishes at offset i/N of the period, like
                      independent clients; burst: all clients at the same instant
  -h, --help          this text

Exit status: 0 done, 1 a runtime failure (the server or the echo could not be started or never
answered, an output could not be written), 2 a usage error (a bad or missing option or value).
)";

struct Options : CommonOptions {
  int clients = 16;
  double seconds = 10;
  double warmup = 1;
  bool spread = true;
  std::string secure_dir;  // --secure: also the raw round trip with the secure profile
};

constexpr const char* kTool = "telegrasp-bench-latency";

[[noreturn]] void usage_error(const std::string& what) { cli::usage_exit(kTool, what); }

Options parse(int argc, char** argv) {
  Options o;
  cli::for_each_option(argc, argv, kUsage, usage_error, [&](const std::string& f, const auto& value) {
    if (parse_common_option(kTool, f, value, o, usage_error)) return true;
    if (f == "--clients")
      o.clients = static_cast<int>(cli::parse_whole(f, value(), 1, 1024, usage_error));
    else if (cli::is_flag(kTool, f, "--duration-s", "--seconds"))
      o.seconds = cli::parse_number(f, value(), 0.1, 86400, usage_error);
    else if (cli::is_flag(kTool, f, "--warmup-s", "--warmup"))
      o.warmup = cli::parse_number(f, value(), 0, 3600, usage_error);
    else if (f == "--secure") {
      o.secure_dir = value();
      if (!std::filesystem::is_directory(o.secure_dir))
        usage_error("--secure expects the folder deploy/security/make-certs.sh made, got '" + o.secure_dir +
                    "' (not a folder)");
    } else if (f == "--phase") {
      const std::string p = value();
      if (p == "spread")
        o.spread = true;
      else if (p == "burst")
        o.spread = false;
      else
        usage_error("--phase expects spread or burst, got '" + p + "'");
    } else {
      return false;
    }
    return true;
  });
  if (o.server.empty()) o.server = default_server_path();
  return o;
}

// ---------------------------------------------------------------------------------------------
// The echo process: takes every ping and writes it straight back from the listener.

class EchoListener : public dds::DataReaderListener {
 public:
  dds::DataWriter* pong = nullptr;
  void on_data_available(dds::DataReader* reader) override {
    dds::SampleInfo info;
    while (reader->take_next_sample(&sample_, &info) == ReturnCode_t::RETCODE_OK)
      if (info.valid_data) pong->write(&sample_);
  }

 private:
  msg::ControllerState sample_;
};

// The echo role's command line: `self_exe() --echo-role --domain D --profile P [--profiles F]
// [--ping-topic T --pong-topic T]`.
int echo_main(int argc, char** argv) {
  struct {
    int domain = 120;
    std::string profile = "loopback", profiles_file;
  } network;
  std::string ping_topic = "bench/Ping", pong_topic = "bench/Pong";
  cli::for_each_option(argc, argv, kUsage, usage_error, [&](const std::string& f, const auto& value) {
    if (f == "--echo-role") return true;
    if (idl::parse_network_flag(f, value, network, usage_error))
      ;
    else if (f == "--ping-topic")
      ping_topic = value();
    else if (f == "--pong-topic")
      pong_topic = value();
    else
      return false;
    return true;
  });
  install_signal_handlers();
  load_profiles(network.profiles_file, network.profile);
  EchoListener listener;
  idl::DdsParticipant p(network.domain, network.profile, network.profiles_file);
  listener.pong = p.writer<msg::ControllerStatePubSubType>(pong_topic, idl::kHandSkeletonTopic);
  p.reader<msg::ControllerStatePubSubType>(ping_topic, &listener, idl::kControllerStateTopic);
  std::cerr << "telegrasp-bench-latency echo: domain " << network.domain << ", profile " << network.profile << "\n";
  while (sleep_unless_stopped(0.2)) {}
  return 0;
}

// ---------------------------------------------------------------------------------------------
// Publication times and their resolution into latencies.

/// Publication time (ns) of every sample of every stream, indexed by sequence number (from 1).
class SendTable {
 public:
  SendTable(std::size_t streams, std::size_t samples)
      : samples_(samples),
        times_(std::make_unique<std::atomic<std::int64_t>[]>(streams * (samples + 1))),
        last_(std::make_unique<std::atomic<std::uint64_t>[]>(streams)) {
    for (std::size_t i = 0; i < streams * (samples + 1); ++i) times_[i] = 0;
    for (std::size_t i = 0; i < streams; ++i) last_[i] = 0;
  }
  std::size_t capacity() const { return samples_; }
  void sent(std::size_t stream, std::uint64_t seq, std::int64_t t) {
    times_[stream * (samples_ + 1) + seq].store(t, std::memory_order_release);
    last_[stream].store(seq, std::memory_order_release);
  }
  std::int64_t at(std::size_t stream, std::uint64_t seq) const {
    if (seq > samples_) return 0;
    return times_[stream * (samples_ + 1) + seq].load(std::memory_order_acquire);
  }
  std::uint64_t last(std::size_t stream) const { return last_[stream].load(std::memory_order_acquire); }

 private:
  std::size_t samples_;
  std::unique_ptr<std::atomic<std::int64_t>[]> times_;
  std::unique_ptr<std::atomic<std::uint64_t>[]> last_;
};

/// Turns "a message reflecting input q of stream k arrived at t" into per-sample latencies: each
/// sample s is counted once, by the first arrival with q >= s. Samples published inside
/// [from_ns, until_ns) are measured; earlier ones (warm-up) are resolved but not recorded.
class Resolver {
 public:
  Resolver(const SendTable& table, std::size_t streams) : table_(table), resolved_(streams, 0) {}
  void set_window(std::int64_t from_ns, std::int64_t until_ns) {
    std::lock_guard lock(mutex_);
    from_ = from_ns;
    until_ = until_ns;
  }
  void arrived(std::size_t stream, std::uint64_t q, std::int64_t t) {
    std::lock_guard lock(mutex_);
    if (stream >= resolved_.size()) return;
    ++arrivals_;
    const std::uint64_t last = std::min<std::uint64_t>(q, table_.last(stream));
    for (std::uint64_t s = resolved_[stream] + 1; s <= last; ++s) {
      const std::int64_t sent = table_.at(stream, s);
      if (sent == 0) break;
      resolved_[stream] = s;
      if (sent < from_ || sent >= until_) continue;
      latencies_us_.push_back(static_cast<double>(t - sent) * 1e-3);
      (s == q ? exact_ : superseded_) += 1;
    }
  }
  /// Samples of the window never resolved (nothing reflecting them arrived).
  std::uint64_t unresolved_in_window() const {
    std::lock_guard lock(mutex_);
    std::uint64_t n = 0;
    for (std::size_t k = 0; k < resolved_.size(); ++k)
      for (std::uint64_t s = resolved_[k] + 1; s <= table_.last(k); ++s)
        if (const std::int64_t t = table_.at(k, s); t >= from_ && t < until_) ++n;
    return n;
  }
  std::vector<double> latencies() const {
    std::lock_guard lock(mutex_);
    return latencies_us_;
  }
  std::uint64_t exact() const {
    std::lock_guard lock(mutex_);
    return exact_;
  }
  std::uint64_t superseded() const {
    std::lock_guard lock(mutex_);
    return superseded_;
  }
  std::uint64_t arrivals() const {
    std::lock_guard lock(mutex_);
    return arrivals_;
  }

 private:
  const SendTable& table_;
  mutable std::mutex mutex_;
  std::vector<std::uint64_t> resolved_;
  std::vector<double> latencies_us_;
  std::int64_t from_ = 0, until_ = 0;
  std::uint64_t exact_ = 0, superseded_ = 0, arrivals_ = 0;
};

/// Client index from "<prefix><i>", or -1.
int client_index(const std::string& id, const std::string& prefix, int clients) {
  if (id.compare(0, prefix.size(), prefix) != 0) return -1;
  char* end = nullptr;
  const long i = std::strtol(id.c_str() + prefix.size(), &end, 10);
  if (*end != '\0' || i < 0 || i >= clients) return -1;
  return static_cast<int>(i);
}

/// Pongs of the raw round trip.
class PongListener : public dds::DataReaderListener {
 public:
  PongListener(Resolver& r, int clients) : resolver_(r), clients_(clients) {}
  void on_data_available(dds::DataReader* reader) override {
    dds::SampleInfo info;
    while (reader->take_next_sample(&sample_, &info) == ReturnCode_t::RETCODE_OK) {
      const std::int64_t t = now_ns();
      if (!info.valid_data) continue;
      const int c = client_index(sample_.client_id().to_string(), "ping-", clients_);
      if (c < 0 || sample_.hand_side() > 1) continue;
      resolver_.arrived(static_cast<std::size_t>(c * 2 + sample_.hand_side()), sample_.sequence_number(), t);
    }
  }

 private:
  Resolver& resolver_;
  int clients_;
  msg::ControllerState sample_;
};

/// Skeletons seen by the observer.
class SkeletonListener : public dds::DataReaderListener {
 public:
  SkeletonListener(Resolver& any, Resolver& tick, int clients) : any_(any), tick_(tick), clients_(clients) {}
  void on_data_available(dds::DataReader* reader) override {
    dds::SampleInfo info;
    while (reader->take_next_sample(&sample_, &info) == ReturnCode_t::RETCODE_OK) {
      const std::int64_t t = now_ns();
      if (!info.valid_data) continue;
      const int c = client_index(sample_.client_id().to_string(), "lat-", clients_);
      if (c < 0 || sample_.hand_side() > 1) continue;
      const auto stream = static_cast<std::size_t>(c * 2 + sample_.hand_side());
      any_.arrived(stream, sample_.input_sequence(), t);
      if (!sample_.late_latched()) tick_.arrived(stream, sample_.input_sequence(), t);
      (sample_.late_latched() ? late_latched : tick_skeletons) += 1;
    }
  }
  std::atomic<std::uint64_t> late_latched{0}, tick_skeletons{0};

 private:
  Resolver &any_, &tick_;
  int clients_;
  msg::HandSkeleton sample_;
};

// ---------------------------------------------------------------------------------------------
// Publishing.

struct PublishStats {
  std::uint64_t samples = 0;
  std::vector<double> lateness_us;  ///< write start minus due time, per client slot
};

/// One thread for all clients: client c publishes both hands at t0 + k/hz (+ c/(N hz) if spread)
/// with sleep_until, for `duration_s`. writers[c] publishes client c (one writer may be shared).
PublishStats publish(const std::vector<dds::DataWriter*>& writers, const std::string& prefix, SendTable& table,
                     double hz, bool spread, Clock::time_point t0, double duration_s) {
  const int clients = static_cast<int>(writers.size());
  const auto period = std::chrono::duration<double>(1.0 / hz);
  std::vector<std::string> ids;
  for (int c = 0; c < clients; ++c) ids.push_back(prefix + std::to_string(c));
  PublishStats st;
  for (std::uint64_t k = 0;; ++k) {
    if (k + 1 > table.capacity()) break;
    for (int c = 0; c < clients; ++c) {
      const double offset = spread ? static_cast<double>(c) / clients : 0.0;
      const auto due = t0 + std::chrono::duration_cast<Clock::duration>(period * (static_cast<double>(k) + offset));
      if (std::chrono::duration<double>(due - t0).count() >= duration_s || stop_requested()) return st;
      std::this_thread::sleep_until(due);
      const auto start = Clock::now();
      st.lateness_us.push_back(std::chrono::duration<double, std::micro>(start - due).count());
      const double t = std::chrono::duration<double>(start - t0).count();
      for (int side = 0; side < 2; ++side) {
        msg::ControllerState s = controller_sample(ids[c], c, side, k + 1, t);
        const std::int64_t sent = now_ns();
        s.client_time_ns(sent);
        table.sent(static_cast<std::size_t>(c * 2 + side), k + 1, sent);
        writers[c]->write(&s);
        ++st.samples;
      }
    }
  }
  return st;
}

// ---------------------------------------------------------------------------------------------
// Reporting.

nlohmann::ordered_json to_json(const Summary& s) {
  auto r = [](double x) { return std::round(x * 10) / 10; };
  return {{"p50", r(s.p50)}, {"p99", r(s.p99)},   {"max", r(s.max)},
          {"p90", r(s.p90)}, {"mean", r(s.mean)}, {"count", s.count}};
}

void print_row(const std::string& name, const Summary& s, std::uint64_t lost) {
  std::cout << std::left << std::setw(28) << name << std::right << std::setw(8) << s.count << std::setw(7) << lost;
  for (double v : {s.p50, s.p90, s.p99, s.max, s.mean})
    std::cout << std::setw(9) << std::fixed << std::setprecision(0) << v;
  std::cout << "\n";
}

struct PhaseResult {
  Summary latency;
  std::uint64_t published = 0, lost = 0, exact = 0, superseded = 0;
  Summary lateness;
  double bench_cpu_pct = 0;
  nlohmann::ordered_json cpu;  ///< raw phase: server, echo, others (% of one core)
};

/// Server figures over [from, until] from the ServerStatus records.
nlohmann::ordered_json server_window(const StatusCollector& collector, std::int64_t from_ns, std::int64_t until_ns,
                                     const std::optional<StatusCollector::Record>& before) {
  nlohmann::ordered_json j;
  std::vector<StatusCollector::Record> in;
  for (const auto& r : collector.since(from_ns))
    if (r.received_ns <= until_ns) in.push_back(r);
  if (in.empty() || !before) return j;
  const auto& last = in.back();
  double tick_max = 0;
  std::vector<double> p50s;
  int hands = 0;
  for (const auto& r : in) {
    tick_max = std::max(tick_max, r.status.tick_us_max());
    p50s.push_back(r.status.tick_us_p50());
    hands = std::max(hands, r.status.hands());
  }
  const double wall_s = static_cast<double>(last.received_ns - before->received_ns) * 1e-9;
  j["missed_ticks"] = last.status.missed_ticks() - before->status.missed_ticks();
  j["ticks"] = last.status.tick() - before->status.tick();
  j["tick_us_p50"] = std::round(summarize(p50s).p50 * 10) / 10;
  j["tick_us_max"] = std::round(tick_max * 10) / 10;
  j["hands"] = hands;
  j["inputs_accepted"] = last.status.inputs_accepted() - before->status.inputs_accepted();
  j["inputs_rejected"] = last.status.inputs_rejected() - before->status.inputs_rejected();
  if (wall_s > 0 && last.server_cpu_us >= 0 && before->server_cpu_us >= 0) {
    j["cpu_pct"] =
        std::round(static_cast<double>(last.server_cpu_us - before->server_cpu_us) / (wall_s * 1e6) * 1000) / 10;
    j["sim_thread_cpu_pct"] =
        std::round(static_cast<double>(last.sim_thread_cpu_us - before->sim_thread_cpu_us) / (wall_s * 1e6) * 1000) /
        10;
    j["bench_process_cpu_pct"] =
        std::round(static_cast<double>(last.self_cpu_us - before->self_cpu_us) / (wall_s * 1e6) * 1000) / 10;
    // Everything else on the machine (other people's builds and tests share the cores).
    j["other_processes_cpu_pct"] = std::round(static_cast<double>((last.machine_busy_us - before->machine_busy_us) -
                                                                  (last.server_cpu_us - before->server_cpu_us) -
                                                                  (last.self_cpu_us - before->self_cpu_us)) /
                                              (wall_s * 1e6) * 1000) /
                                   10;
  }
  j["status_window_s"] = std::round(wall_s * 100) / 100;
  return j;
}

// What both phases share: the server and the echo process, the send tables and the listeners
// that resolve each sample, and the observer participant. Listeners and tables outlive the
// participants that call them (declared first).
struct Bench {
  explicit Bench(const Options& opt)
      : o(opt),
        streams(opt.clients * 2),
        samples_per_stream(static_cast<std::size_t>(std::ceil((opt.warmup + opt.seconds) * opt.sample_hz)) + 4),
        raw_table(streams, samples_per_stream),
        e2e_table(streams, samples_per_stream),
        secure_table(streams, samples_per_stream),
        raw(raw_table, streams),
        e2e_any(e2e_table, streams),
        e2e_tick(e2e_table, streams),
        secure_raw(secure_table, streams),
        pong_listener(raw, opt.clients),
        secure_pong_listener(secure_raw, opt.clients),
        skeleton_listener(e2e_any, e2e_tick, opt.clients) {}

  // The measured window of a phase that starts publishing at t0: after the warm-up, for --duration-s.
  std::pair<std::int64_t, std::int64_t> window(Clock::time_point t0) const {
    const std::int64_t t0_ns = std::chrono::duration_cast<std::chrono::nanoseconds>(t0.time_since_epoch()).count();
    return {t0_ns + static_cast<std::int64_t>(o.warmup * 1e9),
            t0_ns + static_cast<std::int64_t>((o.warmup + o.seconds) * 1e9)};
  }

  static PhaseResult finish(Resolver& r, const PublishStats& ps, std::int64_t cpu0, double wall_s) {
    PhaseResult p;
    p.latency = summarize(r.latencies());
    p.lost = r.unresolved_in_window();
    p.published = p.latency.count + p.lost;
    p.exact = r.exact();
    p.superseded = r.superseded();
    p.lateness = summarize(ps.lateness_us);
    p.bench_cpu_pct = static_cast<double>(self_cpu_us() - cpu0) / (wall_s * 1e6) * 100;
    return p;
  }

  void start_server(const std::string& tmp);
  /// The raw round trip with --profile on bench/Ping and bench/Pong, or (`secure`) with the secure
  /// profile on telegrasp/ControllerState and telegrasp/HandSkeleton.
  PhaseResult raw_phase(const std::string& echo_log, bool secure = false);
  void e2e_phase(PhaseResult& e2e_result, PhaseResult& tick_result, nlohmann::ordered_json& server_json);

  const Options& o;
  const int streams;
  const std::size_t samples_per_stream;
  SendTable raw_table, e2e_table, secure_table;
  Resolver raw, e2e_any, e2e_tick, secure_raw;
  StatusCollector status;
  PongListener pong_listener, secure_pong_listener;
  SkeletonListener skeleton_listener;
  ChildProcess server, echo, secure_echo;
  ServerOptions so;
  std::optional<idl::DdsParticipant> main_participant, secure_participant;
};

void Bench::start_server(const std::string& tmp) {
  so = server_options(o);
  so.log_path = o.server_log.empty() ? tmp + "-server.log" : o.server_log;
  main_participant.emplace(o.domain, o.profile, o.profiles_file);
  main_participant->reader<msg::ServerStatusPubSubType>(idl::kServerStatusTopic, &status);
  std::cerr << "telegrasp-bench-latency: starting " << join_command(server_argv(so)) << " (log " << so.log_path
            << ")\n";
  telegrasp::bench::start_server(server, so, status, 20);
  std::cerr << "telegrasp-bench-latency: server pid " << server.pid() << " answered\n";
}

// (a) Raw round trip through the echo process.
PhaseResult Bench::raw_phase(const std::string& echo_log, bool secure) {
  const std::string profile = secure ? "secure" : o.profile;
  const std::string ping_topic = secure ? idl::kControllerStateTopic : "bench/Ping";
  const std::string pong_topic = secure ? idl::kHandSkeletonTopic : "bench/Pong";
  ChildProcess& echo = secure ? secure_echo : this->echo;
  Resolver& raw = secure ? secure_raw : this->raw;
  SendTable& raw_table = secure ? secure_table : this->raw_table;
  const std::vector<std::string> echo_argv{self_exe(),     "--echo-role", "--domain",     std::to_string(o.domain),
                                           "--profile",    profile,       "--profiles",   o.profiles_file,
                                           "--ping-topic", ping_topic,    "--pong-topic", pong_topic};
  // With security the echo is identity "server" and this process "bench"; DdsParticipant and the
  // echo (at its start) read them from the environment, which then goes back to none for the
  // loopback participants made later.
  if (secure) {
    setenv("TELEGRASP_SECURITY_DIR", o.secure_dir.c_str(), 1);
    setenv("TELEGRASP_IDENTITY", "server", 1);
  }
  echo.start(echo_argv, echo_log);
  if (secure) {
    setenv("TELEGRASP_IDENTITY", "bench", 1);
    try {
      secure_participant.emplace(o.domain, profile, o.profiles_file);
    } catch (...) {
      unsetenv("TELEGRASP_SECURITY_DIR");
      unsetenv("TELEGRASP_IDENTITY");
      throw;
    }
    unsetenv("TELEGRASP_SECURITY_DIR");
    unsetenv("TELEGRASP_IDENTITY");
  }
  idl::DdsParticipant& pinger = secure ? *secure_participant : *main_participant;
  dds::DataWriter* ping = pinger.writer<msg::ControllerStatePubSubType>(ping_topic, idl::kControllerStateTopic);
  dds::DataReader* pong = pinger.reader<msg::ControllerStatePubSubType>(
      pong_topic, secure ? &secure_pong_listener : &pong_listener, idl::kHandSkeletonTopic);
  if (!wait_until([&] { return (matched_readers(ping) > 0 && matched_writers(pong) > 0) || !echo.running(); }, 15) ||
      !echo.running())
    throw std::runtime_error("the echo process (" + join_command(echo_argv) +
                             ") did not match bench/Ping and bench/Pong within 15 s" +
                             (echo.running() ? std::string() : " (it exited: " + echo.exit_description() + ")") +
                             "\n  log " + echo_log + ":\n" + echo.log_tail());
  std::cerr << "telegrasp-bench-latency: raw round trip (" << profile << "): " << streams << " streams at "
            << o.sample_hz << " Hz for " << o.warmup << " + " << o.seconds << " s\n";
  const auto t0 = Clock::now() + std::chrono::milliseconds(100);
  const auto [from, until] = window(t0);
  raw.set_window(from, until);
  const std::int64_t cpu0 = self_cpu_us(), busy0 = machine_busy_us(), server0 = process_cpu_us(server.pid()),
                     echo0 = process_cpu_us(echo.pid());
  const PublishStats ps = publish(std::vector<dds::DataWriter*>(o.clients, ping), "ping-", raw_table, o.sample_hz,
                                  o.spread, t0, o.warmup + o.seconds);
  sleep_unless_stopped(0.5);  // stragglers
  const double wall_s = std::chrono::duration<double>(Clock::now() - t0).count();
  PhaseResult result = finish(raw, ps, cpu0, wall_s);
  const double self_us = static_cast<double>(self_cpu_us() - cpu0),
               busy_us = static_cast<double>(machine_busy_us() - busy0),
               server_us = static_cast<double>(process_cpu_us(server.pid()) - server0),
               echo_us = static_cast<double>(process_cpu_us(echo.pid()) - echo0);
  auto pct = [&](double us) { return std::round(us / (wall_s * 1e6) * 1000) / 10; };
  result.cpu = {{"server_cpu_pct", pct(server_us)},
                {"echo_process_cpu_pct", pct(echo_us)},
                {"bench_process_cpu_pct", pct(self_us)},
                {"other_processes_cpu_pct", pct(busy_us - self_us - server_us - echo_us)}};
  echo.stop();
  std::cerr << "telegrasp-bench-latency: echo stopped: " << echo.exit_description() << "\n";
  // Gone before the next phase: left in the process, the secure participant kept the loopback
  // observer from receiving any skeleton (measured).
  if (secure) secure_participant.reset();
  return result;
}

// (b) End to end through the server.
void Bench::e2e_phase(PhaseResult& e2e_result, PhaseResult& tick_result, nlohmann::ordered_json& server_json) {
  dds::DataReader* skeletons =
      main_participant->reader<msg::HandSkeletonPubSubType>(idl::kHandSkeletonTopic, &skeleton_listener);
  std::vector<std::unique_ptr<idl::DdsParticipant>> clients;
  std::vector<dds::DataWriter*> writers;
  for (int c = 0; c < o.clients; ++c) {
    clients.push_back(std::make_unique<idl::DdsParticipant>(o.domain, o.profile, o.profiles_file));
    writers.push_back(clients.back()->writer<msg::ControllerStatePubSubType>(idl::kControllerStateTopic));
  }
  const bool matched = wait_until(
      [&] {
        if (matched_writers(skeletons) == 0) return false;
        for (auto* w : writers)
          if (matched_readers(w) == 0) return false;
        return true;
      },
      15);
  if (!matched)
    throw std::runtime_error("the " + std::to_string(o.clients) +
                             " client participants and the observer did not all match the server within 15 s");
  std::cerr << "telegrasp-bench-latency: end to end: " << o.clients << " clients x 2 hands at " << o.sample_hz
            << " Hz for " << o.warmup << " + " << o.seconds << " s, late latching " << (o.late_latch ? "on" : "off")
            << "\n";
  const auto t0 = Clock::now() + std::chrono::milliseconds(100);
  const auto [from, until] = window(t0);
  e2e_any.set_window(from, until);
  e2e_tick.set_window(from, until);
  const auto before = status.latest();
  const std::int64_t cpu0 = self_cpu_us();
  const PublishStats ps = publish(writers, "lat-", e2e_table, o.sample_hz, o.spread, t0, o.warmup + o.seconds);
  const std::int64_t end_ns = now_ns();
  sleep_unless_stopped(0.5);
  const double wall_s = std::chrono::duration<double>(Clock::now() - t0).count();
  e2e_result = finish(e2e_any, ps, cpu0, wall_s);
  tick_result = finish(e2e_tick, ps, cpu0, wall_s);
  // The status that covers the end of the run arrives within a second.
  status.wait_for(end_ns, 1.5);
  server_json = server_window(status, from, end_ns + static_cast<std::int64_t>(1.2e9), before);
  server_json["skeletons_late_latched"] = skeleton_listener.late_latched.load();
  server_json["skeletons_tick"] = skeleton_listener.tick_skeletons.load();
}

// The results of both phases, for the table and the JSON.
struct Results {
  PhaseResult raw, e2e, tick;
  std::optional<PhaseResult> secure;  // --secure: the raw round trip with the secure profile
  nlohmann::ordered_json server;
  std::string server_command, server_exit, loadavg;
};

void print_results(const Options& o, const Results& r) {
  std::cout << "telegrasp-bench-latency: " << o.clients << " clients x 2 hands at " << o.sample_hz << " Hz, "
            << o.seconds << " s (+" << o.warmup << " s warm-up), profile " << o.profile << ", late latching "
            << (o.late_latch ? "on" : "off") << ", " << (o.spread ? "spread" : "burst") << " phases\n";
  std::cout << std::left << std::setw(28) << "latency (us)" << std::right << std::setw(8) << "samples" << std::setw(7)
            << "lost" << std::setw(9) << "p50" << std::setw(9) << "p90" << std::setw(9) << "p99" << std::setw(9)
            << "max" << std::setw(9) << "mean"
            << "\n";
  print_row("raw round trip (echo)", r.raw.latency, r.raw.lost);
  if (r.secure) print_row("raw round trip, secure", r.secure->latency, r.secure->lost);
  print_row("e2e, first skeleton", r.e2e.latency, r.e2e.lost);
  print_row("e2e, first tick skeleton", r.tick.latency, r.tick.lost);
  std::cout << "e2e samples reflected exactly " << r.e2e.exact << ", superseded " << r.e2e.superseded << "\n";
  std::cout << "server over the e2e phase: " << r.server.dump() << "\n";
  std::cout << "CPU over the raw phase (% of one core): " << r.raw.cpu.dump() << "\n";
  if (r.secure)
    std::cout << std::setprecision(0) << "DDS Security cost on the raw round trip: p50 +"
              << r.secure->latency.p50 - r.raw.latency.p50 << " us, p99 +" << r.secure->latency.p99 - r.raw.latency.p99
              << " us (secure against " << o.profile << "); CPU over the secure raw phase: " << r.secure->cpu.dump()
              << "\n";
  std::cout << "publisher lateness (us) raw p99 " << std::setprecision(0) << r.raw.lateness.p99 << " max "
            << r.raw.lateness.max << ", e2e p99 " << r.e2e.lateness.p99 << " max " << r.e2e.lateness.max
            << "; bench process CPU raw " << std::setprecision(1) << r.raw.bench_cpu_pct << "%, e2e "
            << r.e2e.bench_cpu_pct << "%\n";
  const double margin = r.e2e.latency.p99 - r.raw.latency.p99;
  std::cout << "target e2e p99 <= raw p99 + 1000 us: " << (margin <= 1000 ? "met" : "NOT met")
            << " (e2e p99 - raw p99 = " << std::setprecision(0) << margin << " us)\n";
}

void write_json(const Options& o, const Results& r) {
  nlohmann::ordered_json j;
  j["clients"] = o.clients;
  j["sample_hz"] = o.sample_hz;
  // null: the server's default
  j["tick_hz"] = o.tick_hz > 0 ? nlohmann::ordered_json(o.tick_hz) : nlohmann::ordered_json();
  j["e2e_us"] = to_json(r.e2e.latency);
  j["raw_rtt_us"] = to_json(r.raw.latency);
  if (r.secure) {
    j["raw_rtt_secure_us"] = to_json(r.secure->latency);
    j["raw_secure_lost"] = r.secure->lost;
    j["raw_secure_phase_cpu"] = r.secure->cpu;
  }
  j["e2e_tick_us"] = to_json(r.tick.latency);
  j["seconds"] = o.seconds;
  j["warmup_s"] = o.warmup;
  j["profile"] = o.profile;
  j["late_latch"] = o.late_latch;
  j["phase"] = o.spread ? "spread" : "burst";
  j["echo"] = "separate process (this program re-executed with --echo-role); echoes from its DataReader listener";
  j["samples"] = {{"raw_published", r.raw.published},     {"raw_lost", r.raw.lost},
                  {"e2e_published", r.e2e.published},     {"e2e_lost", r.e2e.lost},
                  {"e2e_reflected_exactly", r.e2e.exact}, {"e2e_superseded", r.e2e.superseded},
                  {"e2e_tick_lost", r.tick.lost}};
  j["server"] = r.server;
  j["raw_phase_cpu"] = r.raw.cpu;
  j["publisher_lateness_us"] = {{"raw", to_json(r.raw.lateness)}, {"e2e", to_json(r.e2e.lateness)}};
  j["machine"] = {{"cpus", std::thread::hardware_concurrency()}, {"loadavg_at_start", r.loadavg}};
  j["server_command"] = r.server_command;
  j["server_exit"] = r.server_exit;
  std::ofstream out(o.json);
  out << j.dump(2) << "\n";
  if (!out) throw std::runtime_error("--json: cannot write " + o.json);
  std::cerr << "telegrasp-bench-latency: wrote " << o.json << "\n";
}

int run(const Options& o) {
  install_signal_handlers();
  // Start-up and matching waits, two phases with their stragglers, generously.
  const Watchdog watchdog(120 + 3 * (o.warmup + o.seconds + 2) + 0.2 * o.clients);
  load_profiles(o.profiles_file, o.profile);
  if (o.clients * 2 > 256)
    std::cerr << "telegrasp-bench-latency: note: " << o.clients * 2
              << " hands exceed the server's default max_hands (256); pass --server-arg --config --server-arg FILE "
                 "with max_hands\n";
  Results r;
  std::getline(std::ifstream("/proc/loadavg"), r.loadavg);
  const std::string tmp =
      std::filesystem::temp_directory_path() / ("telegrasp-bench-latency-" + std::to_string(::getpid()));
  const std::string echo_log = tmp + "-echo.log";

  Bench bench(o);
  bench.start_server(tmp);
  r.raw = bench.raw_phase(echo_log);
  if (stop_requested()) throw std::runtime_error("interrupted");
  if (!o.secure_dir.empty()) {
    r.secure = bench.raw_phase(echo_log, true);
    if (stop_requested()) throw std::runtime_error("interrupted");
  }
  bench.e2e_phase(r.e2e, r.tick, r.server);
  if (stop_requested()) throw std::runtime_error("interrupted");
  bench.server.stop();
  r.server_exit = bench.server.exit_description();
  r.server_command = join_command(server_argv(bench.so));

  print_results(o, r);
  if (!o.json.empty()) write_json(o, r);
  if (o.server_log.empty()) std::filesystem::remove(bench.so.log_path);
  std::filesystem::remove(echo_log);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  for (int i = 1; i < argc; ++i)
    if (std::string(argv[i]) == "--echo-role") {
      try {
        return echo_main(argc, argv);
      } catch (const std::exception& e) {
        std::cerr << "telegrasp-bench-latency echo: " << e.what() << "\n";
        return 1;
      }
    }
  Options o = parse(argc, argv);
  return run_on_domain(kTool, o, run);
}
