// Tests what the paper's ND reads when a phalanx touches exactly: a rigid phalanx closing onto a
// flat face touches it with the tip of its capsule, and ND, measured at mid-length (CTc), reads
// the gap the tilt leaves there, not the contact.
#include "telegrasp/sim/hand_controller.h"

#include "test_meshes.h"

#include <gtest/gtest.h>

#include <cmath>

namespace telegrasp::sim {
namespace {

constexpr double kDt = 1.0 / 90.0;
constexpr double kTol = 0.05e-3;  // GraspSettings default contact tolerance

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

// The face z = -12 mm lies 7 mm below the bottom of the open capsule, under all of it. Closing,
// the tip's centre b = 27 mm (cos q, -sin q) reaches the face when 0.027 sin q + 0.005 = 0.012:
// q = asin(7/27) = 15.03 deg. There the ND sweep runs along n = (-sin q, 0, -cos q) from
// Sp = 15 mm (cos q, -sin q); the 1 mm sweep sphere meets the face when its centre is 1 mm above
// it, at t = (Sp_z - z_face - rs) / cos q, and the impact point lies rs straight below the
// centre, so ND = t + rs cos q - r: about 3.3 mm, while the capsule touches within 0.05 mm.
TEST(NdMetricTest, TipContactOnAFlatFaceReadsTheTiltGapAtMidLength) {
  const double z_face = -0.012, r = 0.005, rs = 0.001;
  auto rig = std::make_shared<const HandRig>(HandRig::parse(kOnePhalanxRig, "one_phalanx"));
  auto model = make_object_model("slab", testing::box_mesh({0.2, 0.2, 0.01}), 1.0, "test");
  const ObjectView view{ObjectId(1), Eigen::Isometry3d(Eigen::Translation3d(0.1, 0, z_face - 0.01)), model.get()};
  for (double speed : {1.0, 8.0}) {
    SCOPED_TRACE(speed);
    GraspSettings settings;
    settings.speed_scale = speed;
    HandController hand(rig, settings);
    ControllerInput in;
    in.trigger = 1.0;
    for (int t = 0; t < 90 && !hand.state().blocked[0]; ++t) hand.tick(in, kDt, {&view, 1});
    ASSERT_TRUE(hand.state().blocked[0]);

    const double q = hand.state().q[0];
    EXPECT_NEAR(q, std::asin(0.007 / 0.027), kTol / 0.027 + 1e-9);  // the tip touches
    const GraspMetrics m = hand.measure(view);
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
  }
}

}  // namespace
}  // namespace telegrasp::sim
