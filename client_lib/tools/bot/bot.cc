// The bot's object choice, trials and records (bot.h).
#include "bot.h"

#include "telegrasp/idl/cli.h"
#include "grasp_event_record.h"
#include "telegrasp/sim/mesh_loading.h"
#include "telegrasp/sim/standin_objects.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <random>
#include <set>

namespace telegrasp::bot {

using nlohmann::json;

namespace {

constexpr double kTrialLimit = 30.0;  // s of operator time before a trial is cut short
constexpr double kSettleTime = 0.2;  // s at the start pose before the operator starts
constexpr double kFinishLimit = 2.0;  // s to wait for the release after a trial
// s to wait for a grasp event the server sent (the hand was seen holding): GraspEvent is reliable,
// so under packet loss it comes late rather than never; the trial's record needs its metrics.
constexpr double kEventWait = 10.0;
constexpr double kGiveUpAfter = 10.0;  // s an object may be unavailable before it is given up
constexpr double kRestingSpeed = 0.02;  // m/s: slower objects (server's velocity) may be resting ...
constexpr double kStillTime = 0.3;  // s: ... once their pose has stayed this long ...
constexpr double kStillMove = 0.002;  // m: ... within this distance ...
constexpr double kStillTurn = 0.02;  // rad: ... and this angle of where it was then
constexpr double kOnTableZ = -0.05;  // m: an object below this fell off the table
constexpr double kNearObject = 0.15;  // m: a palm this close to an object's centre is working on it
constexpr double kFrameTolerance = 0.002;  // m: a received mesh's centre of mass this far from its origin is off
constexpr double kSameTime = 0.05;  // s of server time: two hands arriving this close together tie
constexpr double kReplanMove = 0.02;  // m: an object moved this far since its plan is planned again ...
constexpr double kReplanTurn = 0.25;  // rad: ... or turned this far
constexpr int kMaxReplans = 3;  // re-plans per trial of an object that moved
// A trial's attempts: two rounds of the operator's kMaxAttempts. After a round of misses on an
// object that did not move, the bot plans again (a new operator, new pose errors) and tries once
// more, as a person over the wire would rather than give up; the records say how many it took.
constexpr int kRounds = 2;
constexpr int kAttemptBudget = kRounds * sim::ScriptedOperator::kMaxAttempts;
constexpr double kFollowSpeed = 0.2;  // m/s: how fast the correction follows the object ...
constexpr double kFollowTurnSpeed = 1.0;  // rad/s: ... and its turn

// A closed box between two corners, counter-clockwise seen from outside.
sim::TriangleMesh box_mesh(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi) {
  sim::TriangleMesh m;
  for (int i = 0; i < 8; ++i)
    m.vertices.emplace_back(i & 1 ? hi.x() : lo.x(), i & 2 ? hi.y() : lo.y(), i & 4 ? hi.z() : lo.z());
  m.triangles = {{0, 2, 1}, {1, 2, 3}, {4, 5, 6}, {5, 7, 6}, {0, 1, 4}, {1, 5, 4},
                 {2, 6, 3}, {3, 6, 7}, {0, 4, 2}, {2, 4, 6}, {1, 3, 5}, {3, 7, 5}};
  return m;
}

const char* side_name(client::HandSide s) { return s == client::HandSide::kRight ? "right" : "left"; }

std::string hand_name(const client::HandKey& k) { return k.client_id + " " + side_name(k.side); }

// Live hands of other clients whose palm is near `o`.
std::vector<client::HandKey> hands_near(const client::ObjectState& o, const std::vector<client::HandSkeleton>& others) {
  std::vector<client::HandKey> out;
  for (const auto& s : others)
    if (!s.frozen && (s.X_WorldPalm.translation() - o.X_WorldObject.translation()).norm() < kNearObject)
      out.push_back(s.hand);
  return out;
}

// The angle between two rotations, rad (quaternions: exact near zero, unlike acos of a trace).
double angle_between(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b) {
  return Eigen::Quaterniond(a.linear()).normalized().angularDistance(Eigen::Quaterniond(b.linear()).normalized());
}

// `from` moved toward `to` by at most `step_m` and `step_rad`.
Eigen::Isometry3d step_toward(const Eigen::Isometry3d& from, const Eigen::Isometry3d& to, double step_m,
                              double step_rad) {
  Eigen::Isometry3d out = Eigen::Isometry3d::Identity();
  const Eigen::Vector3d d = to.translation() - from.translation();
  out.translation() = from.translation() + (d.norm() > step_m ? d * (step_m / d.norm()) : d);
  const Eigen::Quaterniond qa(from.linear()), qb(to.linear());
  const double angle = qa.angularDistance(qb);
  out.linear() = (angle > step_rad ? qa.slerp(step_rad / angle, qb) : qb).normalized().toRotationMatrix();
  return out;
}

// Whether an object at `X` has moved beyond the re-plan thresholds from `X_plan`.
bool moved_beyond(const Eigen::Isometry3d& X, const Eigen::Isometry3d& X_plan) {
  return (X.translation() - X_plan.translation()).norm() > kReplanMove || angle_between(X, X_plan) > kReplanTurn;
}

// Follows whether `t`'s object is still: a grasp is planned on a resting object only. Resting:
// the server's velocity is low and the pose has stayed near one pose (the anchor) for kStillTime.
// A pose test over a window, not between successive scene states, so the solver's sub-millimetre
// jitter on a resting object does not count as motion.
void track_stillness(Target& t, const client::ObjectState* o, double server_time) {
  if (!o) return;
  const Eigen::Isometry3d& X = o->X_WorldObject;
  if (t.X_WorldObject_anchor) {
    t.moved_m = (X.translation() - t.X_WorldObject_anchor->translation()).norm();
    t.turned_rad = angle_between(X, *t.X_WorldObject_anchor);
  }
  if (!t.X_WorldObject_anchor || t.moved_m > kStillMove || t.turned_rad > kStillTurn ||
      o->v_WorldObject.norm() > kRestingSpeed || o->held) {
    t.X_WorldObject_anchor = X;
    t.still_since = server_time;
    t.moved_m = t.turned_rad = 0;
  }
}

// Why an object cannot be started now ("" if it can).
std::string why_unavailable(const Target& t, const client::ObjectState* o,
                            const std::vector<client::HandSkeleton>& others, double server_time) {
  if (!o) return "removed from the scene";
  if (o->held) return "held by " + hand_name(o->holder);
  if (const auto near = hands_near(*o, others); !near.empty()) return "being worked on by " + hand_name(near.front());
  const double z = o->X_WorldObject.translation().z();
  if (z < kOnTableZ) return "off the table (z " + report::fmt(z, 2) + " m)";
  if (server_time - t.still_since < kStillTime)
    return "moving (" + report::fmt(o->v_WorldObject.norm(), 3) + " m/s; " + report::fmt(1000 * t.moved_m, 1) +
           " mm, " + report::fmt(t.turned_rad * 180 / M_PI, 1) + " deg in " +
           report::fmt(std::max(0.0, server_time - t.still_since), 2) + " s)";
  return "";
}

}  // namespace

bool geometry_complete(const client::Client& c, const client::SceneState& scene,
                       const std::map<std::string, sim::ObjectModelPtr>& local) {
  for (const client::ObjectState& o : scene.objects)
    if (!local.count(o.name) && !c.object_geometry(o.name)) return false;
  return true;
}

sim::ObjectModelPtr model_from_geometry(const client::ObjectGeometry& g) {
  const std::string source = "ObjectGeometry " + g.model + " (hash " + cli::format_hex64(g.content_hash) + ")";
  sim::TriangleMesh mesh;
  if (g.mesh_omitted) {
    // Over the server's size limit: plan on the box of its bounds (model frame), the best the wire
    // gives. Fingers close on the box's faces, which lie on or outside the real surface.
    if (!((g.p_ObjectMax - g.p_ObjectMin).array() > 0).all())
      throw sim::MeshLoadError(source + ": published without its mesh (" + std::to_string(g.triangle_count) +
                               " triangles, over the server's limit) and with empty bounds");
    mesh = box_mesh(g.p_ObjectMin, g.p_ObjectMax);
  } else {
    mesh.vertices.reserve(g.vertices.size());
    for (const Eigen::Vector3f& v : g.vertices) mesh.vertices.push_back(v.cast<double>());
    mesh.triangles = g.triangles;
  }
  sim::ObjectModelPtr m = sim::make_object_model_in_model_frame(g.model, std::move(mesh), g.mass_kg,
                                                                source + (g.mesh_omitted ? ", its bounding box" : ""),
                                                                -g.p_ObjectSourceOrigin);
  // The plan is made in the model frame, the frame of ObjectState's pose: its origin is the centre
  // of mass. A mesh whose centroid is elsewhere may not have been published in that frame: say so.
  if (!g.mesh_omitted && m->mass_properties.centroid.norm() > kFrameTolerance)
    std::cerr << "telegrasp-bot: warning: " << source << " may not be in the model frame: its centre of mass is "
              << report::fmt(1000 * m->mass_properties.centroid.norm(), 1) << " mm from its origin\n";
  return m;
}

std::map<std::string, sim::ObjectModelPtr> resolve_models(const client::Client& c, const client::SceneState& scene,
                                                          std::map<std::string, sim::ObjectModelPtr> local) {
  std::map<std::string, sim::ObjectModelPtr> models;
  std::map<std::uint64_t, sim::ObjectModelPtr> built;  // by content hash: each mesh is built once
  std::set<std::string> received, standins;
  for (const client::ObjectState& o : scene.objects) {
    if (models.count(o.name)) continue;
    if (auto it = local.find(o.name); it != local.end()) {
      models.emplace(o.name, it->second);
      continue;
    }
    if (const auto g = c.object_geometry(o.name)) {
      try {
        sim::ObjectModelPtr& m = built[g->content_hash];
        if (!m || m->name != g->model || m->mass_kg != g->mass_kg) m = model_from_geometry(*g);
        models.emplace(o.name, m);
        received.insert(o.name);
        continue;
      } catch (const std::exception& e) {
        std::cerr << "telegrasp-bot: cannot plan on the server's geometry of " << o.name << ": " << e.what() << "\n";
      }
    }
    if (const auto p = sim::find_protocol_object(o.name); p && p->name == o.name) {
      models.emplace(o.name, sim::make_standin_model(*p));
      standins.insert(o.name);
    }
  }
  auto names = [](const std::set<std::string>& s) {
    std::string out;
    for (const std::string& n : s) out += (out.empty() ? "" : ", ") + n;
    return out;
  };
  if (!received.empty())
    std::cerr << "telegrasp-bot: planning on the server's published geometry for " << received.size()
              << " model(s): " << names(received) << "\n";
  if (!standins.empty())
    std::cerr << "telegrasp-bot: no mesh file and no geometry from the server for " << standins.size()
              << " model(s): planning on the built-in stand-ins of " << names(standins) << "\n";
  return models;
}

std::vector<std::shared_ptr<const sim::HandRig>> load_hand_rigs(const std::vector<client::HandSide>& hands) {
  std::vector<std::shared_ptr<const sim::HandRig>> out;
  for (client::HandSide side : hands)
    out.push_back(
        std::make_shared<const sim::HandRig>(sim::HandRig::load(sim::HandRig::builtin_path(sim::HandRig::default_human(
            side == client::HandSide::kRight ? sim::HandSide::kRight : sim::HandSide::kLeft)))));
  return out;
}

Bot::Bot(Options opt, client::Client& c, std::map<std::string, sim::ObjectModelPtr> models,
         std::vector<std::shared_ptr<const sim::HandRig>> rigs)
    : opt_(std::move(opt)), client_(c), models_(std::move(models)), skill_(sim::skill_profile(opt_.skill)) {
  for (std::size_t i = 0; i < opt_.hands.size(); ++i) {
    const client::HandSide side = opt_.hands[i];
    Hand h;
    h.key = {client_.client_id(), side};
    h.rig = std::move(rigs.at(i));
    h.input.X_WorldPalm.translation() = Eigen::Vector3d(0.0, side == client::HandSide::kRight ? -0.3 : 0.3, 0.3);
    hands_.push_back(std::move(h));
  }
}

// Takes the scene's objects as the work list; false if the scene is empty.
bool Bot::set_scene(const client::SceneState& scene) {
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
    if (auto it = models_.find(o.name); it != models_.end())
      t.model = it->second;
    else
      unknown.insert(o.name);
    targets_.push_back(std::move(t));
  }
  if (!unknown.empty()) {
    std::cerr << "telegrasp-bot: no model for " << unknown.size() << " scene object(s) (" << *unknown.begin()
              << (unknown.size() > 1 ? ", ..." : "")
              << "); pass the server's --objects DIR. They are recorded as not grasped.\n";
  }
  // A fixed order from the seed; each hand takes the first free object with the fewest trials started.
  order_.resize(targets_.size());
  for (std::size_t i = 0; i < order_.size(); ++i) order_[i] = i;
  std::mt19937_64 rng(opt_.seed);
  std::shuffle(order_.begin(), order_.end(), rng);
  total_ = static_cast<int>(targets_.size()) * opt_.trials;
  incarnation_ = scene.incarnation;
  for (Target& t : targets_)
    if (!t.model) give_up(t, "no model named '" + t.name + "' (pass the server's --objects DIR)");
  return !targets_.empty();
}

void Bot::server_restarted(const client::SceneState& scene) {
  int interrupted = 0;
  for (Hand& h : hands_) {
    if (h.stage == Stage::kIdle || !h.target) continue;
    if (h.planning.valid()) h.planning.wait();
    BotRecord r;
    r.record.object = h.target->name;
    r.record.trial = h.trial;
    r.record.attempts = h.op ? std::min(h.attempts_before + h.op->attempts(), kAttemptBudget) : 0;
    r.object_id = h.target->id;
    r.target = static_cast<int>(h.target - targets_.data());
    r.hand = h.key.side;
    r.reason = "server restarted";
    r.interrupted = true;
    --h.target->started;  // run again
    h.leave_target();
    add_record(std::move(r));
    ++interrupted;
  }
  // The same objects in the new run: by name, in scene order.
  std::map<std::string, std::vector<int>> ids;
  for (const client::ObjectState& o : scene.objects) ids[o.name].push_back(o.id);
  std::map<std::string, std::size_t> taken;
  int missing = 0;
  for (Target& t : targets_) {
    const std::vector<int>& same = ids[t.name];
    std::size_t& k = taken[t.name];
    t.id = k < same.size() ? same[k] : -1;
    missing += k++ >= same.size();
    t.X_WorldObject_anchor.reset();
    t.unavailable_since.reset();
  }
  std::cerr << "telegrasp-bot: the server restarted (incarnation " << cli::format_hex64(incarnation_) << " -> "
            << cli::format_hex64(scene.incarnation) << "): " << interrupted
            << " trial(s) in progress interrupted, recorded as such"
            << " and run again; " << targets_.size() - missing << " of " << targets_.size()
            << " objects found in the new scene\n";
  incarnation_ = scene.incarnation;
}

int Bot::interrupted() const {
  int n = 0;
  for (const BotRecord& r : records_) n += r.interrupted;
  return n;
}

// One tick of every hand: reads the newest server outputs, steps each hand, publishes.
void Bot::tick(std::int64_t tick, const client::SceneState& scene) {
  std::map<int, const client::ObjectState*> objects;
  for (const auto& o : scene.objects) objects[o.id] = &o;
  for (const client::GraspEvent& e : client_.take_grasp_events()) {
    event_ids_.push_back(e.event_id);
    on_event(e);
  }
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
void Bot::hold() {
  for (Target& t : targets_) t.unavailable_since.reset();
  publish();
}

void Bot::publish() {
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

bool Bot::all_done() const {
  for (const Target& t : targets_)
    if (t.finished < opt_.trials) return false;
  return true;
}

// The trials in progress (not counted when stopped early).
int Bot::in_progress() const {
  int n = 0;
  for (const Hand& h : hands_) n += h.stage != Stage::kIdle;
  return n;
}

// Prints the table and the summary line; writes --json. False if the file cannot be written.
bool Bot::report_results() const {
  std::string hands;
  for (const Hand& h : hands_) hands += (hands.empty() ? "" : "+") + std::string(side_name(h.key.side));
  std::cout << "\n== bot " << opt_.client_id << ", hands " << hands << ", skill " << opt_.skill << " ==\n";
  std::vector<report::ObjectRows> rows;
  std::vector<const report::Record*> all;
  for (const Target& t : targets_) {
    report::ObjectRows row{t.label, {}};
    for (const BotRecord& r : records_)
      if (r.target == static_cast<int>(&t - targets_.data()) && !r.interrupted) row.records.push_back(&r.record);
    all.insert(all.end(), row.records.begin(), row.records.end());
    rows.push_back(std::move(row));
  }
  report::print_object_table(rows);
  json s = report::summarize(all);
  s["skill"] = opt_.skill;
  s["client_id"] = opt_.client_id;
  s["hands"] = hands;
  s["interrupted"] = interrupted();
  std::cout << "summary: " << s.dump() << "\n";
  // The held line: the total, then each object not held in every trial.
  int held = 0;
  std::string failed;
  for (const report::ObjectRows& row : rows) {
    int n = 0;
    for (const report::Record* r : row.records) n += r->held_after_lift;
    held += n;
    if (n < static_cast<int>(row.records.size()) || row.records.empty())
      failed += (failed.empty() ? "" : ", ") + row.object + " " + std::to_string(n) + "/" +
                std::to_string(row.records.size());
  }
  const std::string line = "held " + std::to_string(held) + "/" + std::to_string(all.size()) + " trials on " +
                           std::to_string(rows.size()) + " objects; " +
                           (failed.empty() ? "every object held in every trial" : "not held every time: " + failed);
  std::cout << line << "\n" << std::flush;
  std::cerr << line << "\n";
  const json events = grasp_event_ids_json();
  std::cerr << "grasp events received: " << events["received"] << " (ids " << events["first"] << ".." << events["last"]
            << "), " << events["missing"].size() << " missing, " << events["duplicates"].size() << " duplicated\n";
  if (interrupted() > 0)
    std::cerr << "(" << interrupted() << " trial(s) interrupted by a server restart, run again: not counted above)\n";
  if (opt_.json_path.empty()) return true;
  json grasps = json::array();
  for (const BotRecord& r : records_) {
    json g = report::record_json(r.record);
    g["client_id"] = opt_.client_id;
    g["hand"] = side_name(r.hand);
    g["object_id"] = r.object_id;
    g["reason"] = r.reason.empty() ? json(nullptr) : json(r.reason);
    g["interrupted"] = r.interrupted;
    grasps.push_back(std::move(g));
  }
  std::ofstream out(opt_.json_path);
  out << json{{"grasps", grasps}, {"summary", s}, {"summaries", json::array({s})}, {"grasp_events", events}}.dump(1)
      << "\n";
  if (!out.flush()) {
    std::cerr << "telegrasp-bot: cannot write --json file " << opt_.json_path << "\n";
    return false;
  }
  std::cerr << "wrote " << opt_.json_path << "\n";
  return true;
}

nlohmann::json Bot::grasp_event_ids_json() const {
  std::vector<std::uint64_t> ids = event_ids_;
  std::sort(ids.begin(), ids.end());
  json missing = json::array(), duplicates = json::array();
  for (std::size_t i = 1; i < ids.size(); ++i) {
    if (ids[i] == ids[i - 1] && (duplicates.empty() || duplicates.back() != ids[i])) duplicates.push_back(ids[i]);
    for (std::uint64_t m = ids[i - 1] + 1; m < ids[i]; ++m) missing.push_back(m);
  }
  return {{"received", ids.size()},
          {"first", ids.empty() ? json(nullptr) : json(ids.front())},
          {"last", ids.empty() ? json(nullptr) : json(ids.back())},
          {"missing", missing},
          {"duplicates", duplicates}};
}

bool Bot::all_held() const {
  if (records_.empty()) return false;
  for (const BotRecord& r : records_)
    if (!r.interrupted && !r.record.held_after_lift) return false;
  return true;
}

Hand* Bot::hand_of(const client::HandKey& key) {
  for (Hand& h : hands_)
    if (h.key == key) return &h;
  return nullptr;
}

bool Bot::targeted(const Target& t) const {
  for (const Hand& h : hands_)
    if (h.target == &t) return true;
  return false;
}

void Bot::on_event(const client::GraspEvent& e) {
  Hand* h = hand_of(e.hand);
  if (!h || e.kind != client::GraspEvent::Kind::kGrasp) return;
  if (e.server_incarnation != incarnation_) return;  // of a server run that is gone: its ids mean nothing now
  if (!h->target || e.object_id != h->target->id || h->stage == Stage::kIdle || h->stage == Stage::kSettle) {
    std::cerr << "telegrasp-bot: " << side_name(h->key.side) << " hand grasped " << e.object_name << " (id "
              << e.object_id << "), not its target\n";
    return;
  }
  if (h->got_grasp_event) return;  // a later attempt's grasp: the first one is the trial's
  h->got_grasp_event = true;
  tools::record_grasp_event(e, h->server_t0, *h->rig, h->rec);
}

// Starts or stops each untargeted object's unavailability clock; gives up after kGiveUpAfter.
void Bot::update_availability(const std::map<int, const client::ObjectState*>& objects) {
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
void Bot::give_up(Target& t, const std::string& why) {
  t.given_up = true;
  for (; t.started < opt_.trials; ++t.started, ++t.finished) {
    BotRecord r;
    r.record.object = t.name;
    r.record.trial = t.started;
    r.object_id = t.id;
    r.target = static_cast<int>(&t - targets_.data());
    r.hand = hands_.front().key.side;
    r.reason = why;
    add_record(std::move(r));
  }
}

void Bot::add_record(BotRecord r) {
  const report::Record& rec = r.record;
  if (r.interrupted) {
    std::cerr << "[interrupted] " << side_name(r.hand) << " " << rec.object << " trial " << rec.trial << ": "
              << r.reason << "\n";
    records_.push_back(std::move(r));
    return;
  }
  ++done_;
  std::cerr << "[" << done_ << "/" << total_ << "] " << side_name(r.hand) << " " << rec.object << " trial " << rec.trial
            << (rec.held_after_lift ? " held" : " NOT held");
  if (rec.grasped)
    std::cerr << " (grasp " << report::fmt(rec.time_to_grasp_s) << " s, HandError " << report::fmt(rec.hand_error_mm, 1)
              << " mm)";
  if (!r.reason.empty()) std::cerr << ": " << r.reason;
  std::cerr << "\n";
  records_.push_back(std::move(r));
}

// The next object for `h`: fewest trials started first, then the seeded order.
Target* Bot::pick(const std::map<int, const client::ObjectState*>& objects) {
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

bool Bot::holds_target(const Hand& h, const client::ObjectState* o) const {
  if (o && std::find(o->holders.begin(), o->holders.end(), h.key) != o->holders.end()) return true;
  const auto gs = client_.latest_grasp_state(h.key);
  return gs && gs->grasped_object == h.target->id;
}

void Bot::step(Hand& h, std::int64_t tick, const client::SceneState& scene,
               const std::map<int, const client::ObjectState*>& objects) {
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
    if (!planned || (!h.running && (tick - h.stage_tick) * dt < kSettleTime)) return;
    try {
      h.planning.get();
    } catch (const std::exception& e) {
      h.note = std::string("planning failed: ") + e.what();
      finish_trial(h);
      return;
    }
    if (o && !o->held && h.replans < kMaxReplans && moved_beyond(o->X_WorldObject, h.X_WorldObject_plan)) {
      ++h.replans;
      replan(h, *o, "it moved while the plan was made");  // planning took long and the object moved
      return;
    }
    h.stage = Stage::kRun;
    h.op_tick = tick;
    if (!h.running) {
      h.server_t0 = scene.time;
      h.z0 = o ? o->X_WorldObject.translation().z() : 0;
    }
    h.running = true;
    // The object's motion since the plan (the scene state planned on is older than this one).
    h.X_WorldObject_followed = o ? o->X_WorldObject : h.X_WorldObject_plan;
    h.correction = h.X_WorldObject_followed * h.X_WorldObject_plan.inverse();
  }
  if (h.stage == Stage::kRun) {
    const bool grasped = holds_target(h, o);
    h.seen_grasped |= grasped;
    const double t_op = static_cast<double>(tick - h.op_tick) * dt;
    const sim::OperatorPhase phase_before = h.op->phase();
    const bool approaching = phase_before == sim::OperatorPhase::kReact || phase_before == sim::OperatorPhase::kReach;
    if (approaching) {
      if (const auto other = yields_to(h, o)) {
        abandon(h, *other);
        return;
      }
      if (o && !o->held) {
        // Before a squeeze (the first, or after a miss that pushed the object): follow the object,
        // or plan again where it went if it moved far (fell over, rolled away).
        // The attempts made so far: the one being reached for has not squeezed yet.
        const int made =
            h.attempts_before + std::max(0, h.op->attempts() - (phase_before == sim::OperatorPhase::kReach ? 1 : 0));
        if (h.replans < kMaxReplans && made < kAttemptBudget && moved_beyond(o->X_WorldObject, h.X_WorldObject_plan)) {
          h.attempts_before = made;
          ++h.replans;
          replan(
              h, *o,
              "it moved " +
                  report::fmt(1000 * (o->X_WorldObject.translation() - h.X_WorldObject_plan.translation()).norm(), 0) +
                  " mm since its plan");
          return;
        }
        h.X_WorldObject_followed =
            step_toward(h.X_WorldObject_followed, o->X_WorldObject, kFollowSpeed * dt, kFollowTurnSpeed * dt);
        h.correction = h.X_WorldObject_followed * h.X_WorldObject_plan.inverse();
      }
    }
    if (!o)
      h.note = "removed from the scene during the trial";
    else if (h.seen_grasped && !grasped && o->held && !(o->holder == h.key))
      h.note = "taken by " + hand_name(o->holder);
    for (const client::HandSkeleton& s : own_)
      if (s.hand == h.key) h.op->see_hand_raised(s.resolve_offset.z());
    h.input = h.op->next(t_op, grasped);
    h.input.X_WorldPalm = h.correction * h.input.X_WorldPalm;
    if (h.op->phase() == sim::OperatorPhase::kHold && o) {
      h.z_max = std::max(h.z_max, o->X_WorldObject.translation().z());
      if (grasped)
        if (auto q = tools::hold_quality(client_.latest_grasp_state(h.key), h.target->id)) h.hold_quality = q;
    }
    // A round of misses (the operator gave up, nothing grasped): plan again for another round.
    if (h.op->done() && !h.seen_grasped && o && !o->held && h.retries + 1 < kRounds &&
        h.attempts_before + h.op->attempts() < kAttemptBudget) {
      h.attempts_before += h.op->attempts();
      ++h.retries;
      replan(h, *o, "not grasped in " + std::to_string(h.attempts_before) + " attempt(s)");
      return;
    }
    // Every operator of the trial shares kAttemptBudget: one that begins an attempt past it is done.
    const bool out_of_attempts = h.attempts_before + h.op->attempts() > kAttemptBudget;
    if (h.op->done() || out_of_attempts || t_op > kTrialLimit) {
      if (!h.op->done() && !out_of_attempts) h.note = "cut short after " + report::fmt(kTrialLimit, 0) + " s";
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
    const double waited = (tick - h.stage_tick) * dt;
    if (event_in ? released || waited > kFinishLimit : waited > kEventWait) finish_trial(h);
  }
}

// Before its squeeze a hand gives the object up, as a person would, to a hand that holds it, or
// came near it first, or came at the same time with a greater key (so exactly one of two goes on).
// Returns the hand it gives way to, if any.
std::optional<client::HandKey> Bot::yields_to(Hand& h, const client::ObjectState* o) {
  if (!o) return std::nullopt;
  if (o->held && !(o->holder == h.key)) return o->holder;
  for (const client::HandSkeleton& s : own_)
    if (s.hand == h.key && !h.near_time &&
        (s.X_WorldPalm.translation() - o->X_WorldObject.translation()).norm() < kNearObject)
      h.near_time = s.time;
  for (const client::HandSkeleton& s : others_) {
    if (s.frozen || (s.X_WorldPalm.translation() - o->X_WorldObject.translation()).norm() >= kNearObject) continue;
    const double since = h.others_near_time.try_emplace(s.hand, s.time).first->second;
    if (!h.near_time || since < *h.near_time - kSameTime) return s.hand;
    if (since <= *h.near_time + kSameTime && h.key < s.hand) return s.hand;
  }
  return std::nullopt;
}

void Bot::start_trial(Hand& h, Target& t, std::int64_t tick, const client::ObjectState& o) {
  const double side = h.key.side == client::HandSide::kRight ? 1.0 : -1.0;
  h.target = &t;
  h.trial = t.started++;
  h.stage = Stage::kSettle;
  h.stage_tick = tick;
  h.seen_grasped = h.got_grasp_event = false;
  h.near_time.reset();
  h.others_near_time.clear();
  h.z_max = -1e9;
  h.hold_quality.reset();
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
  h.X_WorldObject_plan = h.X_WorldObject_followed = o.X_WorldObject;
  h.correction = Eigen::Isometry3d::Identity();
  h.plans = h.replans = h.retries = h.attempts_before = 0;
  h.running = false;
  begin_operator(h, o.X_WorldObject, X_WorldStart);
}

void Bot::begin_operator(Hand& h, const Eigen::Isometry3d& X_WorldObject, const Eigen::Isometry3d& X_WorldPalm) {
  // The operator's noise depends on the object, trial and re-plan only, as in telegrasp-eval.
  const std::uint64_t seed = opt_.seed * 1000003ULL + h.target->scene_index * 1009ULL +
                             static_cast<std::uint64_t>(h.trial) + 7919ULL * static_cast<std::uint64_t>(h.plans);
  h.op = std::make_unique<sim::ScriptedOperator>(h.rig, skill_, seed, sim::GraspSettings{}, 1.0 / kRate);
  h.op->put_down_before_release(true);  // the scene is shared: a dropped object may land on another
  sim::ScriptedOperator* op = h.op.get();
  h.planning = std::async(std::launch::async, [op, model = h.target->model, X_WorldObject, X_WorldPalm] {
    op->begin(*model, X_WorldObject, X_WorldPalm, 0.0);
  });
}

void Bot::replan(Hand& h, const client::ObjectState& o, const std::string& why) {
  ++h.plans;
  std::cerr << side_name(h.key.side) << " hand plans " << h.target->label << " trial " << h.trial << " again: " << why
            << "\n";
  h.X_WorldObject_plan = h.X_WorldObject_followed = o.X_WorldObject;
  h.correction = Eigen::Isometry3d::Identity();
  h.input.trigger = 0;
  h.input.curls.clear();
  h.stage = Stage::kSettle;
  h.stage_tick = 0;
  begin_operator(h, o.X_WorldObject, h.input.X_WorldPalm);  // from where the hand is, open
}

// Drops the current trial without counting it: `other` has the object, or came for it first.
void Bot::abandon(Hand& h, const client::HandKey& other) {
  std::cerr << side_name(h.key.side) << " hand leaves " << h.target->label << " to " << hand_name(other)
            << " for now\n";
  --h.target->started;
  h.leave_target();
}

void Bot::finish_trial(Hand& h) {
  BotRecord r;
  r.record = std::move(h.rec);
  r.record.attempts = std::min(h.attempts_before + h.op->attempts(), kAttemptBudget);
  r.record.held_after_lift = h.op->held_after_lift() && h.z_max - h.z0 > 0.8 * sim::ScriptedOperator::kLiftHeight;
  report::set_hold_quality(r.record, h.hold_quality);
  r.object_id = h.target->id;
  r.target = static_cast<int>(h.target - targets_.data());
  r.hand = h.key.side;
  r.reason = h.note;
  if (r.reason.empty() && !r.record.held_after_lift) {
    if (!h.seen_grasped)
      r.reason = "not grasped in " + std::to_string(r.record.attempts) + " attempt(s)";
    else if (!h.op->held_after_lift())
      r.reason = "dropped during the lift or hold";
    else
      r.reason = "rose only " + report::fmt(1000 * (h.z_max - h.z0), 0) + " mm";
  }
  if (h.seen_grasped && !h.got_grasp_event && r.reason.empty()) r.reason = "no grasp event received";
  ++h.target->finished;
  h.leave_target();
  add_record(std::move(r));
}

}  // namespace telegrasp::bot
