// Tests client_lib/tools/view/controller_input: the headset page's sample parsed field by field,
// each error naming its field, and the grip-to-palm offset checked against the WebXR grip axes.
#include "controller_input.h"

#include "telegrasp/sim/hand_rig.h"

#include <gtest/gtest.h>

#include <cmath>

namespace telegrasp::view {
namespace {

const std::string kGood =
    R"({"side":"left","pose":{"position":{"x":0.1,"y":-0.2,"z":0.3},"orientation":{"x":0,"y":0,"z":0.6,"w":0.8}},)"
    R"("trigger":0.25,"curls":[0,0.1,0.2,0.3,1],"tracking":false,"seq":7,"stamp":{"sec":12,"nsec":345}})";

std::string error_of(const std::string& text) {
  std::string error;
  EXPECT_FALSE(parse_controller_input(text, error).has_value()) << text;
  return error;
}

// `text` with the first occurrence of `from` replaced by `to`.
std::string with(std::string text, const std::string& from, const std::string& to) {
  text.replace(text.find(from), from.size(), to);
  return text;
}

TEST(ControllerInputTest, ReadsEveryField) {
  std::string error;
  const auto in = parse_controller_input(kGood, error);
  ASSERT_TRUE(in) << error;
  EXPECT_EQ(in->side, client::HandSide::kLeft);
  EXPECT_EQ(in->X_WorldGrip.translation(), Eigen::Vector3d(0.1, -0.2, 0.3));
  // 0.8 + 0.6k: a turn of 2 atan(0.75) about +z.
  EXPECT_NEAR(Eigen::AngleAxisd(in->X_WorldGrip.linear()).angle(), 2 * std::atan(0.75), 1e-12);
  EXPECT_EQ(in->trigger, 0.25);
  EXPECT_EQ(in->curls, (std::vector<double>{0, 0.1, 0.2, 0.3, 1}));
  EXPECT_FALSE(in->tracking);
  EXPECT_EQ(in->seq, 7u);
  EXPECT_EQ(in->stamp_ns, 12'000'000'345);
  // The optional fields default: tracking true, no curls, no stamp.
  const auto bare = parse_controller_input(
      R"({"side":"right","pose":{"position":{"x":0,"y":0,"z":0},"orientation":{"x":0,"y":0,"z":0,"w":1}},"trigger":1,"seq":1})",
      error);
  ASSERT_TRUE(bare) << error;
  EXPECT_TRUE(bare->tracking);
  EXPECT_TRUE(bare->curls.empty());
  EXPECT_EQ(bare->stamp_ns, 0);
}

TEST(ControllerInputTest, EachErrorNamesItsField) {
  EXPECT_EQ(error_of("[1,2]"), "not a JSON object");
  EXPECT_EQ(error_of("{nope"), "not a JSON object");
  EXPECT_NE(error_of(with(kGood, R"("left")", R"("middle")")).find("side"), std::string::npos);
  EXPECT_NE(error_of(with(kGood, R"("x":0.1)", R"("x":"far")")).find("pose.position.x"), std::string::npos);
  EXPECT_NE(error_of(with(kGood, R"("z":0.3)", R"("z":100.5)")).find("pose.position.z"), std::string::npos);
  EXPECT_NE(error_of(with(kGood, R"("w":0.8)", R"("w":0.9)")).find("not a unit quaternion"), std::string::npos);
  EXPECT_NE(error_of(with(kGood, R"("w":0.8)", R"("W":0.8)")).find("pose.orientation.w"), std::string::npos);
  EXPECT_NE(error_of(with(kGood, "0.25", "1.5")).find("trigger"), std::string::npos);
  EXPECT_NE(error_of(with(kGood, "[0,0.1,0.2,0.3,1]", "[0,0.1]")).find("curls"), std::string::npos);
  EXPECT_NE(error_of(with(kGood, "[0,0.1,0.2,0.3,1]", "[0,0.1,0.2,-0.3,1]")).find("curls[3]"), std::string::npos);
  EXPECT_NE(error_of(with(kGood, R"("tracking":false)", R"("tracking":0)")).find("tracking"), std::string::npos);
  EXPECT_NE(error_of(with(kGood, R"("seq":7)", R"("seq":0)")).find("seq"), std::string::npos);
  EXPECT_NE(error_of(with(kGood, R"("seq":7)", R"("seq":-7)")).find("seq"), std::string::npos);
  EXPECT_NE(error_of(with(kGood, R"("nsec":345)", R"("nsec":"x")")).find("stamp"), std::string::npos);
  EXPECT_NE(error_of(with(kGood, R"("side")", R"("version":2,"side")")).find("version"), std::string::npos);
  EXPECT_NE(error_of(std::string(kMaxControllerInputBytes + 1, ' ')).find("bytes"), std::string::npos);
}

// The grip frame (WebXR): origin at the rig's grasp centre, +X out of the back of a right hand
// (into the palm of a left one), -Z toward the thumb, Y = Z x X.
TEST(ControllerInputTest, GripToPalmPutsTheGripAtTheGraspCentreWithWebXrAxes) {
  for (const auto& [name, side] : {std::pair{"human_right", client::HandSide::kRight},
                                   std::pair{"human_left", client::HandSide::kLeft}}) {
    const sim::HandRig rig = sim::HandRig::load(sim::HandRig::builtin_path(name));
    const Eigen::Isometry3d X_GripPalm = grip_to_palm(rig, side);
    const Eigen::Isometry3d X_PalmGrip = X_GripPalm.inverse();
    EXPECT_TRUE(X_PalmGrip.translation().isApprox(rig.p_PalmGraspCenter(), 1e-12)) << name;
    const Eigen::Matrix3d R = X_PalmGrip.linear();  // columns: the grip's axes in the palm frame
    EXPECT_NEAR(R.determinant(), 1, 1e-12);
    const Eigen::Vector3d back(0, 0, 1), fingers(1, 0, 0);
    const Eigen::Vector3d thumb = side == client::HandSide::kRight ? Eigen::Vector3d(0, 1, 0) : Eigen::Vector3d(0, -1, 0);
    EXPECT_TRUE(R.col(0).isApprox(side == client::HandSide::kRight ? back : Eigen::Vector3d(-back)));
    EXPECT_TRUE((-R.col(2)).isApprox(thumb)) << name;  // -Z toward the thumb
    EXPECT_TRUE(R.col(1).isApprox(R.col(2).cross(R.col(0))));
    EXPECT_TRUE(R.col(1).isApprox(-fingers)) << name;  // so the fingers wrap the handle along -Y
  }
}

}  // namespace
}  // namespace telegrasp::view
