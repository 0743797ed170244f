// Tests ScriptedOperator and plan_grasp: determinism, skills, and complete grasp-lift-release
// trials on stand-ins, including a fast close on the knife that must not tunnel.
#include "telegrasp/sim/scripted_operator.h"

#include "telegrasp/sim/grasp_quality.h"
#include "telegrasp/sim/grasp_type.h"

#include "telegrasp/sim/standin_objects.h"
#include "telegrasp/sim/world.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <fstream>
#include <numbers>
#include <optional>
#include <vector>

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

TEST(ScriptedOperatorTest, FittsTimeIsShannonsFormula) {
  // a + b log2(1 + D / W): D = 0.3 m, W = 0.1 m gives log2(4) = 2 bits.
  EXPECT_DOUBLE_EQ(fitts_time(0.1, 0.2, 0.3, 0.1), 0.1 + 0.2 * 2.0);
  EXPECT_DOUBLE_EQ(fitts_time(0.1, 0.2, 0.0, 0.05), 0.1);  // no distance: the intercept
  EXPECT_DOUBLE_EQ(fitts_time(0.0, 0.15, 0.07, 0.01), 0.15 * 3.0);  // log2(8)
}

TEST(ScriptedOperatorTest, PracticeFactorFollowsThePowerLaw) {
  OperatorSkill s = skill_profile("inexperienced");
  s.learning_gain = 0.6;
  s.learning_exponent = 0.5;
  EXPECT_DOUBLE_EQ(practice_factor(s, 0), 1.6);
  EXPECT_DOUBLE_EQ(practice_factor(s, 3), 1.0 + 0.6 / 2.0);  // (1 + 3)^-0.5
  s.learning_gain = 0;
  EXPECT_DOUBLE_EQ(practice_factor(s, 7), 1.0);
}

TEST(ScriptedOperatorTest, BuiltInProfilesValidate) {
  for (const char* name : {"perfect", "experienced", "inexperienced"})
    EXPECT_EQ(validate_skill(skill_profile(name)), "") << name;
}

TEST(ScriptedOperatorTest, ProfilesParseFromText) {
  const std::vector<OperatorSkill> p = parse_skill_profiles(
      "# fitted\n[experienced]\nreaction_time = 0.2  # s\norientation_error_deg = 2\n\n[novice]\nfitts_slope=0.1\n");
  ASSERT_EQ(p.size(), 2u);
  EXPECT_EQ(p[0].name, "experienced");
  EXPECT_DOUBLE_EQ(p[0].reaction_time, 0.2);
  EXPECT_NEAR(p[0].orientation_error, 2.0 * std::acos(-1.0) / 180.0, 1e-15);
  EXPECT_DOUBLE_EQ(p[0].position_error, skill_profile("experienced").position_error);  // kept from the built-in
  EXPECT_EQ(p[1].name, "novice");  // a new name starts from "experienced"
  EXPECT_DOUBLE_EQ(p[1].fitts_slope, 0.1);
  EXPECT_DOUBLE_EQ(p[1].squeeze_time, skill_profile("experienced").squeeze_time);
}

TEST(ScriptedOperatorTest, BadProfilesAreRejectedWithTheLine) {
  auto error = [](const std::string& text) {
    try {
      parse_skill_profiles(text);
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(error("[experienced]\nspeed = 2\n").find("line 2: unknown key 'speed'"), std::string::npos);
  EXPECT_NE(error("[experienced]\nreaction_time = fast\n").find("line 2"), std::string::npos);
  EXPECT_NE(error("reaction_time = 0.2\n").find("line 1"), std::string::npos);
  EXPECT_NE(error("[experienced]\nsqueeze_time = 0\n").find("squeeze_time"), std::string::npos);
  EXPECT_NE(error("[experienced]\nfitts_slope = -0.1\n").find("fitts_slope"), std::string::npos);
  EXPECT_NE(error("[experienced]\napproach_tolerance = nan\n").find("approach_tolerance"), std::string::npos);
}

TEST(ScriptedOperatorTest, ScaledSkillSpeedsUpEveryTime) {
  OperatorSkill base = skill_profile("experienced");
  base.aperture_time = 0.8;
  const OperatorSkill s = base.scaled(2.0, 0.5);
  EXPECT_DOUBLE_EQ(s.reach_speed, 2.0 * base.reach_speed);
  EXPECT_DOUBLE_EQ(s.reaction_time, base.reaction_time / 2.0);
  EXPECT_DOUBLE_EQ(s.squeeze_time, base.squeeze_time / 2.0);
  EXPECT_DOUBLE_EQ(s.fitts_intercept, base.fitts_intercept / 2.0);
  EXPECT_DOUBLE_EQ(s.fitts_slope, base.fitts_slope / 2.0);
  EXPECT_DOUBLE_EQ(s.aperture_time, 0.4);
  EXPECT_DOUBLE_EQ(s.position_error, base.position_error / 2.0);
  EXPECT_DOUBLE_EQ(s.orientation_error, base.orientation_error / 2.0);
}

// The first input after the reaction at which the hand has reached the grasp pose and squeezes.
double squeeze_start(const OperatorSkill& skill, const std::string& object, std::optional<int> grasps_done) {
  auto model = standin(object);
  ScriptedOperator op(rig("human_right"), skill, 5);
  op.begin(*model, World::resting_pose(*model, 0.45, 0.0, 0.3), Eigen::Isometry3d(Eigen::Translation3d(0.2, -0.2, 0.3)),
           0.0, grasps_done);
  for (int t = 0; t < 900; ++t) {
    op.next(t / 90.0, false);
    if (op.phase() == OperatorPhase::kSqueeze) return t / 90.0;
  }
  return 1e9;
}

TEST(ScriptedOperatorTest, LargerObjectsAndLessPracticeTakeLonger) {
  OperatorSkill s = skill_profile("experienced");
  s.position_error = s.orientation_error = 0;
  s.fitts_intercept = 0.1;
  s.fitts_slope = 0.15;
  s.size_standoff = 0.5;
  s.learning_gain = 0.5;
  EXPECT_GT(squeeze_start(s, "003_cracker_box", 10), squeeze_start(s, "018_plum", 10) + 0.05);
  EXPECT_GT(squeeze_start(s, "018_plum", 0), squeeze_start(s, "018_plum", 10) + 0.2);
  // Without a session, a practised operator: faster than even after 10 grasps.
  EXPECT_LT(squeeze_start(s, "018_plum", std::nullopt), squeeze_start(s, "018_plum", 10));
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
bool trial(const std::string& rig_name, const std::string& object, const std::string& skill,
           GraspSettings settings = {}, double yaw = 0.5) {
  WorldSettings ws;
  ws.grasp = settings;
  World world(ws);
  auto model = standin(object);
  const ObjectId id = world.add_object(model, World::resting_pose(*model, 0.45, 0.02, yaw));
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

TEST(ScriptedOperatorTest, PerfectOperatorLiftsACan) {
  EXPECT_TRUE(trial("human_right", "002_master_chef_can", "perfect"));
}
TEST(ScriptedOperatorTest, LeftHandLiftsABox) { EXPECT_TRUE(trial("human_left", "004_sugar_box", "perfect")); }
TEST(ScriptedOperatorTest, GripperLiftsABall) { EXPECT_TRUE(trial("gripper3", "055_baseball", "perfect")); }

// The phases an operator goes through from its squeeze, told that the hand it sees stands
// `raised` above its controller, holding until it lets go; with the squeeze pose's z and the
// hold's and the last input's.
struct AfterSqueeze {
  std::vector<OperatorPhase> phases;
  double z_grasp = 0, z_hold = 0, z_last = 0;
};
AfterSqueeze run_after_squeeze(ScriptedOperator& op, double raised) {
  const auto model = standin("005_tomato_soup_can");
  op.begin(*model, World::resting_pose(*model, 0.45, 0.0, 0.0),
           Eigen::Isometry3d(Eigen::Translation3d(0.15, -0.2, 0.3)), 0.0);
  AfterSqueeze out;
  double t = 0;
  ControllerInput in;
  while (op.phase() != OperatorPhase::kSqueeze && t < 10) in = op.next(t += 1.0 / 90, false);
  out.z_grasp = in.X_WorldPalm.translation().z();
  op.see_hand_raised(raised);
  while (!op.done() && t < 20) {
    const OperatorPhase before = op.phase();
    in = op.next(t += 1.0 / 90, before != OperatorPhase::kRelease);  // held until it opens
    if (op.phase() == OperatorPhase::kHold) out.z_hold = in.X_WorldPalm.translation().z();
    if (out.phases.empty() || out.phases.back() != op.phase()) out.phases.push_back(op.phase());
  }
  out.z_last = in.X_WorldPalm.translation().z();
  return out;
}

// A person lifts the hand they see: a hand the table held 20 mm above its controller has its
// controller lifted 10 + 2 cm (it rejoins the controller on the way, so the object still rises
// 10 cm). Asked to, the operator puts the object back down, 5 mm above where it grasped, before
// it opens; by default it opens at the top.
TEST(ScriptedOperatorTest, LiftsTheHandItSeesAndPutsTheObjectBackDownWhenAsked) {
  using P = OperatorPhase;
  ScriptedOperator tidy(rig("human_right"), skill_profile("perfect"), 3, {});
  tidy.put_down_before_release(true);
  const AfterSqueeze a = run_after_squeeze(tidy, 0.02);
  EXPECT_NEAR(a.z_hold - a.z_grasp, ScriptedOperator::kLiftHeight + 0.02, 1e-12);
  EXPECT_NEAR(a.z_last - a.z_grasp, ScriptedOperator::kPutDownClearance, 1e-12);
  EXPECT_EQ(a.phases, (std::vector<P>{P::kLift, P::kHold, P::kPutDown, P::kRelease, P::kDone}));

  ScriptedOperator plain(rig("human_right"), skill_profile("perfect"), 3, {});
  const AfterSqueeze b = run_after_squeeze(plain, -0.01);  // a hand below its controller: lifted 10 cm
  EXPECT_NEAR(b.z_hold - b.z_grasp, ScriptedOperator::kLiftHeight, 1e-12);
  EXPECT_NEAR(b.z_last, b.z_hold, 1e-12);
  EXPECT_EQ(b.phases, (std::vector<P>{P::kLift, P::kHold, P::kRelease, P::kDone}));
}

// close_offline measures how far the open hand reaches under the table top: nothing from a metre
// above it; with the palm's centre half a metre below it, at least that plus the palm's half
// thickness (the lowest skin of its rounded box).
TEST(ScriptedOperatorTest, OfflineClosingMeasuresTheOpenHandUnderTheTable) {
  const auto hand_rig = rig("human_right");
  const auto model = standin("005_tomato_soup_can");
  const Eigen::Isometry3d X_WorldObject = World::resting_pose(*model, 0.45, 0.0, 0.0);
  const auto palm_at = [](double z) { return Eigen::Isometry3d(Eigen::Translation3d(0.0, 0.0, z)); };
  EXPECT_EQ(close_offline(hand_rig, {}, *model, X_WorldObject, palm_at(1.0), 1.0 / 90).open_table_depth, 0.0);
  const double h = hand_rig->palm_half_extent().z();
  EXPECT_GE(close_offline(hand_rig, {}, *model, X_WorldObject, palm_at(-0.5), 1.0 / 90).open_table_depth,
            0.5 + h - 1e-12);
}

// The planner keeps the open hand above the table: at these turns the flat drill's best-scored
// plan was a side grasp whose open thumb hung 28 mm under the table top; the resolved pose held
// the hand 54 mm off the plan and every attempt missed. Now a top grasp, and the trial holds.
TEST(ScriptedOperatorTest, PlansKeepTheOpenHandAboveTheTable) {
  const auto hand_rig = rig("human_right");
  const auto model = standin("035_power_drill");
  for (double yaw_deg : {45.0, 90.0, 135.0, 180.0, 270.0}) {
    const Eigen::Isometry3d X_WorldObject = World::resting_pose(*model, 0.45, 0.0, yaw_deg * std::numbers::pi / 180);
    const GraspPlan plan = plan_grasp(hand_rig, {}, *model, X_WorldObject, 1.0 / 90);
    EXPECT_TRUE(plan.predicted_grasp) << yaw_deg;
    const OfflineClosing c = close_offline(hand_rig, {}, *model, X_WorldObject, plan.X_WorldPalm, 1.0 / 90);
    EXPECT_LT(c.open_table_depth, 0.005) << yaw_deg;
  }
  EXPECT_TRUE(trial("human_right", "035_power_drill", "perfect", {}, std::numbers::pi / 2));
}

// A plan made for an upright object, moved with the object along the table (and turned about
// +z), still closes cleanly on it: telegrasp-bench-scale --active plans once per model and moves
// the plan to each hand's object. (plan_grasp at the new pose may pick another, symmetric
// candidate of equal score, so the test closes the moved plan rather than comparing plans.)
Eigen::Isometry3d moved(const Eigen::Isometry3d& X, const Eigen::Vector3d& d) {
  Eigen::Isometry3d out = X;
  out.translation() += d;
  return out;
}

TEST(ScriptedOperatorTest, AMovedPlanStillClosesOnTheObject) {
  const auto hand_rig = rig("human_right");
  for (const char* name : {"005_tomato_soup_can", "004_sugar_box"}) {
    const auto model = standin(name);
    const Eigen::Isometry3d X_here = World::resting_pose(*model, 0.0, 0.0, 0.0);
    const Eigen::Isometry3d X_there = World::resting_pose(*model, -1.4, 1.05, 0.4);
    const GraspPlan here = plan_grasp(hand_rig, {}, *model, X_here, 1.0 / 90);
    ASSERT_TRUE(here.predicted_grasp) << name;
    const Eigen::Isometry3d X_WorldPalm = X_there * X_here.inverse() * here.X_WorldPalm;
    const OfflineClosing c = close_offline(hand_rig, {}, *model, X_there, X_WorldPalm, 1.0 / 90);
    EXPECT_TRUE(c.grasped) << name;
    EXPECT_FALSE(c.penetrating) << name;
    EXPECT_FALSE(c.below_table) << name;
    EXPECT_EQ(c.blocked, here.predicted_blocked) << name;
  }
}

// begin() with the plan plan_grasp makes runs exactly as begin() planning itself.
TEST(ScriptedOperatorTest, BeginWithAPlanRunsAsBeginWithTheModel) {
  const auto hand_rig = rig("human_right");
  const auto model = standin("005_tomato_soup_can");
  const Eigen::Isometry3d X_WorldObject = World::resting_pose(*model, 0.7, -1.05, 0.0);
  const Eigen::Isometry3d X_WorldStart = moved(X_WorldObject, Eigen::Vector3d(-0.15, -0.1, 0.3));
  const GraspPlan plan = plan_grasp(hand_rig, {}, *model, X_WorldObject, 1.0 / 90);
  ScriptedOperator a(hand_rig, skill_profile("experienced"), 5), b(hand_rig, skill_profile("experienced"), 5);
  a.begin(*model, X_WorldObject, X_WorldStart, 0.0);
  b.begin(plan, *model, X_WorldStart, 0.0);
  int ticks = 0;
  for (int k = 0; k < 500 && !a.done(); ++k, ++ticks) {
    const bool grasped = k > 150 && k < 300;  // as a server would answer mid-squeeze, then a drop
    const ControllerInput ia = a.next(k / 90.0, grasped), ib = b.next(k / 90.0, grasped);
    ASSERT_EQ(ia.X_WorldPalm.matrix(), ib.X_WorldPalm.matrix()) << "tick " << k;
    ASSERT_EQ(ia.trigger, ib.trigger) << "tick " << k;
    ASSERT_EQ(a.phase(), b.phase()) << "tick " << k;
  }
  EXPECT_GT(ticks, 150);
}

// A plan made at the origin, moved to an object near the table's corner, lifts it in a world.
TEST(ScriptedOperatorTest, AMovedPlanLiftsTheObject) {
  World world;
  const auto model = standin("005_tomato_soup_can");
  const ObjectId id = world.add_object(model, World::resting_pose(*model, 0.7, -0.65, 0.0));
  const auto hand_rig = rig("human_right");
  const HandId hand = world.add_hand(hand_rig);
  for (int i = 0; i < 30; ++i) world.step();
  GraspPlan plan = plan_grasp(hand_rig, {}, *model, World::resting_pose(*model, 0.0, 0.0, 0.0), 1.0 / 90);
  plan.X_WorldPalm = moved(plan.X_WorldPalm, Eigen::Vector3d(0.7, -0.65, 0.0));
  ScriptedOperator op(hand_rig, skill_profile("perfect"), 1);
  const double z0 = world.object_pose(id).translation().z();
  op.begin(plan, *model, moved(world.object_pose(id), Eigen::Vector3d(-0.15, -0.1, 0.3)), world.time());
  double z_max = z0;
  while (!op.done() && world.time() < 20) {
    world.set_input(hand, op.next(world.time(), world.holder(id) == hand));
    world.step();
    z_max = std::max(z_max, world.object_pose(id).translation().z());
  }
  EXPECT_TRUE(op.held_after_lift());
  EXPECT_GT(z_max - z0, 0.09) << "lifted about 10 cm";
}

void fast_close_on(const ObjectModelPtr& knife);

// The built-in knife, and the YCB scan when ../shared/data/ycb is present.
std::vector<ObjectModelPtr> knives() {
  std::vector<ObjectModelPtr> out{standin("032_knife")};
  if (const char* ycb = std::getenv("TELEGRASP_YCB_DIR")) {
    const std::string scan = std::string(ycb) + "/032_knife.ply";
    if (std::ifstream(scan).good()) out.push_back(load_protocol_object_model(scan));
  }
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

NdSearchResult nd_search(const ObjectModel& model, const Eigen::Isometry3d& X_WorldObject, int refinements,
                         int min_hits = 4) {
  NdSearchSettings search;
  search.random_poses = 40;
  search.refinements = refinements;
  search.min_hits = min_hits;
  search.seed = 11;
  return nd_pose_search(rig("human_right"), model, X_WorldObject, search, 1.0 / 90);
}

// The kept grasp meets every condition of a clean grasp, and its reported mean |ND| is the one
// measured on it.
TEST(ScriptedOperatorTest, NdPoseSearchKeepsACleanGrasp) {
  auto model = standin("004_sugar_box");
  const Eigen::Isometry3d X_WorldObject = World::resting_pose(*model, 0.45, 0.0, 0.3);
  const NdSearchResult r = nd_search(*model, X_WorldObject, 20);
  ASSERT_TRUE(r.best.has_value());
  EXPECT_GE(r.poses_tried, 40);
  EXPECT_LE(r.clean_grasps, r.poses_tried);
  EXPECT_TRUE(r.best->grasped);
  EXPECT_FALSE(r.best->below_table);
  const HandController& hand = r.best->hand;
  const ObjectView view{ObjectId(0), X_WorldObject, model.get()};
  const GraspMetrics m = hand.measure(view);
  double sum = 0;
  int hits = 0;
  for (const CapsuleMetric& c : m.capsules) {
    if (c.blocked) {
      EXPECT_GE(c.signed_distance, -0.1e-3);
    }
    if (c.hit) {
      sum += 1000 * std::abs(c.nd);
      ++hits;
    }
  }
  EXPECT_GE(hits, 4);
  EXPECT_NEAR(r.nd_mean_mm, sum / hits, 1e-9);
  // The palm's centre is outside the box.
  EXPECT_GT(model->distance.signed_distance(X_WorldObject.inverse() * hand.state().X_WorldPalm.translation()), 0);
}

// Refinement starts from the random phase's best (the same draws come first) and keeps only
// improvements; equal seeds give bit-identical results.
TEST(ScriptedOperatorTest, NdPoseSearchRefinesAndRepeats) {
  auto model = standin("013_apple");
  const Eigen::Isometry3d X_WorldObject = World::resting_pose(*model, 0.45, 0.0, 0.3);
  const NdSearchResult coarse = nd_search(*model, X_WorldObject, 0);
  const NdSearchResult fine = nd_search(*model, X_WorldObject, 30);
  const NdSearchResult again = nd_search(*model, X_WorldObject, 30);
  ASSERT_TRUE(coarse.best && fine.best && again.best);
  EXPECT_LE(fine.nd_mean_mm, coarse.nd_mean_mm);
  EXPECT_EQ(fine.poses_tried, coarse.poses_tried + 30);
  EXPECT_EQ(fine.nd_mean_mm, again.nd_mean_mm);
  EXPECT_TRUE(fine.best->hand.state().X_WorldPalm.matrix() == again.best->hand.state().X_WorldPalm.matrix());
}

// Asking for more hits than the rig has capsules finds nothing, and says so.
TEST(ScriptedOperatorTest, NdPoseSearchWithNoCleanGraspKeepsNothing) {
  auto model = standin("013_apple");
  const NdSearchResult r = nd_search(*model, World::resting_pose(*model, 0.45, 0.0, 0.3), 5, 11);
  EXPECT_FALSE(r.best.has_value());
  EXPECT_EQ(r.clean_grasps, 0);
}

// With grasp types the operator plans as people grasp long things lying on a table: across the
// smallest side a hand can reach there (the width, the thickness being upright), in force
// closure, the handle or shaft as well as the middle being candidates.
TEST(ScriptedOperatorTest, TypedPlansCloseAcrossTheReachableWidthInForceClosure) {
  const auto hand_rig = rig("human_right_opposable");
  for (const char* name : {"032_knife", "048_hammer", "030_fork"})
    for (double yaw_deg : {0.0, 60.0, 135.0}) {
      SCOPED_TRACE(std::string(name) + " at " + std::to_string(yaw_deg));
      const auto model = standin(name);
      const Eigen::Isometry3d X_WorldObject = World::resting_pose(*model, 0.45, 0.0, yaw_deg * std::numbers::pi / 180);
      const GraspPlan plan = plan_grasp(hand_rig, {}, *model, X_WorldObject, 1.0 / 90);
      EXPECT_TRUE(plan.predicted_grasp);
      const Eigen::Vector3d up_Object = X_WorldObject.linear().transpose() * Eigen::Vector3d::UnitZ();
      EXPECT_TRUE(closes_across_shortest_side(model->shape, X_WorldObject.inverse() * plan.X_WorldPalm, {}, up_Object));
      const OfflineClosing c = close_offline(hand_rig, {}, *model, X_WorldObject, plan.X_WorldPalm, 1.0 / 90);
      const auto job = c.hand.quality_inputs();
      ASSERT_TRUE(job.has_value());
      EXPECT_TRUE(grasp_quality(job->contacts, job->mu, job->torque_scale).force_closure);
    }
}

// An upright box whose thickness lies across the palm: with the palm centred over it, the thumb,
// opposing from the side of the palm, meets the box's end while the fingers press its face (no
// plan in force closure); a plan whose grasp centre is shifted 3 cm across the palm puts the
// thumb on the face opposite a finger's (other fingers may wrap over the top edge). The stand-in
// sugar box (5 x 9.4 x 17.6 cm).
TEST(ScriptedOperatorTest, TypedPlansCloseAnUprightBoxBetweenThumbAndFingersInForceClosure) {
  const auto hand_rig = rig("human_right_opposable");
  const auto model = standin("004_sugar_box");
  for (double yaw_deg : {0.0, 30.0, 100.0}) {
    SCOPED_TRACE(yaw_deg);
    const Eigen::Isometry3d X_WorldObject = World::resting_pose(*model, 0.45, 0.0, yaw_deg * std::numbers::pi / 180);
    const GraspPlan plan = plan_grasp(hand_rig, {}, *model, X_WorldObject, 1.0 / 90);
    const OfflineClosing c = close_offline(hand_rig, {}, *model, X_WorldObject, plan.X_WorldPalm, 1.0 / 90);
    ASSERT_TRUE(c.grasped);
    const auto job = c.hand.quality_inputs();
    ASSERT_TRUE(job.has_value());
    EXPECT_TRUE(grasp_quality(job->contacts, job->mu, job->torque_scale).force_closure);
    // A thumb contact and a finger contact on opposite faces: normals within 30 degrees of opposite.
    std::vector<Eigen::Vector3d> thumb, fingers;
    for (const Contact& k : c.hand.contacts()) {
      if (!k.phalanx.valid()) continue;  // the palm
      const int finger = hand_rig->phalanges()[k.phalanx.value].finger;
      (hand_rig->fingers()[finger].name == "thumb" ? thumb : fingers).push_back(k.n_World);
    }
    double most_opposed = 1;
    for (const Eigen::Vector3d& t : thumb)
      for (const Eigen::Vector3d& f : fingers) most_opposed = std::min(most_opposed, t.dot(f));
    EXPECT_LT(most_opposed, std::cos(150 * std::numbers::pi / 180));
  }
}

// A typed plan lays the phalanges on the surface rather than touching with their tips. A phalanx
// closing about its joint onto a flat face reads about 3 mm of ND at mid-length when it touches
// with its tip and 0 when it lies flat, so on a box the planned closing's mean |ND| is well under
// that (at most 0.7 mm: 0.45-0.64 with the fingertips closing after the middle phalanges and the
// thumb after the fingers, 0.2-0.3 with every joint closing from trigger 0); on a ball (a straight
// phalanx tangent to a sphere at its mid-length reads 0) under
// the paper's 1.12 mm. Unfitted (the plan chosen before the fit), they read 0.64 mm on the box and
// 2.6 and 3.1 mm on the balls. The standing cracker box, grasped from its top, under 1.12 mm too:
// without the wrist-flexed top grasps its fingers curled over the top edge and read 2.2, 0.75 and
// 2.0 mm. Each stays clean and in force closure. (Not on the cans: there the fitted plans still
// read 0.7-3.5 mm at these turns.)
TEST(ScriptedOperatorTest, TypedPlansLayThePhalangesOnTheSurface) {
  if (!plan_fit_enabled()) GTEST_SKIP() << "TELEGRASP_PLAN_FIT=off: plans are not fitted";
  const auto hand_rig = rig("human_right_opposable");
  for (const auto& [name, bound_mm] : {std::pair{"004_sugar_box", 0.7}, std::pair{"017_orange", 1.12},
                                       std::pair{"055_baseball", 1.12}, std::pair{"003_cracker_box", 1.12}})
    for (double yaw : {0.0, 0.4, 1.0}) {
      SCOPED_TRACE(testing::Message() << name << " yaw " << yaw);
      const auto model = standin(name);
      const Eigen::Isometry3d X_WorldObject = World::resting_pose(*model, 0.45, 0.0, yaw);
      const GraspPlan plan = plan_grasp(hand_rig, {}, *model, X_WorldObject, 1.0 / 90);
      const OfflineClosing c = close_offline(hand_rig, {}, *model, X_WorldObject, plan.X_WorldPalm, 1.0 / 90);
      ASSERT_TRUE(c.grasped);
      EXPECT_FALSE(c.penetrating);
      const auto [mean_mm, hits] = mean_abs_nd_mm(c.metrics);
      ASSERT_GE(hits, 3);
      EXPECT_LT(mean_mm, bound_mm);
      const auto job = c.hand.quality_inputs();
      ASSERT_TRUE(job.has_value());
      EXPECT_TRUE(grasp_quality(job->contacts, job->mu, job->torque_scale).force_closure);
    }
}

// The paper takes ND on the grasp tick, when the fingers that close last may still be in the air.
// The fit weighs that tick as much as the settled hand, so the planned fingers reach the surface
// together: on the stand-in master chef can (a disk grasp from the can's top) at 3 yaws, at least
// 4 capsules' sweeps hit on the grasp tick and their mean |ND| is under 1.5 mm (5, 5 and 4 at
// 1.46, 1.21 and 1.34 mm; with every joint closing from trigger 0, 6, 6 and 5 at 1.65-1.88 mm;
// fitted on the settled hand alone: no sweep hits on that tick at yaws 0 and 0.4, 3.3 mm at 1.0).
TEST(ScriptedOperatorTest, TypedPlansBringTheFingersToTheSurfaceTogether) {
  if (!plan_fit_enabled()) GTEST_SKIP() << "TELEGRASP_PLAN_FIT=off: plans are not fitted";
  const auto hand_rig = rig("human_right_opposable");
  const auto model = standin("002_master_chef_can");
  for (double yaw : {0.0, 0.4, 1.0}) {
    SCOPED_TRACE(testing::Message() << "yaw " << yaw);
    const Eigen::Isometry3d X_WorldObject = World::resting_pose(*model, 0.45, 0.0, yaw);
    const GraspPlan plan = plan_grasp(hand_rig, {}, *model, X_WorldObject, 1.0 / 90);
    const OfflineClosing c = close_offline(hand_rig, {}, *model, X_WorldObject, plan.X_WorldPalm, 1.0 / 90, 0.0,
                                           /*measure_grasp_tick=*/true);
    ASSERT_TRUE(c.grasped);
    EXPECT_FALSE(c.penetrating);
    const auto [mean_mm, hits] = mean_abs_nd_mm(c.grasp_tick_metrics);
    ASSERT_GE(hits, 4);
    EXPECT_LT(mean_mm, 1.5);
  }
}

// The planner's aim errors, written out here: the palm 3 mm off along each of its axes either way,
// or turned 3 degrees about its normal either way.
std::vector<Eigen::Isometry3d> operator_aims() {
  std::vector<Eigen::Isometry3d> aims;
  for (int axis = 0; axis < 3; ++axis)
    for (double d : {0.003, -0.003}) aims.emplace_back(Eigen::Translation3d(d * Eigen::Vector3d::Unit(axis)));
  for (double deg : {3.0, -3.0})
    aims.emplace_back(Eigen::AngleAxisd(deg * std::numbers::pi / 180, Eigen::Vector3d::UnitZ()));
  return aims;
}

// A typed plan's force closure survives the operator's aim: closed again with the palm 3 mm off
// along each of its axes or turned 3 degrees about its normal, each chosen plan in force closure
// stays clean and in force closure in at least 5 of the 8, and in 6.5 on average (ranked by
// epsilon alone, the mustard bottle's YCB scan and the hammer keep 4, and the mean is 5.8).
TEST(ScriptedOperatorTest, TypedPlansKeepForceClosureWithTheOperatorsAimOff) {
  const auto hand_rig = rig("human_right_opposable");
  const std::vector<Eigen::Isometry3d> aims = operator_aims();
  const auto in_closure = [&](const ObjectModel& model, const Eigen::Isometry3d& X_WorldObject,
                              const Eigen::Isometry3d& X_WorldPalm) {
    const OfflineClosing c = close_offline(hand_rig, {}, model, X_WorldObject, X_WorldPalm, 1.0 / 90);
    const auto job = c.hand.quality_inputs();
    return c.grasped && !c.penetrating && job && grasp_quality(job->contacts, job->mu, job->torque_scale).force_closure;
  };
  std::vector<ObjectModelPtr> models;
  const char* ycb = std::getenv("TELEGRASP_YCB_DIR");
  for (const char* name : {"003_cracker_box", "004_sugar_box", "009_gelatin_box", "010_potted_meat_can",
                           "006_mustard_bottle", "048_hammer"}) {
    models.push_back(standin(name));
    const std::string scan = ycb ? std::string(ycb) + "/" + name + ".ply" : "";
    if (ycb && std::ifstream(scan).good()) models.push_back(load_protocol_object_model(scan));
  }
  int kept_sum = 0, plans = 0;
  for (const ObjectModelPtr& model : models) {
    SCOPED_TRACE(model->source);
    const Eigen::Isometry3d X_WorldObject = World::resting_pose(*model, 0.45, 0.0, 0.5);
    const GraspPlan plan = plan_grasp(hand_rig, {}, *model, X_WorldObject, 1.0 / 90);
    if (!in_closure(*model, X_WorldObject, plan.X_WorldPalm)) continue;  // the stand-in cracker box: none is
    int kept = 0;
    for (const Eigen::Isometry3d& aim : aims) kept += in_closure(*model, X_WorldObject, plan.X_WorldPalm * aim);
    EXPECT_GE(kept, 5);
    kept_sum += kept;
    ++plans;
  }
  ASSERT_GE(plans, 4);
  EXPECT_GE(static_cast<double>(kept_sum) / plans, 6.5);
}

// Where every plan in force closure loses the grasp under some aim error, the planner takes one
// out of closure that keeps it. The YCB knife lying where the protocol (seed 1) put it for an
// experienced participant: the best plan in closure stays grasped under 6 of the 8 aim errors,
// and with it the participant missed the knife 3 times; the plan taken keeps all 8.
TEST(ScriptedOperatorTest, TypedPlansKeepTheGraspWithTheOperatorsAimOffBeforeTheClosure) {
  const char* ycb = std::getenv("TELEGRASP_YCB_DIR");
  const std::string scan = ycb ? std::string(ycb) + "/032_knife.ply" : "";
  if (!ycb || !std::ifstream(scan).good()) GTEST_SKIP() << "no YCB knife (TELEGRASP_YCB_DIR)";
  const ObjectModelPtr knife = load_protocol_object_model(scan);
  const auto hand_rig = rig("human_right_opposable");
  Eigen::Isometry3d X_WorldObject = Eigen::Isometry3d::Identity();
  X_WorldObject.linear() =
      Eigen::Quaterniond(0.91542668364190893, 0.0025263484782216726, 0.0057467222417127576, 0.40243580807778473)
          .normalized()
          .toRotationMatrix();
  X_WorldObject.translation() = Eigen::Vector3d(0.48789828785906802, 0.018050000813631308, 0.011991403572218383);
  const GraspPlan plan = plan_grasp(hand_rig, {}, *knife, X_WorldObject, 1.0 / 90);
  int kept = 0;
  for (const Eigen::Isometry3d& aim : operator_aims()) {
    const OfflineClosing c = close_offline(hand_rig, {}, *knife, X_WorldObject, plan.X_WorldPalm * aim, 1.0 / 90);
    kept += c.grasped && !c.penetrating;
  }
  EXPECT_EQ(kept, 8);
}

}  // namespace
}  // namespace telegrasp::sim
