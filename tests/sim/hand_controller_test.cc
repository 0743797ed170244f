// Tests HandController: the interaction manager, finger movement in both closing modes, the
// grasping logic, object selection and the ND / signed-distance metrics on analytic geometry.
#include "telegrasp/sim/hand_controller.h"

#include "telegrasp/sim/hand_kinematics.h"
#include "telegrasp/sim/scripted_operator.h"
#include "telegrasp/sim/standin_objects.h"
#include "telegrasp/sim/world.h"
#include "test_meshes.h"
#include "test_rigs.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace telegrasp::sim {
namespace {

using testing::box_mesh;
using testing::kFingerRig;
constexpr double kDt = 1.0 / 90.0;
constexpr double kDeg = std::numbers::pi / 180.0;
constexpr double kTol = 0.05e-3;  // GraspSettings default contact tolerance

ControllerInput hovering(double capsule_axis_z, double y = 0);

std::shared_ptr<const HandRig> finger_rig() {
  return std::make_shared<const HandRig>(HandRig::parse(kFingerRig, "finger3"));
}

// The finger rig with the first occurrence of each `from` replaced by its `to`.
std::shared_ptr<const HandRig> finger_rig_with(const std::vector<std::pair<std::string, std::string>>& edits) {
  std::string text = kFingerRig;
  for (const auto& [from, to] : edits) text.replace(text.find(from), from.size(), to);
  return std::make_shared<const HandRig>(HandRig::parse(text, "finger3_variant"));
}

// The same finger with a grasp rule that only the palm satisfies, so it never attaches the object.
std::shared_ptr<const HandRig> finger_rig_without_grasp() {
  return finger_rig_with({{R"(grasp_rule { members: ["f_mid", "f_dist"] })", R"(grasp_rule { members: ["palm"] })"}});
}

// A box object with half extents h centred at p (palm frame = world frame: the hand stays at identity).
struct BoxScene {
  ObjectModelPtr model;
  ObjectView view;
  BoxScene(const Eigen::Vector3d& h, const Eigen::Vector3d& p)
      : model(make_object_model("box", box_mesh(h), 1.0, "test")) {
    view.id = ObjectId(7);
    view.X_WorldObject = Eigen::Isometry3d(Eigen::Translation3d(p));
    view.model = model.get();
  }
};

ControllerInput at_identity(double trigger) {
  ControllerInput in;
  in.trigger = trigger;
  return in;
}

// Exact gap between a capsule of `rig` and the bar whose x-z cross-section is the rectangle
// [x0, x1] x [z0, z1] (the bar is long in y): 2D distance from the capsule axis, densely sampled.
double gap_to_bar_2d(const Eigen::Vector3d& a, const Eigen::Vector3d& b, double r, double x0, double x1, double z0,
                     double z1) {
  double best = 1e9;
  constexpr int kSamples = 200000;
  for (int i = 0; i <= kSamples; ++i) {
    const Eigen::Vector3d p = a + (b - a) * (static_cast<double>(i) / kSamples);
    const double dx = std::max({x0 - p.x(), 0.0, p.x() - x1});
    const double dz = std::max({z0 - p.z(), 0.0, p.z() - z1});
    best = std::min(best, std::hypot(dx, dz));
  }
  return best - r;
}

// A bar under the middle phalanx only: the middle capsule blocks, then the distal joint keeps
// closing while the proximal and middle joints hold.
TEST(HandControllerTest, BlockedPhalanxHoldsProximalJoints) {
  auto rig = finger_rig();
  const double x0 = 0.075, x1 = 0.088, z0 = -0.1, z1 = -0.010;
  BoxScene bar({(x1 - x0) / 2, 0.05, (z1 - z0) / 2}, {(x0 + x1) / 2, 0, (z0 + z1) / 2});
  HandController hand(rig, {});
  const int prox = 0, mid = 1, dist = 2;
  int blocked_tick = -1;
  double q_prox = 0, q_mid = 0;
  for (int t = 0; t < 90; ++t) {
    hand.tick(at_identity(1.0), kDt, {&bar.view, 1});
    const HandState& s = hand.state();
    if (blocked_tick < 0 && s.blocked[mid]) {
      blocked_tick = t;
      q_prox = s.q[prox];
      q_mid = s.q[mid];
    } else if (blocked_tick >= 0) {
      // Held: the proximal and middle joints do not move once the middle phalanx is blocked.
      ASSERT_EQ(s.q[prox], q_prox) << "tick " << t;
      ASSERT_EQ(s.q[mid], q_mid) << "tick " << t;
    }
  }
  ASSERT_GE(blocked_tick, 0) << "the middle capsule never touched the bar";
  const HandState& s = hand.state();
  EXPECT_TRUE(s.blocked[mid]);
  EXPECT_FALSE(s.blocked[dist]);
  EXPECT_EQ(s.q[dist], 70 * kDeg) << "the distal joint closes fully, past the bar";
  EXPECT_GT(q_prox, 1 * kDeg);
  // Precise mode: the blocked capsule touches within the tolerance, checked independently.
  const auto& cap = *rig->phalanges()[mid].capsule;
  const double gap = gap_to_bar_2d(s.X_PalmPhalanx[mid] * cap.p_PhalanxA, s.X_PalmPhalanx[mid] * cap.p_PhalanxB,
                                   cap.radius, x0, x1, z0, z1);
  EXPECT_GE(gap, -1e-6);
  EXPECT_LE(gap, kTol + 1e-6);
}

// Smallest (or, with largest = true, largest) exact gap of the blocked capsules to the object.
double min_blocked_gap(const HandController& hand, const ObjectView& view, bool largest = false) {
  double worst = largest ? -1e9 : 1e9;
  const auto& rig = hand.rig();
  for (PhalanxId id : rig.capsule_phalanges()) {
    if (!hand.state().blocked[id.value]) continue;
    const auto& c = *rig.phalanges()[id.value].capsule;
    const Eigen::Isometry3d X =
        view.X_WorldObject.inverse() * hand.state().X_WorldPalm * hand.state().X_PalmPhalanx[id.value];
    const double gap = view.model->distance.capsule_signed_distance(X * c.p_PhalanxA, X * c.p_PhalanxB, c.radius);
    worst = largest ? std::max(worst, gap) : std::min(worst, gap);
  }
  return worst;
}

// Closes on a plate below the whole finger until something blocks; returns the smallest blocked
// gap (the largest in *largest_gap, if given).
double close_on(const ObjectView& view, ClosingMode mode, double speed_scale, bool* blocked_any,
                double* largest_gap = nullptr) {
  GraspSettings settings;
  settings.mode = mode;
  settings.speed_scale = speed_scale;
  HandController hand(finger_rig(), settings);
  for (int t = 0; t < 200; ++t) hand.tick(at_identity(1.0), kDt, {&view, 1});
  *blocked_any = false;
  for (std::uint8_t b : hand.state().blocked) *blocked_any |= b != 0;
  if (largest_gap) *largest_gap = min_blocked_gap(hand, view, true);
  return min_blocked_gap(hand, view);
}

TEST(HandControllerTest, PreciseModeTouchesWithinToleranceAtAnySpeed) {
  BoxScene plate({0.1, 0.1, 0.01}, {0.1, 0, -0.025});
  for (double speed : {1.0, 4.0, 16.0, 64.0}) {
    bool blocked = false;
    double largest = 0;
    const double gap = close_on(plate.view, ClosingMode::kPrecise, speed, &blocked, &largest);
    ASSERT_TRUE(blocked) << "speed x" << speed;
    EXPECT_GE(gap, -1e-9) << "speed x" << speed;
    EXPECT_LE(largest, 2 * kTol) << "speed x" << speed << ": every blocked capsule touches";
  }
}

TEST(HandControllerTest, DiscreteModeSinksMoreAtHigherSpeed) {
  BoxScene plate({0.1, 0.1, 0.01}, {0.1, 0, -0.025});
  bool blocked = false;
  const double slow = close_on(plate.view, ClosingMode::kDiscrete, 1.0, &blocked);
  ASSERT_TRUE(blocked);
  const double fast = close_on(plate.view, ClosingMode::kDiscrete, 8.0, &blocked);
  ASSERT_TRUE(blocked);
  EXPECT_LT(slow, 0.0) << "discrete mode detects contact only once overlapping";
  EXPECT_LT(fast, slow) << "a larger step sinks deeper";
  EXPECT_LT(fast, -1e-3);
}

// A 1 mm plate across the distal phalanx's path, closed at 64x speed (the distal sweeps ~150 degrees
// per tick): the paper's discrete test steps straight through it, precise mode blocks on it.
TEST(HandControllerTest, FastCloseOnThinPlateDoesNotTunnel) {
  BoxScene thin({0.0005, 0.1, 0.085}, {0.09, 0, -0.095});  // top edge 1 cm below the open finger
  bool blocked = false;
  const double gap = close_on(thin.view, ClosingMode::kPrecise, 64.0, &blocked);
  ASSERT_TRUE(blocked);
  EXPECT_GE(gap, -1e-9);
  EXPECT_LE(gap, kTol);
  const double discrete_gap = close_on(thin.view, ClosingMode::kDiscrete, 64.0, &blocked);
  EXPECT_TRUE(!blocked || discrete_gap < -1e-3) << "discrete mode tunnels or sinks deep";
}

// The finger3 rig's middle and distal capsule axes (palm frame, the finger moving in the x-z
// plane) at joint angles q: joints at x = 0.04, then 0.03 and 0.025 along the turned phalanges,
// each turning about +y (x toward -z); the capsules run 25 mm and 15 mm along their phalanges.
struct Finger3Axes {
  std::pair<Eigen::Vector2d, Eigen::Vector2d> middle, distal;
};
Finger3Axes finger3_axes(double q1, double q2, double q3) {
  const auto dir = [](double q) { return Eigen::Vector2d(std::cos(q), -std::sin(q)); };  // (x, z)
  const Eigen::Vector2d j2 = Eigen::Vector2d(0.04, 0) + 0.03 * dir(q1);
  const Eigen::Vector2d j3 = j2 + 0.025 * dir(q1 + q2);
  return {{j2, j3}, {j3, j3 + 0.015 * dir(q1 + q2 + q3)}};
}

// 2-D distance between segment [a, b] and the rectangle [x0, x1] x [z0, z1] (disjoint from it).
double segment_rectangle_distance(const Eigen::Vector2d& a, const Eigen::Vector2d& b, double x0, double x1, double z0,
                                  double z1) {
  const auto to_rect = [&](const Eigen::Vector2d& p) {
    return std::hypot(std::max({x0 - p.x(), 0.0, p.x() - x1}), std::max({z0 - p.y(), 0.0, p.y() - z1}));
  };
  const auto to_seg = [&](const Eigen::Vector2d& p) {
    const Eigen::Vector2d d = b - a;
    const double t = std::clamp((p - a).dot(d) / d.squaredNorm(), 0.0, 1.0);
    return (a + t * d - p).norm();
  };
  return std::min({to_rect(a), to_rect(b), to_seg({x0, z0}), to_seg({x0, z1}), to_seg({x1, z0}), to_seg({x1, z1})});
}

// A fingertip sweeping past the corner of a thin plate blocks on it whenever its path would take
// it into the plate by more than half the tolerance, at any closing speed, and passes when the
// path clears it: the advancement's predicted steps (close_precise) never jump over a graze the
// size of the tolerance. The path and its deepest reach into the plate are computed here from
// the rig's kinematics: each tick every joint turns toward its closed angle by at most 2 degrees
// times the speed (180 deg/s), linearly in between, sampled 400 times a tick.
TEST(HandControllerTest, AFingertipGrazingACornerBlocksOnItWhenItWouldGoInDeeperThanHalfTheTolerance) {
  constexpr double kRadius = 0.005;
  const std::array<double, 3> closed = {90 * kDeg, 90 * kDeg, 70 * kDeg};
  struct Plate {  // cross-section in the x-z plane; long in y
    double x0, x1, z0, z1;
  };
  int must_block = 0, must_pass = 0;
  for (double speed : {1.0, 4.0, 16.0}) {
    std::vector<std::pair<Eigen::Vector2d, Eigen::Vector2d>> path, middle;  // the axes, densely
    std::vector<std::array<double, 3>> ticks = {{0, 0, 0}};
    while (ticks.back() != closed) {
      std::array<double, 3> q = ticks.back();
      for (int k = 0; k < 3; ++k) q[k] = std::min(closed[k], q[k] + 2 * kDeg * speed);
      ticks.push_back(q);
    }
    for (std::size_t t = 1; t < ticks.size(); ++t)
      for (int i = 0; i <= 400; ++i) {
        const double f = i / 400.0;
        const auto q = [&](int k) { return ticks[t - 1][k] + f * (ticks[t][k] - ticks[t - 1][k]); };
        const Finger3Axes axes = finger3_axes(q(0), q(1), q(2));
        path.push_back(axes.distal);
        middle.push_back(axes.middle);
      }
    const auto deepest_reach = [&](const Plate& p, const auto& axes) {  // min over the path of the gap
      double gap = 1e9;
      for (const auto& [a, b] : axes) gap = std::min(gap, segment_rectangle_distance(a, b, p.x0, p.x1, p.z0, p.z1) - kRadius);
      return gap;
    };
    // A plate 0.3 mm thick and 20 mm long, lying along the fingertip's direction at the path's
    // sample i, its near edge `beyond` past the capsule's end.
    const auto plate_beyond = [&](std::size_t i, double beyond) {
      const auto [a, b] = path[i];
      const Eigen::Vector2d u = (b - a).normalized();
      const Eigen::Vector2d near = b + (kRadius + beyond) * u;
      if (std::abs(u.x()) >= std::abs(u.y())) {
        const double far = near.x() + 0.02 * (u.x() > 0 ? 1 : -1);
        return Plate{std::min(near.x(), far), std::max(near.x(), far), near.y() - 1.5e-4, near.y() + 1.5e-4};
      }
      const double far = near.y() + 0.02 * (u.y() > 0 ? 1 : -1);
      return Plate{near.x() - 1.5e-4, near.x() + 1.5e-4, std::min(near.y(), far), std::max(near.y(), far)};
    };
    for (double along : {0.25, 0.45, 0.65, 0.85}) {
      const auto i = static_cast<std::size_t>(along * static_cast<double>(path.size() - 1));
      for (double wanted : {-0.3e-3, -0.1e-3, -0.04e-3, 0.2e-3}) {
        // How far beyond the fingertip the plate must lie for the path to reach `wanted`
        // (bisection: the farther the plate, the shallower the reach).
        double lo = -3e-3, hi = 6e-3;
        for (int it = 0; it < 30; ++it) {
          const double mid = 0.5 * (lo + hi);
          (deepest_reach(plate_beyond(i, mid), path) < wanted ? lo : hi) = mid;
        }
        const Plate p = plate_beyond(i, hi);
        const double reach = deepest_reach(p, path);  // < 0: the path goes into the plate that deep
        if (reach > -0.5 * kTol - 1e-6 && reach < kTol + 1e-6) continue;  // either outcome is right
        if (deepest_reach(p, middle) < 1e-3) continue;  // the middle capsule would meet it: another case
        BoxScene plate({(p.x1 - p.x0) / 2, 0.05, (p.z1 - p.z0) / 2}, {(p.x0 + p.x1) / 2, 0, (p.z0 + p.z1) / 2});
        GraspSettings settings;
        settings.speed_scale = speed;
        settings.resolve_pose = false;  // the finger layer alone: the palm stays put, even over the plate
        HandController hand(finger_rig_without_grasp(), settings);
        for (int t = 0; t < 120; ++t) hand.tick(at_identity(1.0), kDt, {&plate.view, 1});
        const HandState& s = hand.state();
        const std::string where = "speed x" + std::to_string(speed) + ", plate at " + std::to_string(along) +
                                  " of the path, reach " + std::to_string(reach * 1e3) + " mm";
        const auto [a, b] = finger3_axes(s.q[0], s.q[1], s.q[2]).distal;
        const double gap = segment_rectangle_distance(a, b, p.x0, p.x1, p.z0, p.z1) - kRadius;
        if (reach < 0) {
          ++must_block;
          EXPECT_TRUE(s.blocked[2]) << where;
          EXPECT_GE(gap, -1e-9) << where;
          EXPECT_LE(gap, kTol + 1e-9) << where;
        } else {
          ++must_pass;
          EXPECT_FALSE(s.blocked[1] || s.blocked[2]) << where;
          EXPECT_EQ(s.q[2], closed[2]) << where << ": the finger closes fully past the plate";
        }
      }
    }
  }
  EXPECT_GE(must_block, 30);
  EXPECT_GE(must_pass, 10);
}

TEST(HandControllerTest, UnblocksWhenTheHandOpens) {
  BoxScene plate({0.1, 0.1, 0.01}, {0.1, 0, -0.025});
  HandController hand(finger_rig(), {});
  for (int t = 0; t < 60; ++t) hand.tick(at_identity(1.0), kDt, {&plate.view, 1});
  ASSERT_TRUE(hand.state().blocked[1] || hand.state().blocked[2]);
  hand.tick(at_identity(0.0), kDt, {&plate.view, 1});
  EXPECT_FALSE(hand.state().blocked[1]);
  EXPECT_FALSE(hand.state().blocked[2]);
  for (int t = 0; t < 90; ++t) hand.tick(at_identity(0.0), kDt, {&plate.view, 1});
  EXPECT_EQ(hand.state().q[0], 0.0) << "the finger opens fully";
}

// The hand moves 3 mm further down onto the plate after the finger blocked on it (no grasp, so
// the plate stays): precise mode bends the finger back so it rests on the surface instead of
// sinking in; discrete mode sinks. (The finger layer alone: the resolved pose would not let the
// hand move in; pose_resolver_test covers that.)
TEST(HandControllerTest, FingerPushedIntoObjectBendsBackInPreciseMode) {
  BoxScene plate({0.1, 0.1, 0.01}, {0.1, 0, -0.025});
  for (ClosingMode mode : {ClosingMode::kPrecise, ClosingMode::kDiscrete}) {
    GraspSettings settings;
    settings.mode = mode;
    settings.resolve_pose = false;
    HandController hand(finger_rig_without_grasp(), settings);
    for (int t = 0; t < 60; ++t) hand.tick(at_identity(1.0), kDt, {&plate.view, 1});
    ASSERT_TRUE(hand.state().blocked[2]) << "the distal capsule rests on the plate";
    const double q_before = hand.state().q[0];
    ControllerInput pushed = at_identity(1.0);
    pushed.X_WorldPalm.translation().z() = -0.003;
    hand.tick(pushed, kDt, {&plate.view, 1});
    const double gap = min_blocked_gap(hand, plate.view);
    if (mode == ClosingMode::kPrecise) {
      EXPECT_GE(gap, -1e-9);
      EXPECT_LE(gap, kTol);
      EXPECT_LT(hand.state().q[0], q_before) << "the finger extended";
      EXPECT_TRUE(hand.state().blocked[2]);
    } else {
      EXPECT_LT(gap, -1e-3) << "discrete mode leaves the finger sunk by the hand's motion";
    }
  }
}

// The hand is placed 3 mm into a plate: precise mode bends the finger back past its open angle
// (limit -20 deg) onto the surface, a capsule blocks there and the rule (f_mid | f_dist) grasps.
// Releasing the trigger must let go even though the blocked angles lie below the open angle.
// (The finger layer alone: a resolved hand would be pushed out of the plate first.)
TEST(HandControllerTest, GraspAfterBendingBackReleasesWhenTheTriggerIsReleased) {
  auto rig = finger_rig_with({{"open_deg: 0 closed_deg: 90 min_deg: 0", "open_deg: 0 closed_deg: 90 min_deg: -20"},
                              {"open_deg: 0 closed_deg: 90 min_deg: 0", "open_deg: 0 closed_deg: 90 min_deg: -20"},
                              {"open_deg: 0 closed_deg: 70 min_deg: 0", "open_deg: 0 closed_deg: 70 min_deg: -20"}});
  BoxScene plate({0.1, 0.1, 0.01}, {0.1, 0, -0.012});  // top at z = -0.002: the open finger sinks 3 mm
  GraspSettings settings;
  settings.resolve_pose = false;
  HandController hand(rig, settings);
  const HandTickEvents grasp = hand.tick(at_identity(0.3), kDt, {&plate.view, 1});
  ASSERT_TRUE(grasp.grasped);
  EXPECT_LT(hand.state().q[0], 0.0) << "bent back past the open angle";
  const HandTickEvents release = hand.tick(at_identity(0.0), kDt, {&plate.view, 1});
  EXPECT_TRUE(release.released);
  EXPECT_FALSE(hand.state().grasped.valid());
}

// A copy of a controller whose caches are filled (mid-close over a plate) ticks exactly as the
// original does, on its own: through blocking, the hand pushing the finger in, and opening.
TEST(HandControllerTest, CopyTicksLikeTheOriginal) {
  BoxScene plate({0.1, 0.1, 0.01}, {0.1, 0, -0.025});
  HandController hand(finger_rig_without_grasp(), {});
  for (int t = 0; t < 2; ++t) hand.tick(at_identity(1.0), kDt, {&plate.view, 1});
  ASSERT_FALSE(hand.state().blocked[1] || hand.state().blocked[2]) << "copied before any contact";
  HandController copy = hand;
  HandController assigned(finger_rig(), {});
  assigned = hand;
  bool blocked = false;
  for (int t = 0; t < 90; ++t) {
    ControllerInput in = at_identity(t < 70 ? 1.0 : 0.0);
    if (t >= 50) in.X_WorldPalm.translation().z() = -0.003;  // pushes the resting finger in
    copy.tick(in, kDt, {&plate.view, 1});  // the copies first: they must not disturb the original
    assigned.tick(in, kDt, {&plate.view, 1});
    hand.tick(in, kDt, {&plate.view, 1});
    blocked |= hand.state().blocked[2] != 0;
    ASSERT_EQ(copy.state().q, hand.state().q) << "tick " << t;
    ASSERT_EQ(copy.state().blocked, hand.state().blocked) << "tick " << t;
    ASSERT_EQ(assigned.state().q, hand.state().q) << "tick " << t;
    ASSERT_EQ(assigned.state().blocked, hand.state().blocked) << "tick " << t;
  }
  EXPECT_TRUE(blocked) << "the distal capsule blocked on the plate";
}

// A finger resting at its target blocks when the hand brings its capsule into contact.
TEST(HandControllerTest, RestingFingerBlocksWhenTheHandBringsItIntoContact) {
  HandController hand(finger_rig_without_grasp(), {});
  for (int t = 0; t < 90; ++t) hand.tick(at_identity(0.5), kDt, {});  // settle at the half-closed target
  // Put a plate just under the distal capsule's lowest point (gap 0.02 mm).
  const auto& c = *hand.rig().phalanges()[2].capsule;
  const Eigen::Isometry3d& X = hand.state().X_PalmPhalanx[2];
  const double lowest = std::min((X * c.p_PhalanxA).z(), (X * c.p_PhalanxB).z()) - c.radius;
  BoxScene plate({0.2, 0.2, 0.01}, {0, 0, lowest - 0.00002 - 0.01});
  const std::vector<double> q = hand.state().q;
  hand.tick(at_identity(0.5), kDt, {&plate.view, 1});
  EXPECT_TRUE(hand.state().blocked[2]);
  EXPECT_EQ(hand.state().q, q) << "nothing moved";
}

// HandError averages |ND| over the capsules that hit: a capsule whose sweep finds nothing is
// reported as such and left out, not counted as zero.
TEST(HandControllerTest, HandErrorLeavesOutCapsulesWithoutHit) {
  // A box whose top (z = 0) ends at x = 0.09: under the middle capsule's Sp (x = 0.0825), not
  // under the distal's (x = 0.1025).
  BoxScene box({0.05, 0.2, 0.02}, {0.04, 0, -0.02});
  const double g = 0.002;
  HandController hand(finger_rig(), {});
  hand.tick(hovering(0.005 + g), kDt, {});
  const GraspMetrics m = hand.measure(box.view);
  ASSERT_TRUE(m.capsules[0].hit);
  ASSERT_FALSE(m.capsules[1].hit);
  EXPECT_NEAR(m.capsules[0].nd, g, 1e-9);
  EXPECT_NEAR(m.hand_error_mm, 1000 * g, 1e-6);
  EXPECT_EQ(m.capsules_without_hit, 1);
}

// A jump of the trigger from 0 to 1 is spread over ticks at max_speed * dt per joint.
TEST(HandControllerTest, FingerMovementIsRateLimited) {
  HandController hand(finger_rig(), {});
  hand.tick(at_identity(1.0), kDt, {});
  EXPECT_NEAR(hand.state().q[0], 180 * kDeg * kDt, 1e-15);
  for (int t = 0; t < 100; ++t) hand.tick(at_identity(1.0), kDt, {});
  EXPECT_EQ(hand.state().q[0], 90 * kDeg);
  EXPECT_EQ(hand.state().q[2], 70 * kDeg);
}

TEST(HandControllerTest, PerFingerCurlsReplaceTheTrigger) {
  auto rig = std::make_shared<const HandRig>(HandRig::load(HandRig::builtin_path("human_right")));
  HandController hand(rig, {});
  ControllerInput in;
  in.trigger = 0.0;
  in.curls = {0.0, 1.0, 0.0, 0.0, 0.5};  // thumb, index, middle, ring, little
  ASSERT_EQ(validate_input(in, *rig), "");
  for (int t = 0; t < 200; ++t) hand.tick(in, kDt, {});
  const auto& q = hand.state().q;
  EXPECT_EQ(q[rig->find("index_mid").value], target_angle(rig->phalanges()[rig->find("index_mid").value], 1.0));
  EXPECT_EQ(q[rig->find("middle_mid").value], target_angle(rig->phalanges()[rig->find("middle_mid").value], 0.0));
  EXPECT_EQ(q[rig->find("little_dist").value], target_angle(rig->phalanges()[rig->find("little_dist").value], 0.5));
}

TEST(HandControllerTest, ValidateInputNamesTheBadField) {
  const HandRig rig = HandRig::parse(kFingerRig, "finger3");
  ControllerInput in;
  EXPECT_EQ(validate_input(in, rig), "");
  in.trigger = 1.5;
  EXPECT_NE(validate_input(in, rig).find("trigger"), std::string::npos);
  in.trigger = std::nan("");
  EXPECT_NE(validate_input(in, rig).find("trigger"), std::string::npos);
  in.trigger = 0.5;
  in.X_WorldPalm.translation().x() = std::numeric_limits<double>::infinity();
  EXPECT_NE(validate_input(in, rig).find("pose"), std::string::npos);
  in.X_WorldPalm = Eigen::Isometry3d::Identity();
  in.X_WorldPalm.linear() *= 1.1;
  EXPECT_NE(validate_input(in, rig).find("rotation"), std::string::npos);
  in.X_WorldPalm = Eigen::Isometry3d::Identity();
  in.curls = {0.5, 0.5};
  EXPECT_NE(validate_input(in, rig).find("curls"), std::string::npos);
  in.curls = {-0.1};
  EXPECT_NE(validate_input(in, rig).find("curls[0]"), std::string::npos);
}

// Selection by surface distance prefers the big object whose surface is near the palm sphere's
// centre; the paper's origin distance prefers the small object whose centre is nearer.
TEST(HandControllerTest, SelectsNearestBySurfaceOrOrigin) {
  auto rig = finger_rig();  // selection sphere centre at (0.07, 0, 0), radius 0.2
  BoxScene big({0.1, 0.1, 0.1}, {0.07, 0, -0.12});  // surface 2 cm below the centre, origin 12 cm
  BoxScene small({0.01, 0.01, 0.01}, {0.07, 0.1, 0});  // surface 9 cm away, origin 10 cm
  big.view.id = ObjectId(1);
  small.view.id = ObjectId(2);
  const ObjectView views[] = {big.view, small.view};
  GraspSettings surface;
  HandController a(rig, surface);
  a.tick(at_identity(0), kDt, views);
  EXPECT_EQ(a.state().selected, ObjectId(1));
  GraspSettings origin;
  origin.selection = SelectionMetric::kOrigin;
  HandController b(rig, origin);
  b.tick(at_identity(0), kDt, views);
  EXPECT_EQ(b.state().selected, ObjectId(2));
}

// Places the open finger so its capsules lie flat at `height` above z = 0 (palm frame turned
// by nothing: the finger runs along +x).
ControllerInput hovering(double capsule_axis_z, double y) {
  ControllerInput in;
  in.X_WorldPalm.translation() = Eigen::Vector3d(0, y, capsule_axis_z);
  return in;
}

// ND on a box top face: the finger hovers g above it, so ND = g exactly for both capsules,
// the exact signed distance is g, and HandError = (|g| + |g|) / 2.
TEST(HandControllerTest, NdOnBoxFaceIsTheGap) {
  BoxScene box({0.2, 0.2, 0.02}, {0.1, 0, -0.02});  // top face at z = 0
  for (double g : {0.003, 0.0005, -0.002}) {
    HandController hand(finger_rig(), {});
    hand.tick(hovering(0.005 + g), kDt, {});  // capsule radius 5 mm above the face
    const GraspMetrics m = hand.measure(box.view);
    ASSERT_EQ(m.capsules.size(), 2u);
    for (const CapsuleMetric& c : m.capsules) {
      EXPECT_TRUE(c.hit) << g;
      EXPECT_NEAR(c.nd, g, 1e-9) << g;
      EXPECT_NEAR(c.signed_distance, g, 1e-9) << g;
    }
    EXPECT_NEAR(m.hand_error_mm, 1000 * std::abs(g), 1e-6);
  }
}

// Beyond the sweep (|CTc - Sp| + nd_sweep_beyond = 15 mm from Sp) there is no hit, kept apart from zero.
TEST(HandControllerTest, NoHitIsNotZero) {
  BoxScene box({0.2, 0.2, 0.02}, {0.1, 0, -0.02});
  HandController hand(finger_rig(), {});
  hand.tick(hovering(0.005 + 0.012), kDt, {});  // Sp 17 mm above: the 1 mm sphere would touch after 16 mm
  const GraspMetrics m = hand.measure(box.view);
  for (const CapsuleMetric& c : m.capsules) {
    EXPECT_FALSE(c.hit);
    EXPECT_NEAR(c.signed_distance, 0.012, 1e-9);
  }
  EXPECT_EQ(m.hand_error_mm, 0.0);
}

// ND on a sphere of radius R, off-axis by d: the 1 mm sweep sphere touches when its centre is at
// |c| = R + rs, and the impact point is c R / (R + rs).
TEST(HandControllerTest, NdOnSphereMatchesAnalyticSweep) {
  const double R = 0.04, rs = 0.001, r = 0.005, g = 0.002, d = 0.01;
  auto model = make_object_model("sphere", testing::uv_sphere_mesh(R, 180, 360), 1.0, "test");
  // Tessellation: vertices on the sphere, so the surface lies within R (1 - cos(pi/180)) inside it.
  const double kTessellation = R * (1 - std::cos(std::numbers::pi / 180)) * 2;
  ObjectView view{ObjectId(1), Eigen::Isometry3d::Identity(), model.get()};
  HandController hand(finger_rig(), {});
  // Middle capsule's Sp at x = 0.04 + 0.03 + 0.0125 = 0.0825; put it over the sphere centre line at y = d.
  ControllerInput in = hovering(R + g + r, d);
  in.X_WorldPalm.translation().x() = -0.0825;
  hand.tick(in, kDt, {});
  const GraspMetrics m = hand.measure(view);
  const double sp_z = R + g + r;
  const double c_z = std::sqrt((R + rs) * (R + rs) - d * d);
  const double ip_z = c_z * R / (R + rs);
  const double expected = (sp_z - ip_z) - r;
  ASSERT_TRUE(m.capsules[0].hit);
  EXPECT_NEAR(m.capsules[0].nd, expected, kTessellation);
}

// ND on a cylinder lying along x, with the finger along its axis on top: ND = g.
TEST(HandControllerTest, NdOnCylinderTopLineIsTheGap) {
  const double R = 0.03, r = 0.005, g = 0.0015;
  TriangleMesh cyl = testing::cylinder_mesh(R, 0.1, 64);
  for (auto& v : cyl.vertices) v = Eigen::Vector3d(v.z(), v.y(), v.x());  // axis along x, a vertex line on top
  for (auto& t : cyl.triangles) std::swap(t[1], t[2]);  // the axis swap mirrors: restore outward winding
  auto model = make_object_model("cylinder", cyl, 1.0, "test");
  ObjectView view{ObjectId(1), Eigen::Isometry3d::Identity(), model.get()};
  HandController hand(finger_rig(), {});
  ControllerInput in = hovering(R + g + r);
  in.X_WorldPalm.translation().x() = -0.09;
  hand.tick(in, kDt, {});
  const GraspMetrics m = hand.measure(view);
  for (const CapsuleMetric& c : m.capsules) {
    ASSERT_TRUE(c.hit);
    EXPECT_NEAR(c.nd, g, 1e-9);
  }
}

// The grasp rule (f_mid | f_dist) turns true once a capsule touches a plate; the grasp tick
// records metrics and contacts, and opening the hand releases.
TEST(HandControllerTest, GraspsAndReleases) {
  BoxScene plate({0.1, 0.1, 0.01}, {0.1, 0, -0.025});
  HandController hand(finger_rig(), {});
  bool grasped = false;
  for (int t = 0; t < 120 && !grasped; ++t) grasped = hand.tick(at_identity(1.0), kDt, {&plate.view, 1}).grasped;
  ASSERT_TRUE(grasped);
  EXPECT_EQ(hand.state().grasped, plate.view.id);
  ASSERT_TRUE(hand.grasp_metrics().has_value());
  ASSERT_FALSE(hand.contacts().empty());
  for (const Contact& c : hand.contacts()) {
    // Contacts lie on the plate's top face (z = -0.015), normal up.
    EXPECT_NEAR(c.p_WorldContact.z(), -0.015, 1e-9);
    EXPECT_NEAR(c.n_World.z(), 1.0, 1e-9);
  }
  const HandTickEvents ev = hand.tick(at_identity(0.0), kDt, {&plate.view, 1});
  EXPECT_TRUE(ev.released);
  EXPECT_EQ(ev.released_object, plate.view.id);
  EXPECT_FALSE(hand.state().grasped.valid());
}

// With defer_grasp_metrics() (as a World's hands run) the grasp tick takes no metrics; a copy of
// the hand made after that tick takes them later, bit-identical to those an eager hand took on
// the same tick, and the contacts (their ND included) are the same; set_grasp_metrics() delivers
// them to this grasp only. After the next tick there is no grasp tick to measure.
TEST(HandControllerTest, DeferredGraspMetricsEqualTheGraspTicksOwn) {
  auto sphere = make_object_model("sphere", testing::uv_sphere_mesh(0.03, 90, 180), 1.0, "test");
  const ObjectView view{ObjectId(3), Eigen::Isometry3d(Eigen::Translation3d(0.09, 0.004, -0.045)), sphere.get()};
  HandController eager(finger_rig(), {}), deferred(finger_rig(), {});
  deferred.defer_grasp_metrics();
  bool grasped = false;
  for (int t = 0; t < 120 && !grasped; ++t) {
    grasped = eager.tick(at_identity(1.0), kDt, {&view, 1}).grasped;
    ASSERT_EQ(deferred.tick(at_identity(1.0), kDt, {&view, 1}).grasped, grasped);
  }
  ASSERT_TRUE(grasped);
  EXPECT_FALSE(deferred.grasp_metrics().has_value());
  const HandController copy = deferred;
  const std::optional<GraspMetrics> later = copy.grasp_tick_metrics();
  ASSERT_TRUE(later.has_value());
  const GraspMetrics& now = *eager.grasp_metrics();
  EXPECT_EQ(later->hand_error_mm, now.hand_error_mm);
  EXPECT_EQ(later->palm_signed_distance, now.palm_signed_distance);
  ASSERT_EQ(later->capsules.size(), now.capsules.size());
  for (std::size_t i = 0; i < now.capsules.size(); ++i) {
    EXPECT_EQ(later->capsules[i].hit, now.capsules[i].hit) << i;
    EXPECT_EQ(later->capsules[i].nd, now.capsules[i].nd) << i;
    EXPECT_EQ(later->capsules[i].signed_distance, now.capsules[i].signed_distance) << i;
    EXPECT_EQ(later->capsules[i].nd_contact, now.capsules[i].nd_contact) << i;
  }
  const std::vector<Contact> ce = eager.contacts(), cd = deferred.contacts();
  ASSERT_EQ(ce.size(), cd.size());
  ASSERT_FALSE(ce.empty());
  for (std::size_t i = 0; i < ce.size(); ++i) {
    EXPECT_EQ(ce[i].p_ObjectContact, cd[i].p_ObjectContact) << i;
    EXPECT_EQ(ce[i].nd, cd[i].nd) << i;
    EXPECT_EQ(ce[i].nd_hit, cd[i].nd_hit) << i;
    for (const CapsuleMetric& m : now.capsules) {  // each contact's ND is its capsule's
      if (m.phalanx == cd[i].phalanx) {
        EXPECT_EQ(cd[i].nd, m.nd) << i;
      }
    }
  }
  deferred.set_grasp_metrics(deferred.grasp_serial() + 1, *later);
  EXPECT_FALSE(deferred.grasp_metrics().has_value());
  deferred.set_grasp_metrics(deferred.grasp_serial(), *later);
  ASSERT_TRUE(deferred.grasp_metrics().has_value());
  EXPECT_EQ(deferred.grasp_metrics()->hand_error_mm, now.hand_error_mm);
  deferred.tick(at_identity(1.0), kDt, {&view, 1});
  EXPECT_FALSE(deferred.grasp_tick_metrics().has_value());
}

// Capsule `id`'s segment end points in the object frame, for the hand at X_ObjectPalm.
std::pair<Eigen::Vector3d, Eigen::Vector3d> capsule_in(const HandController& hand, PhalanxId id,
                                                       const Eigen::Isometry3d& X_ObjectPalm) {
  const CapsuleSpec& cap = *hand.rig().phalanges()[id.value].capsule;
  const Eigen::Isometry3d X_ObjectPhalanx = X_ObjectPalm * hand.state().X_PalmPhalanx[id.value];
  return {X_ObjectPhalanx * cap.p_PhalanxA, X_ObjectPhalanx * cap.p_PhalanxB};
}

// The grasp tick reuses the closest points the contact search found for its signed distances and
// contacts; they equal the exact answers asked afresh of the mesh. measure() against another mesh
// under the same id reuses nothing.
TEST(HandControllerTest, GraspMetricsAndContactsEqualFreshExactQueries) {
  auto sphere = make_object_model("sphere", testing::uv_sphere_mesh(0.03, 90, 180), 1.0, "test");
  const ObjectView view{ObjectId(3), Eigen::Isometry3d(Eigen::Translation3d(0.09, 0.004, -0.045)), sphere.get()};
  HandController hand(finger_rig(), {});
  bool grasped = false;
  for (int t = 0; t < 120 && !grasped; ++t) grasped = hand.tick(at_identity(1.0), kDt, {&view, 1}).grasped;
  ASSERT_TRUE(grasped);
  const auto& ids = hand.rig().capsule_phalanges();
  const MeshDistance& mesh = sphere->distance;
  const Eigen::Isometry3d X_ObjectPalm = view.X_WorldObject.inverse() * hand.state().X_WorldPalm;
  const GraspMetrics& m = *hand.grasp_metrics();
  ASSERT_EQ(m.capsules.size(), ids.size());
  int blocked = 0;
  for (std::size_t i = 0; i < ids.size(); ++i) {
    const auto [a, b] = capsule_in(hand, ids[i], X_ObjectPalm);
    const double r = hand.rig().phalanges()[ids[i].value].capsule->radius;
    EXPECT_NEAR(m.capsules[i].signed_distance, mesh.capsule_signed_distance(a, b, r), 1e-12) << i;
    blocked += m.capsules[i].blocked;
  }
  EXPECT_GT(blocked, 0);
  // Contacts: the exact closest point of each blocked capsule, in the object frame.
  const std::vector<Contact> contacts = hand.contacts();
  ASSERT_EQ(static_cast<int>(contacts.size()), blocked);
  for (const Contact& c : contacts) {
    const auto [a, b] = capsule_in(hand, c.phalanx, hand.state().X_PalmObject.inverse());
    const SegmentQuery q = mesh.closest_to_segment(a, b);
    EXPECT_NEAR((c.p_ObjectContact - q.point_on_mesh).norm(), 0.0, 1e-12);
    EXPECT_NEAR((c.n_Object - q.normal).norm(), 0.0, 1e-12);
  }
  // The same capsules against a box under the sphere's id.
  BoxScene box({0.03, 0.03, 0.03}, {0.0, 0.0, 0.0});
  const ObjectView other{view.id, view.X_WorldObject, box.model.get()};
  const GraspMetrics mb = hand.measure(other);
  for (std::size_t i = 0; i < ids.size(); ++i) {
    const auto [a, b] = capsule_in(hand, ids[i], X_ObjectPalm);
    const double r = hand.rig().phalanges()[ids[i].value].capsule->radius;
    EXPECT_NEAR(mb.capsules[i].signed_distance, box.model->distance.capsule_signed_distance(a, b, r), 1e-12) << i;
    EXPECT_NE(mb.capsules[i].signed_distance, m.capsules[i].signed_distance) << i;
  }
}

// The grasp tick's quality is that of the grasp's contacts (object frame, about the centre of
// mass) with the rig's friction and the object's radius; an object's own friction replaces the
// rig's, and while held the quality follows the contacts.
TEST(HandControllerTest, GraspQualityIsThatOfTheContacts) {
  auto rig = std::make_shared<const HandRig>(HandRig::load(HandRig::builtin_path("human_right")));
  const ObjectModelPtr bottle = make_standin_model(*find_protocol_object("006_mustard_bottle"));
  auto slippery = std::make_shared<ObjectModel>(*bottle);
  slippery->friction = 0.0;
  EXPECT_NEAR(bottle->max_radius,
              std::max_element(bottle->mesh.vertices.begin(), bottle->mesh.vertices.end(),
                               [](const auto& a, const auto& b) { return a.norm() < b.norm(); })
                  ->norm(),
              0.0);
  auto quality_of = [&](const HandController& hand, const ObjectModel& model, double mu) {
    std::vector<QualityContact> qc;
    for (const Contact& c : hand.contacts()) qc.push_back({c.p_ObjectContact, c.n_Object});
    return grasp_quality(qc, mu, model.max_radius, 8, QualityVolume::kCompute);
  };
  for (const ObjectModelPtr& model : {bottle, ObjectModelPtr(slippery)}) {
    // A World computes the qualities (within the step: quality_delay_ticks 0) and gives them to
    // the hand; a HandController alone has none.
    WorldSettings ws;
    ws.grasp.quality_volume = QualityVolume::kCompute;
    World world(ws);
    const ObjectId id = world.add_object(model, World::resting_pose(*model, 0.45, 0.0, 0.4));
    const GraspPlan plan = plan_grasp(rig, {}, *model, world.object_pose(id), kDt);
    const HandId hand_id = world.add_hand(rig);
    ControllerInput in;
    in.X_WorldPalm = plan.X_WorldPalm;
    std::optional<GraspEvent> grasp;
    for (int t = 0; t < 90 && !grasp; ++t) {
      in.trigger = std::min(1.0, t * kDt / 0.35);
      ASSERT_EQ(world.set_input(hand_id, in), "");
      world.step();
      for (const GraspEvent& e : world.events())
        if (e.kind == GraspEvent::Kind::kGrasp) grasp = e;
    }
    ASSERT_TRUE(grasp) << model->name;
    const HandController& hand = world.hand(hand_id);
    const double mu = model->friction.value_or(0.5);
    const GraspQuality expected = quality_of(hand, *model, mu);
    for (const GraspQuality& q : {hand.grasp_metrics()->quality, grasp->metrics->quality}) {
      EXPECT_EQ(q.epsilon, expected.epsilon);
      EXPECT_EQ(q.volume, expected.volume);
      EXPECT_EQ(q.force_closure, expected.force_closure);
    }
    // Squeezing on, new phalanges block: hold_metrics() follows the contacts.
    in.trigger = 1.0;
    ASSERT_EQ(world.set_input(hand_id, in), "");
    for (int t = 0; t < 30; ++t) world.step();
    ASSERT_TRUE(hand.state().grasped.valid());
    const GraspQuality held = quality_of(hand, *model, mu);
    EXPECT_EQ(hand.hold_metrics()->quality.epsilon, held.epsilon);
    EXPECT_EQ(hand.hold_metrics()->quality.volume, held.volume);
    if (mu > 0) {
      EXPECT_GT(held.volume, 0.0);  // several contacts with friction: a 6-D wrench space
    } else if (hand.contacts().size() <= 6) {
      EXPECT_EQ(held.volume, 0.0);  // frictionless: one wrench per contact, 7 needed to span 6-D
    }
  }
  // A HandController alone grasps with its quality pending.
  const Eigen::Isometry3d X_WorldObject = World::resting_pose(*bottle, 0.45, 0.0, 0.4);
  const GraspPlan plan = plan_grasp(rig, {}, *bottle, X_WorldObject, kDt);
  const ObjectView view{ObjectId(1), X_WorldObject, bottle.get()};
  HandController alone(rig, {});
  ControllerInput in;
  in.X_WorldPalm = plan.X_WorldPalm;
  bool grasped = false;
  for (int t = 0; t < 90 && !grasped; ++t) {
    in.trigger = std::min(1.0, t * kDt / 0.35);
    grasped = alone.tick(in, kDt, {&view, 1}).grasped;
  }
  ASSERT_TRUE(grasped);
  EXPECT_EQ(alone.grasp_metrics()->quality.epsilon, kPendingQuality.epsilon);
  EXPECT_EQ(alone.hold_metrics()->quality.epsilon, kPendingQuality.epsilon);
  // set_quality() delivers one, to this grasp only.
  alone.set_quality(alone.grasp_serial() + 1, {0.5, 1, true}, true);
  EXPECT_EQ(alone.grasp_metrics()->quality.epsilon, kPendingQuality.epsilon);
  alone.set_quality(alone.grasp_serial(), {0.25, 1, true}, true);
  EXPECT_EQ(alone.grasp_metrics()->quality.epsilon, 0.25);
  EXPECT_EQ(alone.hold_metrics()->quality.epsilon, 0.25);
}

std::vector<QualityContact> quality_contacts(const HandController& hand) {
  return HandController::quality_contacts(hand.contacts());
}

bool bit_identical(const std::vector<QualityContact>& a, const std::vector<QualityContact>& b) {
  return a.size() == b.size() && std::equal(a.begin(), a.end(), b.begin(),
                                            [](const auto& x, const auto& y) { return x.p == y.p && x.n == y.n; });
}

// A scripted trial as a bot runs it (reach, squeeze, lift, hold 1 s, release), asking the hold
// quality every tick as the server does: every held tick's quality is exactly a fresh
// grasp_quality() of the current contacts, and the hand builds one hull per distinct contact set
// held, none while the hold is steady; the release, unblocking the fingers that blocked during
// the lift, comes back to contact sets held before and reuses their hulls.
TEST(HandControllerTest, HoldQualityIsAFreshHullOfTheContactsAndOneHullPerContactSet) {
  auto rig = std::make_shared<const HandRig>(HandRig::load(HandRig::builtin_path("human_right")));
  const ObjectModelPtr model = make_standin_model(*find_protocol_object("005_tomato_soup_can"));
  World world;
  const ObjectId id = world.add_object(model, World::resting_pose(*model, 0.45, 0.02, 0.5));
  const HandId hand_id = world.add_hand(rig);
  for (int i = 0; i < 30; ++i) world.step();
  ScriptedOperator op(rig, skill_profile("experienced"), 3);
  op.begin(*model, world.object_pose(id), Eigen::Isometry3d(Eigen::Translation3d(0.15, -0.2, 0.3)), world.time());
  const double mu = model->friction.value_or(rig->friction());
  std::vector<std::vector<QualityContact>> distinct;
  std::vector<QualityContact> previous;
  int held = 0, set_changes = 0;
  std::optional<std::uint64_t> hulls_at_hold;
  while (!op.done() && world.time() < 20) {
    world.set_input(hand_id, op.next(world.time(), world.holder(id) == hand_id));
    world.step();
    const HandController& hand = world.hand(hand_id);
    const auto metrics = hand.hold_metrics();
    if (!metrics) continue;
    ++held;
    const std::vector<QualityContact> kept = quality_contacts(hand);
    const GraspQuality fresh = grasp_quality(kept, mu, model->max_radius);
    EXPECT_EQ(metrics->quality.epsilon, fresh.epsilon) << "tick " << world.tick();
    EXPECT_EQ(metrics->quality.volume, fresh.volume) << "tick " << world.tick();
    EXPECT_EQ(metrics->quality.force_closure, fresh.force_closure);
    if (std::none_of(distinct.begin(), distinct.end(), [&](const auto& d) { return bit_identical(d, kept); }))
      distinct.push_back(kept);
    set_changes += !bit_identical(kept, previous);
    previous = kept;
    if (op.phase() == OperatorPhase::kHold) {
      if (!hulls_at_hold) hulls_at_hold = world.quality_computations(hand_id);
      EXPECT_EQ(world.quality_computations(hand_id), *hulls_at_hold) << "a steady hold builds no hull";
    }
  }
  EXPECT_TRUE(op.held_after_lift());
  EXPECT_GT(held, 100);
  ASSERT_TRUE(hulls_at_hold.has_value());
  EXPECT_EQ(world.quality_computations(hand_id), distinct.size());
  EXPECT_GT(set_changes, static_cast<int>(distinct.size())) << "the release comes back to earlier contact sets";
}

// Two hands holding a long box re-attach to it every tick. While they rise together their
// contacts move by rounding only: no hull is rebuilt, and the quality stays within the bound of
// hand_controller.h (quality_contacts()) of a fresh hull. Pulled apart, the hands slide along the
// box: the contacts really move, and each tick builds a hull per hand.
TEST(HandControllerTest, TwoHandHoldRebuildsTheHullOnlyWhenTheContactsMove) {
  auto rig = std::make_shared<const HandRig>(HandRig::load(HandRig::builtin_path("human_right")));
  const ObjectModelPtr model = make_object_model("long_box", box_mesh({0.3, 0.04, 0.04}), 0.5, "test");
  World world;
  const ObjectId box = world.add_object(model, World::resting_pose(*model, 0.4, 0.0, 0.0));
  const HandId a = world.add_hand(rig), b = world.add_hand(rig);
  for (int i = 0; i < 30; ++i) world.step();
  const GraspPlan plan = plan_grasp(rig, {}, *model, world.object_pose(box), world.dt());
  const Eigen::Isometry3d Xa = Eigen::Translation3d(-0.2, 0, 0) * plan.X_WorldPalm;
  const Eigen::Isometry3d Xb = Eigen::Translation3d(0.2, 0, 0) * plan.X_WorldPalm;
  auto step = [&](const Eigen::Vector3d& up, double apart, double trigger) {
    ControllerInput in;
    in.trigger = trigger;
    in.X_WorldPalm = Eigen::Translation3d(up - Eigen::Vector3d(apart, 0, 0)) * Xa;
    ASSERT_EQ(world.set_input(a, in), "");
    in.X_WorldPalm = Eigen::Translation3d(up + Eigen::Vector3d(apart, 0, 0)) * Xb;
    ASSERT_EQ(world.set_input(b, in), "");
    world.step();
    for (HandId h : {a, b}) world.hand(h).hold_metrics();
  };
  for (int t = 1; t <= 60; ++t) step({0, 0, 0}, 0, std::min(1.0, t / 30.0));
  ASSERT_EQ(world.holders(box).size(), 2u);
  const double mu = model->friction.value_or(rig->friction());
  const std::uint64_t hulls_a = world.quality_computations(a), hulls_b = world.quality_computations(b);
  const std::vector<QualityContact> before_a = quality_contacts(world.hand(a)),
                                    before_b = quality_contacts(world.hand(b));
  int rounded = 0;  // ticks on which rounding moved some contact
  for (int t = 1; t <= 90; ++t) {
    step({0, 0, 0.1 * t / 90}, 0, 1);
    rounded += !bit_identical(quality_contacts(world.hand(a)), before_a) ||
               !bit_identical(quality_contacts(world.hand(b)), before_b);
  }
  ASSERT_EQ(world.holders(box).size(), 2u);
  EXPECT_EQ(world.quality_computations(a), hulls_a);
  EXPECT_EQ(world.quality_computations(b), hulls_b);
  EXPECT_GT(rounded, 0) << "rounding did move the contacts";
  for (HandId h : {a, b}) {
    const std::vector<QualityContact> kept = quality_contacts(world.hand(h));
    const Wrenches w = contact_wrenches(kept, mu, model->max_radius);
    const GraspQuality fresh = wrench_quality(w), held = world.hand(h).hold_metrics()->quality;
    const double d = 1e-11;
    EXPECT_LE(std::abs(held.epsilon - fresh.epsilon), d + 1e-12);
    EXPECT_GT(qhull_wrench_quality(w).volume, 0.0);  // a 6-D wrench set, not a trivially flat one
    EXPECT_EQ(held.volume, kVolumeNotComputed);  // the World's default: no full hull
  }
  for (int t = 1; t <= 30; ++t) step({0, 0, 0.1}, 0.02 * t / 30, 1);
  ASSERT_EQ(world.holders(box).size(), 2u);
  EXPECT_GE(world.quality_computations(a), hulls_a + 25);
  EXPECT_GE(world.quality_computations(b), hulls_b + 25);
}

// The closing modes' names, as flags, configuration files and records write them, read back.
TEST(ClosingModeTest, NamesReadBackAndOthersAreRefused) {
  for (ClosingMode m : {ClosingMode::kPrecise, ClosingMode::kDiscrete})
    EXPECT_EQ(parse_closing_mode(closing_mode_name(m)), m);
  EXPECT_STREQ(closing_mode_name(ClosingMode::kPrecise), "precise");
  EXPECT_STREQ(closing_mode_name(ClosingMode::kDiscrete), "discrete");
  EXPECT_EQ(parse_closing_mode("Precise"), std::nullopt);
  EXPECT_EQ(parse_closing_mode("both"), std::nullopt);
  EXPECT_EQ(parse_closing_mode(""), std::nullopt);
}

}  // namespace
}  // namespace telegrasp::sim
