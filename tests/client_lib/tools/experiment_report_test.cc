// Tests experiment_report.h on a handmade protocol run with known means: the aggregates, the two
// CSV files, the HTML report's bars (one per object per group per mode per chart), its axis ticks,
// that a missing value reads "no data" and never 0, the precise-vs-discrete time comparison, the
// grasp pictures and which grasp they draw, that the page is self-contained and states the unit
// caveat, and loading the paper's per-object numbers.
#include "experiment_aggregate.h"
#include "experiment_report.h"

#include "test_meshes.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <regex>
#include <sstream>
#include <string>

#include <unistd.h>

namespace telegrasp::report {
namespace {

constexpr double kTol = 1e-9;

// A trial not grasped in 3 attempts.
Record miss(const std::string& mode, const std::string& group, int participant, const std::string& object, int trial) {
  Record r;
  r.mode = mode;
  r.group = group;
  r.participant = participant;
  r.object = object;
  r.trial = trial;
  r.attempts = 3;
  return r;
}

// A grasp record; `nd_hit` are the ND (mm, signed) of capsules that hit at the grasp tick, and a
// capsule that did not hit is added to check it is left out of every |ND| mean.
Record grasp(const std::string& mode, const std::string& group, int participant, const std::string& object, int trial,
             double time_s, double hand_error_mm, std::vector<double> nd_hit) {
  Record r = miss(mode, group, participant, object, trial);
  r.attempts = 1;
  r.grasped = r.held_after_lift = true;
  r.time_to_grasp_s = time_s;
  r.grasp_tick_hand_error_mm = hand_error_mm;
  r.hand_error_mm = 99;  // the settled hand: not what the experiment report uses
  // Blocked capsules: nd_contact = |ND| / 100 (mm). Trial 0 is in force closure, 1 is not; the palm
  // is time_s / 10 mm inside the object.
  for (double nd : nd_hit)
    r.grasp_tick_capsules.push_back({"index_dist", true, true, nd, nd - 0.01, true, std::abs(nd) / 100});
  r.grasp_tick_capsules.push_back({"pinky_dist", false, false, 0, 7});
  r.capsules = {{"index_dist", true, true, 50, 50}};  // settled: must not be used either
  r.grasp_tick_figures = {-time_s / 10, trial == 0 ? 0.125 : 0.0, 0.5, trial == 0};
  r.figures = r.grasp_tick_figures;
  r.contacts.resize(2);
  return r;
}

// Two modes, two groups; 004_sugar_box is in the protocol but has no records; 999_custom is not
// in the paper's table; nobody inexperienced grasped 999_custom.
ExperimentRun handmade_run() {
  ExperimentRun run;
  run.protocol = "paper";
  run.command_line = "telegrasp-eval protocol --mode both";
  run.seed = 7;
  run.wall_seconds = 12.5;
  run.created = "2024-05-01T10:00:00Z";
  run.modes = {"precise", "discrete"};
  run.objects = {"014_lemon", "003_cracker_box", "004_sugar_box", "999_custom"};
  run.standin_objects = {"999_custom"};
  run.participants = {{"experienced", 1}, {"inexperienced", 1}};
  auto& r = run.records;
  // precise, experienced, lemon: times 1 and 2 -> mean 1.5, sd sqrt(0.5);
  // per-grasp |ND| means (|1| + |-3|)/2 = 2 and 4 -> mean 3, sd sqrt(2); pooled (1+3+4)/3 = 8/3;
  // HandError 5 and 7 -> 6.
  r.push_back(grasp("precise", "experienced", 1, "014_lemon", 0, 1.0, 5.0, {1.0, -3.0}));
  r.push_back(grasp("precise", "experienced", 1, "014_lemon", 1, 2.0, 7.0, {4.0}));
  // precise, inexperienced, lemon: one grasp (3 s, |ND| 0.5) and one miss -> n 2, grasped 1.
  r.push_back(grasp("precise", "inexperienced", 2, "014_lemon", 0, 3.0, 2.0, {-0.5}));
  r.push_back(miss("precise", "inexperienced", 2, "014_lemon", 1));
  r.push_back(grasp("precise", "experienced", 1, "003_cracker_box", 0, 1.2, 3.0, {1.0}));
  r.push_back(grasp("precise", "inexperienced", 2, "003_cracker_box", 0, 1.4, 3.0, {2.0}));
  r.push_back(grasp("precise", "experienced", 1, "999_custom", 0, 0.8, 1.0, {0.2}));
  // discrete: the same objects, one trial each; inexperienced never grasps the cracker box.
  r.push_back(grasp("discrete", "experienced", 1, "014_lemon", 0, 1.1, 9.0, {3.0}));
  r.push_back(grasp("discrete", "inexperienced", 2, "014_lemon", 0, 1.3, 9.0, {5.0}));
  r.push_back(grasp("discrete", "experienced", 1, "003_cracker_box", 0, 1.5, 9.0, {2.0}));
  r.push_back(miss("discrete", "inexperienced", 2, "003_cracker_box", 0));
  r.push_back(grasp("discrete", "experienced", 1, "999_custom", 0, 0.9, 9.0, {1.0}));
  return run;
}

const nlohmann::json& find_row(const nlohmann::json& rows, const std::string& mode, const std::string& group,
                               const std::string& object = "") {
  for (const nlohmann::json& r : rows)
    if (r["mode"] == mode && r["group"] == group && (object.empty() || r["object"] == object)) return r;
  static const nlohmann::json none;
  ADD_FAILURE() << "no row " << mode << "/" << group << "/" << object;
  return none;
}

std::vector<PaperRow> paper() { return load_paper_results(default_paper_results_path()); }

// The attributes of every <rect class="bar" ...> in `html`.
std::vector<std::map<std::string, std::string>> bars(const std::string& html) {
  std::vector<std::map<std::string, std::string>> out;
  const std::regex rect(R"(<rect class="bar"([^>]*)>)"), attr(R"(([\w-]+)="([^"]*)\")");
  for (auto it = std::sregex_iterator(html.begin(), html.end(), rect); it != std::sregex_iterator(); ++it) {
    const std::string attrs = (*it)[1];
    std::map<std::string, std::string> m;
    for (auto a = std::sregex_iterator(attrs.begin(), attrs.end(), attr); a != std::sregex_iterator(); ++a)
      m[(*a)[1]] = (*a)[2];
    out.push_back(std::move(m));
  }
  return out;
}

int count_bars(const std::vector<std::map<std::string, std::string>>& all, const std::string& chart,
               const std::string& mode, const std::string& group, const std::string& object) {
  int n = 0;
  for (const auto& b : all)
    n += b.at("data-chart") == chart && b.at("data-mode") == mode && b.at("data-group") == group &&
         b.at("data-object") == object;
  return n;
}

int count_substr(const std::string& text, const std::string& what) {
  int n = 0;
  for (auto at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++n;
  return n;
}

std::vector<std::string> read_lines(const std::string& path) {
  std::ifstream in(path);
  std::vector<std::string> lines;
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  return lines;
}

TEST(ExperimentReportTest, AggregatesHaveTheHandComputedMeans) {
  const nlohmann::json j = aggregate_json(handmade_run());
  const auto& lemon = find_row(j["by_mode_group_object"], "precise", "experienced", "014_lemon");
  EXPECT_EQ(lemon["n"], 2);
  EXPECT_EQ(lemon["grasped"], 2);
  EXPECT_NEAR(lemon["time_to_grasp_mean_s"].get<double>(), 1.5, kTol);
  EXPECT_NEAR(lemon["time_to_grasp_sd_s"].get<double>(), std::sqrt(0.5), kTol);
  EXPECT_NEAR(lemon["nd_abs_mean_mm"].get<double>(), 3.0, kTol);
  EXPECT_NEAR(lemon["nd_abs_sd_mm"].get<double>(), std::sqrt(2.0), kTol);
  EXPECT_NEAR(lemon["nd_abs_pooled_mean_mm"].get<double>(), 8.0 / 3.0, kTol);
  EXPECT_EQ(lemon["capsules_hit"], 3);
  EXPECT_NEAR(lemon["hand_error_mean_mm"].get<double>(), 6.0, kTol);

  // The miss counts as a trial but adds no time; one grasp has no sd.
  const auto& lemon_inexp = find_row(j["by_mode_group_object"], "precise", "inexperienced", "014_lemon");
  EXPECT_EQ(lemon_inexp["n"], 2);
  EXPECT_EQ(lemon_inexp["grasped"], 1);
  EXPECT_EQ(lemon_inexp["held_after_lift"], 1);
  EXPECT_NEAR(lemon_inexp["time_to_grasp_mean_s"].get<double>(), 3.0, kTol);
  EXPECT_TRUE(lemon_inexp["time_to_grasp_sd_s"].is_null());
  EXPECT_NEAR(lemon_inexp["nd_abs_mean_mm"].get<double>(), 0.5, kTol);

  // No grasp at all: the means are null, not zero.
  const auto& cracker_miss = find_row(j["by_mode_group_object"], "discrete", "inexperienced", "003_cracker_box");
  EXPECT_EQ(cracker_miss["grasped"], 0);
  EXPECT_TRUE(cracker_miss["time_to_grasp_mean_s"].is_null());
  EXPECT_TRUE(cracker_miss["nd_abs_mean_mm"].is_null());

  // Per object, both groups: lemon precise times 1, 2, 3 -> 2; per-grasp |ND| 2, 4, 0.5 -> 6.5/3.
  const auto& lemon_all = find_row(j["by_mode_object"], "precise", "all", "014_lemon");
  EXPECT_EQ(lemon_all["n"], 4);
  EXPECT_NEAR(lemon_all["time_to_grasp_mean_s"].get<double>(), 2.0, kTol);
  EXPECT_NEAR(lemon_all["nd_abs_mean_mm"].get<double>(), 6.5 / 3.0, kTol);

  // Per mode and group over every object: precise experienced times 1, 2, 1.2, 0.8 -> 1.25.
  const auto& exp_precise = find_row(j["by_mode_group"], "precise", "experienced");
  EXPECT_EQ(exp_precise["n"], 4);
  EXPECT_NEAR(exp_precise["time_to_grasp_mean_s"].get<double>(), 1.25, kTol);

  // The sugar box has no records, so no rows; worst objects by time (precise): lemon 2.0 first.
  for (const auto& r : j["by_mode_group_object"]) EXPECT_NE(r["object"], "004_sugar_box");
  ASSERT_EQ(j["worst_objects"].size(), 2u);
  EXPECT_EQ(j["worst_objects"][0]["mode"], "precise");
  EXPECT_EQ(j["worst_objects"][0]["by_time"][0]["object"], "014_lemon");
  EXPECT_EQ(j["worst_objects"][0]["by_nd"][0]["object"], "014_lemon");
  EXPECT_EQ(j["run"]["seed"], 7);
}

// Precise, experienced, lemon: nd_contact 0.01, 0.03 (trial 0) and 0.04 (trial 1): median 0.03,
// p95 at rank 0.95 x 2 = 1.9: 0.03 + 0.9 x 0.01 = 0.039; palms -0.1 and -0.2 mm (one below
// -0.1); one of the two held grasps in force closure.
TEST(ExperimentReportTest, AggregatesHaveTheFidelityAndForceClosureFigures) {
  const ExperimentRun run = handmade_run();
  const nlohmann::json j = aggregate_json(run);
  const nlohmann::json& lemon = find_row(j["by_mode_group_object"], "precise", "experienced", "014_lemon");
  EXPECT_NEAR(lemon["nd_contact_abs_median_mm"].get<double>(), 0.03, 1e-12);
  EXPECT_NEAR(lemon["nd_contact_abs_p95_mm"].get<double>(), 0.039, 1e-12);
  EXPECT_EQ(lemon["blocked_capsules"], 3);
  EXPECT_EQ(lemon["blocked_without_nd_contact"], 0);
  EXPECT_NEAR(lemon["palm_signed_distance_min_mm"].get<double>(), -0.2, 1e-12);
  EXPECT_EQ(lemon["palm_below_minus_0_1mm"], 1);
  EXPECT_EQ(lemon["held_force_closure"], 1);
  EXPECT_NEAR(lemon["held_force_closure_share"].get<double>(), 0.5, 1e-12);
  const std::string html = html_report(run, {}, nullptr, nullptr);
  EXPECT_NE(html.find("Held grasps in force closure"), std::string::npos);
  EXPECT_NE(html.find("<td>1/2 (50 %)</td>"), std::string::npos);
  EXPECT_NE(html.find("Fidelity: ND at the contact"), std::string::npos);
  EXPECT_NE(html.find("mid-length (nd_midlength"), std::string::npos);
}

// A run whose rig has grasp types gets a table per type (grasps, held, force closure, median
// opposition, mean |ND|) and each picture's caption names the type; a run of "other" only has none.
TEST(ExperimentReportTest, GraspTypesGetTheirOwnTable) {
  ExperimentRun run = handmade_run();
  EXPECT_EQ(html_report(run, {}, nullptr, nullptr).find("id=\"grasp-types\""), std::string::npos);
  int n = 0;
  for (Record& r : run.records) {
    r.grasp_type = n++ % 2 ? "power_sphere" : "other";
    r.opposition_deg = r.grasp_type == "other" ? 100.0 : 150.0;
  }
  const std::string html = html_report(run, {}, nullptr, nullptr);
  ASSERT_NE(html.find("id=\"grasp-types\""), std::string::npos);
  const std::string table = html.substr(html.find("id=\"grasp-types\""));
  EXPECT_NE(table.find("<td>power_sphere</td>"), std::string::npos);
  EXPECT_NE(table.find("<td>150</td>"), std::string::npos) << "the power sphere grasps' median opposition";
  for (Record& r : run.records) r.grasp_type = "other";
  EXPECT_EQ(html_report(run, {}, nullptr, nullptr).find("id=\"grasp-types\""), std::string::npos);
}

TEST(ExperimentReportTest, CsvHasOneRowPerGraspAndPerModeGroupObject) {
  const ExperimentRun run = handmade_run();
  const auto dir = std::filesystem::temp_directory_path() / ("telegrasp_report_test_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const std::string path = (dir / "grasps.csv").string();
  const std::string second = write_csv(run, path);
  EXPECT_EQ(second, (dir / "grasps_by_object.csv").string());

  const auto grasps = read_lines(path);
  ASSERT_EQ(grasps.size(), 1 + run.records.size());
  EXPECT_EQ(grasps[0],
            "mode,group,participant,object,trial,grasped,held_after_lift,attempts,time_to_grasp_s,hand_error_mm,"
            "nd_abs_mean_mm,capsules_hit,min_signed_distance_mm,contacts,nd_contact_abs_max_mm,"
            "blocked_without_nd_contact,palm_signed_distance_mm,epsilon,volume,force_closure");
  // The first lemon grasp: |ND| (1 + 3)/2 = 2 over 2 hit capsules, smallest signed distance -3.01;
  // |nd_contact| at most 0.03, the palm 0.1 mm in, in force closure.
  EXPECT_EQ(grasps[1],
            "precise,experienced,1,014_lemon,0,1,1,1,1.0000,5.0000,2.0000,2,-3.0100,2,0.0300,0,-0.1000,0.125000,"
            "0.500000,1");
  // A miss has empty metrics, not zeros.
  EXPECT_EQ(grasps[4], "precise,inexperienced,2,014_lemon,1,0,0,3,,,,0,,0,,,,,,");

  // 2 modes x (2 groups + "all") x objects with records: precise 3 + 2 (no inexperienced custom)
  // + 3 all; discrete the same: 16 rows.
  const auto by_object = read_lines(second);
  ASSERT_EQ(by_object.size(), 1u + 16u);
  EXPECT_EQ(by_object[0].rfind("mode,group,object,n,grasped,held_after_lift,time_to_grasp_mean_s,", 0), 0u);
  EXPECT_EQ(by_object[1].rfind("precise,experienced,014_lemon,2,2,2,1.5000,0.7071,3.0000,", 0), 0u) << by_object[1];
  std::filesystem::remove_all(dir);
}

TEST(ExperimentReportTest, HtmlHasOneBarPerObjectPerGroupPerModePerChart) {
  const ExperimentRun run = handmade_run();
  const std::string html = html_report(run, paper(), nullptr);
  const auto all = bars(html);
  ASSERT_FALSE(all.empty());

  const std::vector<std::string> recorded = {"014_lemon", "003_cracker_box", "999_custom"};
  for (const std::string mode : {"precise", "discrete"}) {
    for (const std::string kind : {"time_by_group", "nd_by_group"}) {
      const std::string chart = kind + "." + mode;
      for (const std::string& object : recorded) {
        EXPECT_EQ(count_bars(all, chart, mode, "experienced", object), 1) << chart << " " << object;
        // Nobody inexperienced tried the custom object: no bar, not a zero bar (a hatched slot).
        EXPECT_EQ(count_bars(all, chart, mode, "inexperienced", object), object == "999_custom" ? 0 : 1)
            << chart << " " << object;
      }
      // Objects absent from the run get no bar.
      EXPECT_EQ(count_bars(all, chart, mode, "experienced", "004_sugar_box"), 0);
    }
    for (const std::string kind : {"time_overall", "nd_overall"})
      for (const std::string& object : recorded)
        EXPECT_EQ(count_bars(all, kind + "." + mode, mode, "all", object), 1) << kind << " " << object;
  }
  // Paper vs ours: per group a paper bar for the paper's objects only, and a bar per mode.
  for (const std::string group : {"experienced", "inexperienced"})
    for (const std::string kind : {"paper_time.", "paper_error."}) {
      const std::string chart = kind + group;
      EXPECT_EQ(count_bars(all, chart, "paper", group, "014_lemon"), 1) << chart;
      EXPECT_EQ(count_bars(all, chart, "paper", group, "003_cracker_box"), 1) << chart;
      EXPECT_EQ(count_bars(all, chart, "paper", group, "999_custom"), 0) << chart;
      EXPECT_EQ(count_bars(all, chart, "paper", group, "004_sugar_box"), 0) << chart;
      EXPECT_EQ(count_bars(all, chart, "precise", group, "014_lemon"), 1) << chart;
      EXPECT_EQ(count_bars(all, chart, "discrete", group, "014_lemon"), 1) << chart;
    }

  // Total: per mode 5 + 5 group bars, 3 + 3 overall; paper charts 4 x (2 paper + 2 modes x 2 or 3).
  //   modes: 2 x 16 = 32; paper_*.experienced: 2 x (2 + 3 + 3) = 16; inexperienced: 2 x (2 + 2 + 2) = 12.
  EXPECT_EQ(all.size(), 32u + 16u + 12u);

  // Values: the bar is the mean the aggregates computed; an undefined value is a hatched slot of
  // the plot's full height (200 px) saying "no data", not a bar of height 0.
  for (const auto& b : all) {
    if (b.at("data-chart") == "time_by_group.precise" && b.at("data-group") == "experienced" &&
        b.at("data-object") == "014_lemon") {
      EXPECT_NEAR(std::stod(b.at("data-value")), 1.5, 1e-4);
    }
    if (b.at("data-chart") == "nd_by_group.precise" && b.at("data-group") == "experienced" &&
        b.at("data-object") == "014_lemon") {
      EXPECT_NEAR(std::stod(b.at("data-value")), 3.0, 1e-4);
    }
    if (b.at("data-chart") == "paper_time.experienced" && b.at("data-mode") == "paper" &&
        b.at("data-object") == "014_lemon") {
      EXPECT_NEAR(std::stod(b.at("data-value")), 1.344, 1e-4);
    }
    if (b.at("data-chart") == "time_by_group.discrete" && b.at("data-group") == "inexperienced" &&
        b.at("data-object") == "003_cracker_box") {
      EXPECT_EQ(b.at("data-value"), "");
      EXPECT_EQ(b.at("height"), "200.00");
      EXPECT_EQ(b.at("fill").rfind("url(#nd-", 0), 0u) << b.at("fill");
    }
  }
  const std::string time_chart = html.substr(html.find("data-chart=\"time_by_group.discrete\""));
  EXPECT_NE(time_chart.find("003_cracker_box, inexperienced: no data</title>"), std::string::npos);
  // The inexperienced never tried 999_custom: a hatched slot (class "nodata"), titled why.
  EXPECT_NE(html.find("999_custom, inexperienced: no data (no trials)</title>"), std::string::npos);
  // The x axis names the objects (rotated), not the paper's letters.
  for (const std::string object : {"014_lemon", "003_cracker_box", "999_custom"})
    EXPECT_NE(html.find("rotate(-60)\" text-anchor=\"end\">" + object + "</text>"), std::string::npos) << object;
  EXPECT_EQ(html.find(">a</text>"), std::string::npos);
  EXPECT_EQ(html.find(">#3</text>"), std::string::npos);
}

// Nice steps of 1, 2 or 5 x 10^k, at least a fifth of the largest value, worked by hand.
TEST(AxisTicksTest, NiceStepsAndExactLabels) {
  auto labels = [](double largest) {
    std::string out;
    for (const std::string& l : axis_ticks(largest).labels) out += (out.empty() ? "" : " ") + l;
    return out;
  };
  // 12.3 / 5 = 2.46: 1 and 2 are too small, 5 is the step; the top is 3 x 5 = 15.
  EXPECT_EQ(labels(12.3), "0 5 10 15");
  EXPECT_DOUBLE_EQ(axis_ticks(12.3).top, 15);
  EXPECT_DOUBLE_EQ(axis_ticks(12.3).step, 5);
  // The report's old axis: 12 would have had ticks every 2.5 labelled 0 2 5 8 10 12.
  EXPECT_EQ(labels(12), "0 5 10 15");
  // 10 / 5 = 2: the step is 2, and 10 is a tick.
  EXPECT_EQ(labels(10), "0 2 4 6 8 10");
  // 4.16 / 5 = 0.832: 0.1, 0.2 and 0.5 are too small, so 1.
  EXPECT_EQ(labels(4.16), "0 1 2 3 4 5");
  // 0.87 / 5 = 0.174: the step is 0.2 and every label has one decimal.
  EXPECT_EQ(labels(0.87), "0.0 0.2 0.4 0.6 0.8 1.0");
  // 0.046 / 5 = 0.0092: the step is 0.01, two decimals, top 0.05.
  EXPECT_EQ(labels(0.046), "0.00 0.01 0.02 0.03 0.04 0.05");
  // 250 / 5 = 50: a step of 50 exactly.
  EXPECT_EQ(labels(250), "0 50 100 150 200 250");
  // Nothing to plot: 0 to 1 in steps of 0.2.
  EXPECT_EQ(labels(0), "0.0 0.2 0.4 0.6 0.8 1.0");
  EXPECT_EQ(labels(NAN), "0.0 0.2 0.4 0.6 0.8 1.0");
}

// A grasp whose capsules all missed has no |ND| and no HandError (the server sends 0): the
// aggregates say null, the CSV leaves the cell empty, the page says "no data" and never 0.00.
TEST(ExperimentReportTest, NoCapsuleHitIsNoDataNotZero) {
  ExperimentRun run = handmade_run();
  run.objects.push_back("032_knife");
  for (const std::string mode : {"precise", "discrete"}) {
    Record knife = grasp(mode, "experienced", 1, "032_knife", 3, 1.25, 0.0, {});
    run.records.push_back(knife);
  }
  const nlohmann::json j = aggregate_json(run);
  const auto& row = find_row(j["by_mode_group_object"], "precise", "experienced", "032_knife");
  EXPECT_EQ(row["grasped"], 1);
  EXPECT_NEAR(row["time_to_grasp_mean_s"].get<double>(), 1.25, kTol);
  EXPECT_TRUE(row["hand_error_mean_mm"].is_null());
  EXPECT_TRUE(row["nd_abs_mean_mm"].is_null());

  const std::string html = html_report(run, paper(), nullptr);
  // The paper's error table row for the knife: paper, ours per mode, our HandError per mode.
  const auto paper_table = html.find("data-chart=\"paper_error.experienced\"");
  ASSERT_NE(paper_table, std::string::npos);
  const auto knife_row = html.find("<td>032_knife</td>", paper_table);
  ASSERT_NE(knife_row, std::string::npos);
  const std::string row_html = html.substr(knife_row, html.find("</tr>", knife_row) - knife_row);
  EXPECT_EQ(row_html.find("0.00"), std::string::npos) << row_html;
  EXPECT_EQ(count_substr(row_html, "no data"), 4) << row_html;  // |ND| and HandError, both modes
  // The |ND| bar of the knife is a "no data" slot.
  for (const auto& b : bars(html)) {
    if (b.at("data-object") == "032_knife" && b.at("data-chart").rfind("nd_", 0) == 0) {
      EXPECT_EQ(b.at("data-value"), "") << b.at("data-chart");
    }
  }
}

// Precise against discrete, grasp by grasp: four grasps succeeded in both modes in the handmade
// run, all at different times (lemon 1.0 / 1.1 and 3.0 / 1.3, cracker box 1.2 / 1.5, custom
// 0.8 / 0.9): the largest difference is 1.3 - 3.0 = -1.7 s.
TEST(ExperimentReportTest, PreciseAndDiscreteTimesAreComparedGraspByGrasp) {
  const std::string html = html_report(handmade_run(), paper(), nullptr);
  EXPECT_NE(html.find("id=\"mode-times\""), std::string::npos);
  EXPECT_NE(html.find("same simulated person in both modes"), std::string::npos);
  EXPECT_NE(html.find("Of the 4 grasps made in both modes (same group, participant, object and trial), 0 have the same "
                      "time to grasp and 4 differ, by at most 1.700 s"),
            std::string::npos);
  EXPECT_NE(html.find("<td>3.000</td><td>1.300</td><td>-1.700</td>"), std::string::npos);
}

// The hand of a grasp as a participant records it: the palm 5 cm above the object's origin and
// each phalanx 1 cm further along x than the one before (a picture needs poses, not a real hand).
void give_hand(Record& r, const sim::HandRig& rig) {
  r.grasp_tick_X_WorldObject = Eigen::Isometry3d(Eigen::Translation3d(0.45, 0, 0.03));
  r.grasp_tick_hand.push_back({"palm", Eigen::Isometry3d(Eigen::Translation3d(0, 0, 0.05))});
  for (std::size_t i = 0; i < rig.phalanges().size(); ++i)
    r.grasp_tick_hand.push_back(
        {rig.phalanges()[i].name, Eigen::Isometry3d(Eigen::Translation3d(0.01 * static_cast<double>(i), 0.02, 0.03))});
}

// The drawn grasp: held before merely grasped, precise before discrete, experienced before
// inexperienced, then the lowest participant; records without the hand never.
TEST(ExperimentReportTest, RepresentativeGraspFollowsTheStatedOrder) {
  const sim::HandRig rig = sim::HandRig::load(sim::HandRig::builtin_path("human_right"));
  ExperimentRun run;
  run.objects = {"014_lemon"};
  auto add = [&](const std::string& mode, const std::string& group, int participant, bool held, bool hand) {
    Record r = grasp(mode, group, participant, "014_lemon", 0, 1.0, 1.0, {1.0});
    r.held_after_lift = held;
    if (hand) give_hand(r, rig);
    run.records.push_back(r);
  };
  add("precise", "experienced", 1, true, false);  // no hand: never drawn
  add("precise", "experienced", 1, false, true);  // not held
  add("discrete", "experienced", 2, true, true);  // not precise
  add("precise", "inexperienced", 5, true, true);  // not experienced
  add("precise", "experienced", 3, true, true);  // the one
  add("precise", "experienced", 4, true, true);  // a later participant
  const Record* r = representative_grasp(run, "014_lemon");
  ASSERT_NE(r, nullptr);
  EXPECT_EQ(r, &run.records[4]);
  EXPECT_EQ(representative_grasp(run, "003_cracker_box"), nullptr);
}

// With the models and the rig, the page has one picture per object that has a record with the
// hand, an explanation for the others, and still nothing to fetch.
TEST(ExperimentReportTest, HtmlDrawsOneGraspPerObjectWithoutUrls) {
  ExperimentRun run = handmade_run();
  GraspPictureInputs pictures;
  pictures.rig = std::make_shared<const sim::HandRig>(sim::HandRig::load(sim::HandRig::builtin_path("human_right")));
  pictures.models["014_lemon"] =
      sim::make_object_model("014_lemon", sim::testing::uv_sphere_mesh(0.027, 24, 24), 0.05, "test");
  pictures.models["003_cracker_box"] = sim::make_object_model(
      "003_cracker_box", sim::testing::box_mesh(Eigen::Vector3d(0.08, 0.03, 0.105)), 0.4, "test");
  for (Record& r : run.records)
    if (r.object != "999_custom" && r.grasped) give_hand(r, *pictures.rig);
  const std::string html = html_report(run, paper(), nullptr, &pictures);

  EXPECT_NE(html.find("id=\"pictures\""), std::string::npos);
  EXPECT_EQ(count_substr(html, "<figure data-object="), 3);
  EXPECT_EQ(count_substr(html, "<svg class=\"grasp\""), 2);
  // The lemon's drawn grasp is the first experienced participant's, precise, held (trial 0).
  const auto lemon = html.find("<figure data-object=\"014_lemon\">");
  ASSERT_NE(lemon, std::string::npos);
  const std::string lemon_figure = html.substr(lemon, html.find("</figure>", lemon) - lemon);
  EXPECT_NE(lemon_figure.find("precise, experienced participant 1, held; 1.00 s"), std::string::npos) << lemon_figure;
  // Capsules of the rig: ten, every one drawn (in front of or behind the object).
  EXPECT_EQ(count_substr(lemon_figure, "<path class=\"capsule"), 10);
  // The custom object has no hand recorded: said, not drawn.
  EXPECT_NE(html.find("no picture: no record has the hand at the grasp tick"), std::string::npos);
  EXPECT_EQ(html.find("http"), std::string::npos);
  EXPECT_EQ(html.find("xmlns"), std::string::npos);
  EXPECT_EQ(html.find("<img"), std::string::npos);
}

TEST(ExperimentReportTest, HtmlIsSelfContainedAndStatesTheCaveat) {
  std::istringstream answers(
      "id,group,Q1,Q2,Q3,Q4,Q5,Q6,Q7,Q8,Q9,Q10,Q11,Q12,Q13,Q14\n"
      "p1,experienced,3,3,3,3,3,3,3,3,3,3,3,3,3,3\n"
      "p2,experienced,3,3,3,9,3,3,3,3,3,3,3,3,3,3\n");
  const QuestionnaireSummary q = score_questionnaire(answers, "answers.csv");
  const std::string html = html_report(handmade_run(), paper(), &q);

  EXPECT_EQ(html.rfind("<!DOCTYPE html>", 0), 0u);
  EXPECT_NE(html.find("</html>"), std::string::npos);
  // Nothing to fetch: no URL, script, external stylesheet or image.
  EXPECT_EQ(html.find("http://"), std::string::npos);
  EXPECT_EQ(html.find("https://"), std::string::npos);
  EXPECT_EQ(html.find("<script"), std::string::npos);
  EXPECT_EQ(html.find("<link"), std::string::npos);
  EXPECT_EQ(html.find("<img"), std::string::npos);
  EXPECT_NE(html.find("<style>"), std::string::npos);
  // The unit caveat: what the paper's error is, what ours is, and that ours is a bot.
  EXPECT_NE(html.find("id=\"unit-caveat\""), std::string::npos);
  EXPECT_NE(html.find("HandError"), std::string::npos);
  EXPECT_NE(html.find("summed over the five fingers"), std::string::npos);
  EXPECT_NE(html.find("mean |ND| over the capsules that hit"), std::string::npos);
  EXPECT_NE(html.find("scripted bot"), std::string::npos);
  EXPECT_NE(html.find("procedural stand-ins"), std::string::npos);
  // Run summary and questionnaire section, the rejected row named.
  EXPECT_NE(html.find("seed</th><td>7<"), std::string::npos);
  EXPECT_NE(html.find("999_custom"), std::string::npos);
  EXPECT_NE(html.find("id=\"questionnaire\""), std::string::npos);
  EXPECT_NE(html.find("[1.97]"), std::string::npos);
  EXPECT_NE(html.find("answers.csv line 3 (participant p2): Q4 = 9 is outside -3..3"), std::string::npos);

  // The questionnaire-only page has the section and no bars.
  const std::string qpage = questionnaire_html_report(q);
  EXPECT_NE(qpage.find("id=\"questionnaire\""), std::string::npos);
  EXPECT_TRUE(bars(qpage).empty());
  EXPECT_EQ(qpage.find("http"), std::string::npos);
}

TEST(PaperResultsTest, ShippedFileHasThirtyObjectsInThePapersOrder) {
  const std::vector<PaperRow> rows = paper();
  ASSERT_EQ(rows.size(), 30u);
  EXPECT_EQ(rows[0].label, "a");
  EXPECT_EQ(rows[0].object, "014_lemon");
  EXPECT_DOUBLE_EQ(rows[0].time_experienced, 1.344);
  EXPECT_DOUBLE_EQ(rows[0].err_inexperienced, 0.708);
  EXPECT_EQ(rows[29].label, "ad");
  EXPECT_EQ(rows[29].object, "072_a_toy_airplane");
  EXPECT_DOUBLE_EQ(rows[29].err_experienced, 2.537);
}

TEST(PaperResultsTest, BadNumberNamesFileLineAndColumn) {
  const auto path =
      std::filesystem::temp_directory_path() / ("telegrasp_paper_bad_" + std::to_string(::getpid()) + ".csv");
  {
    std::ofstream out(path);
    out << "label,object,time_s_experienced,time_s_inexperienced,err_experienced,err_inexperienced\n"
        << "a,014_lemon,1.344,1.830,0.654,0.708\n"
        << "b,003_cracker_box,1.220,1.8x3,1.207,1.453\n";
  }
  try {
    load_paper_results(path.string());
    FAIL() << "expected an error for 1.8x3";
  } catch (const std::runtime_error& e) {
    EXPECT_EQ(std::string(e.what()), path.string() +
                                         " line 3 column 4 (time_s_inexperienced): '1.8x3' is not a "
                                         "non-negative number");
  }
  {
    std::ofstream out(path);
    out << "label,object,time_s_experienced,err_experienced,err_inexperienced\n";
  }
  try {
    load_paper_results(path.string());
    FAIL() << "expected an error for the missing column";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("line 1: header has no column 'time_s_inexperienced'"), std::string::npos)
        << e.what();
  }
  std::filesystem::remove(path);
  EXPECT_THROW(load_paper_results("/nonexistent/paper.csv"), std::runtime_error);
}

// record_from_json reads back exactly what record_json wrote, protocol fields included.
TEST(GraspRecordJsonTest, RoundTrips) {
  Record r;
  r.object = "014_lemon";
  r.mode = "precise";
  r.speed_scale = 2;
  r.trial = 3;
  r.attempts = 2;
  r.grasped = r.held_after_lift = true;
  r.time_to_grasp_s = 1.25;
  r.hand_error_mm = r.grasp_tick_hand_error_mm = 7.5;
  r.capsules = r.grasp_tick_capsules = {{"index_dist", true, true, -0.25, 0.01, true, 0.02},
                                        {"thumb_mid", false, false, 0, 3.5}};
  r.figures = {-0.05, 0.125, 0.25, true};
  r.grasp_tick_figures = {0.5, 0.0, 0.0, false};
  r.group = "experienced";
  r.participant = 4;
  r.contacts = {{"palm", {0.1, 0.2, 0.3}, {0, 0, 1}, {-0.01, 0.02, 0.03}, {1, 0, 0}}};
  // The hand at the grasp tick, in the object's frame (written rounded to 1e-6).
  r.grasp_tick_X_WorldObject =
      Eigen::Translation3d(0.45, -0.05, 0.027) * Eigen::AngleAxisd(0.5, Eigen::Vector3d::UnitZ());
  r.grasp_tick_hand = {
      {"palm", Eigen::Translation3d(0.01, 0.02, 0.06) * Eigen::AngleAxisd(-2.0, Eigen::Vector3d(1, 1, 0).normalized())},
      {"index_dist", Eigen::Isometry3d(Eigen::Translation3d(0.03, 0.0, 0.01))}};
  r.grasp_type = "tripod";
  r.opposition_deg = 152.5;
  r.across_smallest = true;
  r.across_smallest_ignoring_table = false;
  const Record back = record_from_json(record_json(r));
  EXPECT_EQ(record_json(back), record_json(r));
  EXPECT_EQ(back.grasp_type, "tripod");
  EXPECT_EQ(back.opposition_deg, 152.5);
  EXPECT_EQ(back.across_smallest, true);
  EXPECT_EQ(back.across_smallest_ignoring_table, false);
  EXPECT_EQ(back.capsules.at(0).nd_contact_mm, 0.02);
  EXPECT_EQ(back.figures.epsilon, 0.125);
  EXPECT_EQ(back.grasp_tick_figures.palm_signed_distance_mm, 0.5);
  EXPECT_EQ(back.participant, 4);
  EXPECT_EQ(back.contacts.at(0).p_ObjectContact, Eigen::Vector3d(-0.01, 0.02, 0.03));
  ASSERT_EQ(back.grasp_tick_hand.size(), 2u);
  EXPECT_EQ(back.grasp_tick_hand[0].frame, "palm");
  constexpr double kRounding = 2e-6;  // 1e-6 per written number
  EXPECT_TRUE(back.grasp_tick_hand[0].X_ObjectFrame.isApprox(r.grasp_tick_hand[0].X_ObjectFrame, kRounding));
  EXPECT_TRUE(back.grasp_tick_X_WorldObject.isApprox(r.grasp_tick_X_WorldObject, kRounding));

  // A record without the hand writes no "grasp_tick_hand", and an in-process record (no group)
  // never does.
  r.grasp_tick_hand.clear();
  EXPECT_FALSE(record_json(r).contains("grasp_tick_hand"));
  Record in_process = back;
  in_process.group.clear();
  EXPECT_FALSE(record_json(in_process).contains("grasp_tick_hand"));
}

// The names a record's capsules and grasp carry: nd_midlength_mm with nd_mm as its alias (null
// without a hit), nd_contact_mm (null without contact_hit), and the grasp's figures at the top
// level and in grasp_tick; a record written before them (nd_mm only) still reads.
TEST(GraspRecordJsonTest, NamesTheTwoNdsAndTheGraspFigures) {
  Record r;
  r.object = "014_lemon";
  r.grasped = true;
  r.capsules = r.grasp_tick_capsules = {{"index_dist", true, true, -0.25, 0.01, true, 0.02},
                                        {"thumb_mid", false, false, 0, 3.5}};
  r.figures = {-0.05, 0.125, 0.25, true};
  const nlohmann::json j = record_json(r);
  const nlohmann::json& c = j["capsules"];
  EXPECT_EQ(c[0]["nd_midlength_mm"], -0.25);
  EXPECT_EQ(c[0]["nd_mm"], -0.25);
  EXPECT_EQ(c[0]["contact_hit"], true);
  EXPECT_EQ(c[0]["nd_contact_mm"], 0.02);
  EXPECT_TRUE(c[1]["nd_midlength_mm"].is_null());
  EXPECT_TRUE(c[1]["nd_mm"].is_null());
  EXPECT_TRUE(c[1]["nd_contact_mm"].is_null());
  EXPECT_EQ(j["palm_signed_distance_mm"], -0.05);
  EXPECT_EQ(j["epsilon"], 0.125);
  EXPECT_EQ(j["volume"], 0.25);
  EXPECT_EQ(j["force_closure"], true);
  EXPECT_EQ(j["grasp_tick"]["force_closure"], false);
  r.grasped = false;
  EXPECT_TRUE(record_json(r)["palm_signed_distance_mm"].is_null());

  nlohmann::json old = j;
  for (nlohmann::json& cap : old["capsules"]) {
    cap.erase("nd_midlength_mm");
    cap.erase("contact_hit");
    cap.erase("nd_contact_mm");
  }
  const Record back = record_from_json(old);
  EXPECT_EQ(back.capsules.at(0).nd_midlength_mm, -0.25);
  EXPECT_FALSE(back.capsules.at(0).contact_hit);
}

// The summary's across shares count the grasps that know them: with the table (3 of 4 here)
// and ignoring it (1 of 3: one record predates the field); an ungrasped record counts in neither.
TEST(GraspRecordJsonTest, SummaryCountsClosingAcrossWithAndWithoutTheTable) {
  std::vector<Record> recs(5);
  const bool with_table[] = {true, true, true, false};
  const std::optional<bool> ignoring[] = {true, false, std::nullopt, false};
  for (int i = 0; i < 4; ++i) {
    recs[i].object = "032_knife";
    recs[i].grasped = true;
    recs[i].across_smallest = with_table[i];
    recs[i].across_smallest_ignoring_table = ignoring[i];
  }
  recs[4].across_smallest = true;  // not grasped
  recs[4].across_smallest_ignoring_table = true;
  std::vector<const Record*> ptrs;
  for (const Record& r : recs) ptrs.push_back(&r);
  const nlohmann::json s = summarize(ptrs);
  EXPECT_DOUBLE_EQ(s.at("across_smallest_share").get<double>(), 0.75);
  EXPECT_DOUBLE_EQ(s.at("across_smallest_share_ignoring_table").get<double>(), 1.0 / 3);
}

// A record's force closure is the settled hold's once set_hold_quality gives it one; the grasp
// tick's stays, and the summary counts both: 2 of 3 grasps in closure while held, 1 at the grasp
// tick. A hold with no quality, or a record not grasped, keeps what it had.
TEST(GraspRecordJsonTest, TheHoldsQualityReplacesTheGraspTicksAndTheSummaryGivesBoth) {
  std::vector<Record> recs(4);
  for (Record& r : recs) {
    r.object = "003_cracker_box";
    r.grasped = true;
    r.figures = r.grasp_tick_figures = {12.0, 0.0, 0.5, false};
  }
  recs[0].figures = recs[0].grasp_tick_figures = {12.0, 0.02, 0.5, true};
  set_hold_quality(recs[0], sim::GraspQuality{0.03, 0.7, true});
  set_hold_quality(recs[1], sim::GraspQuality{0.01, 0.6, true});
  set_hold_quality(recs[2], std::nullopt);
  recs[3].grasped = false;
  set_hold_quality(recs[3], sim::GraspQuality{0.05, 0.9, true});
  EXPECT_EQ(recs[0].figures.epsilon, 0.03);
  EXPECT_EQ(recs[0].figures.volume, 0.7);
  EXPECT_EQ(recs[0].figures.palm_signed_distance_mm, 12.0) << "the palm's distance stays the grasp tick's";
  EXPECT_EQ(recs[0].grasp_tick_figures.epsilon, 0.02);
  EXPECT_TRUE(recs[1].figures.force_closure);
  EXPECT_FALSE(recs[1].grasp_tick_figures.force_closure);
  EXPECT_FALSE(recs[2].figures.force_closure);
  EXPECT_FALSE(recs[3].figures.force_closure);
  std::vector<const Record*> ptrs;
  for (const Record& r : recs) ptrs.push_back(&r);
  const nlohmann::json s = summarize(ptrs);
  EXPECT_DOUBLE_EQ(s.at("force_closure_share").get<double>(), 2.0 / 3);
  EXPECT_DOUBLE_EQ(s.at("grasp_tick_force_closure_share").get<double>(), 1.0 / 3);
  // JSON: the record's epsilon is the hold's, "grasp_tick" the grasp tick's; both read back.
  const Record back = record_from_json(record_json(recs[1]));
  EXPECT_TRUE(back.figures.force_closure);
  EXPECT_FALSE(back.grasp_tick_figures.force_closure);
}

}  // namespace
}  // namespace telegrasp::report
