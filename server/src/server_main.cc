// telegrasp-server: the authoritative grasp simulation, driven by VR clients over DDS.
#include "dds_node.h"
#include "input_mailbox.h"
#include "recording.h"
#include "scene_server.h"
#include "scene_setup.h"
#include "server_config.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <csignal>
#include <cstdlib>
#include <iostream>
#include <optional>
#include <string>
#include <vector>

namespace {

using namespace telegrasp;
using namespace telegrasp::server;
using Clock = std::chrono::steady_clock;

constexpr const char* kUsage = R"(Usage: telegrasp-server [options]

The authoritative grasp simulation: reads ControllerState samples from VR clients over DDS,
runs the collision-driven grasp system on a shared physics scene at a fixed tick, and publishes
HandSkeleton, GraspState, ContactSet, GraspEvent, SceneState and ServerStatus.

Options (override the --config file):
  --config FILE       server configuration, protobuf text (schema: server/proto/server_config.proto)
  --domain N          DDS domain, 0..232 (default 0)
  --profile NAME      Fast DDS participant profile: loopback (default), lan, wan
  --profiles FILE     Fast DDS XML profiles (default: deploy/fastdds/telegrasp_profiles.xml)
  --objects DIR       models = every mesh in DIR (default: the 30 built-in stand-ins)
  --fill-standins     with --objects: also the built-in stand-in of each protocol object with no
                      mesh in DIR
  --empty-scene       start with no objects (spawn them with SceneCommand)
  --tick-hz HZ        simulation rate (default 90)
  --mode M            finger closing: precise (default) | discrete
  --no-late-latch     publish skeletons only at ticks, not also on each sample's arrival
  --lockstep          tick as soon as every hand has answered the last tick (ControllerState.
                      lockstep_tick) and its commands have arrived, not on the clock: runs are
                      deterministic and faster than real time. With no hands the scene waits; a
                      hand silent for freeze_after_s is frozen and no longer waited for.
  --record FILE       write every accepted input and every output to FILE (a binary protobuf
                      stream, server/proto/recording.proto); telegrasp-replay re-runs it
  --list-models       print the model names and exit
  -h, --help          this text

Stops cleanly on SIGINT or SIGTERM.
)";

std::atomic<bool> g_stop{false};
extern "C" void on_signal(int) { g_stop = true; }

[[noreturn]] void usage_error(const std::string& what) {
  std::cerr << "telegrasp-server: " << what << "\n(see telegrasp-server --help)\n";
  std::exit(2);
}

double parse_number(const std::string& flag, const std::string& v) {
  char* end = nullptr;
  const double x = std::strtod(v.c_str(), &end);
  if (v.empty() || *end != '\0') usage_error(flag + " expects a number, got '" + v + "'");
  return x;
}

struct Flags {
  ServerSettings settings;
  bool list_models = false;
};

Flags parse(int argc, char** argv) {
  Flags f;
  // The file first, so flags override it whatever their order.
  for (int i = 1; i + 1 < argc; ++i)
    if (std::string(argv[i]) == "--config") {
      try {
        load_server_config(argv[i + 1], f.settings);
      } catch (const std::exception& e) {
        std::cerr << "telegrasp-server: " << e.what() << "\n";
        std::exit(1);
      }
    }
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto value = [&]() -> std::string {
      if (i + 1 >= argc) usage_error(a + " needs a value");
      return argv[++i];
    };
    ServerSettings& s = f.settings;
    if (a == "-h" || a == "--help") { std::cout << kUsage; std::exit(0); }
    else if (a == "--config") value();
    else if (a == "--domain") s.domain = static_cast<int>(parse_number(a, value()));
    else if (a == "--profile") s.profile = value();
    else if (a == "--profiles") s.profiles_file = value();
    else if (a == "--objects") s.objects_dir = value();
    else if (a == "--empty-scene") { s.empty_scene = true; s.objects.clear(); }
    else if (a == "--tick-hz") s.tick_hz = parse_number(a, value());
    else if (a == "--no-late-latch") s.late_latch = false;
    else if (a == "--lockstep") s.lockstep = true;
    else if (a == "--list-models") f.list_models = true;
    else if (a == "--fill-standins") s.fill_standins = true;
    else if (a == "--record") s.record_path = value();
    else if (a == "--mode") {
      const std::string m = value();
      if (m == "precise") s.closing_mode = sim::ClosingMode::kPrecise;
      else if (m == "discrete") s.closing_mode = sim::ClosingMode::kDiscrete;
      else usage_error("--mode expects precise or discrete, got '" + m + "'");
    } else usage_error("unknown option '" + a + "'");
  }
  try {
    validate_settings(f.settings, "command line");
  } catch (const std::exception& e) {
    usage_error(e.what());
  }
  return f;
}

// Median and maximum of the tick work times of one status period.
LoopStats summarize(std::vector<double>& tick_us, std::uint64_t missed) {
  LoopStats s;
  s.missed_ticks = missed;
  if (tick_us.empty()) return s;
  std::nth_element(tick_us.begin(), tick_us.begin() + tick_us.size() / 2, tick_us.end());
  s.tick_us_p50 = tick_us[tick_us.size() / 2];
  s.tick_us_max = *std::max_element(tick_us.begin(), tick_us.end());
  tick_us.clear();
  return s;
}

std::int64_t to_ns(Clock::time_point t) {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(t.time_since_epoch()).count();
}

}  // namespace

int main(int argc, char** argv) {
  const Flags flags = parse(argc, argv);
  const ServerSettings& settings = flags.settings;
  SceneAssets assets;
  try {
    if (!settings.objects_dir.empty()) std::cerr << "telegrasp-server: loading meshes from " << settings.objects_dir << " ...\n";
    assets = load_scene_assets(settings);
    if (flags.list_models) {
      for (const auto& m : assets.models) std::cout << m->name << "\n";
      return 0;
    }
  } catch (const std::exception& e) {
    std::cerr << "telegrasp-server: " << e.what() << "\n";
    return 1;
  }

  InputMailbox mailbox({assets.left_rig->fingers().size(), assets.right_rig->fingers().size()}, settings.max_hands);
  try {
    DdsNode node(settings.domain, settings.profile, settings.profiles_file, mailbox);
    // Declared before the scene, so the scene goes first and the recorder then closes the file.
    std::optional<Recorder> recorder;
    if (!settings.record_path.empty()) recorder.emplace(settings.record_path, settings, assets, node);
    OutputSink& sink = recorder ? static_cast<OutputSink&>(*recorder) : node;
    SceneServer scene(settings, assets.models, assets.right_rig, assets.left_rig, mailbox, sink);
    std::signal(SIGINT, on_signal);
    std::signal(SIGTERM, on_signal);
    std::cerr << "telegrasp-server: domain " << settings.domain << ", profile " << settings.profile << ", "
              << scene.world().objects().size() << " objects, " << settings.tick_hz << " Hz"
              << (settings.lockstep ? " in lockstep" : settings.late_latch ? ", late-latched skeletons" : "") << "; Ctrl-C to stop\n";

    // The simulation thread (this one) owns the scene: it wakes at each tick's due time (in
    // lockstep: when every hand has answered the last tick), and in between whenever a sample or
    // command arrives.
    const auto period = std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(1.0 / settings.tick_hz));
    const auto status_period = std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(settings.status_period_s));
    // Lockstep: when nothing (tick, sample or command) has happened for this long, a tick is taken
    // anyway: it freezes the hands that did not answer, and later ticks no longer wait for them.
    const auto stall_after = std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(settings.freeze_after_s));
    Clock::time_point next_tick = Clock::now() + period, next_status = Clock::now(), last_activity = Clock::now();
    std::vector<double> tick_us;
    std::uint64_t missed = 0;
    LoopStats stats;
    while (!g_stop) {
      mailbox.wait(std::min(settings.lockstep ? last_activity + stall_after : next_tick, next_status));
      const Clock::time_point now = Clock::now();
      if (auto inputs = mailbox.drain(); !inputs.empty()) {
        if (recorder) recorder->inputs(inputs, to_ns(now));
        scene.on_inputs(std::move(inputs), to_ns(now));
        last_activity = now;
      }
      for (const msg::SceneCommand& c : node.take_commands()) {
        if (recorder) recorder->command(c, to_ns(now));
        scene.apply_command(c);
        last_activity = now;
      }
      const bool due = settings.lockstep
                           ? scene.lockstep_ready() || (scene.hand_count() > 0 && now - last_activity >= stall_after)
                           : now >= next_tick;
      if (due) {
        if (recorder) recorder->tick(to_ns(now));
        scene.tick(to_ns(now));
        last_activity = now;
        tick_us.push_back(std::chrono::duration<double, std::micro>(Clock::now() - now).count());
        next_tick += period;
        if (!settings.lockstep && now - next_tick >= period) {  // fell behind by a whole tick or more: count and resync
          missed += static_cast<std::uint64_t>((now - next_tick) / period);
          next_tick = now + period;
        }
      }
      if (now >= next_status) {
        stats = summarize(tick_us, missed);
        sink.publish(scene.status(stats));
        next_status += status_period;
        if (next_status <= now) next_status = now + status_period;
      }
    }
    std::cerr << "telegrasp-server: stopping after " << scene.world().tick() << " ticks, " << mailbox.accepted()
              << " inputs accepted, " << missed << " ticks missed\n";
  } catch (const std::exception& e) {
    std::cerr << "telegrasp-server: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
