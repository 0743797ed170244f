// Tests client_lib/src/conversions.{h,cc}: every client type survives client -> IDL -> client,
// and a few fields are checked against a hand-written IDL message (quaternion order, hand sides,
// enum values), so a swapped field cannot round-trip unnoticed.
#include "conversions.h"

#include "telegrasp/idl/geometry_hash.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <numbers>

namespace telegrasp::client_lib {
namespace {

namespace client = telegrasp::client;

// Rotations go matrix -> quaternion -> matrix: equal up to rounding.
constexpr double kRotationTolerance = 1e-12;

Eigen::Isometry3d make_pose(double angle, const Eigen::Vector3d& axis, const Eigen::Vector3d& p) {
  Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
  X.linear() = Eigen::AngleAxisd(angle, axis.normalized()).toRotationMatrix();
  X.translation() = p;
  return X;
}

void expect_same_pose(const Eigen::Isometry3d& expected, const Eigen::Isometry3d& actual) {
  EXPECT_EQ(expected.translation(), actual.translation());  // copied, not computed
  EXPECT_LT((expected.linear() - actual.linear()).cwiseAbs().maxCoeff(), kRotationTolerance)
      << "expected\n"
      << expected.linear() << "\nactual\n"
      << actual.linear();
}

void expect_same(const client::HandKey& a, const client::HandKey& b) {
  EXPECT_EQ(a.client_id, b.client_id);
  EXPECT_EQ(a.side, b.side);
}

void expect_same(const client::ContactPoint& a, const client::ContactPoint& b) {
  EXPECT_EQ(a.phalanx, b.phalanx);
  EXPECT_EQ(a.p_WorldContact, b.p_WorldContact);
  EXPECT_EQ(a.n_World, b.n_World);
  EXPECT_EQ(a.p_ObjectContact, b.p_ObjectContact);
  EXPECT_EQ(a.n_Object, b.n_Object);
  EXPECT_EQ(a.nd, b.nd);
  EXPECT_EQ(a.nd_hit, b.nd_hit);
}

void expect_same(const client::CapsuleMetric& a, const client::CapsuleMetric& b) {
  EXPECT_EQ(a.phalanx, b.phalanx);
  EXPECT_EQ(a.phalanx_name, b.phalanx_name);
  EXPECT_EQ(a.hit, b.hit);
  EXPECT_EQ(a.nd, b.nd);
  EXPECT_EQ(a.signed_distance, b.signed_distance);
  EXPECT_EQ(a.blocked, b.blocked);
  EXPECT_EQ(a.contact_hit, b.contact_hit);
  EXPECT_EQ(a.nd_contact, b.nd_contact);
}

void expect_same(const client::ObjectState& a, const client::ObjectState& b) {
  EXPECT_EQ(a.id, b.id);
  EXPECT_EQ(a.name, b.name);
  expect_same_pose(a.X_WorldObject, b.X_WorldObject);
  EXPECT_EQ(a.v_WorldObject, b.v_WorldObject);
  EXPECT_EQ(a.held, b.held);
  expect_same(a.holder, b.holder);
  ASSERT_EQ(a.holders.size(), b.holders.size());
  for (std::size_t i = 0; i < a.holders.size(); ++i) expect_same(a.holders[i], b.holders[i]);
  EXPECT_EQ(a.spawn_time, b.spawn_time);
}

template <class T>
void expect_same_each(const std::vector<T>& a, const std::vector<T>& b) {
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size(); ++i) {
    SCOPED_TRACE(i);
    expect_same(a[i], b[i]);
  }
}

client::ContactPoint make_contact(int phalanx, double s) {
  client::ContactPoint c;
  c.phalanx = phalanx;
  c.p_WorldContact = {0.41 * s, -0.02, 0.13};
  c.n_World = Eigen::Vector3d(0.2, -0.9, 0.1 * s).normalized();
  c.p_ObjectContact = {0.01, 0.035 * s, -0.004};
  c.n_Object = Eigen::Vector3d(-0.3, 0.5, 0.8).normalized();
  c.nd = -0.0015 * s;
  c.nd_hit = phalanx % 2 == 0;
  return c;
}

// ---------------------------------------------------------------------------------------------
// Field mappings checked by hand.

TEST(ConversionsTest, QuaternionIsSentInWxyzOrder) {
  // 90 degrees about z: q = (cos 45, 0, 0, sin 45).
  const Eigen::Isometry3d X_WorldPalm = make_pose(std::numbers::pi / 2, Eigen::Vector3d::UnitZ(), {1, 2, 3});
  const msg::Pose3 m = to_msg(X_WorldPalm);
  EXPECT_NEAR(m.orientation().w(), std::sqrt(0.5), 1e-15);
  EXPECT_NEAR(m.orientation().x(), 0, 1e-15);
  EXPECT_NEAR(m.orientation().y(), 0, 1e-15);
  EXPECT_NEAR(m.orientation().z(), std::sqrt(0.5), 1e-15);
  EXPECT_EQ(m.position().x(), 1);
  EXPECT_EQ(m.position().y(), 2);
  EXPECT_EQ(m.position().z(), 3);
}

TEST(ConversionsTest, ReceivedQuaternionIsReadInWxyzOrder) {
  // (w, x, y, z) = (0, 1, 0, 0): half a turn about x, which maps y to -y and z to -z.
  msg::Pose3 m;
  m.orientation().w(0);
  m.orientation().x(1);
  m.orientation().y(0);
  m.orientation().z(0);
  const Eigen::Isometry3d X = from_msg(m);
  EXPECT_LT((X.linear() - Eigen::Vector3d(1, -1, -1).asDiagonal().toDenseMatrix()).cwiseAbs().maxCoeff(), 1e-15);
}

TEST(ConversionsTest, ReceivedQuaternionIsNormalized) {
  msg::Pose3 m;
  m.orientation().w(2);  // twice the identity
  EXPECT_TRUE(from_msg(m).linear().isIdentity(1e-15));
}

TEST(ConversionsTest, HandSidesMatchTheIdlConstants) {
  EXPECT_EQ(to_msg_side(client::HandSide::kLeft), msg::HAND_LEFT);
  EXPECT_EQ(to_msg_side(client::HandSide::kRight), msg::HAND_RIGHT);
  EXPECT_EQ(from_msg_side(msg::HAND_LEFT), client::HandSide::kLeft);
  EXPECT_EQ(from_msg_side(msg::HAND_RIGHT), client::HandSide::kRight);
  // An unknown side passes both ways unchanged: the server, not the client, rejects it.
  EXPECT_EQ(to_msg_side(static_cast<client::HandSide>(7)), 7);
  EXPECT_EQ(from_msg_side(7), static_cast<client::HandSide>(7));
  EXPECT_EQ(client::to_string(static_cast<client::HandSide>(7)), "side7");
  EXPECT_EQ(client::to_string(client::HandSide::kLeft), "left");
}

TEST(ConversionsTest, EnumsMatchTheIdlValues) {
  EXPECT_EQ(to_msg(client::GraspEvent::Kind::kGrasp), msg::GRASP_EVENT_GRASP);
  EXPECT_EQ(to_msg(client::GraspEvent::Kind::kRelease), msg::GRASP_EVENT_RELEASE);
  EXPECT_EQ(to_msg(client::SceneCommand::Kind::kSpawn), msg::SCENE_SPAWN);
  EXPECT_EQ(to_msg(client::SceneCommand::Kind::kRemove), msg::SCENE_REMOVE);
  EXPECT_EQ(to_msg(client::SceneCommand::Kind::kReset), msg::SCENE_RESET);
  for (auto kind : {client::GraspEvent::Kind::kGrasp, client::GraspEvent::Kind::kRelease})
    EXPECT_EQ(from_msg(to_msg(kind)), kind);
  for (auto kind :
       {client::SceneCommand::Kind::kSpawn, client::SceneCommand::Kind::kRemove, client::SceneCommand::Kind::kReset})
    EXPECT_EQ(from_msg(to_msg(kind)), kind);
}

// Invalid values reach the wire unchanged: the server's validation is tested through the client.
TEST(ConversionsTest, ControllerStateKeepsInvalidValues) {
  client::ControllerSample s;
  s.side = static_cast<client::HandSide>(7);
  s.X_WorldPalm.translation().x() = std::numeric_limits<double>::quiet_NaN();
  s.X_WorldPalm.linear() *= 0.5;  // not a rotation
  s.trigger = 5;
  s.curls = {0.5, 2.0};
  s.sequence_number = 3;
  const msg::ControllerState m = to_msg(s, "eve");
  EXPECT_EQ(m.hand_side(), 7);
  EXPECT_TRUE(std::isnan(m.palm().position().x()));
  const msg::Quat& q = m.palm().orientation();
  EXPECT_GT(std::abs(std::sqrt(q.w() * q.w() + q.x() * q.x() + q.y() * q.y() + q.z() * q.z()) - 1), 0.1);
  EXPECT_EQ(m.trigger(), 5);
  EXPECT_EQ(m.curls(), (std::vector<double>{0.5, 2.0}));
  EXPECT_EQ(m.sequence_number(), 3u);
}

// ---------------------------------------------------------------------------------------------
// Round trips: client -> IDL -> client gives the original.

TEST(ConversionsTest, Vec3RoundTrip) {
  const Eigen::Vector3d v(0.125, -3.5, 1e-9);
  EXPECT_EQ(from_msg(to_msg(v)), v);
  const msg::Vec3 m = to_msg(v);
  EXPECT_EQ(m.x(), 0.125);
  EXPECT_EQ(m.y(), -3.5);
  EXPECT_EQ(m.z(), 1e-9);
}

TEST(ConversionsTest, PoseRoundTrip) {
  const Eigen::Isometry3d X_WorldPalm = make_pose(2.1, {1, -2, 0.5}, {0.3, -0.45, 0.92});
  expect_same_pose(X_WorldPalm, from_msg(to_msg(X_WorldPalm)));
  // Near a half turn too, where w is close to 0.
  const Eigen::Isometry3d X_WorldObject = make_pose(std::numbers::pi - 1e-6, {0, 1, 1}, {-1, 0, 0});
  expect_same_pose(X_WorldObject, from_msg(to_msg(X_WorldObject)));
}

TEST(ConversionsTest, ControllerSampleRoundTrip) {
  client::ControllerSample s;
  s.side = client::HandSide::kLeft;
  s.X_WorldPalm = make_pose(0.7, {0.3, 1, -0.2}, {0.1, -0.3, 0.85});
  s.trigger = 0.625;
  s.curls = {0.1, 0.2, 0.3, 0.4, 0.5};
  s.buttons = msg::BUTTON_GRIP | msg::BUTTON_MENU;
  s.tracking_valid = false;
  s.sequence_number = 123456789012ull;
  s.client_time_ns = -42;
  const msg::ControllerState m = to_msg(s, "robot-7");
  EXPECT_EQ(m.client_id().to_string(), "robot-7");
  EXPECT_EQ(m.hand_side(), msg::HAND_LEFT);
  const client::ControllerSample r = from_msg(m);
  EXPECT_EQ(r.side, s.side);
  expect_same_pose(s.X_WorldPalm, r.X_WorldPalm);
  EXPECT_EQ(r.trigger, s.trigger);
  EXPECT_EQ(r.curls, s.curls);
  EXPECT_EQ(r.buttons, s.buttons);
  EXPECT_EQ(r.tracking_valid, s.tracking_valid);
  EXPECT_EQ(r.sequence_number, s.sequence_number);
  EXPECT_EQ(r.client_time_ns, s.client_time_ns);
}

TEST(ConversionsTest, HandSkeletonRoundTrip) {
  client::HandSkeleton s;
  s.hand = {"viewer-3", client::HandSide::kLeft};
  s.rig = "mano_left";
  s.tick = 9001;
  s.time = 100.0125;
  s.input_sequence = 77;
  s.input_client_time_ns = 1'234'567'890'123;
  s.late_latched = true;
  s.frozen = true;
  s.X_WorldPalm = make_pose(0.4, {1, 1, 0}, {0.2, 0.1, 0.9});
  for (int i = 0; i < 15; ++i)
    s.X_WorldPhalanx.push_back(make_pose(0.1 * i, {1, 0.1 * i, 0.3}, {0.01 * i, 0.02, -0.03 * i}));
  s.joint_angles = {0.1, -0.2, 0.3, 1.5, 0.0};
  s.X_WorldTracked = make_pose(0.3, {1, 0, 1}, {0.2, 0.1, 0.85});
  s.resolve_offset = {0, 0, 0.05};
  s.resolve_angle = 0.1;
  const msg::HandSkeleton m = to_msg(s);
  EXPECT_EQ(m.client_id().to_string(), "viewer-3");
  EXPECT_EQ(m.phalanges().size(), 15u);
  const client::HandSkeleton r = from_msg(m);
  expect_same(r.hand, s.hand);
  EXPECT_EQ(r.rig, s.rig);
  EXPECT_EQ(r.tick, s.tick);
  EXPECT_EQ(r.time, s.time);
  EXPECT_EQ(r.input_sequence, s.input_sequence);
  EXPECT_EQ(r.input_client_time_ns, s.input_client_time_ns);
  EXPECT_EQ(r.late_latched, s.late_latched);
  EXPECT_EQ(r.frozen, s.frozen);
  expect_same_pose(s.X_WorldPalm, r.X_WorldPalm);
  ASSERT_EQ(r.X_WorldPhalanx.size(), s.X_WorldPhalanx.size());
  for (std::size_t i = 0; i < s.X_WorldPhalanx.size(); ++i) expect_same_pose(s.X_WorldPhalanx[i], r.X_WorldPhalanx[i]);
  EXPECT_EQ(r.joint_angles, s.joint_angles);
  expect_same_pose(s.X_WorldTracked, r.X_WorldTracked);
  EXPECT_EQ(r.resolve_offset, s.resolve_offset);
  EXPECT_EQ(r.resolve_angle, s.resolve_angle);
}

TEST(ConversionsTest, GraspStateRoundTrip) {
  client::GraspState s;
  s.hand = {"alice", client::HandSide::kRight};
  s.tick = 12;
  s.time = 0.1;
  s.selected_object = 4;
  s.grasped_object = -1;
  s.trigger = 0.875;
  s.blocked = {true, false, false, true, true, false};
  s.palm_contact = true;
  s.epsilon = 0.0625;
  s.volume = 0.125;
  s.force_closure = true;
  s.grasp_type = "power_sphere";
  const client::GraspState r = from_msg(to_msg(s));
  expect_same(r.hand, s.hand);
  EXPECT_EQ(r.tick, s.tick);
  EXPECT_EQ(r.time, s.time);
  EXPECT_EQ(r.selected_object, s.selected_object);
  EXPECT_EQ(r.grasped_object, s.grasped_object);
  EXPECT_EQ(r.trigger, s.trigger);
  EXPECT_EQ(r.blocked, s.blocked);
  EXPECT_EQ(r.palm_contact, s.palm_contact);
  EXPECT_EQ(r.epsilon, s.epsilon);
  EXPECT_EQ(r.volume, s.volume);
  EXPECT_EQ(r.force_closure, s.force_closure);
  EXPECT_EQ(r.grasp_type, "power_sphere");
}

TEST(ConversionsTest, ContactSetRoundTrip) {
  client::ContactSet s;
  s.hand = {"bob", client::HandSide::kLeft};
  s.tick = 5;
  s.time = 2.5;
  s.object_id = 17;
  s.X_WorldObject = make_pose(-1.2, {0, 0, 1}, {0.5, 0.05, 0.8});
  s.contacts = {make_contact(-1, 1), make_contact(3, 2), make_contact(14, 3)};
  const msg::ContactSet m = to_msg(s);
  EXPECT_EQ(m.contacts().at(0).phalanx(), -1);  // the palm
  const client::ContactSet r = from_msg(m);
  expect_same(r.hand, s.hand);
  EXPECT_EQ(r.tick, s.tick);
  EXPECT_EQ(r.time, s.time);
  EXPECT_EQ(r.object_id, s.object_id);
  expect_same_pose(s.X_WorldObject, r.X_WorldObject);
  expect_same_each(s.contacts, r.contacts);
}

TEST(ConversionsTest, ContactPointMapsFramesToTheirFields) {
  const client::ContactPoint c = make_contact(2, 1);
  const msg::ContactPoint m = to_msg(c);
  EXPECT_EQ(from_msg(m.p_world()), c.p_WorldContact);
  EXPECT_EQ(from_msg(m.n_world()), c.n_World);
  EXPECT_EQ(from_msg(m.p_object()), c.p_ObjectContact);
  EXPECT_EQ(from_msg(m.n_object()), c.n_Object);
  expect_same(c, from_msg(m));
}

TEST(ConversionsTest, GraspEventRoundTrip) {
  for (auto kind : {client::GraspEvent::Kind::kGrasp, client::GraspEvent::Kind::kRelease}) {
    client::GraspEvent e;
    e.event_id = 31;
    e.kind = kind;
    e.hand = {"bot-a", client::HandSide::kRight};
    e.object_id = 3;
    e.object_name = "003_cracker_box";
    e.tick = 4000;
    e.time = 44.4;
    e.object_spawn_time = 1.5;
    e.X_WorldObject = make_pose(0.9, {0.2, 0.3, 1}, {0.45, 0.0, 0.81});
    e.input_sequence = 3999;
    e.hand_error_mm = 2.75;
    e.capsules_without_hit = 2;
    for (int i = 0; i < 4; ++i)
      e.capsules.push_back(
          {i, "index_" + std::to_string(i), i != 2, 0.001 * i, -0.0005 * i, i % 2 == 1, i % 2 == 1, 0.00001 * i});
    e.palm_signed_distance = -0.00025;
    e.epsilon = 0.03125;
    e.volume = 0.5;
    e.force_closure = true;
    e.grasp_type = "lateral_pinch";
    e.contacts = {make_contact(0, 1), make_contact(5, -1)};
    e.v_WorldObject = {0.1, -0.2, 0.3};
    e.w_WorldObject = {-1, 2, 0.5};
    const client::GraspEvent r = from_msg(to_msg(e));
    EXPECT_EQ(r.event_id, e.event_id);
    EXPECT_EQ(r.kind, e.kind);
    expect_same(r.hand, e.hand);
    EXPECT_EQ(r.object_id, e.object_id);
    EXPECT_EQ(r.object_name, e.object_name);
    EXPECT_EQ(r.tick, e.tick);
    EXPECT_EQ(r.time, e.time);
    EXPECT_EQ(r.object_spawn_time, e.object_spawn_time);
    expect_same_pose(e.X_WorldObject, r.X_WorldObject);
    EXPECT_EQ(r.input_sequence, e.input_sequence);
    EXPECT_EQ(r.hand_error_mm, e.hand_error_mm);
    EXPECT_EQ(r.capsules_without_hit, e.capsules_without_hit);
    expect_same_each(e.capsules, r.capsules);
    expect_same_each(e.contacts, r.contacts);
    EXPECT_EQ(r.palm_signed_distance, e.palm_signed_distance);
    EXPECT_EQ(r.epsilon, e.epsilon);
    EXPECT_EQ(r.volume, e.volume);
    EXPECT_EQ(r.force_closure, e.force_closure);
    EXPECT_EQ(r.grasp_type, e.grasp_type);
    EXPECT_EQ(r.v_WorldObject, e.v_WorldObject);
    EXPECT_EQ(r.w_WorldObject, e.w_WorldObject);
  }
}

TEST(ConversionsTest, GraspEventMapsReleaseVelocities) {
  client::GraspEvent e;
  e.v_WorldObject = {1, 2, 3};
  e.w_WorldObject = {4, 5, 6};
  const msg::GraspEvent m = to_msg(e);
  EXPECT_EQ(m.release_velocity().y(), 2);
  EXPECT_EQ(m.release_angular_velocity().z(), 6);
}

TEST(ConversionsTest, SceneStateRoundTrip) {
  client::SceneState s;
  s.tick = 77;
  s.time = 0.77;
  s.incarnation = 0xF00DFACE12345678ULL;
  for (int i = 0; i < 3; ++i) {
    client::ObjectState o;
    o.id = 10 + i;
    o.name = "object_" + std::to_string(i);
    o.X_WorldObject = make_pose(0.3 * (i + 1), {i + 1.0, 1, 0}, {0.1 * i, 0.2, 0.75});
    o.v_WorldObject = {0.01 * i, 0, -0.5};
    o.held = i == 1;
    o.holder = i == 1 ? client::HandKey{"carol", client::HandSide::kLeft} : client::HandKey{};
    if (i == 1) o.holders = {o.holder, client::HandKey{"dave", client::HandSide::kRight}};
    o.spawn_time = 0.25 * i;
    s.objects.push_back(o);
  }
  const msg::SceneState m = to_msg(s);
  EXPECT_EQ(m.objects().at(1).holder_client().to_string(), "carol");
  EXPECT_EQ(m.objects().at(1).holder_hand(), msg::HAND_LEFT);
  ASSERT_EQ(m.objects().at(1).holders().size(), 2u);
  EXPECT_EQ(m.objects().at(1).holders().at(1).client_id().to_string(), "dave");
  EXPECT_EQ(m.objects().at(1).holders().at(1).hand_side(), msg::HAND_RIGHT);
  const client::SceneState r = from_msg(m);
  EXPECT_EQ(r.tick, s.tick);
  EXPECT_EQ(r.time, s.time);
  EXPECT_EQ(m.incarnation(), s.incarnation);
  EXPECT_EQ(r.incarnation, s.incarnation);
  expect_same_each(s.objects, r.objects);
}

TEST(ConversionsTest, SceneCommandRoundTrip) {
  client::SceneCommand c;
  c.kind = client::SceneCommand::Kind::kRemove;
  c.model = "011_banana";
  c.object_id = 8;
  c.on_table = false;
  c.x = 0.3;
  c.y = -0.1;
  c.yaw = 1.2;
  c.X_WorldObject = make_pose(0.5, {1, 0, 0}, {0.4, 0.1, 1.1});
  const msg::SceneCommand m = to_msg(c, "operator", 42);
  EXPECT_EQ(m.client_id().to_string(), "operator");
  EXPECT_EQ(m.command_id(), 42u);
  EXPECT_EQ(m.kind(), msg::SCENE_REMOVE);
  const client::SceneCommand r = from_msg(m);
  EXPECT_EQ(r.kind, c.kind);
  EXPECT_EQ(r.model, c.model);
  EXPECT_EQ(r.object_id, c.object_id);
  EXPECT_EQ(r.on_table, c.on_table);
  EXPECT_EQ(r.x, c.x);
  EXPECT_EQ(r.y, c.y);
  EXPECT_EQ(r.yaw, c.yaw);
  expect_same_pose(c.X_WorldObject, r.X_WorldObject);
}

TEST(ConversionsTest, ServerStatusRoundTrip) {
  client::ServerStatus s;
  s.tick = 90000;
  s.time = 1000;
  s.tick_rate_hz = 90;
  s.clients = 3;
  s.hands = 5;
  s.objects = 7;
  s.tick_us_p50 = 410.5;
  s.tick_us_max = 2200.25;
  s.tick_us_p99 = 1900.5;
  s.missed_ticks = 4;
  s.inputs_accepted = 123456;
  s.inputs_rejected = 9;
  s.rejected = {{"non_finite", 2}, {"stale_sequence", 6}, {"unknown_hand_side", 1}};
  s.commands_accepted = 11;
  s.commands_rejected = 2;
  s.models = {"003_cracker_box", "005_tomato_soup_can", "box_5cm"};
  s.incarnation = 0x8000000000000001ULL;
  const msg::ServerStatus m = to_msg(s);
  ASSERT_EQ(m.rejected().size(), 3u);
  EXPECT_EQ(m.rejected()[1].reason().to_string(), "stale_sequence");
  EXPECT_EQ(m.rejected()[1].count(), 6u);
  const client::ServerStatus r = from_msg(m);
  EXPECT_EQ(r.tick, s.tick);
  EXPECT_EQ(r.time, s.time);
  EXPECT_EQ(r.tick_rate_hz, s.tick_rate_hz);
  EXPECT_EQ(r.clients, s.clients);
  EXPECT_EQ(r.hands, s.hands);
  EXPECT_EQ(r.objects, s.objects);
  EXPECT_EQ(r.tick_us_p50, s.tick_us_p50);
  EXPECT_EQ(r.tick_us_max, s.tick_us_max);
  EXPECT_EQ(r.tick_us_p99, s.tick_us_p99);
  EXPECT_EQ(r.missed_ticks, s.missed_ticks);
  EXPECT_EQ(r.inputs_accepted, s.inputs_accepted);
  EXPECT_EQ(r.inputs_rejected, s.inputs_rejected);
  EXPECT_EQ(r.rejected, s.rejected);
  EXPECT_EQ(r.commands_accepted, s.commands_accepted);
  EXPECT_EQ(r.commands_rejected, s.commands_rejected);
  EXPECT_EQ(r.models, s.models);
  EXPECT_EQ(m.incarnation(), s.incarnation);
  EXPECT_EQ(r.incarnation, s.incarnation);
}

// A tetrahedron (4 vertices, 4 triangles) with every field set and its true content hash.
client::ObjectGeometry tetrahedron() {
  client::ObjectGeometry g;
  g.model = "tetra";
  g.vertices = {{0.f, 0.f, 0.f}, {0.1f, 0.f, 0.f}, {0.f, 0.1f, 0.f}, {0.f, 0.f, 0.1f}};
  g.triangles = {{{0, 2, 1}}, {{0, 1, 3}}, {{0, 3, 2}}, {{1, 2, 3}}};
  g.vertex_count = 4;
  g.triangle_count = 4;
  g.p_ObjectMin = {-0.025, -0.025, -0.025};
  g.p_ObjectMax = {0.075, 0.075, 0.075};
  g.mass_kg = 0.25;
  g.volume_m3 = 1.0 / 6000;
  g.inertia_diagonal = {1e-4, 2e-4, 3e-4};
  g.p_ObjectSourceOrigin = {-0.025, -0.025, -0.025};
  const msg::ObjectGeometry m = to_msg(g);
  g.content_hash = idl::geometry_content_hash(m.vertices().data(), 4, m.triangles().data(), 4);
  return g;
}

TEST(ConversionsTest, ObjectGeometryRoundTrip) {
  const client::ObjectGeometry g = tetrahedron();
  const msg::ObjectGeometry m = to_msg(g);
  ASSERT_EQ(m.vertices().size(), 12u);
  EXPECT_EQ(m.vertices()[3], 0.1f) << "x, y, z per vertex, vertex after vertex";
  ASSERT_EQ(m.triangles().size(), 12u);
  EXPECT_EQ(m.triangles()[1], 2u);
  EXPECT_EQ(check_object_geometry(m), "");
  const client::ObjectGeometry r = from_msg(m);
  EXPECT_EQ(r.model, g.model);
  EXPECT_EQ(r.content_hash, g.content_hash);
  EXPECT_EQ(r.vertices, g.vertices);
  EXPECT_EQ(r.triangles, g.triangles);
  EXPECT_EQ(r.vertex_count, g.vertex_count);
  EXPECT_EQ(r.triangle_count, g.triangle_count);
  EXPECT_EQ(r.mesh_omitted, g.mesh_omitted);
  EXPECT_EQ(r.p_ObjectMin, g.p_ObjectMin);
  EXPECT_EQ(r.p_ObjectMax, g.p_ObjectMax);
  EXPECT_EQ(r.mass_kg, g.mass_kg);
  EXPECT_EQ(r.volume_m3, g.volume_m3);
  EXPECT_EQ(r.inertia_diagonal, g.inertia_diagonal);
  EXPECT_EQ(r.p_ObjectSourceOrigin, g.p_ObjectSourceOrigin);
  const client::ObjectGeometry header = from_msg_without_mesh(m);
  EXPECT_TRUE(header.vertices.empty() && header.triangles.empty());
  EXPECT_EQ(header.triangle_count, 4u);
  EXPECT_EQ(header.mass_kg, g.mass_kg);
}

// A received geometry that is cut short, out of range, not finite or not what its hash says is
// refused with the reason.
TEST(ConversionsTest, DamagedObjectGeometryIsRefused) {
  const msg::ObjectGeometry good = to_msg(tetrahedron());
  auto refused = [&](auto&& damage) {
    msg::ObjectGeometry m = good;
    damage(m);
    return check_object_geometry(m);
  };
  EXPECT_NE(refused([](msg::ObjectGeometry& m) { m.vertices().pop_back(); }).find("vertex coordinates"),
            std::string::npos);
  EXPECT_NE(refused([](msg::ObjectGeometry& m) { m.triangle_count(5); }).find("triangle indices"), std::string::npos);
  EXPECT_NE(refused([](msg::ObjectGeometry& m) { m.triangles()[5] = 4; }).find("past the 4 vertices"),
            std::string::npos);
  EXPECT_NE(refused([](msg::ObjectGeometry& m) {
              m.vertices()[7] = std::numeric_limits<float>::quiet_NaN();
            }).find("non-finite"),
            std::string::npos);
  EXPECT_NE(refused([](msg::ObjectGeometry& m) { m.vertices()[7] = 0.2f; }).find("content_hash"), std::string::npos);
  EXPECT_NE(refused([](msg::ObjectGeometry& m) { m.mesh_omitted(true); }).find("mesh_omitted"), std::string::npos);
  // Omitted and empty is whole: there is nothing to check the hash against.
  EXPECT_EQ(refused([](msg::ObjectGeometry& m) {
              m.mesh_omitted(true);
              m.vertices().clear();
              m.triangles().clear();
            }),
            "");
}

}  // namespace
}  // namespace telegrasp::client_lib
