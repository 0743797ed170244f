// telegrasp-server: the authoritative grasp simulation, driven by VR clients over DDS.
#include "dds_node.h"
#include "input_mailbox.h"
#include "live_feed.h"
#include "recording.h"
#include "scene_server.h"
#include "scene_setup.h"
#include "server_config.h"
#include "server_loop.h"
#include "snapshot.h"

#include "telegrasp/idl/cli.h"
#include "telegrasp/idl/network_flags.h"
#include "telegrasp/sim/mesh_loading.h"

#include <pthread.h>
#include <signal.h>
#include <unistd.h>

#include <chrono>
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
  --profile NAME      Fast DDS participant profile: loopback (default), udp, lan, wan, secure (loopback
                      with DDS Security: see --security, --identity and the README)
  --profiles FILE     Fast DDS XML profiles (default: deploy/fastdds/telegrasp_profiles.xml)
  --scene NAME        the scene (room) to serve: its topics are in DDS partition
                      telegrasp/scene/NAME, so clients of other scenes never see them; 1-64
                      letters, digits, '-', '_', '.' (default $TELEGRASP_SCENE, else default).
                      The server announces itself on the scene directory (telegrasp-echo
                      --scenes) and, before serving, waits --claim-wait-s seconds for an older run
                      of the same scene: if one is live, it refuses to start (exit 1)
  --claim-wait-s S    seconds to wait for an older claim on the scene name (default 1.5; 0:
                      do not wait, e.g. in tests that start many servers)
  --discovery-server HOST[:PORT]
                      a Fast DDS discovery server (port 11811 when left out); repeat for more, in
                      the order of their ids (`fastdds discovery -i 0`, `-i 1`, ...): discovery
                      goes through them only, and losing one of two changes nothing (default
                      $TELEGRASP_DISCOVERY_SERVERS "HOST:PORT;HOST:PORT", else the profile's)
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
  --operator ID       a client id that may remove any object and reset the scene (repeat for
                      more; others may spawn, and remove only what they spawned or hold)
  --open-scene        every client is an operator
  --max-hands-per-participant N
                      hands one DDS participant may drive (default 16)
  --relay PREFIX[:N]  a relay (telegrasp-view --drive) owns the client ids starting with PREFIX:
                      the first participant to drive one holds them all until it leaves, up to
                      N hands (default 64; repeat for more relays)
  --max-input-rate HZ ControllerState samples per second per hand (default 250; more are dropped
                      and counted as rate_limited)
  --max-command-rate HZ
                      SceneCommands per second per client (default 20; both rates are not
                      limited with --lockstep, which runs faster than real time)
  --two-hand-mode M   a grasp on an object another hand holds: share (default: both hold it, the
                      object follows both hands) | takeover (the newest grasp takes it)
  --no-late-latch     publish skeletons only at ticks, not also on each sample's arrival
  --quality-delay-ticks K
                      the grasp quality of tick t's contacts is computed on a worker thread and
                      published at tick t + K; GraspEvents wait as long, so they carry it and keep
                      their order (default 2, 0..90; 0: within the tick, on the simulation thread)
  --quality-volume    grasp qualities also carry the wrench hull's volume (Qhull's full 6-D hull:
                      milliseconds per grasp on the simulation thread; default off: volume -1,
                      "not computed"; epsilon and force closure are always computed)
  --lockstep          tick as soon as every hand has answered the last tick (ControllerState.
                      lockstep_tick) and its commands have arrived, not on the clock: runs are
                      deterministic and faster than real time. With no hands the scene waits; a
                      hand silent for freeze_after_s is frozen and no longer waited for.
  --record FILE       write every accepted input and every output to FILE (a binary protobuf
                      stream, server/proto/recording.proto); telegrasp-replay re-runs it
  --snapshot FILE     write the objects' last published poses to FILE about once a second and on
                      a clean stop (protobuf text, server/proto/snapshot.proto; atomically: a
                      temporary file in the same folder, fsync, rename), and, if FILE exists at
                      start, bring the objects back at those poses instead of the configured
                      scene (a SCENE_RESET still goes back to the configured scene). A FILE that
                      exists but is damaged or names an unknown model stops the start (exit 1)
                      with a message naming it: remove it to start from the configuration.
  --list-models       print the model names and exit
  -h, --help          this text

Every run gets a random incarnation id, published in SceneState and ServerStatus: clients
tell a restarted server from the one before (object ids, ticks and times start over).

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
  std::vector<std::string> discovery_servers;  // --discovery-server: replace the config file's
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
  // The network flags set the settings, but --discovery-server replaces the configuration file's
  // list (f.discovery_servers) instead of adding to it.
  struct {
    int& domain;
    std::string& profile;
    std::string& profiles_file;
    std::string& scene;
    std::vector<std::string>& discovery_servers;
  } network{s.domain, s.profile, s.profiles_file, s.scene, f.discovery_servers};
  cli::for_each_option(argc, argv, kUsage, usage_error, [&](const std::string& a, const auto& value) {
    if (a == "--config")
      configs.push_back(value());
    else if (idl::parse_network_flag(a, value, network, usage_error))
      ;
    else if (telegrasp::cli::is_flag("telegrasp-server", a, "--claim-wait-s", "--claim-wait"))
      s.claim_wait_s = cli::parse_number(a, value(), 0, 60, usage_error);
    else if (cli::text_flag(a, value,
                            {{"--security", &f.security_dir}, {"--identity", &f.identity}, {"--record", &s.record_path},
                             {"--snapshot", &s.snapshot_path}}))
      ;
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
    else if (a == "--quality-volume")
      s.quality_volume = true;
    else if (a == "--quality-delay-ticks")
      s.quality_delay_ticks = static_cast<int>(cli::parse_whole(a, value(), 0, 90, usage_error));
    else if (a == "--list-models")
      f.list_models = true;
    else if (a == "--fill-standins")
      s.fill_standins = true;
    else if (a == "--mode") {
      const std::string m = value();
      const std::optional<sim::ClosingMode> mode = sim::parse_closing_mode(m);
      if (!mode) usage_error("--mode expects precise or discrete, got '" + m + "'");
      s.closing_mode = *mode;
    } else if (a == "--operator") {
      const std::string id = value();
      if (id.empty() || id.size() > 64) usage_error("--operator expects a client id of 1..64 characters");
      s.operators.push_back(id);
    } else if (a == "--open-scene") {
      s.open_scene = true;
    } else if (a == "--max-hands-per-participant") {
      s.max_hands_per_participant = static_cast<int>(cli::parse_number(a, value(), 1, 4096, usage_error));
    } else if (a == "--relay") {
      const std::string spec = value();
      const std::size_t colon = spec.rfind(':');
      Relay relay{spec.substr(0, colon), 64};
      if (colon != std::string::npos)
        relay.max_hands = static_cast<int>(cli::parse_whole(a, spec.substr(colon + 1), 1, 4096, usage_error));
      if (relay.prefix.empty() || relay.prefix.size() > 32)
        usage_error("--relay expects PREFIX[:N] with a prefix of 1..32 characters, got '" + spec + "'");
      s.relays.push_back(relay);
    } else if (a == "--max-input-rate") {
      s.max_input_rate_hz = cli::parse_number(a, value(), 1, 1e6, usage_error);
    } else if (a == "--max-command-rate") {
      s.max_command_rate_hz = cli::parse_number(a, value(), 0.1, 1e6, usage_error);
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
  if (!f.discovery_servers.empty()) f.settings.discovery_servers = f.discovery_servers;
  try {
    validate_settings(f.settings, "command line");
    const idl::Network network = idl::resolve_network({f.settings.scene, f.settings.discovery_servers});
    f.settings.scene = network.scene;
  } catch (const std::exception& e) {
    usage_error(e.what());
  }
  return f;
}

// A lockstep run goes faster than real time, paced by its ticks: no rate limits then.
InputLimits input_limits(const ServerSettings& s) {
  return {s.max_hands, s.max_hands_per_participant, s.lockstep ? 0 : s.max_input_rate_hz,
          s.lockstep ? 0 : s.max_command_rate_hz, s.relays};
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

// Announces this run on the scene directory and waits settings.claim_wait_s for an older live
// run of the same scene (the directory's samples come from live servers only: a dead one's writer
// answers nobody). Returns false, having said why, when one keeps the scene.
bool claim_scene(DdsNode& node, const ServerSettings& settings) {
  char host[256] = {};
  gethostname(host, sizeof host - 1);
  const AnnouncerFacts facts{settings.scene, host, telegrasp_version(), settings.incarnation,
                             std::chrono::duration<double>(std::chrono::system_clock::now().time_since_epoch()).count()};
  node.announce(facts);
  const msg::SceneAnnouncement mine = make_claim(facts);
  const auto until = std::chrono::steady_clock::now() + std::chrono::duration<double>(settings.claim_wait_s);
  do {
    if (const auto keeper = older_claim(mine, node.directory())) {
      std::cerr << "telegrasp-server: " << already_served_message(*keeper) << "\n";
      return false;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  } while (std::chrono::steady_clock::now() < until);
  return true;
}

// --snapshot: the objects' poses of the run before, if its file exists (and it can be written
// from now on). False, after saying why, when the file cannot be read or written.
bool restore_snapshot(ServerSettings& settings, const SceneAssets& assets) {
  if (settings.snapshot_path.empty()) return true;
  try {
    check_snapshot_writable(settings.snapshot_path);
    if (const auto snapshot = read_snapshot(settings.snapshot_path)) {
      settings.restored_objects = placed_objects(*snapshot, assets.models, "snapshot " + settings.snapshot_path);
      std::cerr << "telegrasp-server: " << settings.restored_objects->size() << " objects back from snapshot "
                << settings.snapshot_path << " (tick " << snapshot->tick() << " of the run before)\n";
    } else {
      std::cerr << "telegrasp-server: no snapshot " << settings.snapshot_path
                << " yet: the configured scene; writing it from now on\n";
    }
    return true;
  } catch (const SnapshotError& e) {
    std::cerr << "telegrasp-server: " << e.what() << "\n";
    return false;
  }
}

}  // namespace

int main(int argc, char** argv) {
  const Flags flags = parse(argc, argv);
  export_security_flags(flags);
  ServerSettings settings = flags.settings;
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

  settings.incarnation = new_incarnation();
  if (!restore_snapshot(settings, assets)) return cli::kExitFailure;

  InputMailbox mailbox({assets.left_rig->fingers().size(), assets.right_rig->fingers().size()}, input_limits(settings));
  const sigset_t stop_signals = block_stop_signals();  // before the DDS threads start
  try {
    DdsNode node(settings.domain, settings.profile, settings.profiles_file, mailbox,
                 {settings.scene, settings.discovery_servers});
    if (!claim_scene(node, settings)) return cli::kExitFailure;
    node.publish_geometries(assets.models);
    mailbox.set_notifier([&node](const Refusal& r) { node.publish(make_client_notice(r)); });
    // Declared before the scene, so the scene goes first and the recorder then closes the file.
    std::optional<Recorder> recorder;
    if (!settings.record_path.empty()) recorder.emplace(settings.record_path, settings, assets, node);
    OutputSink& recorded = recorder ? static_cast<OutputSink&>(*recorder) : node;
    // Declared before the scene too: it writes the last poses once the scene has stopped.
    std::optional<SnapshotWriter> snapshot;
    if (!settings.snapshot_path.empty()) snapshot.emplace(settings.snapshot_path, recorded);
    OutputSink& sink = snapshot ? static_cast<OutputSink&>(*snapshot) : recorded;
    SceneServer scene(settings, assets.models, assets.right_rig, assets.left_rig, mailbox, sink);
    LiveFeed feed(mailbox, [&node] { return node.take_commands(); });
    ServerLoop loop(loop_settings(settings), scene, feed, feed, sink, recorder ? &*recorder : nullptr);
    const StopOnSignal stop_on_signal(loop, stop_signals);
    std::cerr << "telegrasp-server: scene " << settings.scene << ", domain " << settings.domain << ", profile "
              << settings.profile << ", "
              << scene.world().objects().size() << " objects, " << settings.tick_hz << " Hz"
              << (settings.lockstep     ? " in lockstep"
                  : settings.late_latch ? ", late-latched skeletons"
                                        : "")
              << ", incarnation " << std::hex << settings.incarnation << std::dec << "; Ctrl-C to stop\n";
    loop.run();
    std::cerr << "telegrasp-server: stopping after " << scene.world().tick() << " ticks, " << mailbox.accepted()
              << " inputs accepted, " << loop.missed_ticks() << " ticks missed, " << scene.world().quality_late()
              << " ticks waited for the grasp quality";
    if (scene.held_events() > 0)
      std::cerr << "; " << scene.held_events() << " grasp event(s) of the last " << settings.quality_delay_ticks
                << " ticks, still waiting for their quality, not published";
    std::cerr << "\n";
  } catch (const std::exception& e) {
    std::cerr << "telegrasp-server: " << e.what() << "\n";
    return cli::kExitFailure;
  }
  return 0;
}
