// telegrasp-bench-scale: how many hands telegrasp-server sustains at its tick rate without
// missing a tick, and what each costs in server CPU.
#include "active_hands.h"
#include "bench_common.h"
#include "telegrasp/idl/cli.h"
#include "test_domain.h"

#include "telegrasp/idl/telegraspPubSubTypes.h"
#include "telegrasp/idl/topics.h"

#include <fastdds/dds/publisher/DataWriter.hpp>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <array>
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
level. Each level is measured over --level-s seconds between two ServerStatus samples: missed
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

--active: hands that grasp. The server gets a scene of one object per hand (the built-in stand-in
--active-model, on a grid of 11 x 12 places over its table; at most 128, the scene's bound, so
--max is at most 128 and defaults to it) instead of --empty-scene. The run sweeps twice in one
server: first idle (each hand hovers 0.3 m above its object, moving, trigger oscillating, closing
on nothing), then active: each hand runs the sim's scripted operator ("perfect" skill; the grasp
planned once per hand side by sim::plan_grasp and moved onto the object's pose from the newest
SceneState): reach, close until the server's GraspEvent says it holds, lift 10 cm, hold 1 s,
put it down (as long as the lift took), release, pause 0.3 s, again (trials start staggered over 2 s; each active
level's window opens 3 s after its hands were added). Per level it also reports the
GraspEvents (grasps, releases; grasps/s), the hands that grasped in the window, and the held
fraction (trials held through lift and hold / trials finished). An active level is sustained only
if, besides the above, >= 90% of its hands grasped in the window and >= 80% of the trials
finished in it were held. The summary compares idle and active cost at the largest level both
sweeps sustained (or tolerated, see --allow-missed-pct).

--count-outputs: one more participant in this process subscribes to the server's per-hand and
scene outputs (HandSkeleton, GraspState, ContactSet, SceneState, GraspEvent), as a viewer would,
and counts per level the samples it takes and their serialized (CDR) bytes: the payload a
subscriber receives, per topic and per hand. Every level also records the bytes and packets of
the loopback interface (/proc/net/dev): inside `unshare -n` with --profile udp that is all of the
run's DDS traffic sent by UDP (headers included), so two runs with and without --count-outputs
give the bytes one more subscriber costs on the wire (the shm profile, shared memory only,
crosses no socket: `lo` then counts nothing; loopback sends each sample by both).

Options:
  --sample-hz HZ         controller sample rate per hand (default 90; --hz, its old name, still
                         works for one release)
  --tick-hz HZ           the server's tick rate (default: the server's, 90)
  --step N               hands added per level, even (default 8)
  --max N                last level (default 512; with --active 128, at most 128)
  --level-s S            measured seconds per level (default 3; with --active 6, at least one
                         grasp trial of every hand)
  --active               also sweep hands that grasp objects (above)
  --active-model NAME    the scene's objects with --active (default 005_tomato_soup_can)
  --count-outputs        count what a subscriber of the server's outputs receives (above)
  --allow-missed-pct P   go on past levels whose only fault is missed ticks, up to P% of their
                         ticks (default 0: stop there); hands_sustained still counts only levels
                         with no missed tick, "tolerated" the levels within P%
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
  int max = 0;  // 0: 512, or 128 with --active
  double seconds_per_step = 0;  // 0: 3, or 6 with --active
  int publishers = 2;
  bool active = false;
  std::string active_model = "005_tomato_soup_can";
  bool count_outputs = false;
  double allow_missed_pct = 0;
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
    else if (cli::is_flag(kTool, f, "--level-s", "--seconds-per-step"))
      o.seconds_per_step = cli::parse_number(f, value(), 1, 600, usage_error);
    else if (f == "--publishers")
      o.publishers = static_cast<int>(cli::parse_whole(f, value(), 1, 64, usage_error));
    else if (f == "--active")
      o.active = true;
    else if (f == "--active-model")
      o.active_model = value();
    else if (f == "--count-outputs")
      o.count_outputs = true;
    else if (f == "--allow-missed-pct")
      o.allow_missed_pct = cli::parse_number(f, value(), 0, 100, usage_error);
    else
      return false;
    return true;
  });
  if (o.max == 0) o.max = o.active ? kMaxActiveHands : 512;
  if (o.seconds_per_step == 0) o.seconds_per_step = o.active ? 6 : 3;
  if (!o.active && o.active_model != Options{}.active_model) usage_error("--active-model needs --active");
  if (o.active && !is_active_model(o.active_model))
    usage_error(
        "--active-model expects a built-in stand-in's name (telegrasp-server --list-models without --objects), got '" +
        o.active_model + "'");
  if (o.active && o.max > kMaxActiveHands)
    usage_error("--max with --active is at most " + std::to_string(kMaxActiveHands) +
                " (one object per hand; a scene holds at most 128), got " + std::to_string(o.max));
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
             int max_hands, ActiveHands* active)
      : hz_(hz), active_(active) {
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
            msg::ControllerState s = active_ ? active_->sample(ids_[c], c, side, ++seq[2 * c + side], t)
                                             : controller_sample(ids_[c], c, side, ++seq[2 * c + side], t);
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
  ActiveHands* active_;  // null: the idle bench's hands in the air
  std::vector<std::unique_ptr<idl::DdsParticipant>> participants_;
  std::vector<dds::DataWriter*> writers_;
  std::vector<std::string> ids_;
  std::vector<std::thread> threads_;
  Clock::time_point t0_;
  std::atomic<bool> stop_{false};
  std::atomic<int> hands_{0};
  std::atomic<std::uint64_t> written_{0}, skipped_{0};
};

/// A subscriber of the server's outputs (--count-outputs): its own participant, counting the
/// samples it takes per topic and their serialized (CDR, with the 4-byte encapsulation) size.
class OutputCounter {
 public:
  static constexpr std::array<const char*, 5> kTopics{"HandSkeleton", "GraspState", "ContactSet", "SceneState",
                                                      "GraspEvent"};
  struct Counts {
    std::array<std::uint64_t, kTopics.size()> samples{}, bytes{};
  };

  OutputCounter(int domain, const std::string& profile, const std::string& profiles_file)
      : participant_(domain, profile, profiles_file) {
    participant_.reader<msg::HandSkeletonPubSubType>(idl::kHandSkeletonTopic, &skeletons_);
    participant_.reader<msg::GraspStatePubSubType>(idl::kGraspStateTopic, &grasp_states_);
    participant_.reader<msg::ContactSetPubSubType>(idl::kContactSetTopic, &contacts_);
    participant_.reader<msg::SceneStatePubSubType>(idl::kSceneStateTopic, &scenes_);
    participant_.reader<msg::GraspEventPubSubType>(idl::kGraspEventTopic, &events_);
  }
  Counts counts() const {
    Counts c;
    std::size_t i = 0;
    for (const Tally* t : {&skeletons_.tally, &grasp_states_.tally, &contacts_.tally, &scenes_.tally, &events_.tally}) {
      c.samples[i] = t->samples.load();
      c.bytes[i++] = t->bytes.load();
    }
    return c;
  }

 private:
  struct Tally {
    std::atomic<std::uint64_t> samples{0}, bytes{0};
  };
  template <class T, class PubSubType>
  struct Listener : dds::DataReaderListener {
    void on_data_available(dds::DataReader* reader) override {
      T sample;
      dds::SampleInfo info;
      while (reader->take_next_sample(&sample, &info) == ReturnCode_t::RETCODE_OK) {
        if (!info.valid_data) continue;
        ++tally.samples;
        tally.bytes += type.getSerializedSizeProvider(&sample)();
      }
    }
    PubSubType type;
    Tally tally;
  };
  // The listeners outlive the participant (declared first, destroyed last).
  Listener<msg::HandSkeleton, msg::HandSkeletonPubSubType> skeletons_;
  Listener<msg::GraspState, msg::GraspStatePubSubType> grasp_states_;
  Listener<msg::ContactSet, msg::ContactSetPubSubType> contacts_;
  Listener<msg::SceneState, msg::SceneStatePubSubType> scenes_;
  Listener<msg::GraspEvent, msg::GraspEventPubSubType> events_;
  idl::DdsParticipant participant_;
};

struct Step {
  std::string phase = "idle";  // idle | active (--active's two sweeps)
  int hands = 0;
  int attempt = 1;
  bool sustained = false;
  bool tolerated = false;  // not sustained only for missed ticks, <= --allow-missed-pct of its ticks
  std::string why;  // what failed, if not sustained
  double window_s = 0;
  std::uint64_t ticks = 0, missed = 0;
  std::uint64_t quality_late = 0;  // ticks that waited for the server's grasp-quality worker
  int hands_min = 0, hands_max = 0;
  double tick_us_p50 = 0, tick_us_max = 0;
  double server_cpu_us = 0, sim_cpu_us = 0, pub_cpu_us = 0, other_cpu_us = 0, machine_cpu_us = 0;
  double published_per_hand_hz = 0, accepted_per_hand_hz = 0;
  std::uint64_t rejected = 0, skipped_periods = 0;
  std::vector<std::pair<pid_t, double>> threads_cpu_pct;  // the server's busiest threads
  // --active: what the hands did in the window.
  bool counted_grasps = false;
  std::uint64_t grasps = 0, releases = 0, cycles = 0, cycles_held = 0, objects_missing = 0, objects_fallen = 0;
  int hands_grasping = 0;  // hands with at least one grasp in the window
  double mean_cycle_s = 0;  // since the start of the run
  // --count-outputs: per OutputCounter topic, samples and bytes in the window.
  std::optional<OutputCounter::Counts> outputs;
  double lo_bytes = -1, lo_packets = -1;  // the loopback interface in the window

  double grasps_per_s() const { return window_s > 0 ? static_cast<double>(grasps) / window_s : 0; }
  double held_fraction() const { return cycles ? static_cast<double>(cycles_held) / static_cast<double>(cycles) : 0; }

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
Step measure(int hands, int attempt, const Options& o, StatusCollector& status, Publishers& pubs, pid_t server,
             ActiveHands* active_hands, const OutputCounter* counter) {
  Step st;
  st.phase = active_hands && active_hands->active() ? "active" : "idle";
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
  const std::optional<ActiveCounts> active0 =
      active_hands ? std::optional<ActiveCounts>(active_hands->counts()) : std::nullopt;
  const std::optional<OutputCounter::Counts> outputs0 =
      counter ? std::optional<OutputCounter::Counts>(counter->counts()) : std::nullopt;
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
  if (active0) {
    const ActiveCounts a1 = active_hands->counts();
    st.counted_grasps = true;
    st.grasps = a1.grasps - active0->grasps;
    st.releases = a1.releases - active0->releases;
    st.cycles = a1.cycles - active0->cycles;
    st.cycles_held = a1.cycles_held - active0->cycles_held;
    st.objects_missing = a1.objects_missing - active0->objects_missing;
    st.objects_fallen = a1.objects_fallen - active0->objects_fallen;
    for (int h = 0; h < hands; ++h) st.hands_grasping += a1.grasps_per_hand[h] > active0->grasps_per_hand[h];
    st.mean_cycle_s = active_hands->mean_cycle_s();
  }
  if (outputs0) {
    OutputCounter::Counts d = counter->counts();
    for (std::size_t i = 0; i < d.samples.size(); ++i) {
      d.samples[i] -= outputs0->samples[i];
      d.bytes[i] -= outputs0->bytes[i];
    }
    st.outputs = d;
  }
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
  st.quality_late = end->status.quality_late() - start->status.quality_late();
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
  if (start->lo.bytes >= 0 && end->lo.bytes >= 0) {
    st.lo_bytes = static_cast<double>(end->lo.bytes - start->lo.bytes);
    st.lo_packets = static_cast<double>(end->lo.packets - start->lo.packets);
  }
  st.rejected = end->status.inputs_rejected() - start->status.inputs_rejected();
  st.skipped_periods = skipped1 - skipped0;
  if (hands > 0) {
    st.published_per_hand_hz = static_cast<double>(written1 - written0) / (hands * st.window_s);
    st.accepted_per_hand_hz =
        static_cast<double>(end->status.inputs_accepted() - start->status.inputs_accepted()) / (hands * st.window_s);
  }
  std::vector<std::string> why;
  if (st.hands_min != hands || st.hands_max != hands)
    why.push_back("server reported " + std::to_string(st.hands_min) + ".." + std::to_string(st.hands_max) + " hands");
  if (hands > 0 && st.published_per_hand_hz < 0.9 * o.sample_hz)
    why.push_back("publishers reached only " + cli::format_number(std::round(st.published_per_hand_hz * 10) / 10) +
                  " Hz per hand");
  if (hands > 0 && st.accepted_per_hand_hz < 0.9 * st.published_per_hand_hz)
    why.push_back("server accepted only " + cli::format_number(std::round(st.accepted_per_hand_hz * 10) / 10) +
                  " Hz per hand");
  if (st.rejected > 0) why.push_back(std::to_string(st.rejected) + " inputs rejected");
  if (st.phase == "active" && hands > 0) {
    // A level where the hands do not grasp is not an active level.
    if (st.hands_grasping < 0.9 * hands)
      why.push_back("only " + std::to_string(st.hands_grasping) + " of " + std::to_string(hands) + " hands grasped");
    if (st.cycles == 0 || st.held_fraction() < 0.8)
      why.push_back("held " + std::to_string(st.cycles_held) + " of " + std::to_string(st.cycles) + " trials");
  }
  st.tolerated = why.empty() && st.missed > 0 && o.allow_missed_pct > 0 &&
                 static_cast<double>(st.missed) <= o.allow_missed_pct / 100 * static_cast<double>(st.ticks);
  if (st.missed > 0) why.insert(why.begin(), std::to_string(st.missed) + " ticks missed");
  st.sustained = why.empty();
  for (const auto& w : why) st.why += (st.why.empty() ? "" : "; ") + w;
  return st;
}

void print_header(bool show_phase) {
  if (show_phase) std::cout << std::left << std::setw(7) << "phase";
  std::cout << std::right << std::setw(6) << "hands" << std::setw(4) << "try" << std::setw(7) << "ticks" << std::setw(7)
            << "missed" << std::setw(10) << "tick p50" << std::setw(10) << "tick max" << std::setw(9) << "srv cpu"
            << std::setw(9) << "sim thr" << std::setw(9) << "pub cpu" << std::setw(8) << "others" << std::setw(11)
            << "us/tick" << std::setw(13) << "us/hand/tick" << std::setw(9) << "pub Hz" << std::setw(9) << "acc Hz"
            << std::setw(9) << "machine"
            << "  result\n";
}

void print_step(const Step& s, bool show_phase) {
  if (show_phase) std::cout << std::left << std::setw(7) << s.phase;
  std::cout << std::right << std::fixed << std::setw(6) << s.hands << std::setw(4) << s.attempt << std::setw(7)
            << s.ticks << std::setw(7) << s.missed << std::setprecision(0) << std::setw(10) << s.tick_us_p50
            << std::setw(10) << s.tick_us_max << std::setprecision(1) << std::setw(8)
            << (s.window_s > 0 ? s.server_cpu_pct() : 0) << "%" << std::setw(8)
            << (s.window_s > 0 ? s.sim_cpu_pct() : 0) << "%" << std::setw(8) << (s.window_s > 0 ? s.pub_cpu_pct() : 0)
            << "%" << std::setw(7) << (s.window_s > 0 ? s.other_cpu_pct() : 0) << "%" << std::setprecision(0)
            << std::setw(11) << s.cpu_us_per_tick() << std::setprecision(2) << std::setw(13) << s.cpu_us_per_hand_tick()
            << std::setprecision(1) << std::setw(9) << s.published_per_hand_hz << std::setw(9) << s.accepted_per_hand_hz
            << std::setw(8) << (s.window_s > 0 ? s.machine_cpu_pct() : 0) << (s.saturated() ? "*" : "%") << "  "
            << (s.sustained ? "sustained" : (s.tolerated ? "tolerated: " : "NOT sustained: ") + s.why) << "\n";
  if (s.counted_grasps && s.window_s > 0)
    std::cout << std::setprecision(1) << "       grasp events: " << s.grasps << " grasps (" << s.grasps_per_s()
              << "/s), " << s.releases << " releases; hands that grasped " << s.hands_grasping << "/" << s.hands
              << "; trials held " << s.cycles_held << "/" << s.cycles << std::setprecision(0) << " ("
              << 100 * s.held_fraction() << "%)" << std::setprecision(2) << "; mean trial " << s.mean_cycle_s
              << " s; trials not begun: object away from its place " << s.objects_missing << ", fallen over "
              << s.objects_fallen << "\n";
  if (s.outputs && s.window_s > 0) {
    std::cout << "       a subscriber received, B/s per hand (samples/s per hand):";
    double total = 0;
    for (std::size_t i = 0; i < OutputCounter::kTopics.size(); ++i) {
      const double per = s.hands ? s.window_s * s.hands : s.window_s;
      total += static_cast<double>(s.outputs->bytes[i]) / per;
      std::cout << " " << OutputCounter::kTopics[i] << " " << std::setprecision(0)
                << static_cast<double>(s.outputs->bytes[i]) / per << " (" << std::setprecision(1)
                << static_cast<double>(s.outputs->samples[i]) / per << ")";
    }
    std::cout << std::setprecision(0) << "; total " << total << (s.hands ? " B/s per hand" : " B/s") << "\n";
  }
  if (s.lo_bytes >= 0 && s.window_s > 0 && (s.outputs || s.counted_grasps))
    std::cout << std::setprecision(0) << "       loopback interface: " << s.lo_bytes / s.window_s << " B/s, "
              << s.lo_packets / s.window_s << " packets/s\n";
  std::cout.flush();
  std::cerr << "  server threads (tid: % of one core):";
  for (std::size_t i = 0; i < s.threads_cpu_pct.size() && i < 6; ++i)
    std::cerr << " " << s.threads_cpu_pct[i].first << ": " << std::fixed << std::setprecision(1)
              << s.threads_cpu_pct[i].second;
  std::cerr << "\n";
}

nlohmann::ordered_json to_json(const Step& s) {
  auto r = [](double x, double unit) { return std::round(x / unit) * unit; };
  nlohmann::ordered_json j{{"phase", s.phase},
                           {"hands", s.hands},
                           {"attempt", s.attempt},
                           {"sustained", s.sustained},
                           {"tolerated", s.tolerated},
                           {"why_not", s.why},
                           {"window_s", r(s.window_s, 0.001)},
                           {"ticks", s.ticks},
                           {"missed_ticks", s.missed},
                           {"quality_late", s.quality_late},
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
                              for (const auto& [tid, pct] : s.threads_cpu_pct)
                                a.push_back({{"tid", tid}, {"cpu_pct", r(pct, 0.1)}});
                              return a;
                            }()}};
  if (s.counted_grasps) {
    j["grasps"] = s.grasps;
    j["releases"] = s.releases;
    j["grasps_per_s"] = r(s.grasps_per_s(), 0.01);
    j["hands_grasping"] = s.hands_grasping;
    j["trials"] = s.cycles;
    j["trials_held"] = s.cycles_held;
    j["held_fraction"] = r(s.held_fraction(), 0.001);
    j["trials_not_begun_object_away"] = s.objects_missing;
    j["trials_not_begun_object_fallen"] = s.objects_fallen;
    j["mean_trial_s"] = r(s.mean_cycle_s, 0.01);
  }
  if (s.outputs) {
    nlohmann::ordered_json out;
    for (std::size_t i = 0; i < OutputCounter::kTopics.size(); ++i)
      out[OutputCounter::kTopics[i]] = {{"samples", s.outputs->samples[i]}, {"bytes", s.outputs->bytes[i]}};
    j["subscriber_received"] = out;
  }
  if (s.lo_bytes >= 0) {
    j["loopback_bytes"] = s.lo_bytes;
    j["loopback_packets"] = s.lo_packets;
  }
  return j;
}

/// One sweep's result: the levels and what they came to.
struct Sweep {
  std::string phase;
  std::vector<Step> steps;
  int hands_sustained = 0;
  std::optional<std::size_t> at_sustained;  // index into steps
  int hands_tolerated = 0;  // the last level sustained or tolerated (--allow-missed-pct)
  std::optional<std::size_t> at_tolerated;
  std::string stop_reason;
  int hands_lossless = 0, hands_unsaturated = 0;
  std::optional<std::size_t> at_unsaturated;
  double slope = 0, intercept = 0;  // server CPU us per tick = intercept + slope * hands (least squares)

  double per_hand_tick() const { return at_sustained ? steps[*at_sustained].cpu_us_per_hand_tick() : 0; }
  double per_hand_tick_tolerated() const { return at_tolerated ? steps[*at_tolerated].cpu_us_per_hand_tick() : 0; }
  double per_hand_tick_unsaturated() const {
    return at_unsaturated ? steps[*at_unsaturated].cpu_us_per_hand_tick() : 0;
  }
  /// The last sustained (or tolerated) level with exactly `hands` hands, if any.
  const Step* sustained_at(int hands) const {
    const Step* out = nullptr;
    for (const Step& s : steps)
      if ((s.sustained || s.tolerated) && s.hands == hands) out = &s;
    return out;
  }

  // The last sustained level before the stop whose inputs all (>= 99%) reached the server, and
  // the last one the machine ran unsaturated: there the per-hand cost is the server's own.
  // Marginal cost: least-squares slope of server CPU per tick over hands, across the sustained,
  // unsaturated levels.
  void summarize() {
    for (std::size_t i = 0; i < steps.size(); ++i) {
      const Step& s = steps[i];
      if (!(s.sustained || s.tolerated) || s.hands == 0) continue;
      if (s.input_loss_pct() <= 1.0) hands_lossless = std::max(hands_lossless, s.hands);
      if (!s.saturated() && s.hands >= hands_unsaturated) {
        hands_unsaturated = s.hands;
        at_unsaturated = i;
      }
    }
    double sx = 0, sy = 0, sxx = 0, sxy = 0;
    int n = 0;
    for (const Step& s : steps)
      if ((s.sustained || s.tolerated) && !s.saturated() && s.ticks > 0) {
        const double x = s.hands, y = s.cpu_us_per_tick();
        sx += x, sy += y, sxx += x * x, sxy += x * y, ++n;
      }
    const double denom = n * sxx - sx * sx;
    slope = n >= 2 && denom > 0 ? (n * sxy - sx * sy) / denom : 0;
    intercept = n >= 2 && denom > 0 ? (sy - slope * sx) / n : 0;  // one level (tried twice) gives no line
  }

  nlohmann::ordered_json json() const {
    nlohmann::ordered_json j;
    j["hands_sustained"] = hands_sustained;
    j["cpu_us_per_hand_tick"] = std::round(per_hand_tick() * 1000) / 1000;
    j["hands_tolerated"] = hands_tolerated;
    j["cpu_us_per_hand_tick_tolerated"] = std::round(per_hand_tick_tolerated() * 1000) / 1000;
    j["cpu_us_per_hand_tick_marginal"] = std::round(slope * 1000) / 1000;
    j["cpu_us_per_tick_fixed"] = std::round(intercept * 10) / 10;
    j["hands_unsaturated"] = hands_unsaturated;
    j["cpu_us_per_hand_tick_unsaturated"] = std::round(per_hand_tick_unsaturated() * 1000) / 1000;
    j["hands_sustained_lossless"] = hands_lossless;
    j["stop_reason"] = stop_reason;
    return j;
  }
};

void print_sweep_summary(const Sweep& w, const Options& o, const std::string& label) {
  std::cout << std::fixed << label << "hands sustained at " << cli::format_number(o.sample_hz)
            << " Hz with no missed tick: " << w.hands_sustained << " (stop: " << w.stop_reason << ")\n"
            << std::setprecision(2) << label << "server CPU per hand per tick at that level: " << w.per_hand_tick()
            << " us (all threads, fixed cost included); marginal " << w.slope << " us/hand/tick over a fixed "
            << std::setprecision(0) << w.intercept
            << " us/tick (least squares over the sustained, unsaturated levels)\n"
            << std::setprecision(2);
  if (o.allow_missed_pct > 0)
    std::cout << label << "hands with <= " << cli::format_number(o.allow_missed_pct)
              << "% of ticks missed: " << w.hands_tolerated << ", server CPU per hand per tick there "
              << w.per_hand_tick_tolerated() << " us\n";
  std::cout << label
            << "largest unsaturated level (machine < 80% busy; * marks saturated levels): " << w.hands_unsaturated
            << " hands, " << w.per_hand_tick_unsaturated() << " us/hand/tick; largest sustained"
            << (o.allow_missed_pct > 0 ? " or tolerated" : "") << " level with <= 1% inputs lost: " << w.hands_lossless
            << " hands\n";
}

int run(const Options& o) {
  install_signal_handlers();
  const int sweeps = o.active ? 2 : 1;
  // Start-up and matching waits, then at most two attempts per level with their waits, per sweep.
  const Watchdog watchdog(120 + sweeps * 2.0 * (o.max / o.step + 2) * (o.seconds_per_step + 15));
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
    if (o.active)
      c << "# --active: one " << o.active_model << " per hand\n" << active_objects_config(o.max, o.active_model);
    if (!c) throw std::runtime_error("cannot write " + config);
  }
  ServerOptions so = server_options(o);
  so.empty_scene = !o.active;
  so.extra = {"--config", config};
  so.extra.insert(so.extra.end(), o.server_args.begin(), o.server_args.end());
  so.log_path = own_server_log ? tmp + "-server.log" : o.server_log;

  std::unique_ptr<ActiveHands> active_hands;
  if (o.active) {
    const auto t0 = Clock::now();
    active_hands = std::make_unique<ActiveHands>(o.active_model, o.max, o.sample_hz);
    std::cerr << "telegrasp-bench-scale: planned the grasps of " << o.active_model << " in "
              << std::chrono::duration<double>(Clock::now() - t0).count() << " s\n";
  }
  StatusCollector status;
  ChildProcess server;
  idl::DdsParticipant main_participant(o.domain, o.profile, o.profiles_file);
  main_participant.reader<msg::ServerStatusPubSubType>(idl::kServerStatusTopic, &status);
  if (active_hands) {
    main_participant.reader<msg::GraspEventPubSubType>(idl::kGraspEventTopic, active_hands.get());
    active_hands->set_scene_reader(main_participant.reader<msg::SceneStatePubSubType>(idl::kSceneStateTopic));
  }
  std::cerr << "telegrasp-bench-scale: starting " << join_command(server_argv(so)) << " (log " << so.log_path << ")\n";
  start_server(server, so, status, 20);
  const pid_t server_pid = server.pid();
  std::cerr << "telegrasp-bench-scale: server pid " << server_pid << " answered\n";
  std::unique_ptr<OutputCounter> counter;
  if (o.count_outputs) counter = std::make_unique<OutputCounter>(o.domain, o.profile, o.profiles_file);

  std::vector<Sweep> results;
  {
    Publishers pubs(o.publishers, o.domain, o.profile, o.profiles_file, o.sample_hz, o.max, active_hands.get());
    if (!pubs.matched(15))
      throw std::runtime_error(
          "the publisher participants did not match the server's ControllerState reader within 15 s");
    pubs.start();
    std::cout << "telegrasp-bench-scale: " << o.publishers << " publisher threads at " << o.sample_hz << " Hz, +"
              << o.step << " hands per " << o.seconds_per_step << " s level, up to " << o.max << "; late latching "
              << (o.late_latch ? "on" : "off") << "; CPU in % of one core";
    if (o.active) std::cout << "; one " << o.active_model << " per hand: an idle sweep, then an active one";
    std::cout << "\n";
    print_header(o.active);
    for (int sweep = 0; sweep < sweeps && !stop_requested(); ++sweep) {
      Sweep w;
      w.phase = sweep == 0 ? "idle" : "active";
      if (active_hands) active_hands->set_active(w.phase == "active");
      bool strict = true;  // every level so far had no missed tick
      // The active sweep starts at its first level (level 0 was the idle sweep's baseline).
      for (int hands = sweep == 0 ? 0 : std::min(o.step, o.max);; hands = std::min(hands + o.step, o.max)) {
        pubs.set_hands(hands);
        // Active hands need a trial's time to be in their cycle before the window opens.
        if (w.phase == "active" && !sleep_unless_stopped(3)) break;
        Step s = measure(hands, 1, o, status, pubs, server_pid, active_hands.get(), counter.get());
        print_step(s, o.active);
        w.steps.push_back(s);
        if (!s.sustained && !stop_requested()) {  // confirm: one re-measurement of the same level
          s = measure(hands, 2, o, status, pubs, server_pid, active_hands.get(), counter.get());
          print_step(s, o.active);
          w.steps.push_back(s);
        }
        if (stop_requested()) {
          w.stop_reason = "interrupted";
          break;
        }
        if (!s.sustained && !s.tolerated) {
          w.stop_reason = std::to_string(hands) + " hands not sustained twice: " + s.why;
          break;
        }
        strict = strict && s.sustained;
        if (hands > 0 && strict) {
          w.hands_sustained = hands;
          w.at_sustained = w.steps.size() - 1;
        }
        if (hands > 0) {
          w.hands_tolerated = hands;
          w.at_tolerated = w.steps.size() - 1;
        }
        if (hands >= o.max) {
          w.stop_reason = "reached --max " + std::to_string(o.max);
          break;
        }
      }
      w.summarize();
      results.push_back(std::move(w));
    }
    pubs.stop();
  }
  if (stop_requested()) throw std::runtime_error("interrupted");
  counter.reset();
  server.stop();
  const std::string server_exit = server.exit_description();

  const Sweep& idle = results.front();
  if (!o.active) {
    print_sweep_summary(idle, o, "");
    std::cout << "target >= 128 hands: " << (idle.hands_sustained >= 128 ? "met" : "NOT met") << "\n";
  } else {
    print_sweep_summary(idle, o, "idle: ");
    if (results.size() > 1) {
      const Sweep& act = results[1];
      print_sweep_summary(act, o, "active: ");
      // Idle and active at the same number of hands: the largest level both sweeps sustained.
      const int both = std::min(idle.hands_tolerated, act.hands_tolerated);
      const Step *i = idle.sustained_at(both), *a = act.sustained_at(both);
      if (i && a)
        std::cout << std::setprecision(2) << "at " << both << " hands (" << a->ticks << " ticks, " << a->missed
                  << " missed, " << a->quality_late << " waited for the quality worker): server CPU " << a->cpu_us_per_hand_tick() << " us per active hand-tick vs "
                  << i->cpu_us_per_hand_tick() << " idle (x"
                  << (i->cpu_us_per_hand_tick() > 0 ? a->cpu_us_per_hand_tick() / i->cpu_us_per_hand_tick() : 0)
                  << "), " << std::setprecision(1) << a->server_cpu_pct() << "% vs " << i->server_cpu_pct()
                  << "% of one core; tick p50 " << std::setprecision(0) << a->tick_us_p50 << " vs " << i->tick_us_p50
                  << " us, max " << a->tick_us_max << " vs " << i->tick_us_max << " us; " << std::setprecision(1)
                  << a->grasps_per_s() << " grasps/s, trials held " << a->cycles_held << "/" << a->cycles << "\n";
    }
  }

  if (!o.json.empty()) {
    nlohmann::ordered_json j = idle.json();  // the idle sweep's figures at the top level, as before --active
    if (o.active && results.size() > 1) j["active"] = results[1].json();
    j["sample_hz"] = o.sample_hz;
    // null: the server's default
    j["tick_hz"] = o.tick_hz > 0 ? nlohmann::ordered_json(o.tick_hz) : nlohmann::ordered_json();
    j["step"] = o.step;
    j["max"] = o.max;
    j["seconds_per_step"] = o.seconds_per_step;
    j["publishers"] = o.publishers;
    j["late_latch"] = o.late_latch;
    j["profile"] = o.profile;
    j["active_model"] = o.active ? nlohmann::ordered_json(o.active_model) : nlohmann::ordered_json();
    j["count_outputs"] = o.count_outputs;
    j["cpus"] = std::thread::hardware_concurrency();
    j["loadavg_at_start"] = loadavg;
    j["note"] = "CPU percentages are of one core; the publisher process shares the machine's cores with the server";
    j["server_command"] = join_command(server_argv(so));
    j["server_exit"] = server_exit;
    j["steps"] = nlohmann::ordered_json::array();
    for (const Sweep& w : results)
      for (const Step& s : w.steps) j["steps"].push_back(to_json(s));
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
