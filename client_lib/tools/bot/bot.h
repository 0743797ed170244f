// The bot of telegrasp-bot: the scripted operator of sim/ driving one or two hands of a telegrasp
// server over DDS through telegrasp::client. main.cc parses the options and runs the 90 Hz loop;
// Bot picks objects, runs each hand's trials and records every grasp from the server's GraspEvent.
#pragma once

#include "grasp_report.h"
#include "telegrasp/client/client.h"
#include "telegrasp/sim/hand_rig.h"
#include "telegrasp/sim/object_model.h"
#include "telegrasp/sim/scripted_operator.h"

#include <Eigen/Geometry>
#include <nlohmann/json.hpp>

#include <chrono>
#include <cstdint>
#include <future>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace telegrasp::bot {

namespace client = telegrasp::client;
namespace sim = telegrasp::sim;
namespace report = telegrasp::report;
using Clock = std::chrono::steady_clock;

constexpr double kRate = 90.0;  // controller samples per second per hand
constexpr double kStaleScene = 0.25;  // s without a new SceneState: the server is stalled, wait

// The bot's settings (telegrasp-bot --help).
struct Options {
  std::string client_id;  // default bot-<pid>
  std::vector<client::HandSide> hands{client::HandSide::kRight};
  std::string skill = "experienced", objects_dir, json_path, profile = "loopback", profiles_file;
  std::string scene;  // "": $TELEGRASP_SCENE, else default
  std::vector<std::string> discovery_servers;
  int trials = 1, domain = 0;
  std::uint64_t seed = 1;
  double timeout_s = 20;
};

// The shipped human rig of each hand, in the order given. Throws sim::RigError naming the file if
// one cannot be loaded.
std::vector<std::shared_ptr<const sim::HandRig>> load_hand_rigs(const std::vector<client::HandSide>& hands);

// True once the server's geometry (ObjectGeometry) of every object in `scene` with no model in
// `local` has arrived.
bool geometry_complete(const client::Client& c, const client::SceneState& scene,
                       const std::map<std::string, sim::ObjectModelPtr>& local);

// The models to plan on for the objects of `scene`: the local mesh of that name (--objects) if
// there is one, else a model built from the geometry the server published (once per content
// hash), else the built-in stand-in of that name. Says on stderr which objects are planned on
// received geometry and which on stand-ins.
std::map<std::string, sim::ObjectModelPtr> resolve_models(const client::Client& c, const client::SceneState& scene,
                                                          std::map<std::string, sim::ObjectModelPtr> local);

// A sim model of a received geometry, in the same frame (not recentred). Throws
// sim::MeshLoadError if the geometry carries no mesh or the mesh is unusable.
sim::ObjectModelPtr model_from_geometry(const client::ObjectGeometry& geometry);

// One object of the scene and this bot's trials on it.
struct Target {
  int id = -1;
  std::string name, label;  // label: the table's row name (name, or name#id for duplicates)
  std::size_t scene_index = 0;  // position in the first SceneState: seeds the operator
  sim::ObjectModelPtr model;  // null: this bot has no model of that name
  int started = 0, finished = 0;
  bool given_up = false;
  std::optional<Clock::time_point> unavailable_since;
  // Stillness: the pose the object has stayed near (within kStillMove) and since when (server
  // time), and how far the newest pose is from it.
  std::optional<Eigen::Isometry3d> X_WorldObject_anchor;
  double still_since = 0;
  double moved_m = 0, turned_rad = 0;
};

// A finished trial: the shared record and who did it.
struct BotRecord {
  report::Record record;
  int object_id = -1;
  client::HandSide hand = client::HandSide::kRight;
  std::string reason;  // why it was not held after lift, when known
  int target = -1;  // index in the work list (object ids change when the server restarts)
  // A trial the server's restart cut short ("reason" says so): never a grasp, not counted in the
  // table or the held line, and run again.
  bool interrupted = false;
};

enum class Stage { kIdle, kSettle, kRun, kFinish };

struct Hand {
  client::HandKey key;
  std::shared_ptr<const sim::HandRig> rig;
  Stage stage = Stage::kIdle;
  sim::ControllerInput input;  // what this hand publishes this tick
  // The current trial.
  Target* target = nullptr;
  int trial = 0;
  Eigen::Isometry3d X_WorldStart = Eigen::Isometry3d::Identity();  // where it began, and returns to
  std::unique_ptr<sim::ScriptedOperator> op;
  std::future<void> planning;  // op->begin() runs here so the loop keeps publishing
  // The operator plans on the object's pose when planning began (X_WorldObject_plan); the scene
  // state it then sees is newer. Its palm poses are moved by `correction`, the motion from the
  // planned pose to X_WorldObject_followed: the object's pose followed at a bounded speed before
  // each squeeze, fixed from the squeeze on. A move beyond kReplanMove or kReplanTurn re-plans on
  // the new pose (at most kMaxReplans times).
  Eigen::Isometry3d X_WorldObject_plan = Eigen::Isometry3d::Identity();
  Eigen::Isometry3d X_WorldObject_followed = Eigen::Isometry3d::Identity();
  Eigen::Isometry3d correction = Eigen::Isometry3d::Identity();
  int plans = 0;  // re-plans in all: each operator of the trial gets its own pose errors
  int replans = 0;  // re-plans because the object moved
  int retries = 0;  // re-plans after a round of misses (kRounds)
  int attempts_before = 0;  // attempts of the operators replaced by a re-plan
  bool running = false;  // the trial's operator has run (a re-plan keeps its start time)
  std::int64_t stage_tick = 0, op_tick = 0;
  double server_t0 = 0, z0 = 0, z_max = -1e9;
  bool seen_grasped = false, got_grasp_event = false;
  std::optional<sim::GraspQuality> hold_quality;  // the settled hold's (report::set_hold_quality)
  report::Record rec;
  std::string note;
  // When this hand, and each other client's hand, was first near the target (server time of the
  // skeleton), before our squeeze: every bot sees the same skeletons, so they agree who came first.
  std::optional<double> near_time;
  std::map<client::HandKey, double> others_near_time;

  /// Done with its target (finished, left to another hand or cut short): idle, and back where it
  /// started, clear of the object, so that other people's hands may take it.
  void leave_target() {
    target = nullptr;
    op.reset();
    stage = Stage::kIdle;
    input = {};
    input.X_WorldPalm = X_WorldStart;
  }
};

// The bot's hands, its work list (every object of the first SceneState, --trials times) and its
// records. One thread calls everything.
class Bot {
 public:
  /// `rigs`: load_hand_rigs(opt.hands).
  Bot(Options opt, client::Client& c, std::map<std::string, sim::ObjectModelPtr> models,
      std::vector<std::shared_ptr<const sim::HandRig>> rigs);

  // Takes the scene's objects as the work list; false if the scene is empty.
  bool set_scene(const client::SceneState& scene);

  // The incarnation of the server run the bot works with (SceneState::incarnation).
  std::uint64_t incarnation() const { return incarnation_; }
  // The server restarted (a new incarnation; `scene` is its first SceneState): every trial in
  // progress ends, recorded as interrupted and run again later; the work list's objects are
  // found again in the new scene by name (the k-th object of a name is the k-th again); grasp
  // events of the old run are ignored from now on.
  void server_restarted(const client::SceneState& scene);
  // Trials the restarts interrupted.
  int interrupted() const;

  // One tick of every hand: reads the newest server outputs, steps each hand, publishes.
  void tick(std::int64_t tick, const client::SceneState& scene);

  // While the server is silent: every hand keeps its last input, the operators and the clocks of
  // unavailable objects wait.
  void hold();

  void publish();

  bool all_done() const;

  // The trials in progress (not counted when stopped early).
  int in_progress() const;

  // Prints the table, the JSON summary line and the held line (on stdout, and the held line on
  // stderr too); writes --json. False if the file cannot be written.
  bool report_results() const;

  // Every object held after the lift in every one of its trials (and at least one trial done).
  bool all_held() const;

  // The event_id of every GraspEvent received (every hand's, in arrival order).
  const std::vector<std::uint64_t>& grasp_event_ids() const { return event_ids_; }
  // {"received", "first", "last", "missing" (ids between first and last never received),
  // "duplicates" (ids received more than once)}: GraspEvent is reliable, so both lists stay empty.
  nlohmann::json grasp_event_ids_json() const;

 private:
  Hand* hand_of(const client::HandKey& key);

  bool targeted(const Target& t) const;

  void on_event(const client::GraspEvent& e);

  // Starts or stops each untargeted object's unavailability clock; gives up after kGiveUpAfter.
  void update_availability(const std::map<int, const client::ObjectState*>& objects);

  // Records every remaining trial of `t` as not grasped.
  void give_up(Target& t, const std::string& why);

  void add_record(BotRecord r);

  // The next object for `h`: fewest trials started first, then the seeded order.
  Target* pick(const std::map<int, const client::ObjectState*>& objects);

  bool holds_target(const Hand& h, const client::ObjectState* o) const;

  void step(Hand& h, std::int64_t tick, const client::SceneState& scene,
            const std::map<int, const client::ObjectState*>& objects);

  // Before its squeeze a hand gives the object up, as a person would, to a hand that holds it, or
  // came near it first, or came at the same time with a greater key (so exactly one of two goes on).
  // Returns the hand it gives way to, if any.
  std::optional<client::HandKey> yields_to(Hand& h, const client::ObjectState* o);

  void start_trial(Hand& h, Target& t, std::int64_t tick, const client::ObjectState& o);

  // Starts h's operator planning (asynchronously) on the object at X_WorldObject, the hand at X_WorldPalm.
  void begin_operator(Hand& h, const Eigen::Isometry3d& X_WorldObject, const Eigen::Isometry3d& X_WorldPalm);

  // Plans h's trial again on the object's pose now (it moved far since the plan, or a round of
  // attempts missed), from where the hand is, keeping the trial's attempts and start time.
  void replan(Hand& h, const client::ObjectState& o, const std::string& why);

  // Drops the current trial without counting it: `other` has the object, or came for it first.
  void abandon(Hand& h, const client::HandKey& other);

  void finish_trial(Hand& h);

  Options opt_;
  client::Client& client_;
  std::map<std::string, sim::ObjectModelPtr> models_;
  sim::OperatorSkill skill_;
  std::vector<Hand> hands_;
  std::vector<Target> targets_;
  std::vector<std::size_t> order_;
  std::vector<client::HandSkeleton> others_, own_;  // other clients' hands and ours, this tick
  double server_time_ = 0;  // of the newest scene state
  std::uint64_t incarnation_ = 0;
  std::vector<BotRecord> records_;
  std::vector<std::uint64_t> event_ids_;
  int total_ = 0, done_ = 0;
};

}  // namespace telegrasp::bot
