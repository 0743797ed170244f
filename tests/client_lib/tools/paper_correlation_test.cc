// Tests the paper comparison of a protocol run: average ranks with ties, Spearman's rank
// correlation against hand-computed values, and the per-mode, per-group rows.
#include "paper_correlation.h"

#include <gtest/gtest.h>

#include <cmath>

namespace telegrasp::report {
namespace {

TEST(PaperCorrelationTest, AverageRanksShareTies) {
  EXPECT_EQ(average_ranks({10, 20, 20, 5}), (std::vector<double>{2, 3.5, 3.5, 1}));
  EXPECT_EQ(average_ranks({3, 3, 3}), (std::vector<double>{2, 2, 2}));
  EXPECT_EQ(average_ranks({}), std::vector<double>{});
}

TEST(PaperCorrelationTest, SpearmanWithoutTies) {
  // Ranks a = 1 2 3 4 5, b = 2 1 4 3 5: d^2 sums to 4, so rho = 1 - 6 * 4 / (5 * 24) = 0.8.
  EXPECT_NEAR(spearman({1.0, 2.0, 3.0, 4.0, 5.0}, {0.2, 0.1, 0.4, 0.3, 0.9}), 0.8, 1e-12);
  EXPECT_NEAR(spearman({1, 2, 3}, {30, 20, 10}), -1.0, 1e-12);
  EXPECT_NEAR(spearman({1, 2, 3}, {1, 4, 9}), 1.0, 1e-12);  // any increasing function
}

TEST(PaperCorrelationTest, SpearmanWithTies) {
  // a = {1, 2, 2, 3} ranks {1, 2.5, 2.5, 4}; b = {1, 3, 2, 4} ranks {1, 3, 2, 4}.
  // Deviations from the mean rank 2.5: a {-1.5, 0, 0, 1.5}, b {-1.5, 0.5, -0.5, 1.5};
  // sum ab = 4.5, sum aa = 4.5, sum bb = 5, rho = 4.5 / sqrt(4.5 * 5) = 0.9486833.
  EXPECT_NEAR(spearman({1, 2, 2, 3}, {1, 3, 2, 4}), 4.5 / std::sqrt(22.5), 1e-12);
}

TEST(PaperCorrelationTest, SpearmanUndefinedIsNaN) {
  EXPECT_TRUE(std::isnan(spearman({1, 1, 1}, {1, 2, 3})));
  EXPECT_TRUE(std::isnan(spearman({1}, {1})));
  EXPECT_TRUE(std::isnan(spearman({1, 2}, {1, 2, 3})));
}

Record grasp(const std::string& group, const std::string& object, double time) {
  Record r;
  r.mode = "precise";
  r.group = group;
  r.object = object;
  r.grasped = true;
  r.time_to_grasp_s = time;
  return r;
}

TEST(PaperCorrelationTest, RowsPerGroupAndPooled) {
  ExperimentRun run;
  run.modes = {"precise"};
  run.records = {grasp("experienced", "a", 1.0),   grasp("experienced", "b", 2.0),   grasp("experienced", "c", 3.0),
                 grasp("inexperienced", "a", 3.0), grasp("inexperienced", "b", 2.0), grasp("inexperienced", "c", 1.0)};
  Record missed = grasp("experienced", "c", 99.0);
  missed.grasped = false;  // not grasped: no time
  run.records.push_back(missed);
  const std::vector<PaperRow> paper = {
      {"a", "a", 1.0, 1.0, 0, 0}, {"b", "b", 1.5, 2.0, 0, 0}, {"c", "c", 2.0, 3.0, 0, 0}};
  const nlohmann::json rows = paper_correlation_json(run, paper);
  ASSERT_EQ(rows.size(), 3u);
  EXPECT_EQ(rows[0]["group"], "experienced");
  EXPECT_NEAR(rows[0]["spearman"].get<double>(), 1.0, 1e-12);
  EXPECT_NEAR(rows[0]["time_mean_s"].get<double>(), 2.0, 1e-12);
  EXPECT_NEAR(rows[0]["paper_time_mean_s"].get<double>(), 1.5, 1e-12);
  EXPECT_NEAR(rows[0]["time_ratio"].get<double>(), 2.0 / 1.5, 1e-12);
  EXPECT_EQ(rows[0]["objects"], 3);
  EXPECT_NEAR(rows[1]["spearman"].get<double>(), -1.0, 1e-12);
  // Pooled: ours 2, 2, 2 per object (all equal: undefined); the paper's weighted 4:6.
  EXPECT_EQ(rows[2]["group"], "all");
  EXPECT_TRUE(rows[2]["spearman"].is_null());
  EXPECT_NEAR(rows[2]["paper_time_mean_s"].get<double>(), (4 * 1.5 + 6 * 2.0) / 10, 1e-12);
  EXPECT_NE(paper_correlation_html(rows).find("data-spearman=\"1.000\""), std::string::npos);
}

}  // namespace
}  // namespace telegrasp::report
