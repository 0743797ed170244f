// telegrasp-server: the authoritative grasp simulation, driven by VR clients over DDS.
#include "dds_node.h"
#include "input_mailbox.h"
#include "live_feed.h"
#include "recording.h"
#include "scene_server.h"
#include "scene_setup.h"
#include "server_config.h"
#include "server_loop.h"

#include "cli.h"
#include "telegrasp/sim/mesh_loading.h"

#include <pthread.h>
#include <signal.h>

#include <cstdlib>
#include <iostream>
#include <optional>
#include <string>
#include <thread>
#include <vector>

namespace {

using namespace telegrasp;
using namespace telegrasp::server;

constexpr const char* kUsage = R"(Usage: telegrasp-server [options]

The authoritative grasp simulation: reads ControllerState samples from VR clients over DDS,
runs the collision-driven grasp system on a shared physics scene at a fixed tick, and publishes
HandSkeleton, GraspState, ContactSet, GraspEvent, SceneState and ServerStatus.

Options (override the --config file):
  --config FILE       server configuration, protobuf text (schema: server/proto/server_config.proto)
  --domain N          DDS domain, 0..232 (default 0)
  --profile NAME      Fast DDS participant profile: loopback (default), lan, wan, secure (loopback
                      with DDS Security: see --security, --identity and the README)
  --profiles FILE     Fast DDS XML profiles (default: deploy/fastdds/telegrasp_profiles.xml)
  --security DIR      with --profile secure: the folder deploy/security/make-certs.sh made
                      (default $TELEGRASP_SECURITY_DIR)
  --identity NAME     with --profile secure: this server's identity in it (default
                      $TELEGRASP_IDENTITY, else server)
  --objects DIR       models = every mesh in DIR (default: the 30 built-in stand-ins)
  --fill-standins     with --objects: also the built-in stand-in of each protocol object with no
                      mesh in DIR
  --empty-scene       start with no objects (spawn them with SceneCommand)
  --tick-hz HZ        simulation rate (default 90)
  --mode M            finger closing: precise (default) | discrete
  --two-hand-mode M   a grasp on an object another hand holds: share (default: both hold it, the
                      object follows both hands) | takeover (the newest grasp takes it)
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
Exit status: 0 stopped cleanly (or --list-models done), 1 a runtime failure (a configuration,
rig or mesh file or the --objects folder missing or unreadable, DDS could not start), 2 a usage
error (a bad or missing option or value).
)";

[[noreturn]] void usage_error(const std::string& what) { cli::usage_exit("telegrasp-server", what); }

struct Flags {
  ServerSettings settings;
  bool list_models = false;
  bool objects_flag = false;  // --objects given (else objects_dir, if any, is the config file's)
  std::string security_dir, identity;  // --security, --identity ("": the environment's)
};

// --security and --identity are passed to DdsParticipant (security.h) as the environment it reads;
// a secure server with no identity named is "server", as make-certs.sh names it.
void export_security_flags(const Flags& f) {
  if (!f.security_dir.empty()) setenv("TELEGRASP_SECURITY_DIR", f.security_dir.c_str(), 1);
  if (!f.identity.empty()) setenv("TELEGRASP_IDENTITY", f.identity.c_str(), 1);
  const char* identity = std::getenv("TELEGRASP_IDENTITY");
  if (identity == nullptr || *identity == '\0') setenv("TELEGRASP_IDENTITY", "server", 1);
}

// Applies the flags onto `f` (after any --config file: flags override it whatever their order);
// collects the --config files into `configs`.
void apply_flags(int argc, char** argv, Flags& f, std::vector<std::string>& configs) {
  ServerSettings& s = f.settings;
  cli::for_each_option(argc, argv, kUsage, usage_error, [&](const std::string& a, const auto& value) {
    if (a == "--config")
      configs.push_back(value());
    else if (a == "--domain")
      s.domain = cli::parse_domain(a, value(), usage_error);
    else if (a == "--profile")
      s.profile = cli::parse_profile(a, value(), usage_error);
    else if (a == "--profiles")
      s.profiles_file = value();
    else if (a == "--security")
      f.security_dir = value();
    else if (a == "--identity")
      f.identity = value();
    else if (a == "--objects")
      s.objects_dir = value(), f.objects_flag = true;
    else if (a == "--empty-scene")
      s.empty_scene = true, s.objects.clear();
    else if (a == "--tick-hz")
      s.tick_hz = cli::parse_number(a, value(), 1, 2000, usage_error);
    else if (a == "--no-late-latch")
      s.late_latch = false;
    else if (a == "--lockstep")
      s.lockstep = true;
    else if (a == "--list-models")
      f.list_models = true;
    else if (a == "--fill-standins")
      s.fill_standins = true;
    else if (a == "--record")
      s.record_path = value();
    else if (a == "--mode") {
      const std::string m = value();
      const std::optional<sim::ClosingMode> mode = sim::parse_closing_mode(m);
      if (!mode) usage_error("--mode expects precise or discrete, got '" + m + "'");
      s.closing_mode = *mode;
    } else if (a == "--two-hand-mode") {
      const std::string m = value();
      const std::optional<sim::TwoHandMode> mode = sim::parse_two_hand_mode(m);
      if (!mode) usage_error("--two-hand-mode expects share or takeover, got '" + m + "'");
      s.two_hand_mode = *mode;
    } else {
      return false;
    }
    return true;
  });
}

Flags parse(int argc, char** argv) {
  // Every flag is checked first, then the files are read, then the flags applied over them.
  std::vector<std::string> configs;
  Flags checked;
  apply_flags(argc, argv, checked, configs);
  Flags f;
  for (const std::string& config : configs) {
    try {
      load_server_config(config, f.settings);
    } catch (const std::exception& e) {
      std::cerr << "telegrasp-server: " << e.what() << "\n";
      std::exit(cli::kExitFailure);
    }
  }
  std::vector<std::string> again;
  apply_flags(argc, argv, f, again);
  try {
    validate_settings(f.settings, "command line");
  } catch (const std::exception& e) {
    usage_error(e.what());
  }
  return f;
}

// SIGINT and SIGTERM, blocked in every thread (threads started later inherit the mask) and taken
// by one thread that calls ServerLoop::stop() on the first: no code runs in a signal handler.
sigset_t block_stop_signals() {
  sigset_t signals;
  sigemptyset(&signals);
  sigaddset(&signals, SIGINT);
  sigaddset(&signals, SIGTERM);
  pthread_sigmask(SIG_BLOCK, &signals, nullptr);
  return signals;
}

class StopOnSignal {
 public:
  StopOnSignal(ServerLoop& loop, sigset_t signals)
      : signals_(signals), thread_([this, &loop] {
          int signal = 0;
          sigwait(&signals_, &signal);
          loop.stop();
        }) {}
  // Releases the thread if no signal came (the loop ended otherwise): a signal only it takes.
  ~StopOnSignal() {
    pthread_kill(thread_.native_handle(), SIGTERM);
    thread_.join();
  }

 private:
  sigset_t signals_;
  std::thread thread_;
};

}  // namespace

int main(int argc, char** argv) {
  const Flags flags = parse(argc, argv);
  export_security_flags(flags);
  const ServerSettings& settings = flags.settings;
  SceneAssets assets;
  try {
    if (!settings.objects_dir.empty())
      std::cerr << "telegrasp-server: loading meshes from " << settings.objects_dir << " ...\n";
    assets = load_scene_assets(settings);
    if (flags.list_models) {
      for (const auto& m : assets.models) std::cout << m->name << "\n";
      return 0;
    }
  } catch (const sim::MeshLoadError& e) {  // names the folder or the file in it
    const char* origin = settings.objects_dir.empty() ? "" : flags.objects_flag ? "--objects " : "objects_dir ";
    std::cerr << "telegrasp-server: " << origin << e.what() << "\n";
    return cli::kExitFailure;
  } catch (const std::exception& e) {
    std::cerr << "telegrasp-server: " << e.what() << "\n";
    return cli::kExitFailure;
  }

  InputMailbox mailbox({assets.left_rig->fingers().size(), assets.right_rig->fingers().size()}, settings.max_hands);
  const sigset_t stop_signals = block_stop_signals();  // before the DDS threads start
  try {
    DdsNode node(settings.domain, settings.profile, settings.profiles_file, mailbox);
    node.publish_geometries(assets.models);
    // Declared before the scene, so the scene goes first and the recorder then closes the file.
    std::optional<Recorder> recorder;
    if (!settings.record_path.empty()) recorder.emplace(settings.record_path, settings, assets, node);
    OutputSink& sink = recorder ? static_cast<OutputSink&>(*recorder) : node;
    SceneServer scene(settings, assets.models, assets.right_rig, assets.left_rig, mailbox, sink);
    LiveFeed feed(mailbox, [&node] { return node.take_commands(); });
    ServerLoop loop(loop_settings(settings), scene, feed, feed, sink, recorder ? &*recorder : nullptr);
    const StopOnSignal stop_on_signal(loop, stop_signals);
    std::cerr << "telegrasp-server: domain " << settings.domain << ", profile " << settings.profile << ", "
              << scene.world().objects().size() << " objects, " << settings.tick_hz << " Hz"
              << (settings.lockstep     ? " in lockstep"
                  : settings.late_latch ? ", late-latched skeletons"
                                        : "")
              << "; Ctrl-C to stop\n";
    loop.run();
    std::cerr << "telegrasp-server: stopping after " << scene.world().tick() << " ticks, " << mailbox.accepted()
              << " inputs accepted, " << loop.missed_ticks() << " ticks missed\n";
  } catch (const std::exception& e) {
    std::cerr << "telegrasp-server: " << e.what() << "\n";
    return cli::kExitFailure;
  }
  return 0;
}
