// Tests server/src/input_validation: one case per reason a controller state is dropped.
#include "input_validation.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

namespace telegrasp::server {
namespace {

constexpr std::array<std::size_t, 2> kFiveFingers{5, 5};

msg::ControllerState valid_state() {
  msg::ControllerState s;
  s.client_id("alice");
  s.hand_side(1);
  s.sequence_number(1);
  s.palm().orientation().w(1);
  s.palm().position().z(0.3);
  s.trigger(0.5);
  return s;
}

RejectReason reason_of(const msg::ControllerState& s, std::array<std::size_t, 2> fingers = kFiveFingers) {
  RejectReason r{};
  EXPECT_FALSE(validate_controller_state(s, fingers, r)) << "expected a rejection";
  return r;
}

TEST(InputValidationTest, AcceptsAValidState) {
  RejectReason r{};
  EXPECT_TRUE(validate_controller_state(valid_state(), kFiveFingers, r));
  msg::ControllerState s = valid_state();
  s.curls({0, 0.25, 0.5, 0.75, 1});
  s.trigger(1);
  s.palm().orientation().w(1 + 0.5 * kUnitQuaternionTolerance);  // within tolerance
  EXPECT_TRUE(validate_controller_state(s, kFiveFingers, r));
}

TEST(InputValidationTest, RejectsEachBadField) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  msg::ControllerState s = valid_state();
  s.client_id("");
  EXPECT_EQ(reason_of(s), RejectReason::kEmptyClientId);

  s = valid_state();
  s.hand_side(2);
  EXPECT_EQ(reason_of(s), RejectReason::kUnknownHandSide);

  s = valid_state();
  s.palm().position().x(nan);
  EXPECT_EQ(reason_of(s), RejectReason::kNonFinite);
  s = valid_state();
  s.palm().position().y(std::numeric_limits<double>::infinity());
  EXPECT_EQ(reason_of(s), RejectReason::kNonFinite);
  s = valid_state();
  s.trigger(nan);
  EXPECT_EQ(reason_of(s), RejectReason::kNonFinite);
  s = valid_state();
  s.curls({0, 0, nan, 0, 0});
  EXPECT_EQ(reason_of(s), RejectReason::kNonFinite);

  s = valid_state();
  s.palm().orientation().w(0.9);  // |q| = 0.9
  EXPECT_EQ(reason_of(s), RejectReason::kQuaternionNotUnit);
  s = valid_state();
  s.palm().orientation().w(0);  // the zero quaternion of a default-constructed sample
  EXPECT_EQ(reason_of(s), RejectReason::kQuaternionNotUnit);

  s = valid_state();
  s.palm().position().z(-100.5);  // kMaxPalmCoordinate = 100 m
  EXPECT_EQ(reason_of(s), RejectReason::kPositionOutOfRange);
  s.palm().position().z(99.5);
  RejectReason r{};
  EXPECT_TRUE(validate_controller_state(s, kFiveFingers, r)) << "99.5 m is still a valid palm";

  s = valid_state();
  s.trigger(-0.01);
  EXPECT_EQ(reason_of(s), RejectReason::kTriggerOutOfRange);
  s.trigger(1.01);
  EXPECT_EQ(reason_of(s), RejectReason::kTriggerOutOfRange);

  s = valid_state();
  s.curls({0.5, 0.5});
  EXPECT_EQ(reason_of(s), RejectReason::kCurlsWrongCount);
  s.curls({0.5, 0.5, 0.5, 0.5, 1.5});
  EXPECT_EQ(reason_of(s), RejectReason::kCurlsOutOfRange);
}

// Curls count per side follows each side's rig (e.g. a three-finger gripper on the left).
TEST(InputValidationTest, CurlCountFollowsTheSidesRig) {
  msg::ControllerState s = valid_state();
  s.hand_side(0);
  s.curls({0.1, 0.2, 0.3});
  RejectReason r{};
  EXPECT_TRUE(validate_controller_state(s, {3, 5}, r));
  EXPECT_EQ(reason_of(s, {5, 5}), RejectReason::kCurlsWrongCount);
}

TEST(InputValidationTest, ReasonsHaveStableNames) {
  EXPECT_EQ(name(RejectReason::kNonFinite), "non_finite");
  EXPECT_EQ(name(RejectReason::kClientIdOwnedByAnotherParticipant), "client_id_owned_by_another_participant");
  EXPECT_EQ(name(RejectReason::kTooManyHands), "too_many_hands");
  EXPECT_EQ(name(RejectReason::kRateLimited), "rate_limited");
  EXPECT_EQ(name(RejectReason::kPositionOutOfRange), "position_out_of_range");
}

}  // namespace
}  // namespace telegrasp::server
