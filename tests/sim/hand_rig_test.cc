// Tests HandRig: loading the shipped rigs, and errors that name the file and field.
#include "telegrasp/sim/hand_rig.h"

#include <gtest/gtest.h>

#include <fstream>
#include <sstream>

namespace telegrasp::sim {
namespace {

std::string read_builtin(const std::string& name) {
  std::ifstream in(HandRig::builtin_path(name));
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// Replaces the first occurrence of `from` in `text`.
std::string edit(std::string text, const std::string& from, const std::string& to) {
  const auto pos = text.find(from);
  EXPECT_NE(pos, std::string::npos) << "test setup: '" << from << "' not in the rig text";
  if (pos != std::string::npos) text.replace(pos, from.size(), to);
  return text;
}

std::string error_of(const std::string& text) {
  try {
    HandRig::parse(text, "bad.textproto");
  } catch (const RigError& e) {
    return e.what();
  }
  return "";
}

TEST(HandRigTest, LoadsHumanRightHand) {
  const HandRig rig = HandRig::load(HandRig::builtin_path("human_right"));
  EXPECT_EQ(rig.name(), "human_right");
  EXPECT_EQ(rig.side(), HandSide::kRight);
  ASSERT_EQ(rig.fingers().size(), 5u);
  EXPECT_EQ(rig.phalanges().size(), 15u);
  // Capsules on the middle and distal phalanx of every finger.
  EXPECT_EQ(rig.capsule_phalanges().size(), 10u);
  for (const auto& f : rig.fingers()) {
    EXPECT_FALSE(rig.phalanges()[f.phalanges[0].value].capsule.has_value()) << f.name;
    EXPECT_TRUE(rig.phalanges()[f.phalanges[1].value].capsule.has_value()) << f.name;
    EXPECT_TRUE(rig.phalanges()[f.phalanges[2].value].capsule.has_value()) << f.name;
  }
  // The paper's rule: (thumb_mid | thumb_dist | palm) & (index_mid | index_dist | middle_mid | middle_dist).
  ASSERT_EQ(rig.grasp_rule().size(), 2u);
  EXPECT_EQ(rig.grasp_rule()[0].size(), 3u);
  EXPECT_TRUE(rig.grasp_rule()[0][2].palm);
  EXPECT_EQ(rig.grasp_rule()[1].size(), 4u);
  EXPECT_EQ(rig.grasp_rule()[1][0].phalanx, rig.find("index_mid"));
}

// human_right_opposable: human_right with two more phalanges on the thumb, its carpometacarpal
// joint's abduction and axial rotation, of length 0 and without a capsule, closing early.
TEST(HandRigTest, OpposableThumbIsWrittenAsZeroLengthPhalanges) {
  const HandRig rig = HandRig::load(HandRig::builtin_path("human_right_opposable"));
  const HandRig planar = HandRig::load(HandRig::builtin_path("human_right"));
  EXPECT_EQ(rig.phalanges().size(), 17u);
  EXPECT_EQ(rig.fingers()[0].phalanges.size(), 5u);
  for (const char* axis : {"thumb_cmc_abd", "thumb_cmc_rot"}) {
    const PhalanxSpec& p = rig.phalanges()[rig.find(axis).value];
    EXPECT_EQ(p.finger, 0) << axis;
    EXPECT_EQ(p.length, 0.0) << axis;
    EXPECT_FALSE(p.capsule.has_value()) << axis;
    EXPECT_EQ(p.closes_from, 0.0) << axis;
    EXPECT_LT(p.closes_until, 0.5) << axis;
  }
  EXPECT_EQ(rig.capsule_phalanges().size(), planar.capsule_phalanges().size());
  EXPECT_EQ(rig.grasp_rule().size(), planar.grasp_rule().size());
}

TEST(HandRigTest, GripperStatesItsOwnGraspGroups) {
  const HandRig rig = HandRig::load(HandRig::builtin_path("gripper3"));
  EXPECT_EQ(rig.fingers().size(), 3u);
  EXPECT_EQ(rig.capsule_phalanges().size(), 6u);
  ASSERT_EQ(rig.grasp_rule().size(), 2u);
  EXPECT_EQ(rig.grasp_rule()[0][0].phalanx, rig.find("a_mid"));
  EXPECT_EQ(rig.grasp_rule()[1][3].phalanx, rig.find("c_dist"));
}

TEST(HandRigTest, MissingFileNamesThePath) {
  try {
    HandRig::load("/nonexistent/rig.textproto");
    FAIL() << "expected RigError";
  } catch (const RigError& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/rig.textproto"), std::string::npos) << e.what();
  }
}

TEST(HandRigTest, SyntaxErrorNamesTheLine) {
  const std::string msg = error_of("name: \"x\"\nfingers { name: }\n");
  EXPECT_NE(msg.find("bad.textproto"), std::string::npos) << msg;
  EXPECT_NE(msg.find("line 2"), std::string::npos) << msg;
}

TEST(HandRigTest, BadFieldsAreNamed) {
  const std::string good = read_builtin("human_right");
  ASSERT_EQ(error_of(good), "");
  // The index finger is fingers[1]; its middle phalanx is phalanges[1].
  EXPECT_NE(error_of(edit(good, "radius: 0.0085", "radius: 0")).find("fingers[1].phalanges[1].capsule.radius"),
            std::string::npos);
  EXPECT_NE(error_of(edit(good, "\"index_dist\", \"middle_mid\"", "\"index_nail\", \"middle_mid\""))
                .find("unknown phalanx 'index_nail'"),
            std::string::npos);
  EXPECT_NE(error_of(edit(good, "open_deg: 5 closed_deg: 80 min_deg: -10", "open_deg: -20 closed_deg: 80 min_deg: -10"))
                .find("fingers[1].phalanges[0].joint.open_deg"),
            std::string::npos);
  EXPECT_NE(error_of(edit(good, "name: \"human_right\"", "name: \"\"")).find("field 'name'"), std::string::npos);
  EXPECT_NE(
      error_of(edit(good, "name: \"index_mid\"", "name: \"thumb_mid\"")).find("duplicate phalanx name 'thumb_mid'"),
      std::string::npos);
  EXPECT_NE(error_of(edit(good, "palm_selection_sphere { center { x: 0.035 y: 0 z: -0.04 } radius: 0.09 }", ""))
                .find("palm_selection_sphere.radius"),
            std::string::npos);
  EXPECT_NE(
      error_of(edit(good, "joint { axis { x: 0 y: 1 z: 0 }", "joint { axis { x: 0 y: 0 z: 0 }")).find("joint.axis"),
      std::string::npos);
}

// A joint's part of the trigger defaults to all of it and must be an interval within [0, 1]; a
// phalanx may have length 0 (another axis of the next joint), not less.
TEST(HandRigTest, ClosingRangeAndZeroLength) {
  const std::string good = read_builtin("gripper3");  // written before either field existed
  const HandRig old = HandRig::parse(good, "old");
  for (const PhalanxSpec& p : old.phalanges()) {
    EXPECT_EQ(p.closes_from, 0.0) << p.name;
    EXPECT_EQ(p.closes_until, 1.0) << p.name;
  }
  const std::string human = read_builtin("human_right");
  const std::string first_joint = "joint { axis { x: 0 y: 1 z: 0 } open_deg: 5 closed_deg: 80";
  const HandRig late = HandRig::parse(edit(human, first_joint, first_joint + " closes_from: 0.25 closes_until: 0.75"), "late");
  EXPECT_EQ(late.phalanges()[late.find("index_prox").value].closes_from, 0.25);
  EXPECT_EQ(late.phalanges()[late.find("index_prox").value].closes_until, 0.75);
  for (const char* range : {" closes_from: 0.5 closes_until: 0.5", " closes_until: 1.5", " closes_from: -0.1",
                            " closes_from: nan"}) {
    const std::string msg = error_of(edit(human, first_joint, first_joint + range));
    EXPECT_NE(msg.find("fingers[1].phalanges[0].joint.closes_from/closes_until"), std::string::npos) << range << ": " << msg;
  }
  EXPECT_NE(error_of(edit(human, "length: 0.045", "length: -0.045")).find("fingers[1].phalanges[0].length"),
            std::string::npos);
}

TEST(HandRigTest, FrictionDefaultsToHalfAndMustBeFiniteAndNonNegative) {
  const std::string good = read_builtin("human_right");
  EXPECT_EQ(HandRig::parse(good, "good").friction(), 0.5);
  const std::string without = edit(good, "friction: 0.5", "");
  EXPECT_EQ(HandRig::parse(without, "without").friction(), 0.5);
  EXPECT_EQ(HandRig::parse(edit(good, "friction: 0.5", "friction: 0"), "zero").friction(), 0.0);
  EXPECT_EQ(HandRig::parse(edit(good, "friction: 0.5", "friction: 0.8"), "high").mirrored().friction(), 0.8);
  EXPECT_NE(error_of(edit(good, "friction: 0.5", "friction: -0.1")).find("field 'friction'"), std::string::npos);
  EXPECT_NE(error_of(edit(good, "friction: 0.5", "friction: nan")).find("field 'friction'"), std::string::npos);
  EXPECT_NE(error_of(edit(good, "friction: 0.5", "friction: inf")).find("field 'friction'"), std::string::npos);
}

}  // namespace
}  // namespace telegrasp::sim
