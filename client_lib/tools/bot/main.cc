// telegrasp-bot: the scripted operator of sim/ driving one or two hands of a telegrasp server
// over DDS. It grasps every object of the server's scene --trials times, records each grasp
// from the server's GraspEvent, and prints the same table and JSON records as telegrasp-eval.
#include "client_options.h"
#include "bot.h"
#include "telegrasp/idl/cli.h"
#include "telegrasp/idl/network_flags.h"
#include "telegrasp/sim/standin_objects.h"
#include "skill_flag.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <csignal>
#include <cstdint>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>

#include <unistd.h>

namespace {

namespace client = telegrasp::client;
namespace sim = telegrasp::sim;
using telegrasp::bot::Bot;
using telegrasp::bot::Clock;
using telegrasp::bot::kRate;
using telegrasp::bot::kStaleScene;
using Options = telegrasp::bot::Options;

using telegrasp::cli::kExitInterrupted;
using telegrasp::cli::kExitNotHeld;
using telegrasp::cli::kExitRefused;

// Input refusals after which no grasp can happen: the bot stops at once.
bool fatal_refusal(const client::Notice& n) {
  return n.kind == client::Notice::Kind::kInputRejected &&
         (n.reason == "client_id_owned_by_another_participant" || n.reason == "too_many_hands" ||
          n.reason == "too_many_hands_for_participant");
}

constexpr const char* kUsage = R"(Usage: telegrasp-bot [options]

The scripted operator of telegrasp-eval driving one or two hands of a telegrasp server over DDS.
Each hand picks a free object from the server's SceneState (resting on the table, held by
nobody, no other client's hand at it), appears 30 cm from it, reaches, grasps, lifts 10 cm (the
hand it sees: more if the table held the hand up), holds 1 s, puts the object back down and
releases, publishing its controller at 90 Hz. It plans on the object's pose of
the newest SceneState and moves its hand with the object until it squeezes; an object that moved
over 2 cm (or 0.25 rad) since its plan is planned again. A missed squeeze is tried again; after 3
misses the bot plans again and tries up to 3 more times (6 attempts a trial at most, the JSON
"attempts" says how many). An object is started only once it rests (under 0.02 m/s, within 2 mm
and 0.02 rad of one pose for 0.3 s). Every object in the scene (as the bot first sees it) is
grasped --trials times; each grasp is recorded from the server's GraspEvent. A server that
restarts (a new incarnation in its SceneState) is followed without restarting the bot: the
trials in progress end, recorded with "interrupted": true and "reason": "server restarted"
(never as a grasp, not counted in the table), and are run again on the new server's scene. A hand leaves an
object to another client's hand that got there first; an object unavailable for 10 s is given
up (recorded as not grasped, with the reason). Progress goes to stderr (one line per trial),
then the per-object table of telegrasp-eval goes to stdout.

Options:
  --client-id ID      names this bot's hands on the server (default bot-<pid>)
  --hands H           right | left | both (default right)
  --skill NAME        perfect | experienced | inexperienced (default experienced)
  --trials N          grasps per object in the scene (default 1)
  --seed S            random seed: object order and operator noise (default 1)
  --objects DIR       meshes of the server's models (default: none); an object with no mesh
                      here is planned on the geometry the server publishes (ObjectGeometry)
  --json FILE         write every grasp record as telegrasp-eval does, plus "client_id",
                      "hand", "object_id", "reason" and "interrupted" (true: cut short by a
                      server restart, run again; "mode" and "speed_scale" are null: they are the
                      server's settings); the summary adds "interrupted" (their count), and
                      "grasp_events": the event_ids of every GraspEvent received, any hand's
                      ({"received", "first", "last", "missing", "duplicates"}; reliable events
                      leave both lists empty)
  --domain N          DDS domain, 0..232 (default 0)
  --profile NAME      Fast DDS participant profile: loopback (default), udp, lan, wan, secure
  --profiles FILE     Fast DDS XML profiles (default: $TELEGRASP_PROFILES, else the shipped file)
  --scene NAME        the scene (room) to join (default $TELEGRASP_SCENE, else default)
  --discovery-server HOST[:PORT]
                      a Fast DDS discovery server; repeat in id order (telegrasp-server --help)
  --timeout-s S       give up when no server is found (or it goes silent) for S seconds
                      (default 20)
  -h, --help          this text

The last line on stdout (and stderr) says how many trials held, then each object not held in
every trial with its count, e.g. "held 88/90 trials on 30 objects; not held every time: spoon 2/3".

Exit status: 0 every trial done and every object held after the lift in every trial, 1 a runtime
failure (the --objects folder or a mesh in it missing or unreadable, the --json file not
writable, DDS could not start, no server found or it went silent), 2 a usage error (a bad or
missing option or value), 4 the server refused this bot's hands (the client id taken or no hand
slot left: the bot stops at once) or one of its commands; every ClientNotice is printed, and
other dropped inputs (e.g. rate_limited) do not change the status, 5 every trial done but some
object not held in every trial (or the scene had no object: nothing grasped), 130 stopped by
SIGINT or SIGTERM (the table shows the trials
done).
)";

[[noreturn]] void usage_error(const std::string& what) { telegrasp::cli::usage_exit("telegrasp-bot", what); }

Options parse(int argc, char** argv) {
  Options o;
  o.client_id = "bot-" + std::to_string(getpid());
  telegrasp::cli::for_each_option(argc, argv, kUsage, usage_error, [&](const std::string& a, const auto& value) {
    if (a == "--client-id") {
      o.client_id = value();
      if (o.client_id.empty() || o.client_id.size() > 64)
        usage_error("--client-id expects 1 to 64 characters, got '" + o.client_id + "'");
    } else if (a == "--hands") {
      const std::string h = value();
      if (h == "right")
        o.hands = {client::HandSide::kRight};
      else if (h == "left")
        o.hands = {client::HandSide::kLeft};
      else if (h == "both")
        o.hands = {client::HandSide::kRight, client::HandSide::kLeft};
      else
        usage_error("--hands expects right, left or both, got '" + h + "'");
    } else if (a == "--skill")
      o.skill = telegrasp::tools::parse_skill(a, value(), usage_error);
    else if (a == "--trials")
      o.trials = static_cast<int>(telegrasp::cli::parse_whole(a, value(), 1, 10000, usage_error));
    else if (a == "--seed")
      o.seed = static_cast<std::uint64_t>(telegrasp::cli::parse_whole(a, value(), 0, 1L << 62, usage_error));
    else if (telegrasp::cli::text_flag(a, value, {{"--objects", &o.objects_dir}, {"--json", &o.json_path}}))
      ;
    else if (telegrasp::idl::parse_network_flag(a, value, o, usage_error))
      ;
    else if (telegrasp::cli::is_flag("telegrasp-bot", a, "--timeout-s", "--timeout"))
      o.timeout_s = telegrasp::cli::parse_number(a, value(), 0.1, 86400, usage_error);
    else {
      return false;
    }
    return true;
  });
  return o;
}

std::atomic<bool> g_stop{false};
extern "C" void on_signal(int) { g_stop = true; }

// Waits up to `timeout` for `ready`, in short steps so that a signal stops the wait.
template <class F>
bool wait_until(F ready, double timeout_s) {
  const auto deadline = Clock::now() + std::chrono::duration<double>(timeout_s);
  while (!g_stop) {
    if (ready()) return true;
    if (Clock::now() >= deadline) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  return false;
}

// The meshes of --objects by name; without it, none (every model comes from the server's
// published geometry, resolve_models). Exits 1 naming the folder or file that does not load.
std::map<std::string, sim::ObjectModelPtr> load_models(const Options& opt) {
  std::map<std::string, sim::ObjectModelPtr> models;
  try {
    if (!opt.objects_dir.empty())
      for (auto& m : sim::load_protocol_object_dir(opt.objects_dir)) models.emplace(m->name, std::move(m));
  } catch (const std::exception& e) {  // MeshLoadError, naming the folder or the file in it
    std::cerr << "telegrasp-bot: --objects " << e.what() << "\n";
    std::exit(telegrasp::cli::kExitFailure);
  }
  return models;
}

// The bot's DDS client, or null after saying why it could not start.
std::unique_ptr<client::Client> connect(const Options& opt) {
  try {
    return std::make_unique<client::Client>(telegrasp::tools::client_options(
        opt, opt.client_id,
        client::kNotices | client::kHandSkeletons | client::kGraspStates | client::kGraspEvents | client::kSceneStates |
            client::kServerStatuses | client::kObjectGeometries));
  } catch (const std::exception& e) {
    std::cerr << "telegrasp-bot: " << e.what() << "\n";
    return nullptr;
  }
}

// Why the server refuses us (ClientNotice): reported as it comes, kept for the exit status.
// Made before the client it listens to, so that it outlives the client's threads.
class Refusals {
 public:
  void listen(const Options& opt, client::Client& c) {
    c.on_notice([this, id = opt.client_id](const client::Notice& n) {
      std::cerr << "telegrasp-bot " << id << ": the server refused our "
                << (n.kind == client::Notice::Kind::kInputRejected ? "controller states" : "scene command") << ": "
                << n.reason << (n.detail.empty() ? "" : " (" + n.detail + ")") << "\n";
      // A dropped input now and then (rate_limited after a stall, a stale sample) costs nothing:
      // only refusals that keep the hands out or refuse a command decide the exit status.
      if (n.kind == client::Notice::Kind::kInputRejected && !fatal_refusal(n)) return;
      std::lock_guard lock(mutex_);
      if (!refusal_ || fatal_refusal(n)) refusal_ = n;
    });
  }
  bool any() const {
    std::lock_guard lock(mutex_);
    return refusal_.has_value();
  }
  bool fatal() const {
    std::lock_guard lock(mutex_);
    return refusal_ && fatal_refusal(*refusal_);
  }

 private:
  mutable std::mutex mutex_;
  std::optional<client::Notice> refusal_;
};

// One loop at 90 Hz steps every hand and publishes its controller, until every trial is done, a
// signal, a fatal refusal or a server silent for --timeout-s; returns the exit status so far. The
// operators' clock (`tick`) runs only while the server's scene state is fresh, so a stalled server
// does not fail trials.
int run_trials(const Options& opt, client::Client& c, Bot& bot, client::SceneState scene, const Refusals& refusals) {
  const auto period = std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(1.0 / kRate));
  const auto stale_after = std::chrono::duration<double>(kStaleScene);
  auto next = Clock::now();
  std::uint64_t last_scene_tick = scene.tick;
  auto last_scene_change = Clock::now();
  bool paused = false;
  for (std::int64_t tick = 0; !bot.all_done();) {
    if (g_stop) return kExitInterrupted;
    if (refusals.fatal()) {
      std::cerr << "telegrasp-bot: the server will not take this bot's hands; stopping\n";
      return kExitRefused;
    }
    if (auto s = c.latest_scene_state(); s && (s->tick != last_scene_tick || s->incarnation != bot.incarnation())) {
      scene = std::move(*s);
      last_scene_tick = scene.tick;
      last_scene_change = Clock::now();
      // A restarted server (the client library noticed its new incarnation): the trials in progress
      // are interrupted, the bot goes on with the new run's scene.
      if (scene.incarnation != bot.incarnation()) bot.server_restarted(scene);
    }
    const auto silent = Clock::now() - last_scene_change;
    if (silent > std::chrono::duration<double>(opt.timeout_s)) {
      std::cerr << "telegrasp-bot: the server sent no scene state for " << opt.timeout_s
                << " s (--timeout-s); stopping\n";
      return telegrasp::cli::kExitFailure;
    }
    if (silent > stale_after) {
      if (!paused) std::cerr << "telegrasp-bot: no scene state from the server for " << kStaleScene << " s; waiting\n";
      paused = true;
      bot.hold();
    } else {
      if (paused) std::cerr << "telegrasp-bot: the server is back\n";
      paused = false;
      bot.tick(tick++, scene);
    }
    next += period;
    const auto now = Clock::now();
    if (now > next + 5 * period) next = now;  // fell behind (a stall): do not burst to catch up
    std::this_thread::sleep_until(next);
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  const Options opt = parse(argc, argv);
  std::map<std::string, sim::ObjectModelPtr> models = load_models(opt);
  if (!opt.json_path.empty() && !std::ofstream(opt.json_path, std::ios::app)) {
    std::cerr << "telegrasp-bot: --json " << opt.json_path << ": cannot write\n";
    return telegrasp::cli::kExitFailure;
  }
  std::vector<std::shared_ptr<const sim::HandRig>> rigs;
  try {  // the rigs first: an installation without them fails before any waiting
    rigs = telegrasp::bot::load_hand_rigs(opt.hands);
  } catch (const std::exception& e) {
    std::cerr << "telegrasp-bot: " << e.what() << "\n";
    return telegrasp::cli::kExitFailure;
  }
  std::signal(SIGINT, on_signal);
  std::signal(SIGTERM, on_signal);
  Refusals refusals;
  const std::unique_ptr<client::Client> c = connect(opt);
  if (!c) return telegrasp::cli::kExitFailure;

  std::cerr << "telegrasp-bot " << opt.client_id << ": waiting for a server on domain " << opt.domain << " (profile "
            << opt.profile << ") ...\n";
  std::optional<client::SceneState> scene;
  const bool found = wait_until([&] { return c->wait_for_server(std::chrono::milliseconds(0)); }, opt.timeout_s) &&
                     wait_until([&] { return (scene = c->latest_scene_state()).has_value(); }, opt.timeout_s);
  if (g_stop) return kExitInterrupted;
  if (!found) {
    std::cerr << "telegrasp-bot: no telegrasp server found on domain " << opt.domain << " with profile " << opt.profile
              << " within " << opt.timeout_s << " s (--timeout-s)\n";
    return telegrasp::cli::kExitFailure;
  }
  // Objects with no local mesh are planned on the geometry the server publishes: wait for it (a
  // server that publishes none leaves the built-in stand-ins).
  wait_until([&] { return telegrasp::bot::geometry_complete(*c, *scene, models); }, std::min(opt.timeout_s, 10.0));
  if (g_stop) return kExitInterrupted;

  refusals.listen(opt, *c);
  Bot bot(opt, *c, telegrasp::bot::resolve_models(*c, *scene, std::move(models)), std::move(rigs));
  if (!bot.set_scene(*scene)) {
    std::cerr << "telegrasp-bot: the server's scene has no objects\n";
    bot.report_results();
    return kExitNotHeld;
  }
  std::cerr << "telegrasp-bot " << opt.client_id << ": " << scene->objects.size() << " objects x " << opt.trials
            << " trial(s), " << opt.hands.size() << " hand(s), skill " << opt.skill << "\n";

  int status = run_trials(opt, *c, bot, std::move(*scene), refusals);
  if (status != 0 && bot.in_progress() > 0)
    std::cerr << "telegrasp-bot: " << bot.in_progress() << " trial(s) in progress not counted\n";
  if (!bot.report_results() && status == 0) status = telegrasp::cli::kExitFailure;
  if (status == 0 && !bot.all_held()) status = kExitNotHeld;
  if ((status == 0 || status == kExitNotHeld) && refusals.any()) status = kExitRefused;
  return status;
}
