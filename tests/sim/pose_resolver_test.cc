// Tests the resolved hand pose (PoseResolver through HandController and World): the visible hand
// stays outside objects and the table while the tracked pose goes through them, rejoins the
// tracked pose at a bounded speed, does not tunnel through thin objects, ignores the held object.
#include "telegrasp/sim/pose_resolver.h"

#include "telegrasp/sim/hand_controller.h"
#include "telegrasp/sim/world.h"
#include "test_meshes.h"
#include "test_rigs.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

namespace telegrasp::sim {
namespace {

using testing::box_mesh;
constexpr double kDt = 1.0 / 90.0;
constexpr double kFloor = -0.1e-3;  // the target: nothing deeper than 0.1 mm

std::shared_ptr<const HandRig> human() {
  static auto rig = std::make_shared<const HandRig>(HandRig::load(HandRig::builtin_path("human_right")));
  return rig;
}

// A box object with half extents h centred at p.
struct Box {
  ObjectModelPtr model;
  ObjectView view;
  Box(const Eigen::Vector3d& h, const Eigen::Vector3d& p) : model(make_object_model("box", box_mesh(h), 1.0, "test")) {
    view.id = ObjectId(3);
    view.X_WorldObject = Eigen::Isometry3d(Eigen::Translation3d(p));
    view.model = model.get();
  }
};

// The palm down (its -z toward -z world) at p, trigger t.
ControllerInput palm_at(const Eigen::Vector3d& p, double trigger = 0) {
  ControllerInput in;
  in.X_WorldPalm.translation() = p;
  in.trigger = trigger;
  return in;
}

// Smallest exact signed distance of the palm volumes and every capsule of `hand` to `view`.
double min_gap(const HandController& hand, const ObjectView& view) {
  const HandState& s = hand.state();
  const Eigen::Isometry3d X_ObjectPalm = view.X_WorldObject.inverse() * s.X_WorldPalm;
  const MeshDistance& mesh = view.model->distance;
  double worst = 1e9;
  for (const HandVolume& v : palm_volumes(hand.rig().palm_half_extent()))
    worst = std::min(worst, mesh.capsule_signed_distance(X_ObjectPalm * v.p_PalmA, X_ObjectPalm * v.p_PalmB, v.radius));
  for (PhalanxId id : hand.rig().capsule_phalanges()) {
    const CapsuleSpec& c = *hand.rig().phalanges()[id.value].capsule;
    const Eigen::Isometry3d X = X_ObjectPalm * s.X_PalmPhalanx[id.value];
    worst = std::min(worst, mesh.capsule_signed_distance(X * c.p_PhalanxA, X * c.p_PhalanxB, c.radius));
  }
  return worst;
}

// Lowest world z of the palm volumes and capsules.
double lowest_z(const HandController& hand) {
  const HandState& s = hand.state();
  double low = 1e9;
  for (const HandVolume& v : palm_volumes(hand.rig().palm_half_extent()))
    low = std::min({low, (s.X_WorldPalm * v.p_PalmA).z() - v.radius, (s.X_WorldPalm * v.p_PalmB).z() - v.radius});
  for (PhalanxId id : hand.rig().capsule_phalanges()) {
    const CapsuleSpec& c = *hand.rig().phalanges()[id.value].capsule;
    const Eigen::Isometry3d X = s.X_WorldPalm * s.X_PalmPhalanx[id.value];
    low = std::min({low, (X * c.p_PhalanxA).z() - c.radius, (X * c.p_PhalanxB).z() - c.radius});
  }
  return low;
}

TEST(PoseResolverTest, PalmVolumesSpanThePalmBox) {
  const Eigen::Vector3d h(0.045, 0.042, 0.013);
  const auto v = palm_volumes(h);
  ASSERT_GE(v.size(), 2u);
  EXPECT_DOUBLE_EQ(v.front().p_PalmA.y(), -(h.y() - h.z()));
  EXPECT_DOUBLE_EQ(v.back().p_PalmA.y(), h.y() - h.z());
  for (std::size_t i = 1; i < v.size(); ++i) EXPECT_LE(v[i].p_PalmA.y() - v[i - 1].p_PalmA.y(), 1.2 * h.z() + 1e-12);
  for (const HandVolume& c : v) {
    EXPECT_TRUE(c.palm);
    EXPECT_DOUBLE_EQ(c.radius, h.z());
    EXPECT_DOUBLE_EQ(c.p_PalmB.x() + c.radius, h.x());
  }
}

// The controller comes down onto a box and goes on 20 mm into it: the resolved hand stays on the
// top, the tracked pose is the controller's.
TEST(PoseResolverTest, HandPushedIntoABoxStaysOutside) {
  Box box({0.15, 0.15, 0.05}, {0.03, 0, -0.05});  // top at z = 0
  HandController hand(human(), {});
  for (int t = 0; t <= 60; ++t) {
    const double z = std::max(0.06 - 0.5 * t * kDt, -0.02);  // 0.5 m/s down to 20 mm inside
    const ControllerInput in = palm_at({0, 0, z});
    hand.tick(in, kDt, {&box.view, 1});
    ASSERT_GE(min_gap(hand, box.view), kFloor) << "tick " << t;
    ASSERT_EQ(hand.state().X_WorldTracked.matrix(), in.X_WorldPalm.matrix()) << "tick " << t;
  }
  EXPECT_NEAR(lowest_z(hand), 0.0, 0.1e-3) << "resting on the top";
  EXPECT_TRUE(hand.state().X_WorldPalm.linear().isApprox(Eigen::Matrix3d::Identity(), 1e-12)) << "not turned";
  EXPECT_NEAR(hand.state().X_WorldPalm.translation().x(), 0.0, 1e-9) << "pushed straight up";
}

// The controller leaves the box at once: the resolved pose closes the gap at <= 1 m/s, never
// entering the box, and then equals the tracked pose.
TEST(PoseResolverTest, RejoinsTheTrackedPoseAtABoundedSpeed) {
  Box box({0.15, 0.15, 0.05}, {0.03, 0, -0.05});
  HandController hand(human(), {});
  for (int t = 0; t <= 60; ++t) hand.tick(palm_at({0, 0, std::max(0.06 - 0.5 * t * kDt, -0.03)}), kDt, {&box.view, 1});
  const double rejoin = hand.settings().rejoin_speed * kDt;
  double offset = (hand.state().X_WorldPalm.translation() - hand.state().X_WorldTracked.translation()).norm();
  ASSERT_GT(offset, 0.03);
  int ticks = 0;
  // Out of the box at 5 cm/tick sideways and up, then still.
  for (int t = 0; t < 30 && offset > 0; ++t, ++ticks) {
    const double s = std::min(1.0, (t + 1) / 3.0);
    hand.tick(palm_at({0.25 * s, 0, -0.03 + 0.1 * s}), kDt, {&box.view, 1});
    const double now = (hand.state().X_WorldPalm.translation() - hand.state().X_WorldTracked.translation()).norm();
    ASSERT_GE(now, offset - rejoin - 1e-12) << "tick " << t << ": closed faster than the rejoin speed";
    ASSERT_GE(min_gap(hand, box.view), kFloor) << "tick " << t;
    offset = now;
  }
  EXPECT_EQ(offset, 0.0) << "rejoined";
  EXPECT_EQ(hand.state().X_WorldPalm.matrix(), hand.state().X_WorldTracked.matrix());
  EXPECT_LE(ticks, 10);
}

// The controller passes through a wall (4 cm thick) and stops 0.3 m beyond it: the hand, caught on
// the near side, never enters the wall and, once the tracked pose is clear and more than the snap
// distance away, is at the tracked pose. With snapping off it stays caught behind the wall.
TEST(PoseResolverTest, AHandCaughtFarBehindAWallJumpsToItsControllerOnceClear) {
  Box wall({0.02, 0.3, 0.3}, {0.25, 0, 0.3});
  for (const double snap : {0.2, 0.0}) {
    GraspSettings settings;
    settings.snap_distance = snap;
    HandController hand(human(), settings);
    for (int t = 0; t <= 120; ++t) {
      hand.tick(palm_at({std::min(0.5 * t * kDt, 0.55), 0, 0.3}), kDt, {&wall.view, 1});
      ASSERT_GE(min_gap(hand, wall.view), kFloor) << "snap " << snap << " tick " << t;
    }
    const HandState& s = hand.state();
    if (snap > 0) {
      EXPECT_EQ(s.X_WorldPalm.matrix(), s.X_WorldTracked.matrix());
    } else {
      EXPECT_LT(s.X_WorldPalm.translation().x(), 0.23) << "still on the near side";
    }
  }
}

// A controller 0.3 m deep in a block: farther than the snap distance, but the tracked pose is not
// clear, so the hand stays on the top (every tick it looks again).
TEST(PoseResolverTest, NeverJumpsIntoAnObject) {
  Box block({0.5, 0.5, 0.5}, {0.03, 0, -0.5});  // top at z = 0
  HandController hand(human(), {});
  for (int t = 0; t <= 90; ++t) {
    hand.tick(palm_at({0, 0, std::max(0.06 - 0.5 * t * kDt, -0.3)}), kDt, {&block.view, 1});
    ASSERT_GE(min_gap(hand, block.view), kFloor) << "tick " << t;
  }
  EXPECT_NEAR(lowest_z(hand), 0.0, 0.1e-3) << "resting on the top";
  EXPECT_GT((hand.state().X_WorldPalm.translation() - hand.state().X_WorldTracked.translation()).norm(), 0.3);
}

// The World's table: a controller below z = 0 leaves the hand above it.
TEST(PoseResolverTest, HandStaysAboveTheTable) {
  World world;
  const HandId h = world.add_hand(human());
  for (int t = 0; t <= 40; ++t) {
    world.set_input(h, palm_at({0.2, 0.1, std::max(0.1 - 0.5 * t * kDt, -0.05)}));
    world.step();
    ASSERT_GE(lowest_z(world.hand(h)), kFloor) << "tick " << t;
  }
  EXPECT_NEAR(lowest_z(world.hand(h)), 0.0, 0.1e-3);
  EXPECT_DOUBLE_EQ(world.hand(h).state().X_WorldTracked.translation().z(), -0.05);
}

// A controller moving at 5 m/s through a knife-like plate 2 mm thick, down through its flat and
// sideways through its edge: the resolved hand stops on the plate, whatever the direction.
TEST(PoseResolverTest, FastSweepDoesNotTunnelThroughAThinPlate) {
  struct Case {
    Eigen::Vector3d half, centre, from, to;
  };
  const std::vector<Case> cases = {
      {{0.1, 0.1, 0.001}, {0.03, 0, 0}, {0, 0, 0.1}, {0, 0, -0.15}},  // flat, from above
      {{0.1, 0.001, 0.1}, {0.03, 0, 0}, {0, 0.15, 0}, {0, -0.15, 0}},  // standing edge-on, from the side
  };
  for (const Case& c : cases) {
    Box plate(c.half, c.centre);
    HandController hand(human(), {});
    const double length = (c.to - c.from).norm();
    const int ticks = static_cast<int>(std::ceil(length / (5.0 * kDt))) + 10;
    for (int t = 0; t <= ticks; ++t) {
      const double s = std::min(1.0, 5.0 * t * kDt / length);
      hand.tick(palm_at(c.from + s * (c.to - c.from)), kDt, {&plate.view, 1});
      ASSERT_GE(min_gap(hand, plate.view), kFloor) << "tick " << t;
    }
    const Eigen::Vector3d p = hand.state().X_WorldPalm.translation() - c.centre;
    EXPECT_GT(p.dot(c.from - c.centre), 0.0) << "the hand stayed on the side it came from";
  }
}

// The finger rig (test_rigs.h) grasping a bar under its fingers, then pushed down:
// the held bar is part of the hand, so the resolved pose follows the controller exactly.
TEST(PoseResolverTest, HeldObjectIsNotTestedAgainstItself) {
  auto rig = std::make_shared<const HandRig>(HandRig::parse(testing::kFingerRig, "finger3"));
  Box bar({0.0065, 0.05, 0.045}, {0.0815, 0, -0.055});
  HandController hand(rig, {});
  bool grasped = false;
  for (int t = 0; t < 90 && !grasped; ++t) grasped = hand.tick(palm_at({0, 0, 0}, 1.0), kDt, {&bar.view, 1}).grasped;
  ASSERT_TRUE(grasped);
  const Eigen::Isometry3d X_PalmObject = hand.state().X_PalmObject;
  for (int t = 1; t <= 20; ++t) {  // down 30 mm, into where the bar is held
    const ControllerInput in = palm_at({0, 0, -0.0015 * t}, 1.0);
    hand.tick(in, kDt, {&bar.view, 1});
    ASSERT_TRUE(hand.state().grasped.valid()) << "tick " << t;
    ASSERT_EQ(hand.state().X_WorldPalm.matrix(), in.X_WorldPalm.matrix()) << "tick " << t;
    ASSERT_TRUE(hand.grasped_object_pose()->isApprox(in.X_WorldPalm * X_PalmObject, 1e-12)) << "follows the hand";
  }
}

// Equal inputs give bit-identical resolved poses, and a copy resolves as the original.
TEST(PoseResolverTest, Deterministic) {
  Box box({0.04, 0.03, 0.05}, {0.06, 0, 0.05});
  auto run = [&](HandController& hand, int from, int to) {
    for (int t = from; t < to; ++t) {
      ControllerInput in = palm_at({0.01 * std::sin(0.3 * t), 0.02 * std::cos(0.2 * t), 0.1 + 0.06 * std::sin(0.1 * t)},
                                   0.5 + 0.5 * std::sin(0.05 * t));
      in.X_WorldPalm.linear() =
          Eigen::AngleAxisd(0.2 * std::sin(0.07 * t), Eigen::Vector3d::UnitX()).toRotationMatrix();
      hand.tick(in, kDt, {&box.view, 1});
    }
  };
  HandController a(human(), {}), b(human(), {});
  run(a, 0, 100);
  HandController c = a;
  run(a, 100, 200);
  run(b, 0, 200);
  run(c, 100, 200);
  EXPECT_EQ(a.state().X_WorldPalm.matrix(), b.state().X_WorldPalm.matrix());
  EXPECT_EQ(a.state().q, b.state().q);
  EXPECT_EQ(a.state().X_WorldPalm.matrix(), c.state().X_WorldPalm.matrix());
  EXPECT_EQ(a.state().q, c.state().q);
}

}  // namespace
}  // namespace telegrasp::sim
