// The grasping logic: grasped = AND over the rig's groups of (OR over blocked members).
#pragma once

#include "telegrasp/sim/hand_rig.h"

#include <cstdint>
#include <vector>

namespace telegrasp::sim {

/// Evaluates the rig's grasp rule; `blocked` is indexed by phalanx, `palm_contact` is the palm
/// contact volume overlapping the selected object. For the human hand this is
/// (thumb_mid | thumb_dist | palm) & (index_mid | index_dist | middle_mid | middle_dist).
bool evaluate_grasp_rule(const std::vector<std::vector<GraspTerm>>& rule, const std::vector<std::uint8_t>& blocked,
                         bool palm_contact);

}  // namespace telegrasp::sim
