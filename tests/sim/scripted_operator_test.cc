// Tests ScriptedOperator and plan_grasp: determinism, skills, and complete grasp-lift-release
// trials on stand-ins, including a fast close on the knife that must not tunnel.
#include "telegrasp/sim/scripted_operator.h"

#include "telegrasp/sim/world.h"

#include <gtest/gtest.h>

#include <fstream>

namespace telegrasp::sim {
namespace {

std::shared_ptr<const HandRig> rig(const std::string& name) {
  return std::make_shared<const HandRig>(HandRig::load(HandRig::builtin_path(name)));
}

ObjectModelPtr standin(const std::string& name) { return make_standin_model(*find_protocol_object(name)); }

TEST(ScriptedOperatorTest, UnknownSkillIsNamed) {
  try {
    skill_profile("wizard");
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("wizard"), std::string::npos);
  }
}

std::vector<double> inputs(std::uint64_t seed) {
  auto model = standin("013_apple");
  const Eigen::Isometry3d X_WorldObject = World::resting_pose(*model, 0.45, 0.0, 0.3);
  ScriptedOperator op(rig("human_right"), skill_profile("inexperienced"), seed);
  op.begin(*model, X_WorldObject, Eigen::Isometry3d::Identity(), 0.0);
  std::vector<double> out;
  for (int t = 0; t < 200; ++t) {
    const ControllerInput in = op.next(t / 90.0, false);
    out.insert(out.end(), in.X_WorldPalm.data(), in.X_WorldPalm.data() + 16);
    out.push_back(in.trigger);
  }
  return out;
}

TEST(ScriptedOperatorTest, SeededAndDeterministic) {
  EXPECT_EQ(inputs(3), inputs(3));
  EXPECT_NE(inputs(3), inputs(4));
}

// A full trial in a world; returns whether the object was held through the lift and hold.
bool trial(const std::string& rig_name, const std::string& object, const std::string& skill, GraspSettings settings = {}) {
  WorldSettings ws;
  ws.grasp = settings;
  World world(ws);
  auto model = standin(object);
  const ObjectId id = world.add_object(model, World::resting_pose(*model, 0.45, 0.02, 0.5));
  auto hand_rig = rig(rig_name);
  const HandId hand = world.add_hand(hand_rig);
  for (int i = 0; i < 30; ++i) world.step();
  ScriptedOperator op(hand_rig, skill_profile(skill), 9, settings);
  const double z0 = world.object_pose(id).translation().z();
  op.begin(*model, world.object_pose(id), Eigen::Isometry3d(Eigen::Translation3d(0.15, -0.2, 0.3)), world.time());
  double z_max = z0;
  while (!op.done() && world.time() < 20) {
    world.set_input(hand, op.next(world.time(), world.holder(id) == hand));
    world.step();
    if (op.phase() == OperatorPhase::kHold) z_max = std::max(z_max, world.object_pose(id).translation().z());
  }
  EXPECT_TRUE(op.done());
  if (op.held_after_lift()) {
    EXPECT_GT(z_max - z0, 0.09) << "lifted about 10 cm";
  }
  return op.held_after_lift();
}

TEST(ScriptedOperatorTest, PerfectOperatorLiftsACan) { EXPECT_TRUE(trial("human_right", "002_master_chef_can", "perfect")); }
TEST(ScriptedOperatorTest, LeftHandLiftsABox) { EXPECT_TRUE(trial("human_left", "004_sugar_box", "perfect")); }
TEST(ScriptedOperatorTest, GripperLiftsABall) { EXPECT_TRUE(trial("gripper3", "055_baseball", "perfect")); }

void fast_close_on(const ObjectModelPtr& knife);

// The built-in knife, and the YCB scan when ../shared/data/ycb is present.
std::vector<ObjectModelPtr> knives() {
  std::vector<ObjectModelPtr> out{standin("032_knife")};
  const std::string scan = std::string(TELEGRASP_YCB_DIR) + "/032_knife.ply";
  if (std::ifstream(scan).good()) out.push_back(load_object_model(scan));
  return out;
}

// A fast close on the knife (10x the rig's finger speed, the trigger jumping to 1) grasps it
// without any blocked phalanx sinking into the blade.
TEST(ScriptedOperatorTest, FastCloseOnKnifeDoesNotTunnel) {
  for (const ObjectModelPtr& knife : knives()) {
    SCOPED_TRACE(knife->source);
    fast_close_on(knife);
  }
}

void fast_close_on(const ObjectModelPtr& knife) {
  auto hand_rig = rig("human_right");
  const Eigen::Isometry3d X_WorldObject = World::resting_pose(*knife, 0.45, 0.0, 0.9);
  GraspSettings fast;
  fast.speed_scale = 10.0;
  const GraspPlan plan = plan_grasp(hand_rig, fast, *knife, X_WorldObject, 1.0 / 90);
  ASSERT_TRUE(plan.predicted_grasp);
  HandController hand(hand_rig, fast);
  const ObjectView view{ObjectId(0), X_WorldObject, knife.get()};
  ControllerInput in;
  in.X_WorldPalm = plan.X_WorldPalm;
  in.trigger = 1.0;  // the trigger jumps fully closed at once
  for (int t = 0; t < 30 && !hand.state().grasped.valid(); ++t) hand.tick(in, 1.0 / 90, {&view, 1});
  ASSERT_TRUE(hand.state().grasped.valid());
  const GraspMetrics m = hand.measure(view);
  int blocked = 0;
  for (const CapsuleMetric& c : m.capsules) {
    if (!c.blocked) continue;
    ++blocked;
    EXPECT_GE(c.signed_distance, -0.1e-3) << hand_rig->phalanges()[c.phalanx.value].name;
  }
  EXPECT_GE(blocked, 2);
}

}  // namespace
}  // namespace telegrasp::sim
