// The grasping logic.
#include "telegrasp/sim/grasp_rule.h"

#include <algorithm>

namespace telegrasp::sim {

bool evaluate_grasp_rule(const std::vector<std::vector<GraspTerm>>& rule, const std::vector<std::uint8_t>& blocked,
                         bool palm_contact) {
  if (rule.empty()) return false;
  return std::all_of(rule.begin(), rule.end(), [&](const std::vector<GraspTerm>& group) {
    return std::any_of(group.begin(), group.end(),
                       [&](const GraspTerm& t) { return t.palm ? palm_contact : blocked[t.phalanx.value] != 0; });
  });
}

}  // namespace telegrasp::sim
