// Tests two hands holding one object in World: both hands lift a long box at its ends and it
// stays level, one hand circling the other turns the box about the first hand's attach point, one
// hand opening leaves the box with the other without a jump, the last hand's velocity on release,
// a third hand, removals, and the takeover option (today's behaviour).
#include "telegrasp/sim/world.h"

#include "telegrasp/sim/scripted_operator.h"
#include "telegrasp/sim/two_hand_hold.h"
#include "test_meshes.h"

#include <gtest/gtest.h>

#include <cmath>

namespace telegrasp::sim {
namespace {

constexpr double kExact = 1e-9;  // m and rotation-matrix norm: poses that must agree but for rounding
constexpr double kLevel = 1e-6;  // how far the box's axes may turn while both hands rise equally

std::shared_ptr<const HandRig> human_right() {
  static auto rig = std::make_shared<const HandRig>(HandRig::load(HandRig::builtin_path("human_right")));
  return rig;
}

Eigen::Isometry3d shifted(const Eigen::Vector3d& by, const Eigen::Isometry3d& X) {
  return Eigen::Translation3d(by) * X;
}

double gap(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b) {
  return (a.translation() - b.translation()).norm() + (a.linear() - b.linear()).norm();
}

// A 0.6 x 0.08 x 0.08 m box along x resting on the table, and two right hands (two clients) with
// one grasp pose planned at the box's middle, shifted 0.2 m towards either end: the box's cross
// section is the same there, so both hands grip it alike.
struct LongBoxScene {
  World world;
  ObjectModelPtr model = make_object_model("long_box", testing::box_mesh({0.3, 0.04, 0.04}), 0.5, "test");
  ObjectId box;
  HandId first, second;
  Eigen::Isometry3d X_WorldPalm1, X_WorldPalm2;  // grasp poses
  std::vector<GraspEvent> seen;  // every event since the scene was made

  explicit LongBoxScene(TwoHandMode mode = TwoHandMode::kShare) : world(settings(mode)) {
    box = world.add_object(model, World::resting_pose(*model, 0.4, 0.0, 0.0));
    first = world.add_hand(human_right());
    second = world.add_hand(human_right());
    for (int i = 0; i < 30; ++i) world.step();
    const GraspPlan plan = plan_grasp(human_right(), {}, *model, world.object_pose(box), world.dt());
    EXPECT_TRUE(plan.predicted_grasp);
    X_WorldPalm1 = shifted({-0.2, 0, 0}, plan.X_WorldPalm);
    X_WorldPalm2 = shifted({0.2, 0, 0}, plan.X_WorldPalm);
  }
  static WorldSettings settings(TwoHandMode mode) {
    WorldSettings s;
    s.two_hand_mode = mode;
    return s;
  }
  void set(HandId hand, const Eigen::Isometry3d& X_WorldPalm, double trigger) {
    ControllerInput in;
    in.X_WorldPalm = X_WorldPalm;
    in.trigger = trigger;
    ASSERT_EQ(world.set_input(hand, in), "");
  }
  void step() {
    world.step();
    seen.insert(seen.end(), world.events().begin(), world.events().end());
  }
  // Squeezes `hand` at `X_WorldPalm` until its grasp event (other hands keep their inputs).
  bool grasp(HandId hand, const Eigen::Isometry3d& X_WorldPalm) {
    for (int t = 1; t <= 90; ++t) {
      set(hand, X_WorldPalm, std::min(1.0, t / 30.0));
      step();
      for (const GraspEvent& e : world.events())
        if (e.kind == GraspEvent::Kind::kGrasp && e.hand == hand) return true;
    }
    return false;
  }
  // Both hands grasp, the first one first.
  void grasp_both() {
    ASSERT_TRUE(grasp(first, X_WorldPalm1));
    ASSERT_TRUE(grasp(second, X_WorldPalm2));
  }
  // Both hands move up by `height` over `ticks`, squeezing.
  void lift(double height, int ticks) {
    for (int t = 1; t <= ticks; ++t) {
      const Eigen::Vector3d up(0, 0, height * t / ticks);
      set(first, shifted(up, X_WorldPalm1), 1.0);
      set(second, shifted(up, X_WorldPalm2), 1.0);
      step();
    }
    X_WorldPalm1 = shifted({0, 0, height}, X_WorldPalm1);
    X_WorldPalm2 = shifted({0, 0, height}, X_WorldPalm2);
  }
  int count(GraspEvent::Kind kind, HandId hand) const {
    return static_cast<int>(
        std::count_if(seen.begin(), seen.end(), [&](const GraspEvent& e) { return e.kind == kind && e.hand == hand; }));
  }
};

TEST(TwoHandWorldTest, ASecondGraspJoinsTheFirst) {
  LongBoxScene s;
  s.grasp_both();
  EXPECT_EQ(s.world.holders(s.box), (std::vector<HandId>{s.first, s.second}));
  EXPECT_EQ(s.world.holder(s.box), s.first) << "holder() is the first";
  EXPECT_EQ(s.count(GraspEvent::Kind::kGrasp, s.second), 1);
  EXPECT_EQ(s.count(GraspEvent::Kind::kRelease, s.first), 0);
  EXPECT_EQ(s.world.hand(s.first).state().grasped, s.box);
  EXPECT_EQ(s.world.hand(s.second).state().grasped, s.box);
}

TEST(TwoHandWorldTest, BothHandsLiftALongBoxAtItsEndsAndItStaysLevel) {
  LongBoxScene s;
  s.grasp_both();
  const Eigen::Isometry3d X_before = s.world.object_pose(s.box);
  for (int t = 1; t <= 90; ++t) {
    s.lift(0.1 / 90, 1);
    const Eigen::Isometry3d X = s.world.object_pose(s.box);
    ASSERT_LT((X.linear() - X_before.linear()).norm(), kLevel) << "tick " << t;
  }
  EXPECT_EQ(s.world.holders(s.box).size(), 2u);
  EXPECT_EQ(s.count(GraspEvent::Kind::kRelease, s.first) + s.count(GraspEvent::Kind::kRelease, s.second), 0);
  const Eigen::Isometry3d X_after = s.world.object_pose(s.box);
  EXPECT_NEAR(X_after.translation().z() - X_before.translation().z(), 0.1, kExact);
  EXPECT_LT((X_after.translation() - X_before.translation()).head<2>().norm(), kExact);
  // Level in the world too: the box rested flat, and its long axis is still horizontal.
  EXPECT_LT(std::abs(X_after.linear().col(0).z()), 1e-4);
}

// The second hand, turning with the circle, goes a quarter turn round the first hand's attach
// point: the box turns about that point.
TEST(TwoHandWorldTest, OneHandCirclingTheOtherTurnsTheBoxAboutTheFirstAttachPoint) {
  LongBoxScene s;
  s.grasp_both();
  s.lift(0.05, 45);
  const Eigen::Isometry3d X_before = s.world.object_pose(s.box);
  const Eigen::Vector3d a1 = s.X_WorldPalm1 * human_right()->palm_contact().p_PalmCenter;
  const auto about_a1 = [&](double angle) {
    return Eigen::Translation3d(a1) * Eigen::AngleAxisd(angle, Eigen::Vector3d::UnitZ()) * Eigen::Translation3d(-a1);
  };
  const int ticks = 180;
  const double quarter = M_PI / 2;
  for (int t = 1; t <= ticks; ++t) {
    s.set(s.second, about_a1(quarter * t / ticks) * s.X_WorldPalm2, 1.0);
    s.step();
    ASSERT_EQ(s.world.holders(s.box).size(), 2u) << "tick " << t;
  }
  EXPECT_LT(gap(s.world.object_pose(s.box), about_a1(quarter) * X_before), kExact);
}

TEST(TwoHandWorldTest, OneHandOpensAndTheOtherKeepsTheBoxWithoutAJump) {
  LongBoxScene s;
  s.grasp_both();
  s.lift(0.1, 90);
  // The second hand rises 2 cm more: the box tilts, away from where the first hand alone would hold it.
  const Eigen::Isometry3d X_level = s.world.object_pose(s.box);
  for (int t = 1; t <= 40; ++t) {
    s.set(s.second, shifted({0, 0, 0.02 * t / 40}, s.X_WorldPalm2), 1.0);
    s.step();
  }
  s.X_WorldPalm2 = shifted({0, 0, 0.02}, s.X_WorldPalm2);
  ASSERT_EQ(s.world.holders(s.box).size(), 2u);
  ASSERT_GT(gap(s.world.object_pose(s.box), X_level), 0.01) << "tilted";
  // The second hand opens where it is; the first stays.
  Eigen::Isometry3d X_previous = s.world.object_pose(s.box);
  int release_tick = -1;
  for (int t = 0; t < 90 && release_tick < 0; ++t) {
    s.set(s.second, s.X_WorldPalm2, 0.0);
    s.step();
    const Eigen::Isometry3d X = s.world.object_pose(s.box);
    ASSERT_LT(gap(X, X_previous), kExact) << "tick " << t;
    X_previous = X;
    for (const GraspEvent& e : s.world.events())
      if (e.kind == GraspEvent::Kind::kRelease) {
        EXPECT_EQ(e.hand, s.second);
        EXPECT_EQ(e.v_WorldObject, Eigen::Vector3d::Zero()) << "not let go to physics";
        release_tick = t;
      }
  }
  ASSERT_GE(release_tick, 0) << "the second hand let go";
  EXPECT_EQ(s.world.holders(s.box), std::vector<HandId>{s.first});
  EXPECT_FALSE(s.world.hand(s.second).state().grasped.valid());
  // The first hand holds it alone, at its current relative pose: it stays, then follows the hand.
  for (int t = 0; t < 30; ++t) s.step();
  EXPECT_LT(gap(s.world.object_pose(s.box), X_previous), kExact) << "held, not fallen";
  const Eigen::Vector3d move(0.02, -0.01, 0.03);
  s.set(s.first, shifted(move, s.X_WorldPalm1), 1.0);
  s.step();
  EXPECT_LT(gap(s.world.object_pose(s.box), shifted(move, X_previous)), kExact);
  EXPECT_EQ(s.world.holders(s.box), std::vector<HandId>{s.first});
}

// The object goes back to physics only when the last hand lets go, with that hand's velocity.
TEST(TwoHandWorldTest, TheLastHandToLetGoGivesTheReleaseVelocity) {
  LongBoxScene s;
  s.grasp_both();
  s.lift(0.1, 90);
  for (int t = 0; t < 90 && s.world.holders(s.box).size() == 2; ++t) {
    s.set(s.second, s.X_WorldPalm2, 0.0);
    s.step();
  }
  ASSERT_EQ(s.world.holders(s.box), std::vector<HandId>{s.first});
  // The first hand moves at v and opens.
  const Eigen::Vector3d v(0.2, 0.1, 0.3);
  std::optional<GraspEvent> release;
  Eigen::Isometry3d X_WorldPalm = s.X_WorldPalm1;
  for (int t = 0; t < 90 && !release; ++t) {
    X_WorldPalm = shifted(v * s.world.dt(), X_WorldPalm);
    s.set(s.first, X_WorldPalm, 0.0);
    s.step();
    for (const GraspEvent& e : s.world.events())
      if (e.kind == GraspEvent::Kind::kRelease) release = e;
  }
  ASSERT_TRUE(release.has_value());
  EXPECT_EQ(release->hand, s.first);
  EXPECT_LT((release->v_WorldObject - v).norm(), kExact);
  EXPECT_TRUE(s.world.holders(s.box).empty());
  EXPECT_FALSE(s.world.holder(s.box).valid());
}

// A third hand's grasp takes the place of the first holder: never more than two.
TEST(TwoHandWorldTest, AThirdGraspReplacesTheFirstHolder) {
  LongBoxScene s;
  s.grasp_both();
  const HandId third = s.world.add_hand(human_right());
  ASSERT_TRUE(s.grasp(third, shifted({0.2, 0, 0}, s.X_WorldPalm1)));  // at the middle
  EXPECT_EQ(s.world.holders(s.box), (std::vector<HandId>{s.second, third}));
  EXPECT_EQ(s.count(GraspEvent::Kind::kRelease, s.first), 1);
  EXPECT_FALSE(s.world.hand(s.first).state().grasped.valid());
}

TEST(TwoHandWorldTest, RemovingOneOfTwoHoldersLeavesTheBoxWithTheOther) {
  LongBoxScene s;
  s.grasp_both();
  s.lift(0.05, 45);
  const Eigen::Isometry3d X_before = s.world.object_pose(s.box);
  s.world.remove_hand(s.first);
  EXPECT_EQ(s.world.holders(s.box), std::vector<HandId>{s.second});
  for (int t = 0; t < 30; ++t) s.step();
  EXPECT_LT(gap(s.world.object_pose(s.box), X_before), kExact) << "held, not fallen";
  EXPECT_EQ(s.count(GraspEvent::Kind::kRelease, s.first), 1);
}

TEST(TwoHandWorldTest, RemovingABoxTwoHandsHoldReleasesBoth) {
  LongBoxScene s;
  s.grasp_both();
  s.world.remove_object(s.box);
  s.step();
  EXPECT_EQ(s.count(GraspEvent::Kind::kRelease, s.first), 1);
  EXPECT_EQ(s.count(GraspEvent::Kind::kRelease, s.second), 1);
  EXPECT_FALSE(s.world.hand(s.first).state().grasped.valid());
  EXPECT_FALSE(s.world.hand(s.second).state().grasped.valid());
}

// TwoHandMode::kTakeover: the second grasp takes the box, the first hand lets go in the same tick.
TEST(TwoHandWorldTest, TakeoverModeHandsTheBoxToTheNewestGrasp) {
  LongBoxScene s(TwoHandMode::kTakeover);
  ASSERT_TRUE(s.grasp(s.first, s.X_WorldPalm1));
  ASSERT_TRUE(s.grasp(s.second, s.X_WorldPalm2));
  ASSERT_EQ(s.world.events().size(), 2u);
  EXPECT_EQ(s.world.events()[0].kind, GraspEvent::Kind::kRelease);
  EXPECT_EQ(s.world.events()[0].hand, s.first);
  EXPECT_EQ(s.world.events()[1].kind, GraspEvent::Kind::kGrasp);
  EXPECT_EQ(s.world.events()[1].hand, s.second);
  EXPECT_EQ(s.world.holders(s.box), std::vector<HandId>{s.second});
  EXPECT_FALSE(s.world.hand(s.first).state().grasped.valid());
  // The box follows the second hand alone, as one hand carries an object (the first hand opens).
  const Eigen::Isometry3d X_PalmObject = s.world.hand(s.second).state().X_PalmObject;
  const Eigen::Isometry3d X_WorldPalm2 = shifted({0, 0, 0.05}, s.X_WorldPalm2);
  s.set(s.first, s.X_WorldPalm1, 0.0);
  s.set(s.second, X_WorldPalm2, 1.0);
  s.step();
  EXPECT_EQ(s.world.holders(s.box), std::vector<HandId>{s.second});
  EXPECT_LT(gap(s.world.object_pose(s.box), X_WorldPalm2 * X_PalmObject), kExact);
}

TEST(TwoHandWorldTest, ModeNamesRoundTrip) {
  for (TwoHandMode mode : {TwoHandMode::kShare, TwoHandMode::kTakeover})
    EXPECT_EQ(parse_two_hand_mode(two_hand_mode_name(mode)), mode);
  EXPECT_FALSE(parse_two_hand_mode("both").has_value());
  EXPECT_EQ(WorldSettings{}.two_hand_mode, TwoHandMode::kShare);
}

}  // namespace
}  // namespace telegrasp::sim
