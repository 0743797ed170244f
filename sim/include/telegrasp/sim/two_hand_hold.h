// TwoHandHold: the pose of an object held by two hands at once, from both hands' attachments.
//
// Each hand's attach point is a fixed point of its palm frame, p_PalmAttach (the World uses the
// centre of the rig's palm contact sphere, where the hand grips); in the world it is
// a_i = X_WorldPalm_i * p_PalmAttach_i. When the second hand joins (tick 0 of the hold) the object
// is fixed in a frame B at the attach points' midpoint m0 = (a1 + a2) / 2 with world axes. On every
// later tick B is at the current midpoint m = (a1 + a2) / 2, turned by
//   R_B = S * T,
//   S = the minimal rotation taking d0 to d (d = unit(a2 - a1) now, d0 at the join; the swing),
//   T = the twist about d0 of S^-1 * dR1, with dR1 = R_WorldPalm1 * R_WorldPalm1(join)^-1 the
//       first hand's rotation since the join (rotating hand 1 about the line between the hands
//       rolls the object about it);
// and the object follows B rigidly: X_WorldObject = [R_B, m] * [I, m0]^-1 * X_WorldObject(join).
// If both hands move as one rigid body (rotation R), R_B = R exactly: the object moves with them.
// If hand 1 stays and hand 2 circles it, the object turns about a1. When the attach points are
// (nearly) one point, d is undefined and R_B = dR1 (the first hand alone turns the object).
#pragma once

#include <Eigen/Geometry>

namespace telegrasp::sim {

/// The reference of a two-hand hold, taken when the second hand joins.
struct TwoHandHold {
  Eigen::Vector3d p_Palm1Attach{0, 0, 0};  ///< First hand's attach point, its palm frame.
  Eigen::Vector3d p_Palm2Attach{0, 0, 0};  ///< Second hand's attach point, its palm frame.
  Eigen::Matrix3d R_WorldPalm1 = Eigen::Matrix3d::Identity();  ///< First hand's rotation at the join.
  Eigen::Vector3d d_World{0, 0, 0};  ///< Unit a2 - a1 at the join; zero when the points (nearly) coincide.
  Eigen::Isometry3d X_MidObject = Eigen::Isometry3d::Identity();  ///< Object in frame B at the join.
};

/// Attach points closer than this (m) give no direction: the first hand alone turns the object.
inline constexpr double kTwoHandMinSpan = 1e-6;

/// The reference of a hold starting now, with the object at `X_WorldObject`.
TwoHandHold start_two_hand_hold(const Eigen::Isometry3d& X_WorldPalm1, const Eigen::Vector3d& p_Palm1Attach,
                                const Eigen::Isometry3d& X_WorldPalm2, const Eigen::Vector3d& p_Palm2Attach,
                                const Eigen::Isometry3d& X_WorldObject);

/// The object's pose for the hands' current palm poses (the definition above).
Eigen::Isometry3d two_hand_object_pose(const TwoHandHold& hold, const Eigen::Isometry3d& X_WorldPalm1,
                                       const Eigen::Isometry3d& X_WorldPalm2);

}  // namespace telegrasp::sim
