// Tests the grasping logic: the full truth table of the paper's rule, and a gripper's own rule.
#include "telegrasp/sim/grasp_rule.h"

#include <gtest/gtest.h>

namespace telegrasp::sim {
namespace {

TEST(GraspRuleTest, HumanRuleTruthTable) {
  const HandRig rig = HandRig::load(HandRig::builtin_path("human_right"));
  const char* names[] = {"thumb_mid",  "thumb_dist",  "index_mid", "index_dist",
                         "middle_mid", "middle_dist", "ring_mid",  "little_dist"};
  // Every combination of the eight capsules that matter or must not matter, and the palm.
  for (unsigned bits = 0; bits < (1u << 9); ++bits) {
    std::vector<std::uint8_t> blocked(rig.phalanges().size(), 0);
    for (int i = 0; i < 8; ++i) blocked[rig.find(names[i]).value] = (bits >> i) & 1;
    const bool palm = (bits >> 8) & 1;
    const bool th = (bits & 1) || (bits & 2), in = (bits & 4) || (bits & 8), mi = (bits & 16) || (bits & 32);
    const bool expected = (th || palm) && (in || mi);  // sim/README.md, section 3.4 Grasping logic
    EXPECT_EQ(evaluate_grasp_rule(rig.grasp_rule(), blocked, palm), expected) << "bits " << bits;
  }
}

TEST(GraspRuleTest, GripperOpposesFingerAOrPalmWithBOrC) {
  const HandRig rig = HandRig::load(HandRig::builtin_path("gripper3"));
  std::vector<std::uint8_t> blocked(rig.phalanges().size(), 0);
  blocked[rig.find("b_dist").value] = 1;
  EXPECT_FALSE(evaluate_grasp_rule(rig.grasp_rule(), blocked, false));
  EXPECT_TRUE(evaluate_grasp_rule(rig.grasp_rule(), blocked, true));
  blocked[rig.find("a_mid").value] = 1;
  EXPECT_TRUE(evaluate_grasp_rule(rig.grasp_rule(), blocked, false));
  blocked[rig.find("b_dist").value] = 0;
  EXPECT_FALSE(evaluate_grasp_rule(rig.grasp_rule(), blocked, true));
}

TEST(GraspRuleTest, EmptyRuleNeverGrasps) { EXPECT_FALSE(evaluate_grasp_rule({}, {1, 1}, true)); }

}  // namespace
}  // namespace telegrasp::sim
