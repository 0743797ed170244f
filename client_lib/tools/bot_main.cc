// telegrasp-bot: the scripted operator of sim/ driving one or two hands of a telegrasp server
// over DDS. It grasps every object of the server's scene --trials times, records each grasp
// from the server's GraspEvent, and prints the same table and JSON records as telegrasp-eval.
#include "cli.h"
#include "grasp_report.h"
#include "telegrasp/client/client.h"
#include "telegrasp/sim/hand_rig.h"
#include "telegrasp/sim/object_model.h"
#include "telegrasp/sim/scripted_operator.h"
#include "telegrasp/sim/standin_objects.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <csignal>
#include <cstdint>
#include <cstdio>
#include <fstream>
#include <future>
#include <iostream>
#include <map>
#include <memory>
#include <optional>
#include <random>
#include <set>
#include <string>
#include <thread>
#include <vector>

#include <unistd.h>

namespace {

namespace client = telegrasp::client;
namespace sim = telegrasp::sim;
namespace report = telegrasp::report;
using nlohmann::json;
using Clock = std::chrono::steady_clock;

constexpr const char* kUsage = R"(Usage: telegrasp-bot [options]

The scripted operator of telegrasp-eval driving one or two hands of a telegrasp server over DDS.
Each hand picks a free object from the server's SceneState (resting on the table, held by
nobody, no other client's hand at it), appears 30 cm from it, reaches, grasps, lifts 10 cm,
holds 1 s and releases, publishing its controller at 90 Hz. Every object in the scene (as the
bot first sees it) is grasped --trials times; each grasp is recorded from the server's
GraspEvent. A hand leaves an object to another client's hand that got there first; an object
unavailable for 10 s is given up (recorded as not grasped, with the reason). Progress goes to
stderr (one line per trial), then the per-object table of telegrasp-eval goes to stdout.

Options:
  --client-id ID      names this bot's hands on the server (default bot-<pid>)
  --hands H           right | left | both (default right)
  --skill NAME        perfect | experienced | inexperienced (default experienced)
  --trials N          grasps per object in the scene (default 1)
  --seed S            random seed: object order and operator noise (default 1)
  --objects DIR       the server's mesh folder, to know each object's geometry (default: the
                      30 built-in stand-ins)
  --json FILE         write every grasp record as telegrasp-eval does, plus "client_id",
                      "hand", "object_id" and "reason" ("mode" and "speed_scale" are null: they
                      are the server's settings)
  --domain N          DDS domain, 0..232 (default 0)
  --profile NAME      Fast DDS participant profile: loopback (default), lan, wan
  --profiles FILE     Fast DDS XML profiles (default: $TELEGRASP_PROFILES, else the shipped file)
  --timeout S         give up when no server is found (or it goes silent) for S seconds
                      (default 20)
  -h, --help          this text

Exit status: 0 when every trial is done, 1 if no server was found or it went silent,
2 for a bad option, 130 when stopped by SIGINT or SIGTERM (the table shows the trials done).
)";

constexpr double kRate = 90.0;                 // controller samples per second per hand
constexpr double kTrialLimit = 30.0;           // s of operator time before a trial is cut short
constexpr double kSettleTime = 0.2;            // s at the start pose before the operator starts
constexpr double kFinishLimit = 2.0;           // s to wait for the release (and grasp event) after a trial
constexpr double kGiveUpAfter = 10.0;          // s an object may be unavailable before it is given up
constexpr double kRestingSpeed = 0.01;         // m/s: slower objects may be resting ...
constexpr double kStillTime = 0.3;             // s: ... once their pose has not changed for this long
constexpr double kStillMove = 1e-4;            // m, rad: pose changes below this between scene states are none
constexpr double kOnTableZ = -0.05;            // m: an object below this fell off the table
constexpr double kNearObject = 0.15;           // m: a palm this close to an object's centre is working on it
constexpr double kSameTime = 0.05;             // s of server time: two hands arriving this close together tie
constexpr double kStaleScene = 0.25;           // s without a new SceneState: the server is stalled, wait

struct Options {
  std::string client_id = "bot-" + std::to_string(getpid());
  std::vector<client::HandSide> hands{client::HandSide::kRight};
  std::string skill = "experienced", objects_dir, json_path, profile = "loopback", profiles_file;
  int trials = 1, domain = 0;
  std::uint64_t seed = 1;
  double timeout_s = 20;
};

[[noreturn]] void usage_error(const std::string& what) {
  std::cerr << "telegrasp-bot: " << what << "\n(see telegrasp-bot --help)\n";
  std::exit(2);
}

Options parse(int argc, char** argv) {
  Options o;
  telegrasp::cli::for_each_option(argc, argv, kUsage, usage_error, [&](const std::string& a, const auto& value) {
    if (a == "--client-id") {
      o.client_id = value();
      if (o.client_id.empty() || o.client_id.size() > 64) usage_error("--client-id expects 1 to 64 characters, got '" + o.client_id + "'");
    } else if (a == "--hands") {
      const std::string h = value();
      if (h == "right") o.hands = {client::HandSide::kRight};
      else if (h == "left") o.hands = {client::HandSide::kLeft};
      else if (h == "both") o.hands = {client::HandSide::kRight, client::HandSide::kLeft};
      else usage_error("--hands expects right, left or both, got '" + h + "'");
    } else if (a == "--skill") {
      o.skill = value();
      try {
        sim::skill_profile(o.skill);
      } catch (const std::exception&) {
        usage_error("--skill expects perfect, experienced or inexperienced, got '" + o.skill + "'");
      }
    }
    else if (a == "--trials") o.trials = static_cast<int>(telegrasp::cli::parse_whole(a, value(), 1, 10000, usage_error));
    else if (a == "--seed") o.seed = static_cast<std::uint64_t>(telegrasp::cli::parse_whole(a, value(), 0, 1L << 62, usage_error));
    else if (a == "--objects") o.objects_dir = value();
    else if (a == "--json") o.json_path = value();
    else if (a == "--domain") o.domain = static_cast<int>(telegrasp::cli::parse_whole(a, value(), 0, 232, usage_error));
    else if (a == "--profile") o.profile = value();
    else if (a == "--profiles") o.profiles_file = value();
    else if (a == "--timeout") {
      const std::string v = value();
      char* end = nullptr;
      o.timeout_s = std::strtod(v.c_str(), &end);
      if (v.empty() || *end != '\0' || !(o.timeout_s > 0) || o.timeout_s > 86400)
        usage_error("--timeout expects seconds in (0, 86400], got '" + v + "'");
    } else {
      return false;
    }
    return true;
  });
  return o;
}

std::atomic<bool> g_stop{false};
extern "C" void on_signal(int) { g_stop = true; }

// One object of the scene and this bot's trials on it.
struct Target {
  int id = -1;
  std::string name, label;     // label: the table's row name (name, or name#id for duplicates)
  std::size_t scene_index = 0; // position in the first SceneState: seeds the operator
  sim::ObjectModelPtr model;   // null: this bot has no model of that name
  int started = 0, finished = 0;
  bool given_up = false;
  std::optional<Clock::time_point> unavailable_since;
  // Stillness: the last pose seen and since when (server time) it has not changed.
  std::optional<Eigen::Isometry3d> X_WorldObject_last;
  double still_since = 0;
};

// A finished trial: the shared record and who did it.
struct BotRecord {
  report::Record record;
  int object_id = -1;
  client::HandSide hand = client::HandSide::kRight;
  std::string reason;  // why it was not held after lift, when known
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
  std::int64_t stage_tick = 0, op_tick = 0;
  double server_t0 = 0, z0 = 0, z_max = -1e9;
  bool seen_grasped = false, got_grasp_event = false;
  report::Record rec;
  std::string note;
  // When this hand, and each other client's hand, was first near the target (server time of the
  // skeleton), before our squeeze: every bot sees the same skeletons, so they agree who came first.
  std::optional<double> near_time;
  std::map<client::HandKey, double> others_near_time;
};

const char* side_name(client::HandSide s) { return s == client::HandSide::kRight ? "right" : "left"; }

std::string hand_name(const client::HandKey& k) { return k.client_id + " " + side_name(k.side); }

// Live hands of other clients whose palm is near `o`.
std::vector<client::HandKey> hands_near(const client::ObjectState& o, const std::vector<client::HandSkeleton>& others) {
  std::vector<client::HandKey> out;
  for (const auto& s : others)
    if (!s.frozen && (s.X_WorldPalm.translation() - o.X_WorldObject.translation()).norm() < kNearObject) out.push_back(s.hand);
  return out;
}

// Follows whether `t`'s object is still: a grasp is planned on a resting object only.
void track_stillness(Target& t, const client::ObjectState* o, double server_time) {
  if (!o) return;
  const Eigen::Isometry3d& X = o->X_WorldObject;
  const bool same = t.X_WorldObject_last &&
                    (X.translation() - t.X_WorldObject_last->translation()).norm() < kStillMove &&
                    Eigen::AngleAxisd(X.linear() * t.X_WorldObject_last->linear().transpose()).angle() < kStillMove;
  if (!same || o->v_WorldObject.norm() > kRestingSpeed) t.still_since = server_time;
  t.X_WorldObject_last = X;
}

// Why an object cannot be started now ("" if it can).
std::string why_unavailable(const Target& t, const client::ObjectState* o, const std::vector<client::HandSkeleton>& others,
                            double server_time) {
  if (!o) return "removed from the scene";
  if (o->held) return "held by " + hand_name(o->holder);
  if (const auto near = hands_near(*o, others); !near.empty()) return "being worked on by " + hand_name(near.front());
  const double z = o->X_WorldObject.translation().z();
  if (z < kOnTableZ) return "off the table (z " + report::fmt(z, 2) + " m)";
  if (server_time - t.still_since < kStillTime) return "moving (" + report::fmt(o->v_WorldObject.norm(), 2) + " m/s)";
  return "";
}

class Bot {
 public:
  Bot(Options opt, client::Client& c, std::map<std::string, sim::ObjectModelPtr> models)
      : opt_(std::move(opt)), client_(c), models_(std::move(models)), skill_(sim::skill_profile(opt_.skill)) {
    for (client::HandSide side : opt_.hands) {
      Hand h;
      h.key = {client_.client_id(), side};
      h.rig = std::make_shared<const sim::HandRig>(
          sim::HandRig::load(sim::HandRig::builtin_path(side == client::HandSide::kRight ? "human_right" : "human_left")));
      h.input.X_WorldPalm.translation() = Eigen::Vector3d(0.0, side == client::HandSide::kRight ? -0.3 : 0.3, 0.3);
      hands_.push_back(std::move(h));
    }
  }

  // Takes the scene's objects as the work list; false if the scene is empty.
  bool set_scene(const client::SceneState& scene) {
    std::map<std::string, int> count;
    for (const auto& o : scene.objects) ++count[o.name];
    std::set<std::string> unknown;
    for (std::size_t i = 0; i < scene.objects.size(); ++i) {
      const client::ObjectState& o = scene.objects[i];
      Target t;
      t.id = o.id;
      t.name = o.name;
      t.label = count[o.name] > 1 ? o.name + "#" + std::to_string(o.id) : o.name;
      t.scene_index = i;
      if (auto it = models_.find(o.name); it != models_.end()) t.model = it->second;
      else unknown.insert(o.name);
      targets_.push_back(std::move(t));
    }
    if (!unknown.empty()) {
      std::cerr << "telegrasp-bot: no model for " << unknown.size() << " scene object(s) (" << *unknown.begin()
                << (unknown.size() > 1 ? ", ..." : "") << "); pass the server's --objects DIR. They are recorded as not grasped.\n";
    }
    // A fixed order from the seed; each hand takes the first free object with the fewest trials started.
    order_.resize(targets_.size());
    for (std::size_t i = 0; i < order_.size(); ++i) order_[i] = i;
    std::mt19937_64 rng(opt_.seed);
    std::shuffle(order_.begin(), order_.end(), rng);
    total_ = static_cast<int>(targets_.size()) * opt_.trials;
    for (Target& t : targets_)
      if (!t.model) give_up(t, "no model named '" + t.name + "' (pass the server's --objects DIR)");
    return !targets_.empty();
  }

  // One tick of every hand: reads the newest server outputs, steps each hand, publishes.
  void tick(std::int64_t tick, const client::SceneState& scene) {
    std::map<int, const client::ObjectState*> objects;
    for (const auto& o : scene.objects) objects[o.id] = &o;
    for (const client::GraspEvent& e : client_.take_grasp_events()) on_event(e);
    others_.clear();
    own_.clear();
    for (client::HandSkeleton& s : client_.latest_hand_skeletons())
      (s.hand.client_id == client_.client_id() ? own_ : others_).push_back(std::move(s));
    server_time_ = scene.time;
    for (Target& t : targets_) {
      auto it = objects.find(t.id);
      track_stillness(t, it == objects.end() ? nullptr : it->second, scene.time);
    }
    update_availability(objects);
    for (Hand& h : hands_) step(h, tick, scene, objects);
    publish();
  }

  // While the server is silent: every hand keeps its last input, the operators and the clocks of
  // unavailable objects wait.
  void hold() {
    for (Target& t : targets_) t.unavailable_since.reset();
    publish();
  }

  void publish() {
    for (const Hand& h : hands_) {
      client::ControllerSample s;
      s.side = h.key.side;
      s.X_WorldPalm = h.input.X_WorldPalm;
      s.trigger = h.input.trigger;
      if (h.input.curls.size() == 5) s.curls = h.input.curls;
      s.tracking_valid = h.input.tracking_valid;
      client_.publish(s);
    }
  }

  bool all_done() const {
    for (const Target& t : targets_)
      if (t.finished < opt_.trials) return false;
    return true;
  }

  // The trials in progress (not counted when stopped early).
  int in_progress() const {
    int n = 0;
    for (const Hand& h : hands_) n += h.stage != Stage::kIdle;
    return n;
  }

  // Prints the table and the summary line; writes --json. False if the file cannot be written.
  bool report_results() const {
    std::string hands;
    for (const Hand& h : hands_) hands += (hands.empty() ? "" : "+") + std::string(side_name(h.key.side));
    std::cout << "\n== bot " << opt_.client_id << ", hands " << hands << ", skill " << opt_.skill << " ==\n";
    std::vector<report::ObjectRows> rows;
    std::vector<const report::Record*> all;
    for (const Target& t : targets_) {
      report::ObjectRows row{t.label, {}};
      for (const BotRecord& r : records_)
        if (r.object_id == t.id) row.records.push_back(&r.record);
      all.insert(all.end(), row.records.begin(), row.records.end());
      rows.push_back(std::move(row));
    }
    report::print_object_table(rows);
    json s = report::summarize(all);
    s["skill"] = opt_.skill;
    s["client_id"] = opt_.client_id;
    s["hands"] = hands;
    std::cout << "summary: " << s.dump() << "\n" << std::flush;
    if (opt_.json_path.empty()) return true;
    json grasps = json::array();
    for (const BotRecord& r : records_) {
      json g = report::record_json(r.record);
      g["client_id"] = opt_.client_id;
      g["hand"] = side_name(r.hand);
      g["object_id"] = r.object_id;
      g["reason"] = r.reason.empty() ? json(nullptr) : json(r.reason);
      grasps.push_back(std::move(g));
    }
    std::ofstream out(opt_.json_path);
    out << json{{"grasps", grasps}, {"summary", s}, {"summaries", json::array({s})}}.dump(1) << "\n";
    if (!out.flush()) {
      std::cerr << "telegrasp-bot: cannot write --json file " << opt_.json_path << "\n";
      return false;
    }
    std::cerr << "wrote " << opt_.json_path << "\n";
    return true;
  }

 private:
  Hand* hand_of(const client::HandKey& key) {
    for (Hand& h : hands_)
      if (h.key == key) return &h;
    return nullptr;
  }

  bool targeted(const Target& t) const {
    for (const Hand& h : hands_)
      if (h.target == &t) return true;
    return false;
  }

  void on_event(const client::GraspEvent& e) {
    Hand* h = hand_of(e.hand);
    if (!h || e.kind != client::GraspEvent::Kind::kGrasp) return;
    if (!h->target || e.object_id != h->target->id || h->stage == Stage::kIdle || h->stage == Stage::kSettle) {
      std::cerr << "telegrasp-bot: " << side_name(h->key.side) << " hand grasped " << e.object_name << " (id " << e.object_id
                << "), not its target\n";
      return;
    }
    if (h->got_grasp_event) return;  // a later attempt's grasp: the first one is the trial's
    h->got_grasp_event = true;
    report::Record& r = h->rec;
    r.grasped = true;
    r.time_to_grasp_s = e.time - h->server_t0;
    r.hand_error_mm = r.grasp_tick_hand_error_mm = e.hand_error_mm;
    r.capsules.clear();
    for (const client::CapsuleReport& c : e.capsules)
      r.capsules.push_back({c.phalanx_name, c.hit, c.blocked, 1000 * c.nd, 1000 * c.signed_distance});
    r.grasp_tick_capsules = r.capsules;
  }

  // Starts or stops each untargeted object's unavailability clock; gives up after kGiveUpAfter.
  void update_availability(const std::map<int, const client::ObjectState*>& objects) {
    const auto now = Clock::now();
    for (Target& t : targets_) {
      if (t.given_up || t.started >= opt_.trials || targeted(t)) continue;
      auto it = objects.find(t.id);
      const std::string why = why_unavailable(t, it == objects.end() ? nullptr : it->second, others_, server_time_);
      if (why.empty()) {
        t.unavailable_since.reset();
        continue;
      }
      if (!t.unavailable_since) t.unavailable_since = now;
      if (now - *t.unavailable_since > std::chrono::duration<double>(kGiveUpAfter))
        give_up(t, "unavailable for " + report::fmt(kGiveUpAfter, 0) + " s: " + why);
    }
  }

  // Records every remaining trial of `t` as not grasped.
  void give_up(Target& t, const std::string& why) {
    t.given_up = true;
    for (; t.started < opt_.trials; ++t.started, ++t.finished) {
      BotRecord r;
      r.record.object = t.name;
      r.record.trial = t.started;
      r.object_id = t.id;
      r.hand = hands_.front().key.side;
      r.reason = why;
      add_record(std::move(r));
    }
  }

  void add_record(BotRecord r) {
    ++done_;
    const report::Record& rec = r.record;
    std::cerr << "[" << done_ << "/" << total_ << "] " << side_name(r.hand) << " " << rec.object << " trial " << rec.trial
              << (rec.held_after_lift ? " held" : " NOT held");
    if (rec.grasped) std::cerr << " (grasp " << report::fmt(rec.time_to_grasp_s) << " s, HandError " << report::fmt(rec.hand_error_mm, 1) << " mm)";
    if (!r.reason.empty()) std::cerr << ": " << r.reason;
    std::cerr << "\n";
    records_.push_back(std::move(r));
  }

  // The next object for `h`: fewest trials started first, then the seeded order.
  Target* pick(const std::map<int, const client::ObjectState*>& objects) {
    Target* best = nullptr;
    for (std::size_t i : order_) {
      Target& t = targets_[i];
      if (t.given_up || t.started >= opt_.trials || targeted(t)) continue;
      auto it = objects.find(t.id);
      if (!why_unavailable(t, it == objects.end() ? nullptr : it->second, others_, server_time_).empty()) continue;
      if (!best || t.started < best->started) best = &t;
    }
    return best;
  }

  bool holds_target(const Hand& h, const client::ObjectState* o) const {
    if (o && o->held && o->holder == h.key) return true;
    const auto gs = client_.latest_grasp_state(h.key);
    return gs && gs->grasped_object == h.target->id;
  }

  void step(Hand& h, std::int64_t tick, const client::SceneState& scene, const std::map<int, const client::ObjectState*>& objects) {
    const double dt = 1.0 / kRate;
    if (h.stage == Stage::kIdle) {
      Target* t = pick(objects);
      if (!t) return;
      start_trial(h, *t, tick, *objects.at(t->id));
    }
    auto it = objects.find(h.target->id);
    const client::ObjectState* o = it == objects.end() ? nullptr : it->second;
    if (h.stage == Stage::kSettle) {
      if (const auto other = yields_to(h, o)) {
        h.planning.wait();
        abandon(h, *other);
        return;
      }
      const bool planned = h.planning.wait_for(std::chrono::seconds(0)) == std::future_status::ready;
      if (!planned || (tick - h.stage_tick) * dt < kSettleTime) return;
      try {
        h.planning.get();
      } catch (const std::exception& e) {
        h.note = std::string("planning failed: ") + e.what();
        finish_trial(h);
        return;
      }
      h.stage = Stage::kRun;
      h.op_tick = tick;
      h.server_t0 = scene.time;
      h.z0 = o ? o->X_WorldObject.translation().z() : 0;
    }
    if (h.stage == Stage::kRun) {
      const bool grasped = holds_target(h, o);
      h.seen_grasped |= grasped;
      const double t_op = static_cast<double>(tick - h.op_tick) * dt;
      const sim::OperatorPhase phase_before = h.op->phase();
      if (phase_before == sim::OperatorPhase::kReact || phase_before == sim::OperatorPhase::kReach) {
        if (const auto other = yields_to(h, o)) {
          abandon(h, *other);
          return;
        }
      }
      if (!o) h.note = "removed from the scene during the trial";
      else if (h.seen_grasped && !grasped && o->held && !(o->holder == h.key)) h.note = "taken by " + hand_name(o->holder);
      h.input = h.op->next(t_op, grasped);
      if (h.op->phase() == sim::OperatorPhase::kHold && o) h.z_max = std::max(h.z_max, o->X_WorldObject.translation().z());
      if (h.op->done() || t_op > kTrialLimit) {
        if (!h.op->done()) h.note = "cut short after " + report::fmt(kTrialLimit, 0) + " s";
        h.input.trigger = 0;
        h.input.curls.clear();
        h.stage = Stage::kFinish;
        h.stage_tick = tick;
      }
      return;
    }
    if (h.stage == Stage::kFinish) {
      // Open hand, still; wait until the server has released the object and sent the grasp event.
      const bool released = !holds_target(h, o);
      const bool event_in = h.got_grasp_event || !h.seen_grasped;
      if ((released && event_in) || (tick - h.stage_tick) * dt > kFinishLimit) finish_trial(h);
    }
  }

  // Before its squeeze a hand gives the object up, as a person would, to a hand that holds it, or
  // came near it first, or came at the same time with a greater key (so exactly one of two goes on).
  // Returns the hand it gives way to, if any.
  std::optional<client::HandKey> yields_to(Hand& h, const client::ObjectState* o) {
    if (!o) return std::nullopt;
    if (o->held && !(o->holder == h.key)) return o->holder;
    for (const client::HandSkeleton& s : own_)
      if (s.hand == h.key && !h.near_time && (s.X_WorldPalm.translation() - o->X_WorldObject.translation()).norm() < kNearObject)
        h.near_time = s.time;
    for (const client::HandSkeleton& s : others_) {
      if (s.frozen || (s.X_WorldPalm.translation() - o->X_WorldObject.translation()).norm() >= kNearObject) continue;
      const double since = h.others_near_time.try_emplace(s.hand, s.time).first->second;
      if (!h.near_time || since < *h.near_time - kSameTime) return s.hand;
      if (since <= *h.near_time + kSameTime && h.key < s.hand) return s.hand;
    }
    return std::nullopt;
  }

  void start_trial(Hand& h, Target& t, std::int64_t tick, const client::ObjectState& o) {
    const double side = h.key.side == client::HandSide::kRight ? 1.0 : -1.0;
    h.target = &t;
    h.trial = t.started++;
    h.stage = Stage::kSettle;
    h.stage_tick = tick;
    h.seen_grasped = h.got_grasp_event = false;
    h.near_time.reset();
    h.others_near_time.clear();
    h.z_max = -1e9;
    h.note.clear();
    h.rec = {};
    h.rec.object = t.name;
    h.rec.trial = h.trial;
    // The start pose: 30 cm from the object, palm down (as telegrasp-eval starts).
    Eigen::Isometry3d X_WorldStart = Eigen::Isometry3d::Identity();
    X_WorldStart.translation() = o.X_WorldObject.translation() + Eigen::Vector3d(-0.3, -0.2 * side, 0.25);
    h.X_WorldStart = X_WorldStart;
    h.input = {};
    h.input.X_WorldPalm = X_WorldStart;
    // The operator's noise depends on the object and trial only, as in telegrasp-eval.
    const std::uint64_t seed = opt_.seed * 1000003ULL + t.scene_index * 1009ULL + static_cast<std::uint64_t>(h.trial);
    h.op = std::make_unique<sim::ScriptedOperator>(h.rig, skill_, seed, sim::GraspSettings{}, 1.0 / kRate);
    sim::ScriptedOperator* op = h.op.get();
    h.planning = std::async(std::launch::async, [op, model = t.model, X_WorldObject = o.X_WorldObject, X_WorldStart] {
      op->begin(*model, X_WorldObject, X_WorldStart, 0.0);
    });
  }

  // Drops the current trial without counting it: `other` has the object, or came for it first.
  void abandon(Hand& h, const client::HandKey& other) {
    std::cerr << side_name(h.key.side) << " hand leaves " << h.target->label << " to " << hand_name(other) << " for now\n";
    --h.target->started;
    h.target = nullptr;
    h.op.reset();
    h.stage = Stage::kIdle;
    h.input = {};
    h.input.X_WorldPalm = h.X_WorldStart;
  }

  void finish_trial(Hand& h) {
    BotRecord r;
    r.record = std::move(h.rec);
    r.record.attempts = h.op->attempts();
    r.record.held_after_lift = h.op->held_after_lift() && h.z_max - h.z0 > 0.8 * sim::ScriptedOperator::kLiftHeight;
    r.object_id = h.target->id;
    r.hand = h.key.side;
    r.reason = h.note;
    if (r.reason.empty() && !r.record.held_after_lift) {
      if (!h.seen_grasped) r.reason = "not grasped in " + std::to_string(r.record.attempts) + " attempt(s)";
      else if (!h.op->held_after_lift()) r.reason = "dropped during the lift or hold";
      else r.reason = "rose only " + report::fmt(1000 * (h.z_max - h.z0), 0) + " mm";
    }
    if (h.seen_grasped && !h.got_grasp_event && r.reason.empty()) r.reason = "no grasp event received";
    ++h.target->finished;
    h.target = nullptr;
    h.op.reset();
    h.stage = Stage::kIdle;
    // Back to where it started, clear of the object, so that other people's hands may take it.
    h.input = {};
    h.input.X_WorldPalm = h.X_WorldStart;
    add_record(std::move(r));
  }

  Options opt_;
  client::Client& client_;
  std::map<std::string, sim::ObjectModelPtr> models_;
  sim::OperatorSkill skill_;
  std::vector<Hand> hands_;
  std::vector<Target> targets_;
  std::vector<std::size_t> order_;
  std::vector<client::HandSkeleton> others_, own_;  // other clients' hands and ours, this tick
  double server_time_ = 0;                          // of the newest scene state
  std::vector<BotRecord> records_;
  int total_ = 0, done_ = 0;
};

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

}  // namespace

int main(int argc, char** argv) {
  const Options opt = parse(argc, argv);
  std::map<std::string, sim::ObjectModelPtr> models;
  try {
    if (opt.objects_dir.empty()) {
      for (const auto& o : sim::protocol_objects()) models.emplace(o.name, sim::make_standin_model(o));
    } else {
      for (auto& m : sim::load_protocol_object_dir(opt.objects_dir)) models.emplace(m->name, std::move(m));
    }
  } catch (const std::exception& e) {
    std::cerr << "telegrasp-bot: --objects " << opt.objects_dir << ": " << e.what() << "\n";
    return 2;
  }
  if (!opt.json_path.empty() && !std::ofstream(opt.json_path, std::ios::app)) {
    std::cerr << "telegrasp-bot: cannot write --json file " << opt.json_path << "\n";
    return 2;
  }

  std::signal(SIGINT, on_signal);
  std::signal(SIGTERM, on_signal);

  client::ClientOptions copt;
  copt.client_id = opt.client_id;
  copt.domain = opt.domain;
  copt.profile = opt.profile;
  copt.profiles_file = opt.profiles_file;
  copt.topics = client::kHandSkeletons | client::kGraspStates | client::kGraspEvents | client::kSceneStates | client::kServerStatuses;
  std::unique_ptr<client::Client> c;
  try {
    c = std::make_unique<client::Client>(copt);
  } catch (const std::exception& e) {
    std::cerr << "telegrasp-bot: " << e.what() << "\n";
    return 2;
  }

  std::cerr << "telegrasp-bot " << opt.client_id << ": waiting for a server on domain " << opt.domain << " (profile "
            << opt.profile << ") ...\n";
  std::optional<client::SceneState> scene;
  const bool found = wait_until([&] { return c->wait_for_server(std::chrono::milliseconds(0)); }, opt.timeout_s) &&
                     wait_until([&] { return (scene = c->latest_scene_state()).has_value(); }, opt.timeout_s);
  if (g_stop) return 130;
  if (!found) {
    std::cerr << "telegrasp-bot: no telegrasp server found on domain " << opt.domain << " with profile " << opt.profile
              << " within " << opt.timeout_s << " s (--timeout)\n";
    return 1;
  }

  Bot bot(opt, *c, std::move(models));
  if (!bot.set_scene(*scene)) {
    std::cerr << "telegrasp-bot: the server's scene has no objects\n";
    bot.report_results();
    return 0;
  }
  std::cerr << "telegrasp-bot " << opt.client_id << ": " << scene->objects.size() << " objects x " << opt.trials
            << " trial(s), " << opt.hands.size() << " hand(s), skill " << opt.skill << "\n";

  // One loop at 90 Hz steps every hand and publishes its controller. The operators' clock (`tick`)
  // runs only while the server's scene state is fresh, so a stalled server does not fail trials.
  const auto period = std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(1.0 / kRate));
  const auto stale_after = std::chrono::duration<double>(kStaleScene);
  auto next = Clock::now();
  std::uint64_t last_scene_tick = scene->tick;
  auto last_scene_change = Clock::now();
  bool paused = false;
  int status = 0;
  for (std::int64_t tick = 0; !bot.all_done();) {
    if (g_stop) { status = 130; break; }
    if (auto s = c->latest_scene_state(); s && s->tick != last_scene_tick) {
      scene = std::move(s);
      last_scene_tick = scene->tick;
      last_scene_change = Clock::now();
    }
    const auto silent = Clock::now() - last_scene_change;
    if (silent > std::chrono::duration<double>(opt.timeout_s)) {
      std::cerr << "telegrasp-bot: the server sent no scene state for " << opt.timeout_s << " s (--timeout); stopping\n";
      status = 1;
      break;
    }
    if (silent > stale_after) {
      if (!paused) std::cerr << "telegrasp-bot: no scene state from the server for " << kStaleScene << " s; waiting\n";
      paused = true;
      bot.hold();
    } else {
      if (paused) std::cerr << "telegrasp-bot: the server is back\n";
      paused = false;
      bot.tick(tick++, *scene);
    }
    next += period;
    const auto now = Clock::now();
    if (now > next + 5 * period) next = now;  // fell behind (a stall): do not burst to catch up
    std::this_thread::sleep_until(next);
  }
  if (status != 0 && bot.in_progress() > 0)
    std::cerr << "telegrasp-bot: " << bot.in_progress() << " trial(s) in progress not counted\n";
  if (!bot.report_results() && status == 0) status = 1;
  return status;
}
