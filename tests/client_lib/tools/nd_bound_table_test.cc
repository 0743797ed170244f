// Tests the run-beside-oracle table (telegrasp-eval run --bound): reading nd-bound's JSON, naming
// what is wrong in a bad file, and the pooled means over every object and over those the oracle
// takes to the paper's figure, against hand-computed values.
#include "nd_bound_table.h"

#include "commands.h"
#include "telegrasp/idl/cli.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <string>

namespace telegrasp::report {
namespace {

std::string write_file(const std::string& name, const std::string& text) {
  const std::filesystem::path p = std::filesystem::temp_directory_path() / name;
  std::ofstream(p) << text;
  return p.string();
}

// A grasped record whose grasp tick's capsules that hit read `nd_mm`, plus one that misses.
Record grasp(const std::string& object, std::vector<double> nd_mm) {
  Record r;
  r.object = object;
  r.grasped = true;
  for (double nd : nd_mm)
    r.grasp_tick_capsules.push_back({.phalanx = "index_dist", .hit = true, .nd_midlength_mm = nd});
  r.grasp_tick_capsules.push_back({.phalanx = "thumb_dist", .hit = false, .blocked = true});
  return r;
}

std::string message_of(const std::string& path) {
  try {
    read_nd_bounds(path);
  } catch (const std::runtime_error& e) {
    return e.what();
  }
  return "";
}

TEST(NdBoundTableTest, ReadsKeptGraspsAndObjectsWithoutOne) {
  const std::string path = write_file("telegrasp_nd_bound_ok.json", R"({"objects": [
      {"object": "box", "kept": {"nd_mean_mm": 0.25, "hand_error_mm": 1.0}},
      {"object": "fork", "kept": null}],
    "summary": {"rig": "human_right_opposable", "min_hits": 4}})");
  const NdBounds b = read_nd_bounds(path);
  EXPECT_EQ(b.rig, "human_right_opposable");
  ASSERT_EQ(b.nd_mean_mm.size(), 2u);
  EXPECT_DOUBLE_EQ(*b.nd_mean_mm.at("box"), 0.25);
  EXPECT_FALSE(b.nd_mean_mm.at("fork").has_value());
}

TEST(NdBoundTableTest, ABadFileIsNamedWithWhatIsWrong) {
  EXPECT_NE(message_of("/nonexistent/telegrasp.json").find("cannot open"), std::string::npos);
  EXPECT_NE(message_of(write_file("telegrasp_nd_bound_text.json", "no json")).find("not JSON"), std::string::npos);
  EXPECT_NE(message_of(write_file("telegrasp_nd_bound_grasps.json", R"({"grasps": []})")).find("\"objects\""),
            std::string::npos);
  const std::string no_kept =
      message_of(write_file("telegrasp_nd_bound_nokept.json", R"({"objects": [{"object": "a"}]})"));
  EXPECT_NE(no_kept.find("objects[0]"), std::string::npos) << no_kept;
  EXPECT_NE(no_kept.find("kept"), std::string::npos) << no_kept;
  const std::string bad_nd = message_of(
      write_file("telegrasp_nd_bound_badnd.json", R"({"objects": [{"object": "a", "kept": {"nd_mean_mm": "x"}}]})"));
  EXPECT_NE(bad_nd.find("nd_mean_mm"), std::string::npos) << bad_nd;
}

TEST(NdBoundTableTest, PoolsTheGraspTickOverTheObjectsTheOracleReaches) {
  // box: hits 1, 2 and 0.6 (mean 1.2); knife: 4 and 6 (the oracle's best 2.4 mm is above 1.12);
  // fork: 3 (no clean grasp for the oracle); cup: 0.5, not in the file; ball: grasped with no hit.
  const Record box1 = grasp("box", {1.0, 2.0}), box2 = grasp("box", {0.6}), knife = grasp("knife", {4.0, 6.0}),
               fork = grasp("fork", {3.0}), cup = grasp("cup", {0.5}), ball = grasp("ball", {});
  Record missed = grasp("box", {9.0});
  missed.grasped = false;  // a grasp that never happened counts nowhere
  const std::vector<ObjectRows> rows = {
      {"box", {&box1, &box2, &missed}}, {"knife", {&knife}}, {"fork", {&fork}}, {"cup", {&cup}}, {"ball", {&ball}}};
  NdBounds bounds;
  bounds.nd_mean_mm = {{"box", 0.3}, {"knife", 2.4}, {"fork", std::nullopt}, {"ball", 0.7}};
  const nlohmann::json j = print_nd_bound_table(rows, bounds);
  // Every hit: (1 + 2 + 0.6 + 4 + 6 + 3 + 0.5) / 7 = 17.1 / 7.
  EXPECT_NEAR(j["grasp_tick_nd_abs_mean_mm"].get<double>(), 17.1 / 7, 1e-12);
  // Reachable: box and ball (no hit), 3.6 / 3.
  EXPECT_NEAR(j["reachable"]["grasp_tick_nd_abs_mean_mm"].get<double>(), 1.2, 1e-12);
  EXPECT_EQ(j["reachable"]["capsules_hit"], 3);
  EXPECT_EQ(j["reachable"]["objects"], nlohmann::json({"box", "ball"}));
  EXPECT_EQ(j["beyond"], nlohmann::json({"knife", "fork"}));
  EXPECT_EQ(j["unknown"], nlohmann::json({"cup"}));
  EXPECT_DOUBLE_EQ(j["paper_nd_mm"].get<double>(), 1.12);
}

// telegrasp-eval run says which file is wrong and stops before any trial runs.
TEST(NdBoundTableTest, RunStopsOnABadBoundFileAndNamesIt) {
  const std::string path = write_file("telegrasp_nd_bound_run.json", R"({"objects": [{"object": 1, "kept": null}]})");
  std::string args[] = {"run", "--trials", "1", "--bound", path};
  char* argv[] = {args[0].data(), args[1].data(), args[2].data(), args[3].data(), args[4].data()};
  testing::internal::CaptureStderr();
  EXPECT_EQ(telegrasp::eval::run_in_process(5, argv), telegrasp::cli::kExitFailure);
  const std::string err = testing::internal::GetCapturedStderr();
  EXPECT_NE(err.find("--bound " + path + ": objects[0]: no \"object\" name"), std::string::npos) << err;
}

}  // namespace
}  // namespace telegrasp::report
