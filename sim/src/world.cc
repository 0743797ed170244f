// The physics scene: Bullet rigid bodies for the table and objects, and the hands.
#include "telegrasp/sim/world.h"

#include "telegrasp/sim/two_hand_hold.h"

#include <btBulletDynamicsCommon.h>
#include <LinearMath/btConvexHullComputer.h>

#include <algorithm>
#include <cassert>
#include <deque>
#include <functional>
#include <map>
#include <optional>
#include <stdexcept>

namespace telegrasp::sim {
namespace {

btVector3 to_bt(const Eigen::Vector3d& v) { return {btScalar(v.x()), btScalar(v.y()), btScalar(v.z())}; }
Eigen::Vector3d to_eigen(const btVector3& v) { return {v.x(), v.y(), v.z()}; }

btTransform to_bt(const Eigen::Isometry3d& X) {
  const Eigen::Quaterniond q(X.linear());
  return btTransform(btQuaternion(btScalar(q.x()), btScalar(q.y()), btScalar(q.z()), btScalar(q.w())),
                     to_bt(X.translation()));
}

Eigen::Isometry3d to_eigen(const btTransform& t) {
  const btQuaternion q = t.getRotation();
  Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
  X.linear() = Eigen::Quaterniond(q.w(), q.x(), q.y(), q.z()).normalized().toRotationMatrix();
  X.translation() = to_eigen(t.getOrigin());
  return X;
}

constexpr double kHullMargin = 0.0005;

}  // namespace

std::optional<TwoHandMode> parse_two_hand_mode(std::string_view name) {
  if (name == "share") return TwoHandMode::kShare;
  if (name == "takeover") return TwoHandMode::kTakeover;
  return std::nullopt;
}

const char* two_hand_mode_name(TwoHandMode mode) { return mode == TwoHandMode::kTakeover ? "takeover" : "share"; }

struct World::Impl {
  struct Object {
    ObjectModelPtr model;
    std::unique_ptr<btConvexHullShape> shape;
    std::unique_ptr<btDefaultMotionState> motion;
    std::unique_ptr<btRigidBody> body;
    std::vector<HandId> holders;  // in the order they grasped: holders[0] is the first hand
    std::optional<TwoHandHold> shared;  // while two hands hold it, taken the tick the second joined

    bool held_by(HandId hand) const { return std::find(holders.begin(), holders.end(), hand) != holders.end(); }
    // `hand` no longer holds it; a two-hand hold ends (one restarts when a second hand joins again).
    void forget(HandId hand) {
      holders.erase(std::remove(holders.begin(), holders.end(), hand), holders.end());
      shared.reset();
    }
  };
  struct Hand {
    std::unique_ptr<HandController> controller;
    ControllerInput input;
  };

  WorldSettings settings;
  btDefaultCollisionConfiguration collision_config;
  btCollisionDispatcher dispatcher{&collision_config};
  btDbvtBroadphase broadphase;
  btSequentialImpulseConstraintSolver solver;
  btDiscreteDynamicsWorld dynamics{&dispatcher, &broadphase, &solver, &collision_config};
  std::unique_ptr<btBoxShape> table_shape;
  std::unique_ptr<btRigidBody> table;
  std::map<int, Object> objects;  // ordered by id: deterministic iteration
  std::map<int, Hand> hands;  // ordered by id: hands tick in id order
  std::vector<GraspEvent> events;
  std::vector<GraspEvent> pending;  // from calls between steps, delivered with the next step's
  // Grasp qualities: the worker, the last job id of each step still to deliver, what each hand
  // last asked for (its grasp and contacts), this step's deliveries and the counts.
  std::unique_ptr<QualityWorker> quality;
  std::deque<std::pair<std::uint64_t, std::uint64_t>> quality_due;  // (tick, last job id through it)
  struct Asked {
    std::uint64_t grasp = 0;
    std::vector<QualityContact> contacts;
  };
  std::map<int, Asked> quality_asked;
  std::map<int, std::function<std::shared_ptr<GraspMetrics>()>> metrics_of;  // this step's grasps, by hand
  std::vector<QualityResult> quality_results;
  std::map<int, std::uint64_t> quality_computed;
  std::uint64_t next_job = 1;
  std::uint64_t quality_late = 0;
  int next_object = 0;
  int next_hand = 0;
  std::uint64_t tick = 0;

  Object& object(ObjectId id) {
    auto it = objects.find(id.value);
    if (it == objects.end()) throw std::out_of_range("World: unknown object id " + std::to_string(id.value));
    return it->second;
  }
  // Puts a body at a pose (its motion state too, so kinematic velocities follow).
  static void place(Object& o, const btTransform& pose) {
    o.motion->setWorldTransform(pose);
    o.body->setWorldTransform(pose);
  }
  Hand& hand(HandId id) {
    auto it = hands.find(id.value);
    if (it == hands.end()) throw std::out_of_range("World: unknown hand id " + std::to_string(id.value));
    return it->second;
  }
  // A release that happens between steps (object or hand removed), delivered with the next step.
  void pend_release(HandId hand_id, ObjectId object_id) {
    GraspEvent e;
    e.kind = GraspEvent::Kind::kRelease;
    e.hand = hand_id;
    e.object = object_id;
    e.tick = tick;
    e.time = static_cast<double>(tick) * settings.dt;
    pending.push_back(std::move(e));
  }

  void make_kinematic(Object& o, bool kinematic) {
    btRigidBody& body = *o.body;
    if (kinematic) {
      body.setCollisionFlags(body.getCollisionFlags() | btCollisionObject::CF_KINEMATIC_OBJECT);
      body.setActivationState(DISABLE_DEACTIVATION);
    } else {
      body.setCollisionFlags(body.getCollisionFlags() & ~btCollisionObject::CF_KINEMATIC_OBJECT);
      body.forceActivationState(ACTIVE_TAG);
      body.setDeactivationTime(0);
    }
  }

  GraspEvent event(GraspEvent::Kind kind, HandId hand_id, ObjectId object_id) const {
    GraspEvent e;
    e.kind = kind;
    e.hand = hand_id;
    e.object = object_id;
    e.tick = tick + 1;
    e.time = static_cast<double>(tick + 1) * settings.dt;
    return e;
  }

  // `hand` let go of the object in `ev`: another holder keeps it, else it goes back to physics
  // where the hand let go of it, with the hand's motion: v = v_palm + w x (p_object - p_palm).
  void on_release(HandId hand_id, const HandController& hand, const HandTickEvents& ev) {
    auto it = objects.find(ev.released_object.value);
    if (it == objects.end() || !it->second.held_by(hand_id)) return;
    Object& o = it->second;
    o.forget(hand_id);
    GraspEvent e = event(GraspEvent::Kind::kRelease, hand_id, ev.released_object);
    if (o.holders.empty()) {
      place(o, to_bt(ev.X_WorldReleased));
      make_kinematic(o, false);
      const HandState& s = hand.state();
      const Eigen::Vector3d r = ev.X_WorldReleased.translation() - s.X_WorldPalm.translation();
      e.v_WorldObject = s.v_WorldPalm + s.w_WorldPalm.cross(r);
      e.w_WorldObject = s.w_WorldPalm;
      o.body->setLinearVelocity(to_bt(e.v_WorldObject));
      o.body->setAngularVelocity(to_bt(e.w_WorldObject));
    }
    events.push_back(std::move(e));
  }

  // `holder` lets go because another hand's grasp took its place (zero velocity: it stays held).
  void displace(Object& o, HandId holder, ObjectId object_id) {
    hand(holder).controller->release();
    o.forget(holder);
    events.push_back(event(GraspEvent::Kind::kRelease, holder, object_id));
  }

  // `hand` grasped an object: it takes it over, or joins its holder (the oldest of two lets go).
  void on_grasp(HandId hand_id, const HandController& hand) {
    const ObjectId oid = hand.state().grasped;
    Object& o = object(oid);
    const std::size_t keep = settings.two_hand_mode == TwoHandMode::kTakeover ? 0 : 1;
    while (o.holders.size() > keep) displace(o, o.holders.front(), oid);
    o.holders.push_back(hand_id);
    o.shared.reset();
    make_kinematic(o, true);
    GraspEvent e = event(GraspEvent::Kind::kGrasp, hand_id, oid);
    // The metrics come with the quality (ask_qualities): taken on the worker from a copy of the
    // hand as it grasped, which keeps the object's model alive.
    metrics_of[hand_id.value] = [snapshot = std::make_shared<const HandController>(hand), model = o.model] {
      const std::optional<GraspMetrics> m = snapshot->grasp_tick_metrics();
      return m ? std::make_shared<GraspMetrics>(*m) : nullptr;
    };
    e.contacts = hand.contacts();
    e.grasp_type = hand.state().grasp_type;
    events.push_back(std::move(e));
  }

  // Hands the worker the contacts of every holding hand whose grasp or contacts changed this step
  // (the step numbered `now`).
  void ask_qualities(std::uint64_t now) {
    const std::uint64_t first = next_job;
    for (auto& [h, hand_entry] : hands) {
      const HandController& hand = *hand_entry.controller;
      std::optional<QualityJob> job = hand.quality_inputs();
      const auto metrics = metrics_of.find(h);
      if (!job && metrics != metrics_of.end()) job.emplace();  // grasped and let go within the step
      if (!job) continue;
      if (metrics != metrics_of.end()) job->metrics = std::move(metrics->second);
      Asked& asked = quality_asked[h];
      const bool new_grasp = asked.grasp != hand.grasp_serial();
      if (!new_grasp && same_contacts(asked.contacts, job->contacts)) continue;
      asked.grasp = hand.grasp_serial();
      asked.contacts = job->contacts;
      job->id = next_job++;
      job->hand = HandId(h);
      job->grasp = hand.grasp_serial();
      job->tick = now;
      job->grasp_tick = new_grasp;
      if (new_grasp)
        for (GraspEvent& e : events)
          if (e.kind == GraspEvent::Kind::kGrasp && e.hand == HandId(h)) e.quality_job = job->id;
      quality->submit(std::move(*job));
    }
    metrics_of.clear();
    if (next_job > first) quality_due.emplace_back(now, next_job - 1);
  }

  static bool same_contacts(const std::vector<QualityContact>& a, const std::vector<QualityContact>& b) {
    return a.size() == b.size() && std::equal(a.begin(), a.end(), b.begin(),
                                              [](const auto& x, const auto& y) { return x.p == y.p && x.n == y.n; });
  }

  // Delivers the qualities of the contact sets of step `now - quality_delay_ticks` and before.
  void deliver_qualities(std::uint64_t now) {
    quality_results.clear();
    const std::uint64_t k = static_cast<std::uint64_t>(settings.quality_delay_ticks);
    std::uint64_t last = 0;
    while (!quality_due.empty() && quality_due.front().first + k <= now) {
      last = quality_due.front().second;
      quality_due.pop_front();
    }
    if (last == 0) return;
    bool waited = false;
    quality_results = quality->take(last, waited);
    quality_late += waited;
    for (const QualityResult& r : quality_results) {
      if (r.job.forget) continue;
      quality_computed[r.job.hand.value] = r.computed;
      auto it = hands.find(r.job.hand.value);
      if (it != hands.end()) {
        if (r.metrics) it->second.controller->set_grasp_metrics(r.job.grasp, *r.metrics);
        it->second.controller->set_quality(r.job.grasp, r.quality, r.job.grasp_tick);
      }
      if (r.job.grasp_tick)  // this step's own grasp event (quality_delay_ticks 0)
        for (GraspEvent& e : events)
          if (e.quality_job == r.job.id && r.metrics) e.metrics = *r.metrics;
    }
  }

  // A held object follows its holder exactly, or both holders (two_hand_hold.h), who then hold it
  // where it is.
  void follow_holders(Object& o) {
    HandController& first = *hand(o.holders.front()).controller;
    const auto X_WorldAlone = first.grasped_object_pose();
    assert(X_WorldAlone);
    if (o.holders.size() == 1) {
      place(o, to_bt(*X_WorldAlone));
      return;
    }
    HandController& second = *hand(o.holders[1]).controller;
    const Eigen::Isometry3d& X_WorldPalm1 = first.state().X_WorldPalm;
    const Eigen::Isometry3d& X_WorldPalm2 = second.state().X_WorldPalm;
    if (!o.shared)
      o.shared = start_two_hand_hold(X_WorldPalm1, first.rig().palm_contact().p_PalmCenter, X_WorldPalm2,
                                     second.rig().palm_contact().p_PalmCenter, *X_WorldAlone);
    place(o, to_bt(two_hand_object_pose(*o.shared, X_WorldPalm1, X_WorldPalm2)));
    const Eigen::Isometry3d X_WorldObject = to_eigen(o.body->getWorldTransform());
    first.reattach(X_WorldObject);
    second.reattach(X_WorldObject);
  }
};

World::World(WorldSettings settings) : impl_(std::make_unique<Impl>()) {
  if (!(settings.dt > 0)) throw std::invalid_argument("WorldSettings.dt must be > 0");
  if (settings.quality_delay_ticks < 0) throw std::invalid_argument("WorldSettings.quality_delay_ticks must be >= 0");
  impl_->settings = settings;
  impl_->quality = std::make_unique<QualityWorker>(settings.quality_delay_ticks > 0);
  // The hands keep out of the table too (unless the caller gave them a table of their own).
  if (!(settings.grasp.table_half_extent > 0)) impl_->settings.grasp.table_half_extent = settings.table_half_extent;
  impl_->dynamics.setGravity(to_bt(settings.gravity));
  if (!(settings.table_half_extent > 0)) throw std::invalid_argument("WorldSettings.table_half_extent must be > 0");
  impl_->table_shape =
      std::make_unique<btBoxShape>(btVector3(settings.table_half_extent, settings.table_half_extent, 0.05));
  btRigidBody::btRigidBodyConstructionInfo info(0, nullptr, impl_->table_shape.get());
  info.m_friction = 0.8;
  impl_->table = std::make_unique<btRigidBody>(info);
  impl_->table->setWorldTransform(btTransform(btQuaternion::getIdentity(), btVector3(0, 0, -0.05)));
  impl_->dynamics.addRigidBody(impl_->table.get());
}

World::~World() {
  for (auto& [id, o] : impl_->objects) impl_->dynamics.removeRigidBody(o.body.get());
  impl_->dynamics.removeRigidBody(impl_->table.get());
}

ObjectId World::add_object(ObjectModelPtr model, const Eigen::Isometry3d& X_WorldObject) {
  Impl::Object o;
  // Dynamics use the convex hull of the mesh; fingers use the exact mesh.
  btConvexHullComputer hull;
  std::vector<double> coords;
  coords.reserve(model->mesh.vertices.size() * 3);
  for (const auto& v : model->mesh.vertices) coords.insert(coords.end(), {v.x(), v.y(), v.z()});
  hull.compute(coords.data(), 3 * sizeof(double), static_cast<int>(model->mesh.vertices.size()), 0, 0);
  o.shape = std::make_unique<btConvexHullShape>();
  for (int i = 0; i < hull.vertices.size(); ++i) o.shape->addPoint(hull.vertices[i], false);
  o.shape->recalcLocalAabb();
  o.shape->setMargin(kHullMargin);
  const Eigen::Matrix3d& I = model->mass_properties.inertia_per_density;
  const double density = model->mass_kg / model->mass_properties.volume;
  const btVector3 inertia(I(0, 0) * density, I(1, 1) * density, I(2, 2) * density);
  o.motion = std::make_unique<btDefaultMotionState>(to_bt(X_WorldObject));
  btRigidBody::btRigidBodyConstructionInfo info(btScalar(model->mass_kg), o.motion.get(), o.shape.get(), inertia);
  info.m_friction = 0.8;
  info.m_rollingFriction = 0.001;
  info.m_spinningFriction = 0.001;
  o.body = std::make_unique<btRigidBody>(info);
  o.model = std::move(model);
  impl_->dynamics.addRigidBody(o.body.get());
  const ObjectId id(impl_->next_object++);
  impl_->objects.emplace(id.value, std::move(o));
  return id;
}

void World::remove_object(ObjectId id) {
  auto it = impl_->objects.find(id.value);
  if (it == impl_->objects.end()) return;
  for (HandId holder : it->second.holders) {
    impl_->hand(holder).controller->release();
    impl_->pend_release(holder, id);
  }
  impl_->dynamics.removeRigidBody(it->second.body.get());
  impl_->objects.erase(it);
}

bool World::place_object(ObjectId id, const Eigen::Isometry3d& X_WorldObject) {
  auto it = impl_->objects.find(id.value);
  if (it == impl_->objects.end() || !it->second.holders.empty()) return false;
  Impl::Object& o = it->second;
  Impl::place(o, to_bt(X_WorldObject));
  o.body->setLinearVelocity(btVector3(0, 0, 0));
  o.body->setAngularVelocity(btVector3(0, 0, 0));
  o.body->activate(true);
  return true;
}

Eigen::Isometry3d World::resting_pose(const ObjectModel& model, double x, double y, double yaw) {
  Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
  X.linear() = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  X.translation() = Eigen::Vector3d(x, y, -model.p_ObjectMin.z() + kHullMargin);
  return X;
}

HandId World::add_hand(std::shared_ptr<const HandRig> rig) {
  const HandId id(impl_->next_hand++);
  auto controller = std::make_unique<HandController>(std::move(rig), impl_->settings.grasp);
  controller->defer_grasp_metrics();  // the QualityWorker takes them (Impl::on_grasp)
  impl_->hands.emplace(id.value, Impl::Hand{std::move(controller), {}});
  return id;
}

void World::remove_hand(HandId id) {
  auto it = impl_->hands.find(id.value);
  if (it == impl_->hands.end()) return;
  const ObjectId held = it->second.controller->release();
  if (held.valid()) {
    Impl::Object& o = impl_->object(held);
    if (o.held_by(id)) {
      o.forget(id);
      if (o.holders.empty()) {
        // Dropped where it is, at rest: physics takes it from here.
        impl_->make_kinematic(o, false);
        o.body->setLinearVelocity(btVector3(0, 0, 0));
        o.body->setAngularVelocity(btVector3(0, 0, 0));
      }
      impl_->pend_release(id, held);
    }
  }
  impl_->hands.erase(it);
  // The worker forgets the hand's memo in order with its jobs; what it still computes for the
  // hand is delivered to nobody.
  if (impl_->quality_asked.erase(id.value) > 0) {
    QualityJob forget;
    forget.id = impl_->next_job++;
    forget.hand = id;
    forget.tick = impl_->tick;
    forget.forget = true;
    impl_->quality_due.emplace_back(impl_->tick, forget.id);
    impl_->quality->submit(std::move(forget));
  }
  impl_->quality_computed.erase(id.value);
}

std::string World::set_input(HandId hand, const ControllerInput& input) {
  Impl::Hand& h = impl_->hand(hand);
  std::string why = validate_input(input, h.controller->rig());
  if (why.empty()) h.input = input;
  return why;
}

void World::step() {
  Impl& w = *impl_;
  w.events = std::move(w.pending);
  w.pending.clear();
  const double dt = w.settings.dt;
  std::vector<ObjectView> views;
  views.reserve(w.objects.size());
  for (auto& [id, o] : w.objects) views.push_back({ObjectId(id), to_eigen(o.body->getWorldTransform()), o.model.get()});

  for (auto& [h, hand_entry] : w.hands) {
    HandController& hand = *hand_entry.controller;
    const HandTickEvents ev = hand.tick(hand_entry.input, dt, views);
    if (ev.released) w.on_release(HandId(h), hand, ev);
    if (ev.grasped) w.on_grasp(HandId(h), hand);
  }
  for (auto& [id, o] : w.objects)
    if (!o.holders.empty()) w.follow_holders(o);
  w.ask_qualities(w.tick + 1);
  w.dynamics.stepSimulation(btScalar(dt), 1, btScalar(dt));
  ++w.tick;
  w.deliver_qualities(w.tick);
}

double World::dt() const { return impl_->settings.dt; }
double World::time() const { return static_cast<double>(impl_->tick) * impl_->settings.dt; }
std::uint64_t World::tick() const { return impl_->tick; }

std::vector<ObjectId> World::objects() const {
  std::vector<ObjectId> out;
  for (const auto& [id, o] : impl_->objects) out.emplace_back(id);
  return out;
}

bool World::has_object(ObjectId id) const { return impl_->objects.count(id.value) > 0; }

std::vector<HandId> World::hands() const {
  std::vector<HandId> out;
  for (const auto& [id, h] : impl_->hands) out.emplace_back(id);
  return out;
}

const ObjectModel& World::object_model(ObjectId id) const { return *impl_->object(id).model; }
Eigen::Isometry3d World::object_pose(ObjectId id) const {
  return to_eigen(impl_->object(id).body->getWorldTransform());
}
Eigen::Vector3d World::object_velocity(ObjectId id) const {
  return to_eigen(impl_->object(id).body->getLinearVelocity());
}
HandId World::holder(ObjectId id) const {
  const std::vector<HandId>& holders = impl_->object(id).holders;
  return holders.empty() ? HandId() : holders.front();
}
std::vector<HandId> World::holders(ObjectId id) const { return impl_->object(id).holders; }
const HandController& World::hand(HandId id) const { return *impl_->hand(id).controller; }
const std::vector<GraspEvent>& World::events() const { return impl_->events; }
const std::vector<QualityResult>& World::quality_results() const { return impl_->quality_results; }
std::uint64_t World::quality_late() const { return impl_->quality_late; }
std::uint64_t World::quality_computations(HandId hand) const {
  auto it = impl_->quality_computed.find(hand.value);
  return it == impl_->quality_computed.end() ? 0 : it->second;
}

}  // namespace telegrasp::sim
