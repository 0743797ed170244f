// Tests forward kinematics against hand-computed chains, and that the left hand mirrors the right.
#include "telegrasp/sim/hand_kinematics.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>
#include <string>
#include <utility>
#include <vector>

namespace telegrasp::sim {
namespace {

constexpr double kExact = 1e-12;

// What every test rig here has besides its finger.
constexpr const char* kPalm = R"(
palm_selection_sphere { radius: 0.1 }
palm_contact_volume { radius: 0.01 }
palm_half_extent { x: 0.04 y: 0.04 z: 0.01 }
default_max_speed_deg_s: 90
nd_sweep_beyond: 0.01
)";

// A planar two-phalanx finger on the palm at (0.04, 0.01, 0), flexing about +y.
const std::string kTwoLinkRig = std::string("name: \"two_link\"") + kPalm + R"(
fingers {
  name: "f"
  phalanges { name: "f_mid" rest { translation { x: 0.04 y: 0.01 } }
    joint { axis { y: 1 } open_deg: 0 closed_deg: 90 min_deg: 0 max_deg: 90 } length: 0.03
    capsule { a { } b { x: 0.03 } radius: 0.005 ctc { x: 0.015 z: -0.005 } sp { x: 0.015 } } }
  phalanges { name: "f_dist" rest { translation { x: 0.03 } }
    joint { axis { y: 1 } open_deg: 0 closed_deg: 60 min_deg: 0 max_deg: 60 } length: 0.02
    capsule { a { } b { x: 0.015 } radius: 0.005 ctc { x: 0.0075 z: -0.005 } sp { x: 0.0075 } } }
}
grasp_rule { members: ["f_mid"] }
)";

TEST(HandKinematicsTest, PlanarChainMatchesHandComputedTip) {
  const HandRig rig = HandRig::parse(kTwoLinkRig, "inline");
  for (double a : {0.0, 0.3, 1.1}) {
    for (double b : {0.0, 0.5, 1.0}) {
      std::vector<Eigen::Isometry3d> X;
      forward_kinematics(rig, {a, b}, &X);
      const Eigen::Vector3d tip = X[1] * Eigen::Vector3d(0.02, 0, 0);
      // Flexion about +y turns +x toward -z.
      const Eigen::Vector3d expected(0.04 + 0.03 * std::cos(a) + 0.02 * std::cos(a + b), 0.01,
                                     -(0.03 * std::sin(a) + 0.02 * std::sin(a + b)));
      EXPECT_LT((tip - expected).norm(), kExact) << a << " " << b;
    }
  }
}

TEST(HandKinematicsTest, TargetAngleInterpolatesAndClamps) {
  const HandRig rig = HandRig::parse(kTwoLinkRig, "inline");
  const PhalanxSpec& p = rig.phalanges()[0];
  EXPECT_DOUBLE_EQ(target_angle(p, 0.0), 0.0);
  EXPECT_DOUBLE_EQ(target_angle(p, 0.5), std::numbers::pi / 4);
  EXPECT_DOUBLE_EQ(target_angle(p, 1.0), std::numbers::pi / 2);
}

// A joint with closes_from 0.2 and closes_until 0.6 is open up to 20 % of the closing input,
// closed from 60 %, and linear between.
TEST(HandKinematicsTest, TargetAngleFollowsTheJointsPartOfTheInput) {
  std::string text = kTwoLinkRig;
  const std::string joint = "open_deg: 0 closed_deg: 90 min_deg: 0 max_deg: 90";
  text.replace(text.find(joint), joint.size(), joint + " closes_from: 0.2 closes_until: 0.6");
  const HandRig rig = HandRig::parse(text, "inline");
  const PhalanxSpec& p = rig.phalanges()[0];
  constexpr double kHalfPi = std::numbers::pi / 2;
  EXPECT_EQ(target_angle(p, 0.0), 0.0);
  EXPECT_EQ(target_angle(p, 0.2), 0.0);
  EXPECT_NEAR(target_angle(p, 0.3), kHalfPi / 4, kExact);
  EXPECT_NEAR(target_angle(p, 0.4), kHalfPi / 2, kExact);
  EXPECT_EQ(target_angle(p, 0.6), kHalfPi);
  EXPECT_EQ(target_angle(p, 1.0), kHalfPi);
}

// A joint with two axes: a phalanx of length 0 turning about z, then one flexing about its y.
// The tip of the second is at R_z(a) R_y(b) (0.03, 0, 0) from the joint.
TEST(HandKinematicsTest, ZeroLengthPhalanxIsAnotherAxisOfTheSameJoint) {
  const HandRig rig = HandRig::parse(std::string("name: \"two_axis\"") + kPalm + R"(
fingers {
  name: "f"
  phalanges { name: "f_abd" rest { translation { x: 0.04 y: 0.01 } }
    joint { axis { z: 1 } open_deg: 0 closed_deg: 40 min_deg: -40 max_deg: 40 } length: 0 }
  phalanges { name: "f_mid" rest { }
    joint { axis { y: 1 } open_deg: 0 closed_deg: 90 min_deg: 0 max_deg: 90 } length: 0.03
    capsule { a { } b { x: 0.03 } radius: 0.005 ctc { x: 0.015 z: -0.005 } sp { x: 0.015 } } }
}
grasp_rule { members: ["f_mid"] }
)",
                                     "inline");
  for (double a : {-0.5, 0.0, 0.6}) {
    for (double b : {0.0, 0.4, 1.2}) {
      std::vector<Eigen::Isometry3d> X;
      forward_kinematics(rig, {a, b}, &X);
      EXPECT_LT((X[0].translation() - X[1].translation()).norm(), kExact);
      const Eigen::Vector3d tip = X[1] * Eigen::Vector3d(0.03, 0, 0);
      const Eigen::Vector3d expected(0.04 + 0.03 * std::cos(b) * std::cos(a), 0.01 + 0.03 * std::cos(b) * std::sin(a),
                                     -0.03 * std::sin(b));
      EXPECT_LT((tip - expected).norm(), kExact) << a << " " << b;
    }
  }
}

// Left hand mirrors right: every phalanx frame of the shipped left hand is the reflection
// M X M (M = diag(1, -1, 1)) of the right hand's at the same joint angles.
void expect_mirrored(const std::string& right_name, const std::string& left_name) {
  SCOPED_TRACE(left_name);
  const HandRig right = HandRig::load(HandRig::builtin_path(right_name));
  const HandRig left = HandRig::load(HandRig::builtin_path(left_name));
  const HandRig mirrored = right.mirrored();
  ASSERT_EQ(left.phalanges().size(), right.phalanges().size());
  EXPECT_EQ(left.side(), HandSide::kLeft);
  EXPECT_EQ(mirrored.side(), HandSide::kLeft);
  const Eigen::Matrix4d M = Eigen::Vector4d(1, -1, 1, 1).asDiagonal();
  for (double u : {0.0, 0.35, 0.8, 1.0}) {
    std::vector<double> q;
    for (const auto& p : right.phalanges()) q.push_back(target_angle(p, u));
    std::vector<Eigen::Isometry3d> XR, XL, XM;
    forward_kinematics(right, q, &XR);
    forward_kinematics(left, q, &XL);
    forward_kinematics(mirrored, q, &XM);
    for (std::size_t i = 0; i < q.size(); ++i) {
      const Eigen::Matrix4d expected = M * XR[i].matrix() * M;
      EXPECT_LT((XL[i].matrix() - expected).cwiseAbs().maxCoeff(), 1e-9) << left.phalanges()[i].name << " u=" << u;
      EXPECT_LT((XM[i].matrix() - expected).cwiseAbs().maxCoeff(), 1e-12) << left.phalanges()[i].name << " u=" << u;
    }
  }
  // Capsules and metric points mirror too.
  const auto mirror = [](const Eigen::Vector3d& p) { return Eigen::Vector3d(p.x(), -p.y(), p.z()); };
  for (PhalanxId id : right.capsule_phalanges()) {
    const auto& r = *right.phalanges()[id.value].capsule;
    const auto& l = *left.phalanges()[id.value].capsule;
    EXPECT_LT((l.p_PhalanxA - mirror(r.p_PhalanxA)).norm(), kExact);
    EXPECT_LT((l.p_PhalanxB - mirror(r.p_PhalanxB)).norm(), kExact);
    EXPECT_LT((l.p_PhalanxCTc - mirror(r.p_PhalanxCTc)).norm(), kExact);
    EXPECT_LT((l.p_PhalanxSp - mirror(r.p_PhalanxSp)).norm(), kExact);
    EXPECT_EQ(l.radius, r.radius);
  }
  EXPECT_LT((left.selection_sphere().p_PalmCenter - mirror(right.selection_sphere().p_PalmCenter)).norm(), kExact);
  EXPECT_LT((left.palm_contact().p_PalmCenter - mirror(right.palm_contact().p_PalmCenter)).norm(), kExact);
}

TEST(HandKinematicsTest, LeftHandMirrorsRight) {
  expect_mirrored("human_right", "human_left");
  expect_mirrored("human_right_opposable", "human_left_opposable");
}

// A three-joint finger turning about z, then y, then x (a path that leaves every plane), with a
// capsule on its last phalanx.
const std::string kTwistedRig = std::string("name: \"twisted\"") + kPalm + R"(
fingers {
  name: "f"
  phalanges { name: "f_prox" rest { translation { x: 0.04 } }
    joint { axis { z: 1 } open_deg: -90 closed_deg: 90 min_deg: -90 max_deg: 90 } length: 0.03 }
  phalanges { name: "f_mid" rest { translation { x: 0.03 } }
    joint { axis { y: 1 } open_deg: -90 closed_deg: 90 min_deg: -90 max_deg: 90 } length: 0.025 }
  phalanges { name: "f_dist" rest { translation { x: 0.025 } }
    joint { axis { x: 1 } open_deg: -90 closed_deg: 90 min_deg: -90 max_deg: 90 } length: 0.02
    capsule { a { y: 0.004 } b { x: 0.018 z: 0.003 } radius: 0.007 ctc { x: 0.009 z: -0.007 } sp { x: 0.009 } } }
}
grasp_rule { members: ["f_dist"] }
)";

// The certified advance's claim, checked by sampling: over random joint angles and steps of the
// twisted finger, no point outside both end capsules of an advance lies deeper than the graze
// inside the capsule anywhere in between. The rate, turn and reach are measured here from the
// sampled motion (the controller bounds them from the rig). Advances three times as long do
// leave deeper points uncovered, so the sampling would see a bound that claimed too much.
TEST(HandKinematicsTest, ACertifiedAdvanceLeavesNoPointDeeperThanTheGrazeUncovered) {
  const HandRig rig = HandRig::parse(kTwistedRig, "inline");
  const CapsuleSpec& cap = *rig.phalanges()[2].capsule;
  const double r = cap.radius;
  constexpr double kGraze = 25e-6;
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> angle(-1.2, 1.2), delta(-0.4, 0.4), unit(0.0, 1.0);
  const auto segment_distance = [](const Eigen::Vector3d& p, const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
    const Eigen::Vector3d d = b - a;
    const double t = std::clamp((p - a).dot(d) / d.squaredNorm(), 0.0, 1.0);
    return (a + t * d - p).norm();
  };
  int checked = 0, in_band = 0, longer_uncovered = 0;
  for (int trial = 0; trial < 60; ++trial) {
    const std::vector<double> q0 = {angle(rng), angle(rng), angle(rng)};
    const std::vector<double> dq = {delta(rng), delta(rng), delta(rng)};
    std::vector<Eigen::Isometry3d> X;
    const auto axis_at = [&](double s) {  // the capsule's axis at fraction s of the step
      forward_kinematics(rig, {q0[0] + s * dq[0], q0[1] + s * dq[1], q0[2] + s * dq[2]}, &X);
      return std::pair(X[2] * cap.p_PhalanxA, X[2] * cap.p_PhalanxB);
    };
    // rate: the fastest axis end per unit step; reach: the farthest axis end from a joint origin.
    double rate = 0, reach = 0;
    constexpr int kSamples = 2000;
    for (int i = 0; i < kSamples; ++i) {
      const double s = static_cast<double>(i) / kSamples, ds = 1.0 / kSamples;
      const auto [a0, b0] = axis_at(s);
      for (int k = 0; k < 3; ++k) reach = std::max({reach, (a0 - X[k].translation()).norm(), (b0 - X[k].translation()).norm()});
      const auto [a1, b1] = axis_at(s + ds);
      rate = std::max({rate, (a1 - a0).norm() / ds, (b1 - b0).norm() / ds});
    }
    rate *= 1.01;
    const double turn = std::abs(dq[0]) + std::abs(dq[1]) + std::abs(dq[2]);
    const double h = certified_advance(rate, turn, reach, r, kGraze);
    ASSERT_GT(h, 0);
    for (double factor : {1.0, 3.0}) {
      const double span = std::min(1.0, factor * h);
      const auto [a0, b0] = axis_at(0);
      const auto [a1, b1] = axis_at(span);
      for (int i = 0; i < 400; ++i) {
        // A point at depth r - rho inside the capsule at a moment in between, across the path of
        // an axis point from its chord (where the end capsules leave room).
        const double u = unit(rng), s = span * (0.05 + 0.9 * unit(rng));
        const Eigen::Vector3d chord = (a1 + u * (b1 - a1)) - (a0 + u * (b0 - a0));
        const auto [a, b] = axis_at(s);
        Eigen::Vector3d n = chord.cross(b - a);  // square to the chord and to the axis
        if (!(n.norm() > 1e-15)) continue;
        n = (unit(rng) < 0.5 ? 1.0 : -1.0) * n.normalized();
        const double rho = r - 3 * kGraze * unit(rng);
        const Eigen::Vector3d y = a + u * (b - a) + rho * n;
        if (segment_distance(y, a, b) < rho - 1e-12) continue;  // nearer another axis point: deeper than drawn
        if (segment_distance(y, a0, b0) < r || segment_distance(y, a1, b1) < r) continue;  // inside an end
        if (factor == 1.0) {
          ++checked;
          in_band += rho >= r - kGraze;
          EXPECT_GE(rho, r - kGraze) << "trial " << trial << ": a point " << (r - rho) * 1e6
                                     << " um deep is outside both end capsules of a certified advance";
        } else {
          longer_uncovered += rho < r - kGraze;
        }
      }
    }
  }
  EXPECT_GT(checked, 100) << "points outside both ends were drawn";
  EXPECT_GT(in_band, 0);
  EXPECT_GT(longer_uncovered, 0) << "three times the certified advance leaves deeper points uncovered";
}

}  // namespace
}  // namespace telegrasp::sim
