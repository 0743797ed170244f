// Tests server/src/server_config: reading a text config, and errors that name the field.
#include "server_config.h"

#include "server_config.pb.h"

#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>

namespace telegrasp::server {
namespace {

// ctest runs each test as its own process, two at a time: the file name carries the test's name
// so that two tests never write the same file.
std::string write_temp(const std::string& name, const std::string& text) {
  const std::string test = ::testing::UnitTest::GetInstance()->current_test_info()->name();
  const auto path =
      std::filesystem::temp_directory_path() / ("telegrasp_server_config_test_" + test + "_" + name + ".textproto");
  std::ofstream(path) << text;
  return path.string();
}

std::string error_of(const std::string& text) {
  ServerSettings s;
  try {
    load_server_config(write_temp("bad", text), s);
  } catch (const std::runtime_error& e) {
    return e.what();
  }
  return "";
}

TEST(ServerConfigTest, ReadsEveryFieldAndKeepsDefaultsElsewhere) {
  ServerSettings s;
  load_server_config(write_temp("good", R"(
    domain: 7
    profile: "lan"
    tick_hz: 120
    objects { model: "005_tomato_soup_can" x: 0.4 y: 0.1 yaw: 0.5 }
    closing_mode: "discrete"
    two_hand_mode: "takeover"
    late_latch: false
  )"),
                     s);
  EXPECT_EQ(s.domain, 7);
  EXPECT_EQ(s.profile, "lan");
  EXPECT_EQ(s.tick_hz, 120);
  ASSERT_EQ(s.objects.size(), 1u);
  EXPECT_EQ(s.objects[0].model, "005_tomato_soup_can");
  EXPECT_EQ(s.objects[0].y, 0.1);
  EXPECT_EQ(s.closing_mode, sim::ClosingMode::kDiscrete);
  EXPECT_EQ(s.two_hand_mode, sim::TwoHandMode::kTakeover);
  EXPECT_FALSE(s.late_latch);
  EXPECT_EQ(s.freeze_after_s, 0.25);  // default kept
  EXPECT_EQ(ServerSettings{}.two_hand_mode, sim::TwoHandMode::kShare);
}

TEST(ServerConfigTest, ErrorsNameTheFileAndField) {
  EXPECT_NE(error_of("tick_hz: 0").find("tick_hz"), std::string::npos);
  EXPECT_NE(error_of("domain: 300").find("domain"), std::string::npos);
  EXPECT_NE(error_of("closing_mode: \"fast\"").find("closing_mode"), std::string::npos);
  EXPECT_NE(error_of("two_hand_mode: \"both\"").find("two_hand_mode"), std::string::npos);
  EXPECT_NE(error_of("remove_after_s: 2").find("remove_after_s"), std::string::npos);
  const std::string typo = error_of("tick_hertz: 90");
  EXPECT_NE(typo.find("tick_hertz"), std::string::npos);
  EXPECT_NE(typo.find("line 1"), std::string::npos);
  EXPECT_NE(typo.find("telegrasp_server_config_test_ErrorsNameTheFileAndField_bad"), std::string::npos);
  ServerSettings s;
  EXPECT_THROW(load_server_config("/no/such/file.textproto", s), std::runtime_error);
}

// A scene object may set the friction of hand contacts on it (grasp quality); it stays unset
// otherwise, goes into the recorded configuration, and must be finite and >= 0.
TEST(ServerConfigTest, SceneObjectFriction) {
  ServerSettings s;
  load_server_config(write_temp("friction", R"(
    objects { model: "005_tomato_soup_can" x: 0.4 friction: 0.8 }
    objects { model: "006_mustard_bottle" x: 0.2 }
  )"),
                     s);
  ASSERT_EQ(s.objects.size(), 2u);
  EXPECT_EQ(s.objects[0].friction, 0.8);
  EXPECT_FALSE(s.objects[1].friction.has_value());
  const ServerSettings back = settings_from_proto(to_proto(s), "recording");
  EXPECT_EQ(back.objects[0].friction, 0.8);
  EXPECT_FALSE(back.objects[1].friction.has_value());
  const std::string negative = error_of("objects { model: \"005_tomato_soup_can\" friction: -0.1 }");
  EXPECT_NE(negative.find("friction"), std::string::npos);
  EXPECT_NE(negative.find("005_tomato_soup_can"), std::string::npos);
  EXPECT_NE(error_of("objects { model: \"005_tomato_soup_can\" friction: nan }").find("friction"), std::string::npos);
}

// A scene object may set its shape class (the grasp type's input); it stays unset (read from the
// mesh) otherwise, goes into the recorded configuration, and must be one of the five names.
TEST(ServerConfigTest, SceneObjectShape) {
  ServerSettings s;
  load_server_config(write_temp("shape", R"(
    objects { model: "011_banana" x: 0.4 shape: "cylinder" }
    objects { model: "006_mustard_bottle" x: 0.2 }
  )"),
                     s);
  ASSERT_EQ(s.objects.size(), 2u);
  EXPECT_EQ(s.objects[0].shape, sim::ShapeClass::kCylinder);
  EXPECT_FALSE(s.objects[1].shape.has_value());
  const ServerSettings back = settings_from_proto(to_proto(s), "recording");
  EXPECT_EQ(back.objects[0].shape, sim::ShapeClass::kCylinder);
  EXPECT_FALSE(back.objects[1].shape.has_value());
  const std::string wrong = error_of("objects { model: \"011_banana\" shape: \"banana\" }");
  EXPECT_NE(wrong.find("shape"), std::string::npos) << wrong;
  EXPECT_NE(wrong.find("011_banana"), std::string::npos) << wrong;
  EXPECT_NE(wrong.find("'banana'"), std::string::npos) << wrong;
}

// Relays: prefix and hand limit (64 when left out) survive the recorded configuration; an empty
// prefix, a limit out of range, or one prefix starting another is refused by name.
TEST(ServerConfigTest, Relays) {
  ServerSettings s;
  load_server_config(write_temp("relays", R"(
    relays { prefix: "xr-" max_hands: 32 }
    relays { prefix: "lab-" }
  )"),
                     s);
  ASSERT_EQ(s.relays.size(), 2u);
  EXPECT_EQ(s.relays[0].prefix, "xr-");
  EXPECT_EQ(s.relays[0].max_hands, 32);
  EXPECT_EQ(s.relays[1].max_hands, 64);
  const ServerSettings back = settings_from_proto(to_proto(s), "recording");
  ASSERT_EQ(back.relays.size(), 2u);
  EXPECT_EQ(back.relays[1].prefix, "lab-");
  EXPECT_EQ(back.relays[0].max_hands, 32);
  EXPECT_NE(error_of("relays { prefix: \"\" }").find("relays"), std::string::npos);
  EXPECT_NE(error_of("relays { prefix: \"xr-\" max_hands: 5000 }").find("max_hands"), std::string::npos);
  const std::string nested = error_of("relays { prefix: \"xr\" } relays { prefix: \"xr-a\" }");
  EXPECT_NE(nested.find("one prefix starts the other"), std::string::npos) << nested;
}

// The example shipped for deployments loads as it is.
TEST(ServerConfigTest, ShippedExampleLoads) {
  ServerSettings s;
  const char* source_dir = std::getenv("TELEGRASP_SOURCE_DIR");
  ASSERT_NE(source_dir, nullptr) << "TELEGRASP_SOURCE_DIR is not set (ctest sets it)";
  load_server_config(std::string(source_dir) + "/deploy/server.example.textproto", s);
  EXPECT_EQ(s.objects.size(), 3u);
  EXPECT_TRUE(s.late_latch);
}

}  // namespace
}  // namespace telegrasp::server
