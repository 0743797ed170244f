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

}  // namespace telegrasp::sim
