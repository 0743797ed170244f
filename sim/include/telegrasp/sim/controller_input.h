// ControllerInput: one controller sample for one hand (pose, trigger, per-finger curls), and
// its check against the hand's rig.
#pragma once

#include "telegrasp/sim/hand_rig.h"

#include <Eigen/Geometry>

#include <string>
#include <vector>

namespace telegrasp::sim {

/// One controller sample for one hand.
struct ControllerInput {
  Eigen::Isometry3d X_WorldPalm = Eigen::Isometry3d::Identity();
  double trigger = 0;  ///< 0 open .. 1 closed.
  std::vector<double> curls;  ///< Empty, or one value in [0, 1] per finger of the rig.
  bool tracking_valid = true;  ///< False: keep the last pose, still apply trigger and curls.
};

/// Returns "" for a usable input, else the reason it is not (names the field).
std::string validate_input(const ControllerInput& input, const HandRig& rig);

}  // namespace telegrasp::sim
