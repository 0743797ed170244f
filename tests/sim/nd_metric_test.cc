// Tests what the paper's ND reads when a phalanx touches exactly: a rigid phalanx closing onto a
// flat face touches it with the tip of its capsule, and ND, measured at mid-length (CTc), reads
// the gap the tilt leaves there, not the contact; nd_contact, taken toward the contact, reads the
// gap. Also: every blocked capsule has an nd_contact, and the palm box's exact signed distance.
#include "telegrasp/sim/hand_controller.h"
#include "telegrasp/sim/scripted_operator.h"
#include "telegrasp/sim/standin_objects.h"

#include "test_meshes.h"

#include <Eigen/Geometry>

#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <limits>
#include <numbers>

namespace telegrasp::sim {
namespace {

constexpr double kDt = 1.0 / 90.0;
constexpr double kTol = 0.05e-3;

// One phalanx hinged at (0.04, 0, 0) in the palm frame, flexing about +y (the tip goes to -z):
// capsule from x = 3 mm to 27 mm, radius 5 mm; Sp on its axis and CTc on the palmar skin at
// mid-length (x = 15 mm); the ND sweep sphere has radius 1 mm.
constexpr const char* kOnePhalanxRig = R"(
name: "one_phalanx"
palm_selection_sphere { center { x: 0.05 } radius: 0.2 }
palm_contact_volume { radius: 0.001 }
palm_half_extent { x: 0.04 y: 0.04 z: 0.01 }
default_max_speed_deg_s: 180
nd_sweep_radius: 0.001
nd_sweep_beyond: 0.01
fingers {
  name: "f"
  phalanges { name: "f_mid" rest { translation { x: 0.04 } }
    joint { axis { y: 1 } open_deg: 0 closed_deg: 90 min_deg: 0 max_deg: 90 } length: 0.03
    capsule { a { x: 0.003 } b { x: 0.027 } radius: 0.005 ctc { x: 0.015 z: -0.005 } sp { x: 0.015 } } }
}
grasp_rule { members: ["f_mid"] }
)";

std::shared_ptr<const HandRig> one_phalanx_rig() {
  return std::make_shared<const HandRig>(HandRig::parse(kOnePhalanxRig, "one_phalanx"));
}

// A box 400 x 400 mm wide and 2 * half_height tall under the phalanx, its top face at z = z_face.
struct Slab {
  Slab(const std::string& name, double z_face, double half_height)
      : model(make_object_model(name, testing::box_mesh({0.2, 0.2, half_height}), 1.0, "test")),
        view{ObjectId(1), Eigen::Isometry3d(Eigen::Translation3d(0.1, 0, z_face - half_height)), model.get()} {}
  ObjectModelPtr model;
  ObjectView view;
};

// Pulls the trigger until the capsule is blocked by `view`, for at most 90 ticks.
void close_until_blocked(HandController& hand, const ObjectView& view) {
  ControllerInput in;
  in.trigger = 1.0;
  for (int t = 0; t < 90 && !hand.state().blocked[0]; ++t) hand.tick(in, kDt, {&view, 1});
}

// The mean |ND| the planner and the eval report: over the capsules whose sweep hit only, a gap and
// a penetration alike by their size, in mm: (1 + 3) / 2.
TEST(NdMetricTest, MeanAbsNdCountsOnlyTheCapsulesThatHit) {
  GraspMetrics m;
  m.capsules.resize(3);
  m.capsules[0].hit = true;
  m.capsules[0].nd = 0.001;
  m.capsules[1].hit = true;
  m.capsules[1].nd = -0.003;
  m.capsules[2].nd = 0.005;  // no hit: left out
  const auto [mean_mm, hits] = mean_abs_nd_mm(m);
  EXPECT_NEAR(mean_mm, 2.0, 1e-12);
  EXPECT_EQ(hits, 2);
  EXPECT_EQ(mean_abs_nd_mm(GraspMetrics{}), (std::pair<double, int>{0.0, 0}));
}

// The face z = -12 mm lies 7 mm below the bottom of the open capsule, under all of it. Closing,
// the tip's centre b = 27 mm (cos q, -sin q) reaches the face when 0.027 sin q + 0.005 = 0.012:
// q = asin(7/27) = 15.03 deg. There the ND sweep runs along n = (-sin q, 0, -cos q) from
// Sp = 15 mm (cos q, -sin q); the 1 mm sweep sphere meets the face when its centre is 1 mm above
// it, at t = (Sp_z - z_face - rs) / cos q, and the impact point lies rs straight below the
// centre, so ND = t + rs cos q - r: about 3.3 mm, while the capsule touches within 0.05 mm.
TEST(NdMetricTest, TipContactOnAFlatFaceReadsTheTiltGapAtMidLength) {
  const double z_face = -0.012, r = 0.005, rs = 0.001;
  auto rig = one_phalanx_rig();
  const Slab slab("slab", z_face, 0.01);
  for (double speed : {1.0, 8.0}) {
    SCOPED_TRACE(speed);
    GraspSettings settings;
    settings.speed_scale = speed;
    HandController hand(rig, settings);
    close_until_blocked(hand, slab.view);
    ASSERT_TRUE(hand.state().blocked[0]);

    const double q = hand.state().q[0];
    EXPECT_NEAR(q, std::asin(0.007 / 0.027), kTol / 0.027 + 1e-9);  // the tip touches
    const GraspMetrics m = hand.measure(slab.view);
    ASSERT_EQ(m.capsules.size(), 1u);
    const CapsuleMetric& c = m.capsules[0];
    EXPECT_GE(c.signed_distance, 0.0);
    EXPECT_LE(c.signed_distance, kTol);

    const double sp_z = -0.015 * std::sin(q);
    const double expected_nd = (sp_z - z_face - rs) / std::cos(q) + rs * std::cos(q) - r;
    ASSERT_TRUE(c.hit);
    EXPECT_NEAR(c.nd, expected_nd, 1e-9);
    EXPECT_GT(c.nd, 3.2e-3);
    EXPECT_LT(c.nd, 3.5e-3);
    // nd_contact sweeps straight down from the tip's centre b: ND = b_z - z_face - r, the gap.
    ASSERT_TRUE(c.contact_hit);
    EXPECT_NEAR(c.nd_contact, -0.027 * std::sin(q) - z_face - r, 1e-9);
    EXPECT_GE(c.nd_contact, 0.0);
    EXPECT_LE(c.nd_contact, kTol);
  }
}

// Discrete closing sinks the tip into the face by up to one step. At speed 8 (24 deg a tick) the
// tip's centre stays above the face (ND_contact = b_z - z_face - r < 0, the exact depth); at speed
// 30 (60 deg) it ends below the face, the axis crosses it, and nd_contact sweeps from the deep end:
// the same formula, now with b_z < z_face.
TEST(NdMetricTest, DiscreteSinkingReadsTheDepthAtTheTip) {
  const double z_face = -0.012, r = 0.005;
  auto rig = one_phalanx_rig();
  // 100 mm thick: the face is the surface nearest every point the tip can reach.
  const Slab block("block", z_face, 0.05);
  for (double speed : {8.0, 30.0}) {
    SCOPED_TRACE(speed);
    GraspSettings settings;
    settings.mode = ClosingMode::kDiscrete;
    settings.speed_scale = speed;
    HandController hand(rig, settings);
    close_until_blocked(hand, block.view);
    ASSERT_TRUE(hand.state().blocked[0]);
    const double b_z = -0.027 * std::sin(hand.state().q[0]);
    const CapsuleMetric c = hand.measure(block.view).capsules.at(0);
    ASSERT_TRUE(c.contact_hit);
    EXPECT_NEAR(c.nd_contact, b_z - z_face - r, 1e-9);
    EXPECT_NEAR(c.signed_distance, b_z - z_face - r, 1e-9);
    EXPECT_LT(c.nd_contact, 0.0);
    if (speed > 10) {
      EXPECT_LT(b_z, z_face);
    }
  }
}

// A capsule closing onto a sphere touches it where the sphere is nearest the axis; nd_contact,
// swept along the line through the axis point and the contact, reads that gap: within the
// contact tolerance and equal to the exact signed distance.
TEST(NdMetricTest, CapsuleTouchingASphereReadsItsGap) {
  auto rig = one_phalanx_rig();
  auto model = make_object_model("ball", testing::uv_sphere_mesh(0.015, 48, 96), 1.0, "test");
  const ObjectView view{ObjectId(1), Eigen::Isometry3d(Eigen::Translation3d(0.06, 0.004, -0.03)), model.get()};
  HandController hand(rig, GraspSettings{});
  close_until_blocked(hand, view);
  ASSERT_TRUE(hand.state().blocked[0]);
  const CapsuleMetric c = hand.measure(view).capsules.at(0);
  ASSERT_TRUE(c.contact_hit);
  EXPECT_GE(c.nd_contact, 0.0);
  EXPECT_LE(c.nd_contact, 2 * kTol);
  EXPECT_NEAR(c.nd_contact, c.signed_distance, 1e-9);
}

// Unblocked capsules have no nd_contact; blocked ones always do, and in precise mode it reads
// their gap (within the release hysteresis), whatever the object: the human hand closed by the
// planner on stand-ins of every shape class.
TEST(NdMetricTest, EveryBlockedCapsuleHasAnNdContact) {
  auto rig = std::make_shared<const HandRig>(HandRig::load(HandRig::builtin_path("human_right")));
  const Eigen::Isometry3d X_WorldObject(Eigen::Translation3d(0, 0, 0.1));
  int blocked = 0;
  for (const char* name :
       {"013_apple", "004_sugar_box", "032_knife", "035_power_drill", "011_banana", "030_fork", "006_mustard_bottle"}) {
    SCOPED_TRACE(name);
    const auto spec = find_protocol_object(name);
    ASSERT_TRUE(spec.has_value());
    const ObjectModelPtr model = make_standin_model(*spec);
    const GraspPlan plan = plan_grasp(rig, GraspSettings{}, *model, X_WorldObject, kDt);
    const OfflineClosing closing = close_offline(rig, GraspSettings{}, *model, X_WorldObject, plan.X_WorldPalm, kDt);
    for (const CapsuleMetric& c : closing.metrics.capsules) {
      EXPECT_EQ(c.contact_hit, c.blocked);
      if (!c.blocked) continue;
      ++blocked;
      EXPECT_GE(c.nd_contact, -1e-9);
      EXPECT_LE(c.nd_contact, 2 * kTol + 1e-9);
      EXPECT_NEAR(c.nd_contact, c.signed_distance, 1e-6);
    }
  }
  EXPECT_GT(blocked, 12);
}

// The palm volume of the one-phalanx rig (pose_resolver.h palm_volumes): its box, half extents
// 40 x 40 x 10 mm, with rounded edges: six capsules of radius 10 mm along x over [-30, 30] mm, at
// y = -30, -18, -6, 6, 18 and 30 mm.
class PalmDistanceTest : public ::testing::Test {
 protected:
  double palm_distance(const TriangleMesh& mesh, const Eigen::Isometry3d& X_WorldObject,
                       const Eigen::Isometry3d& X_WorldPalm = Eigen::Isometry3d::Identity()) {
    auto model = make_object_model("object", mesh, 1.0, "test");
    HandController hand(rig_, GraspSettings{});
    ControllerInput in;
    in.X_WorldPalm = X_WorldPalm;
    const ObjectView view{ObjectId(1), X_WorldObject, model.get()};
    hand.tick(in, kDt, {});
    return hand.measure(view).palm_signed_distance;
  }
  std::shared_ptr<const HandRig> rig_ = one_phalanx_rig();
  TriangleMesh slab_ = testing::box_mesh({0.2, 0.2, 0.01});  // top face at +10 mm
};

// Face to face: the palm's bottom (z = -10 mm) 3 mm above a slab's top face.
TEST_F(PalmDistanceTest, FlatAboveASlab) {
  EXPECT_NEAR(palm_distance(slab_, Eigen::Isometry3d(Eigen::Translation3d(0, 0, -0.023))), 0.003, 1e-12);
}

// Tilted 30 deg about x: the lowest capsule axis (y = 30 mm) lies 30 sin 30 = 15 mm below the
// centre, its surface 25 mm; the slab's top is 35 mm below the centre.
TEST_F(PalmDistanceTest, TiltedEdgeAboveASlab) {
  const Eigen::Isometry3d X_WorldPalm(Eigen::AngleAxisd(std::numbers::pi / 6, Eigen::Vector3d::UnitX()));
  EXPECT_NEAR(palm_distance(slab_, Eigen::Isometry3d(Eigen::Translation3d(0, 0, -0.045)), X_WorldPalm), 0.010, 1e-12);
}

// A cube standing on a corner, its top corner (a mesh vertex, 10 sqrt 3 mm above its centre)
// 12 mm straight below the axis of the capsule at y = -6 mm: 2 mm below its surface. Every other
// point of the cube lies lower and so farther from that axis (along x).
TEST_F(PalmDistanceTest, CubeCornerUnderThePalmFace) {
  const Eigen::Quaterniond R = Eigen::Quaterniond::FromTwoVectors(Eigen::Vector3d(1, 1, 1), Eigen::Vector3d::UnitZ());
  const Eigen::Isometry3d X_WorldObject = Eigen::Translation3d(0.005, -0.006, -0.012 - 0.01 * std::sqrt(3.0)) * R;
  EXPECT_NEAR(palm_distance(testing::box_mesh({0.01, 0.01, 0.01}), X_WorldObject), 0.002, 1e-12);
}

// The palm pressed 2 mm into a slab: every capsule's lowest line is 2 mm deep.
TEST_F(PalmDistanceTest, PressedIntoASlab) {
  EXPECT_NEAR(palm_distance(slab_, Eigen::Isometry3d(Eigen::Translation3d(0, 0, -0.018))), -0.002, 1e-12);
}

// A ball (radius 20 mm, pole up) under the axis of the capsule at y = 6 mm, poking 1 mm into it:
// 1 mm deep, less the facets' sag (< 2 um).
TEST_F(PalmDistanceTest, BallPokingIntoThePalmFace) {
  const double d = palm_distance(testing::uv_sphere_mesh(0.02, 48, 96),
                                 Eigen::Isometry3d(Eigen::Translation3d(0, 0.006, -0.01 + 0.001 - 0.02)));
  EXPECT_LE(d, -0.001 + 2e-6);
  EXPECT_GE(d, -0.001 - 1e-12);
}

// Between two capsules (y = 0, midway between the axes at -6 and 6 mm) the rounded palm's face
// dips up to z = -sqrt(10^2 - 6^2) = -8 mm: a ball pole at -9 mm is 0.39 mm deep, not 1 mm.
TEST_F(PalmDistanceTest, TheDipBetweenTwoCapsules) {
  const double d = palm_distance(testing::uv_sphere_mesh(0.02, 48, 96),
                                 Eigen::Isometry3d(Eigen::Translation3d(0, 0, -0.009 - 0.02)));
  const double expected = std::hypot(0.006, 0.029) - 0.02 - 0.01;
  EXPECT_LE(d, expected + 2e-6);
  EXPECT_GE(d, expected - 1e-6);
}

// Entirely inside a large block (half side 60 mm, centred 30 mm below the palm): the deepest
// palm point is a capsule's lowest line, 30 + 10 = 40 mm below the block's top face.
TEST_F(PalmDistanceTest, InsideABlock) {
  EXPECT_NEAR(
      palm_distance(testing::box_mesh({0.06, 0.06, 0.06}), Eigen::Isometry3d(Eigen::Translation3d(0, 0, -0.03))), -0.04,
      1e-9);
}

}  // namespace
}  // namespace telegrasp::sim
