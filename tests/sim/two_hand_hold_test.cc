// Tests the two-hand hold pose (two_hand_hold.h) against poses worked out by hand: rigid motion
// of both hands, one hand circling the other, the first hand's twist, and coinciding attach points.
#include "telegrasp/sim/two_hand_hold.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

namespace telegrasp::sim {
namespace {

constexpr double kTol = 1e-12;  // rounding of a few rotations and products

Eigen::Isometry3d pose(const Eigen::Vector3d& p, const Eigen::AngleAxisd& r = Eigen::AngleAxisd::Identity()) {
  Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
  X.linear() = r.toRotationMatrix();
  X.translation() = p;
  return X;
}

// The gap between two poses: translation distance plus rotation matrix difference.
double gap(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b) {
  return (a.translation() - b.translation()).norm() + (a.linear() - b.linear()).norm();
}

// Two palms 0.4 m apart along x (each turned about z) holding an object, attach points 3 cm under
// each palm: the line between the attach points is +x.
struct Scene {
  const Eigen::Vector3d p_Attach{0, 0, -0.03};
  const Eigen::Isometry3d X_WorldPalm1 = pose({0.2, 0.1, 0.3}, Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitZ()));
  const Eigen::Isometry3d X_WorldPalm2 = pose({0.6, 0.1, 0.3}, Eigen::AngleAxisd(-0.2, Eigen::Vector3d::UnitZ()));
  const Eigen::Isometry3d X_WorldObject = pose({0.4, 0.12, 0.25}, Eigen::AngleAxisd(0.7, Eigen::Vector3d::UnitZ()));
  TwoHandHold hold = start_two_hand_hold(X_WorldPalm1, p_Attach, X_WorldPalm2, p_Attach, X_WorldObject);
};

TEST(TwoHandHoldTest, AtTheJoinTheObjectStaysWhereItIs) {
  Scene s;
  EXPECT_LT(gap(two_hand_object_pose(s.hold, s.X_WorldPalm1, s.X_WorldPalm2), s.X_WorldObject), kTol);
}

TEST(TwoHandHoldTest, BothHandsMovingRigidlyCarryTheObjectRigidly) {
  Scene s;
  const Eigen::Isometry3d M = pose({0.05, -0.3, 0.2}, Eigen::AngleAxisd(1.1, Eigen::Vector3d(1, -2, 0.5).normalized()));
  const Eigen::Isometry3d got = two_hand_object_pose(s.hold, M * s.X_WorldPalm1, M * s.X_WorldPalm2);
  EXPECT_LT(gap(got, M * s.X_WorldObject), kTol);
}

TEST(TwoHandHoldTest, BothHandsRisingEquallyKeepTheOrientation) {
  Scene s;
  const Eigen::Isometry3d up = pose({0, 0, 0.1});
  const Eigen::Isometry3d got = two_hand_object_pose(s.hold, up * s.X_WorldPalm1, up * s.X_WorldPalm2);
  EXPECT_LT((got.linear() - s.X_WorldObject.linear()).norm(), kTol);
  EXPECT_LT((got.translation() - s.X_WorldObject.translation() - Eigen::Vector3d(0, 0, 0.1)).norm(), kTol);
}

// Hand 2 (turning with it) circles hand 1's attach point about +z: the object turns about that point.
TEST(TwoHandHoldTest, OneHandCirclingTheOtherTurnsTheObjectAboutTheFirstAttachPoint) {
  Scene s;
  const Eigen::Vector3d a1 = s.X_WorldPalm1 * s.p_Attach;
  for (double angle : {0.1, 0.8, 2.0, -1.3}) {
    const Eigen::Isometry3d turn =
        pose(a1) * pose({0, 0, 0}, Eigen::AngleAxisd(angle, Eigen::Vector3d::UnitZ())) * pose(-a1);
    const Eigen::Isometry3d got = two_hand_object_pose(s.hold, s.X_WorldPalm1, turn * s.X_WorldPalm2);
    EXPECT_LT(gap(got, turn * s.X_WorldObject), kTol) << "angle " << angle;
  }
}

// Hand 2 rising by h at a horizontal distance L from hand 1 tilts the object by atan(h / L) about
// the horizontal axis perpendicular to the line between them (here +y, pitching down towards hand 2 as it rises).
TEST(TwoHandHoldTest, OneHandRisingTiltsTheObjectByTheAngleOfTheLineBetweenTheHands) {
  Scene s;
  const double h = 0.05, L = 0.4;
  const Eigen::Isometry3d got = two_hand_object_pose(s.hold, s.X_WorldPalm1, pose({0, 0, h}) * s.X_WorldPalm2);
  const Eigen::Matrix3d expected_R =
      Eigen::AngleAxisd(-std::atan2(h, L), Eigen::Vector3d::UnitY()).toRotationMatrix() * s.X_WorldObject.linear();
  EXPECT_LT((got.linear() - expected_R).norm(), kTol);
  // The midpoint of the attach points carries the object.
  const Eigen::Vector3d m0 = 0.5 * (s.X_WorldPalm1 * s.p_Attach + s.X_WorldPalm2 * s.p_Attach);
  const Eigen::Vector3d m = m0 + Eigen::Vector3d(0, 0, h / 2);
  const Eigen::Vector3d expected_p =
      m + Eigen::AngleAxisd(-std::atan2(h, L), Eigen::Vector3d::UnitY()) * (s.X_WorldObject.translation() - m0);
  EXPECT_LT((got.translation() - expected_p).norm(), kTol);
}

// Hand 1 turning about the line between the hands (hand 2 still) rolls the object about that line.
TEST(TwoHandHoldTest, TheFirstHandsTwistAboutTheLineRollsTheObject) {
  Scene s;
  const Eigen::Vector3d a1 = s.X_WorldPalm1 * s.p_Attach;
  const Eigen::AngleAxisd roll(0.4, Eigen::Vector3d::UnitX());  // the line a1 -> a2 is +x here
  const Eigen::Isometry3d turn = pose(a1) * pose({0, 0, 0}, roll) * pose(-a1);
  const Eigen::Isometry3d got = two_hand_object_pose(s.hold, turn * s.X_WorldPalm1, s.X_WorldPalm2);
  const Eigen::Vector3d m0 = 0.5 * (a1 + s.X_WorldPalm2 * s.p_Attach);
  EXPECT_LT(gap(got, pose(m0) * pose({0, 0, 0}, roll) * pose(-m0) * s.X_WorldObject), kTol);
}

// The second hand's own rotation (with its attach point fixed) does not turn the object.
TEST(TwoHandHoldTest, TheSecondHandTurningInPlaceLeavesTheObject) {
  Scene s;
  const Eigen::Vector3d a2 = s.X_WorldPalm2 * s.p_Attach;
  const Eigen::Isometry3d turn =
      pose(a2) * pose({0, 0, 0}, Eigen::AngleAxisd(0.9, Eigen::Vector3d(0, 1, 1).normalized())) * pose(-a2);
  const Eigen::Isometry3d got = two_hand_object_pose(s.hold, s.X_WorldPalm1, turn * s.X_WorldPalm2);
  EXPECT_LT(gap(got, s.X_WorldObject), kTol);
}

// Attach points at one spot: no line between them, the first hand alone turns the object about the midpoint.
TEST(TwoHandHoldTest, CoincidingAttachPointsFollowTheFirstHandsRotation) {
  const Eigen::Vector3d p_Attach(0, 0, -0.03);
  const Eigen::Isometry3d X_WorldPalm = pose({0.3, 0, 0.2});
  const Eigen::Isometry3d X_WorldObject = pose({0.3, 0.01, 0.16});
  const TwoHandHold hold = start_two_hand_hold(X_WorldPalm, p_Attach, X_WorldPalm, p_Attach, X_WorldObject);
  EXPECT_TRUE(hold.d_World.isZero());
  const Eigen::AngleAxisd r(std::numbers::pi / 3, Eigen::Vector3d::UnitZ());
  const Eigen::Isometry3d turned = X_WorldPalm * pose({0, 0, 0}, r);
  const Eigen::Isometry3d got = two_hand_object_pose(hold, turned, X_WorldPalm);
  const Eigen::Vector3d m0 = X_WorldPalm * p_Attach, m = 0.5 * (turned * p_Attach + m0);
  EXPECT_LT((got.translation() - (m + r * (X_WorldObject.translation() - m0))).norm(), kTol);
  EXPECT_LT((got.linear() - r.toRotationMatrix()).norm(), kTol);
}

}  // namespace
}  // namespace telegrasp::sim
