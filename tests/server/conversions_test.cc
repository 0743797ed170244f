// Tests server/src/conversions: sim <-> IDL round trips and hand-checked field mappings.
#include "conversions.h"

#include "telegrasp/idl/geometry_hash.h"
#include "telegrasp/sim/hand_rig.h"
#include "test_scene.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <numbers>
#include <vector>

namespace telegrasp::server {
namespace {

constexpr double kTol = 1e-12;

Eigen::Isometry3d some_pose() {
  Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
  X.linear() = Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, -2, 0.5).normalized()).toRotationMatrix();
  X.translation() = Eigen::Vector3d(0.3, -1.25, 2.5);
  return X;
}

TEST(ConversionsTest, PoseRoundTrips) {
  const Eigen::Isometry3d X = some_pose();
  EXPECT_TRUE(to_eigen(to_msg(X)).isApprox(X, kTol));
}

// A quarter turn about +z is (w, x, y, z) = (cos 45°, 0, 0, sin 45°): the wire order is w first.
TEST(ConversionsTest, QuaternionIsWFirst) {
  Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
  X.linear() = Eigen::AngleAxisd(std::numbers::pi / 2, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  const msg::Pose3 p = to_msg(X);
  EXPECT_NEAR(p.orientation().w(), std::sqrt(0.5), kTol);
  EXPECT_NEAR(p.orientation().x(), 0, kTol);
  EXPECT_NEAR(p.orientation().y(), 0, kTol);
  EXPECT_NEAR(p.orientation().z(), std::sqrt(0.5), kTol);
  // And back: the x axis maps to +y.
  EXPECT_TRUE((to_eigen(p).linear() * Eigen::Vector3d::UnitX()).isApprox(Eigen::Vector3d::UnitY(), kTol));
}

TEST(ConversionsTest, ControllerStateToSimInput) {
  msg::ControllerState s;
  s.palm(to_msg(some_pose()));
  s.trigger(0.25);
  s.curls({0.1, 0.2, 0.3, 0.4, 0.5});
  s.tracking_valid(false);
  const sim::ControllerInput in = to_sim_input(s);
  EXPECT_TRUE(in.X_WorldPalm.isApprox(some_pose(), kTol));
  EXPECT_EQ(in.trigger, 0.25);
  EXPECT_EQ(in.curls, (std::vector<double>{0.1, 0.2, 0.3, 0.4, 0.5}));
  EXPECT_FALSE(in.tracking_valid);
}

TEST(ConversionsTest, ContactRoundTrips) {
  sim::Contact c;
  c.phalanx = sim::PhalanxId(7);
  c.p_WorldContact = {1, 2, 3};
  c.n_World = {0, 0, 1};
  c.p_ObjectContact = {-1, 0.5, 0.25};
  c.n_Object = {1, 0, 0};
  c.nd = -0.0012;
  c.nd_hit = true;
  const sim::Contact back = to_sim(to_msg(c));
  EXPECT_EQ(back.phalanx, c.phalanx);
  EXPECT_EQ(back.p_WorldContact, c.p_WorldContact);
  EXPECT_EQ(back.n_World, c.n_World);
  EXPECT_EQ(back.p_ObjectContact, c.p_ObjectContact);
  EXPECT_EQ(back.n_Object, c.n_Object);
  EXPECT_EQ(back.nd, c.nd);
  EXPECT_EQ(back.nd_hit, c.nd_hit);
  sim::Contact palm;  // the palm's phalanx is the invalid id -1
  EXPECT_EQ(to_msg(palm).phalanx(), -1);
}

// Every phalanx is published in the world frame: X_WorldPhalanx = X_WorldPalm * X_PalmPhalanx; a
// late-latched skeleton moves the whole hand to the new palm pose and keeps the fingers.
TEST(ConversionsTest, SkeletonIsTheHandInTheWorldFrame) {
  auto rig = server::rig("human_right");
  sim::HandController hand(rig, {});
  sim::ControllerInput in;
  in.X_WorldPalm = some_pose();
  in.trigger = 0.5;
  for (int i = 0; i < 10; ++i) hand.tick(in, 1.0 / 90, {});
  const HandAddress address{"alice", 1};
  const msg::HandSkeleton m = make_hand_skeleton(address, hand, 10, 0.11, {42, 99}, false);
  EXPECT_EQ(m.client_id().to_string(), "alice");
  EXPECT_EQ(m.hand_side(), 1);
  EXPECT_EQ(m.rig().to_string(), rig->name());
  EXPECT_EQ(m.input_sequence(), 42u);
  EXPECT_EQ(m.input_client_time_ns(), 99);
  EXPECT_FALSE(m.late_latched());
  ASSERT_EQ(m.phalanges().size(), rig->phalanges().size());
  ASSERT_EQ(m.joint_angles(), hand.state().q);
  for (std::size_t i = 0; i < m.phalanges().size(); ++i)
    EXPECT_TRUE(to_eigen(m.phalanges()[i]).isApprox(some_pose() * hand.state().X_PalmPhalanx[i], 1e-9));
  // Nothing in the way: the tracked pose is the resolved one.
  EXPECT_TRUE(to_eigen(m.tracked_palm()).isApprox(some_pose(), 1e-12));
  EXPECT_EQ(to_eigen(m.resolve_offset()), Eigen::Vector3d::Zero());
  EXPECT_NEAR(m.resolve_angle(), 0.0, 1e-12);

  Eigen::Isometry3d moved = some_pose();
  moved.translation() += Eigen::Vector3d(0.1, 0, 0);
  const msg::HandSkeleton latched = make_hand_skeleton(address, hand, 10, 0.11, {43, 100}, false, &moved);
  EXPECT_TRUE(latched.late_latched());
  EXPECT_TRUE(to_eigen(latched.palm()).isApprox(moved, 1e-12));
  for (std::size_t i = 0; i < latched.phalanges().size(); ++i)
    EXPECT_TRUE(to_eigen(latched.phalanges()[i]).isApprox(moved * hand.state().X_PalmPhalanx[i], 1e-9));
}

// Two hands share an object: the first is in the old holder fields, both in holders, in grasp order.
TEST(ConversionsTest, HoldersAreTheFirstHolderAndEveryHolder) {
  msg::ObjectState two;
  set_holders(two, {{"alice", 1}, {"bob", 0}});
  expect_held_by(two, {{"alice", 1}, {"bob", 0}});
  msg::ObjectState free;
  set_holders(free, {});
  EXPECT_FALSE(free.held());
  EXPECT_TRUE(free.holders().empty());
}

TEST(ConversionsTest, GraspEventCarriesMetricsAndNames) {
  auto rig = server::rig("human_right");
  sim::GraspEvent e;
  e.kind = sim::GraspEvent::Kind::kGrasp;
  e.hand = sim::HandId(3);
  e.object = sim::ObjectId(5);
  e.tick = 77;
  e.time = 0.5;
  sim::GraspMetrics metrics;
  metrics.hand_error_mm = 2.5;
  metrics.capsules_without_hit = 1;
  sim::CapsuleMetric capsule;
  capsule.phalanx = sim::PhalanxId(2);
  capsule.hit = true;
  capsule.nd = -0.0004;
  capsule.contact_hit = true;
  capsule.nd_contact = 0.00003;
  capsule.signed_distance = -0.0001;
  capsule.blocked = true;
  metrics.capsules.push_back(capsule);
  metrics.palm_signed_distance = 0.002;
  metrics.quality = {0.125, 0.5, true};
  e.metrics = metrics;
  e.grasp_type = sim::GraspType::kLateralPinch;
  EventContext ctx;
  ctx.hand = {"bob", 0};
  ctx.event_id = 11;
  ctx.object_name = "can";
  ctx.object_spawn_time = 0.25;
  ctx.X_WorldObject = some_pose();
  ctx.input_sequence = 1234;
  const msg::GraspEvent m = make_grasp_event(e, *rig, ctx);
  EXPECT_EQ(m.event_id(), 11u);
  EXPECT_EQ(m.kind(), msg::GRASP_EVENT_GRASP);
  EXPECT_EQ(m.client_id().to_string(), "bob");
  EXPECT_EQ(m.hand_side(), 0);
  EXPECT_EQ(m.object_id(), 5);
  EXPECT_EQ(m.object_name().to_string(), "can");
  EXPECT_EQ(m.tick(), 77u);
  EXPECT_EQ(m.input_sequence(), 1234u);
  EXPECT_TRUE(to_eigen(m.object_pose()).isApprox(some_pose(), 1e-12));
  EXPECT_EQ(m.hand_error_mm(), 2.5);
  EXPECT_EQ(m.capsules_without_hit(), 1);
  ASSERT_EQ(m.capsules().size(), 1u);
  EXPECT_EQ(m.capsules()[0].phalanx_name().to_string(), rig->phalanges()[2].name);
  EXPECT_EQ(m.capsules()[0].nd(), -0.0004);
  EXPECT_EQ(m.capsules()[0].signed_distance(), -0.0001);
  EXPECT_TRUE(m.capsules()[0].hit());
  EXPECT_TRUE(m.capsules()[0].blocked());
  EXPECT_TRUE(m.capsules()[0].contact_hit());
  EXPECT_EQ(m.capsules()[0].nd_contact(), 0.00003);
  EXPECT_EQ(m.palm_signed_distance(), 0.002);
  EXPECT_EQ(m.epsilon(), 0.125);
  EXPECT_EQ(m.volume(), 0.5);
  EXPECT_TRUE(m.force_closure());
  EXPECT_EQ(m.grasp_type().to_string(), "lateral_pinch");
}

// Quality moves republish a held hand's GraspState only beyond 5 % or 1e-3 (whichever is larger),
// or when force closure flips.
TEST(ConversionsTest, GraspQualityChangeHasAThreshold) {
  msg::GraspState before, now;
  before.epsilon(0.1);
  before.volume(0.01);
  before.force_closure(true);
  now = before;
  now.epsilon(0.104);  // 4 % of 0.1
  EXPECT_FALSE(quality_changed(before, now));
  now.epsilon(0.106);  // 6 %
  EXPECT_TRUE(quality_changed(before, now));
  now = before;
  now.volume(0.0109);  // 9 % but below 1e-3
  EXPECT_FALSE(quality_changed(before, now));
  now.volume(0.0111);  // 1.1e-3
  EXPECT_TRUE(quality_changed(before, now));
  now = before;
  now.force_closure(false);
  EXPECT_TRUE(quality_changed(before, now));
}

// A 0.125 x 0.25 x 0.5 m box with a corner at the origin (8 vertices, 12 triangles, outward),
// built inline. Its sizes are powers of two, so its recentred corners are exact in float32.
sim::TriangleMesh corner_box() {
  sim::TriangleMesh m;
  for (int i = 0; i < 8; ++i) m.vertices.emplace_back(i & 1 ? 0.125 : 0.0, i & 2 ? 0.25 : 0.0, i & 4 ? 0.5 : 0.0);
  m.triangles = {{0, 2, 1}, {1, 2, 3}, {4, 5, 6}, {5, 7, 6}, {0, 1, 4}, {1, 5, 4},
                 {2, 6, 3}, {3, 6, 7}, {0, 4, 2}, {2, 4, 6}, {1, 3, 5}, {3, 7, 5}};
  return m;
}

// FNV-1a 64 over a byte buffer laid out by hand (little-endian host): a second implementation of
// the content hash's definition in telegrasp.idl.
std::uint64_t fnv1a64_of_bytes(const std::vector<unsigned char>& bytes) {
  std::uint64_t h = 0xcbf29ce484222325ull;
  for (unsigned char b : bytes) h = (h ^ b) * 0x100000001b3ull;
  return h;
}

template <class T>
void append_bytes(std::vector<unsigned char>& out, const T& value) {
  unsigned char b[sizeof(T)];
  std::memcpy(b, &value, sizeof(T));
  out.insert(out.end(), b, b + sizeof(T));
}

// The cube's geometry goes out in the model frame (recentred on the centre of mass) with its 8
// vertices and 12 triangles, comes back as the same mesh, and carries the box's analytic bounds,
// volume, inertia and hash.
TEST(ConversionsTest, ObjectGeometryOfABoxRoundTripsWithItsBoundsMassAndHash) {
  const double mass = 2.0, a = 0.125, b = 0.25, c = 0.5;
  const sim::ObjectModelPtr model = sim::make_object_model("box", corner_box(), mass, "test");
  const msg::ObjectGeometry m = make_object_geometry(*model);

  EXPECT_EQ(m.model().to_string(), "box");
  EXPECT_EQ(m.vertex_count(), 8u);
  EXPECT_EQ(m.triangle_count(), 12u);
  EXPECT_FALSE(m.mesh_omitted());
  ASSERT_EQ(m.vertices().size(), 24u);
  ASSERT_EQ(m.triangles().size(), 36u);

  // Back to a sim mesh: the same triangles, the same (float-exact) corners.
  const sim::TriangleMesh back = to_sim_mesh(m);
  ASSERT_EQ(back.vertices.size(), 8u);
  EXPECT_EQ(back.triangles, model->mesh.triangles);
  constexpr double kFloat32Rounding = 1e-7;  // m, on coordinates under 1 m
  for (std::size_t i = 0; i < 8; ++i)
    EXPECT_LT((back.vertices[i] - model->mesh.vertices[i]).cwiseAbs().maxCoeff(), kFloat32Rounding) << "vertex " << i;
  // The model frame has its origin at the box's centre: every corner is at (+-a/2, +-b/2, +-c/2).
  for (const Eigen::Vector3d& v : back.vertices) EXPECT_EQ(v.cwiseAbs(), Eigen::Vector3d(a / 2, b / 2, c / 2));

  constexpr double kTolerance = 1e-12;
  EXPECT_TRUE(to_eigen(m.p_min()).isApprox(Eigen::Vector3d(-a / 2, -b / 2, -c / 2), kTolerance));
  EXPECT_TRUE(to_eigen(m.p_max()).isApprox(Eigen::Vector3d(a / 2, b / 2, c / 2), kTolerance));
  EXPECT_EQ(m.mass(), mass);
  EXPECT_NEAR(m.volume(), a * b * c, kTolerance);
  // A solid box: I_xx = m (b^2 + c^2) / 12, and so on.
  const Eigen::Vector3d I(mass * (b * b + c * c) / 12, mass * (a * a + c * c) / 12, mass * (a * a + b * b) / 12);
  EXPECT_TRUE(to_eigen(m.inertia_diagonal()).isApprox(I, kTolerance)) << to_eigen(m.inertia_diagonal()).transpose();
  // The source file's origin (the box's corner) seen from the centre.
  EXPECT_TRUE(to_eigen(m.p_source_origin()).isApprox(Eigen::Vector3d(-a / 2, -b / 2, -c / 2), kTolerance));

  // The hash, laid out byte by byte as the IDL defines it.
  std::vector<unsigned char> bytes;
  append_bytes(bytes, std::uint32_t{8});
  append_bytes(bytes, std::uint32_t{12});
  for (float x : m.vertices()) append_bytes(bytes, x);
  for (std::uint32_t i : m.triangles()) append_bytes(bytes, i);
  EXPECT_EQ(m.content_hash(), fnv1a64_of_bytes(bytes));
}

// One coordinate one float step away, or one triangle turned round, is another hash.
TEST(ConversionsTest, ObjectGeometryHashChangesWithTheMesh) {
  const msg::ObjectGeometry m = make_object_geometry(*sim::make_object_model("box", corner_box(), 1.0, "test"));
  std::vector<float> xyz = m.vertices();
  std::vector<std::uint32_t> idx = m.triangles();
  EXPECT_EQ(idl::geometry_content_hash(xyz.data(), 8, idx.data(), 12), m.content_hash());
  xyz[4] = std::nextafter(xyz[4], 1.0f);
  EXPECT_NE(idl::geometry_content_hash(xyz.data(), 8, idx.data(), 12), m.content_hash());
  xyz = m.vertices();
  std::swap(idx[0], idx[1]);
  EXPECT_NE(idl::geometry_content_hash(xyz.data(), 8, idx.data(), 12), m.content_hash());
}

// Over the size limit, the mesh stays home: no vertices or triangles, everything else (the hash of
// the whole mesh included) as before.
TEST(ConversionsTest, ObjectGeometryOverTheLimitIsPublishedWithoutItsMesh) {
  const sim::ObjectModelPtr model = sim::make_object_model("box", corner_box(), 1.0, "test");
  const msg::ObjectGeometry whole = make_object_geometry(*model);
  const msg::ObjectGeometry omitted = make_object_geometry(*model, 11);
  EXPECT_TRUE(omitted.mesh_omitted());
  EXPECT_TRUE(omitted.vertices().empty());
  EXPECT_TRUE(omitted.triangles().empty());
  EXPECT_EQ(omitted.vertex_count(), 8u);
  EXPECT_EQ(omitted.triangle_count(), 12u);
  EXPECT_EQ(omitted.content_hash(), whole.content_hash());
  EXPECT_EQ(omitted.mass(), whole.mass());
  EXPECT_TRUE(to_sim_mesh(omitted).triangles.empty());
  EXPECT_FALSE(make_object_geometry(*model, 12).mesh_omitted()) << "the limit itself is allowed";
}

}  // namespace
}  // namespace telegrasp::server
