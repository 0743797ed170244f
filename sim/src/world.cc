// The physics scene: Bullet rigid bodies for the table and objects, and the hands.
#include "telegrasp/sim/world.h"

#include <btBulletDynamicsCommon.h>
#include <LinearMath/btConvexHullComputer.h>

#include <algorithm>
#include <cassert>
#include <map>
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

struct World::Impl {
  struct Object {
    ObjectModelPtr model;
    std::unique_ptr<btConvexHullShape> shape;
    std::unique_ptr<btDefaultMotionState> motion;
    std::unique_ptr<btRigidBody> body;
    HandId holder;
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
};

World::World(WorldSettings settings) : impl_(std::make_unique<Impl>()) {
  if (!(settings.dt > 0)) throw std::invalid_argument("WorldSettings.dt must be > 0");
  impl_->settings = settings;
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
  if (it->second.holder.valid()) {
    impl_->hand(it->second.holder).controller->release();
    impl_->pend_release(it->second.holder, id);
  }
  impl_->dynamics.removeRigidBody(it->second.body.get());
  impl_->objects.erase(it);
}

bool World::place_object(ObjectId id, const Eigen::Isometry3d& X_WorldObject) {
  auto it = impl_->objects.find(id.value);
  if (it == impl_->objects.end() || it->second.holder.valid()) return false;
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
  impl_->hands.emplace(id.value,
                       Impl::Hand{std::make_unique<HandController>(std::move(rig), impl_->settings.grasp), {}});
  return id;
}

void World::remove_hand(HandId id) {
  auto it = impl_->hands.find(id.value);
  if (it == impl_->hands.end()) return;
  const ObjectId held = it->second.controller->release();
  if (held.valid()) {
    Impl::Object& o = impl_->object(held);
    if (o.holder == id) {
      // Dropped where it is, at rest: physics takes it from here.
      o.holder = HandId();
      impl_->make_kinematic(o, false);
      o.body->setLinearVelocity(btVector3(0, 0, 0));
      o.body->setAngularVelocity(btVector3(0, 0, 0));
      impl_->pend_release(id, held);
    }
  }
  impl_->hands.erase(it);
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
  const double now = static_cast<double>(w.tick + 1) * dt;
  std::vector<ObjectView> views;
  views.reserve(w.objects.size());
  for (auto& [id, o] : w.objects) views.push_back({ObjectId(id), to_eigen(o.body->getWorldTransform()), o.model.get()});

  for (auto& [h, hand_entry] : w.hands) {
    HandController& hand = *hand_entry.controller;
    const HandId hand_id(h);
    const HandTickEvents ev = hand.tick(hand_entry.input, dt, views);
    if (ev.released) {
      auto it = w.objects.find(ev.released_object.value);
      if (it != w.objects.end() && it->second.holder == hand_id) {
        Impl::Object& o = it->second;
        o.holder = HandId();
        // Let go where the hand holds it now, with the hand's motion: v = v_palm + w x (p_object - p_palm).
        Impl::place(o, to_bt(ev.X_WorldReleased));
        w.make_kinematic(o, false);
        const HandState& s = hand.state();
        const Eigen::Vector3d r = ev.X_WorldReleased.translation() - s.X_WorldPalm.translation();
        const Eigen::Vector3d v = s.v_WorldPalm + s.w_WorldPalm.cross(r);
        o.body->setLinearVelocity(to_bt(v));
        o.body->setAngularVelocity(to_bt(s.w_WorldPalm));
        GraspEvent e{
            GraspEvent::Kind::kRelease, hand_id, ev.released_object, w.tick + 1, now, {}, {}, v, s.w_WorldPalm};
        w.events.push_back(std::move(e));
      }
    }
    if (ev.grasped) {
      const ObjectId oid = hand.state().grasped;
      Impl::Object& o = w.object(oid);
      // Hand-to-hand takeover: the newest grasp wins, the previous holder lets go.
      if (o.holder.valid() && o.holder != hand_id) {
        w.hand(o.holder).controller->release();
        GraspEvent e{GraspEvent::Kind::kRelease, o.holder, oid, w.tick + 1, now, {}, {}, {0, 0, 0}, {0, 0, 0}};
        w.events.push_back(std::move(e));
      }
      o.holder = hand_id;
      w.make_kinematic(o, true);
      GraspEvent e{GraspEvent::Kind::kGrasp, hand_id,         oid,       w.tick + 1, now,
                   hand.grasp_metrics(),     hand.contacts(), {0, 0, 0}, {0, 0, 0}};
      w.events.push_back(std::move(e));
    }
  }
  // Held objects follow their hands exactly.
  for (auto& [id, o] : w.objects) {
    if (!o.holder.valid()) continue;
    const auto pose = w.hand(o.holder).controller->grasped_object_pose();
    assert(pose);
    Impl::place(o, to_bt(*pose));
  }
  w.dynamics.stepSimulation(btScalar(dt), 1, btScalar(dt));
  ++w.tick;
}

double World::dt() const { return impl_->settings.dt; }
double World::time() const { return static_cast<double>(impl_->tick) * impl_->settings.dt; }
std::uint64_t World::tick() const { return impl_->tick; }

std::vector<ObjectId> World::objects() const {
  std::vector<ObjectId> out;
  for (const auto& [id, o] : impl_->objects) out.emplace_back(id);
  return out;
}

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
HandId World::holder(ObjectId id) const { return impl_->object(id).holder; }
const HandController& World::hand(HandId id) const { return *impl_->hand(id).controller; }
const std::vector<GraspEvent>& World::events() const { return impl_->events; }

}  // namespace telegrasp::sim
