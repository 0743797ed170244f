// Forward kinematics of a hand rig: phalanx frames from joint angles.
#pragma once

#include "telegrasp/sim/hand_rig.h"

#include <Eigen/Geometry>

#include <vector>

namespace telegrasp::sim {

/// Pose of phalanx `i` in the palm frame given its parent's pose and its joint angle.
Eigen::Isometry3d phalanx_pose(const PhalanxSpec& phalanx, const Eigen::Isometry3d& X_PalmParent, double q);

/// X_PalmPhalanx for every phalanx of `rig` at joint angles `q` (size = phalanges().size()).
void forward_kinematics(const HandRig& rig, const std::vector<double>& q,
                        std::vector<Eigen::Isometry3d>* X_PalmPhalanx);

/// Target joint angle at closing input `u` in [0, 1]: open + t (closed - open), within limits,
/// t = (u - closes_from) / (closes_until - closes_from) clamped to [0, 1] (t = u by default).
double target_angle(const PhalanxSpec& phalanx, double u);

/// The longest advance h (as a fraction of a finger step) over which a capsule of `radius`,
/// clear of a surface at both ends of the advance, can have come at most `graze` inside it in
/// between, when its axis points move at most `rate` per unit step and their paths' second
/// derivative is at most turn^2 reach (turn: the sum of |joint delta| up to the capsule's
/// phalanx per unit step; reach: the largest distance from those joints' axes to the capsule's
/// axis). Between the ends, a material axis point lies within A h^2 / 8 of the chord between its
/// end positions (A = turn^2 reach), and the two end balls around them cover the ball of radius
/// sqrt(radius^2 - c^2 / 4) around any point of that chord (c <= rate h): the depth left
/// uncovered is at most c^2 / (7.4 radius) + A h^2 / 8 for c <= radius. Infinite when nothing moves.
double certified_advance(double rate, double turn, double reach, double radius, double graze);

}  // namespace telegrasp::sim
