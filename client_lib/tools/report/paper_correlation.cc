#include "paper_correlation.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <numeric>

namespace telegrasp::report {
namespace {

using nlohmann::json;

constexpr double kPaperExperienced = 4, kPaperInexperienced = 6;  // the paper's participants per group

double mean(const std::vector<double>& x) {
  return x.empty() ? std::numeric_limits<double>::quiet_NaN()
                   : std::accumulate(x.begin(), x.end(), 0.0) / static_cast<double>(x.size());
}

double pearson(const std::vector<double>& a, const std::vector<double>& b) {
  const double ma = mean(a), mb = mean(b);
  double ab = 0, aa = 0, bb = 0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    ab += (a[i] - ma) * (b[i] - mb);
    aa += (a[i] - ma) * (a[i] - ma);
    bb += (b[i] - mb) * (b[i] - mb);
  }
  if (aa <= 0 || bb <= 0) return std::numeric_limits<double>::quiet_NaN();
  return ab / std::sqrt(aa * bb);
}

// The paper's mean time of `row` for a group, "all" being its mean over every participant.
double paper_time(const PaperRow& row, const std::string& group) {
  if (group == "experienced") return row.time_experienced;
  if (group == "inexperienced") return row.time_inexperienced;
  return (kPaperExperienced * row.time_experienced + kPaperInexperienced * row.time_inexperienced) /
         (kPaperExperienced + kPaperInexperienced);
}

// The row of one mode and group.
json correlation_row(const ExperimentRun& run, const std::vector<PaperRow>& paper, const std::string& mode,
                     const std::string& group) {
  std::map<std::string, std::vector<double>> times;  // per object, the grasped trials' times
  std::vector<double> all;
  for (const Record& r : run.records)
    if (r.mode == mode && (group == "all" || r.group == group) && r.grasped) {
      times[r.object].push_back(r.time_to_grasp_s);
      all.push_back(r.time_to_grasp_s);
    }
  std::vector<double> ours, theirs, paper_all;
  for (const PaperRow& row : paper) {
    paper_all.push_back(paper_time(row, group));
    if (auto it = times.find(row.object); it != times.end()) {
      ours.push_back(mean(it->second));
      theirs.push_back(paper_time(row, group));
    }
  }
  auto number = [](double v) { return std::isfinite(v) ? json(v) : json(nullptr); };
  const double ratio = mean(all) / mean(paper_all);
  return {{"mode", mode},
          {"group", group},
          {"objects", ours.size()},
          {"spearman", number(spearman(ours, theirs))},
          {"time_mean_s", number(mean(all))},
          {"paper_time_mean_s", number(mean(paper_all))},
          {"time_ratio", number(ratio)}};
}

std::string text(const json& v, int decimals) {
  if (!v.is_number()) return "n/a";
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.*f", decimals, v.get<double>());
  return buf;
}

}  // namespace

std::vector<double> average_ranks(const std::vector<double>& x) {
  std::vector<std::size_t> order(x.size());
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](std::size_t i, std::size_t j) { return x[i] < x[j]; });
  std::vector<double> ranks(x.size());
  for (std::size_t i = 0; i < order.size();) {
    std::size_t j = i;
    while (j + 1 < order.size() && x[order[j + 1]] == x[order[i]]) ++j;
    const double rank = 0.5 * static_cast<double>(i + j) + 1.0;  // the mean of ranks i+1 .. j+1
    for (std::size_t k = i; k <= j; ++k) ranks[order[k]] = rank;
    i = j + 1;
  }
  return ranks;
}

double spearman(const std::vector<double>& a, const std::vector<double>& b) {
  if (a.size() != b.size() || a.size() < 2) return std::numeric_limits<double>::quiet_NaN();
  return pearson(average_ranks(a), average_ranks(b));
}

json paper_correlation_json(const ExperimentRun& run, const std::vector<PaperRow>& paper) {
  json out = json::array();
  if (paper.empty()) return out;
  for (const std::string& mode : run.modes)
    for (const char* group : {"experienced", "inexperienced", "all"})
      out.push_back(correlation_row(run, paper, mode, group));
  return out;
}

void print_paper_correlation(const json& correlation) {
  if (correlation.empty()) return;
  std::printf("\npaper times (per-object mean time to grasp, Spearman over objects; \"all\" = both groups pooled):\n");
  for (const json& r : correlation)
    std::printf("  %s, %s: ours %s s, paper %s s (x%s), Spearman %s over %d objects\n", r.value("mode", "").c_str(),
                r.value("group", "").c_str(), text(r["time_mean_s"], 2).c_str(),
                text(r["paper_time_mean_s"], 2).c_str(), text(r["time_ratio"], 2).c_str(),
                text(r["spearman"], 2).c_str(), r.value("objects", 0));
}

std::string paper_correlation_html(const json& correlation) {
  if (correlation.empty()) return "";
  std::string h =
      "<section id=\"paper-correlation\"><h2>Time to grasp against the paper's participants</h2>\n"
      "<p>Mean time to grasp over grasped trials, ours and the paper's (mean of its per-object means), and "
      "Spearman's rank correlation of the per-object mean times over the objects (group \"all\": both groups "
      "pooled, the paper's side weighted by its 4 + 6 participants). The skill profiles are fitted to these "
      "means (README, \"Calibration\"); the per-object order comes from the operator model's mechanisms "
      "(object size, practice), not from the paper's numbers.</p>\n"
      "<table class=\"paper-correlation\"><tr><th>mode</th><th>group</th><th>ours, s</th><th>paper, s</th>"
      "<th>ours / paper</th><th>Spearman</th><th>objects</th></tr>\n";
  for (const json& r : correlation)
    h += "<tr><td>" + r.value("mode", "") + "</td><td>" + r.value("group", "") + "</td><td>" +
         text(r["time_mean_s"], 2) + "</td><td>" + text(r["paper_time_mean_s"], 2) + "</td><td>" +
         text(r["time_ratio"], 2) + "</td><td data-spearman=\"" + text(r["spearman"], 3) + "\">" +
         text(r["spearman"], 2) + "</td><td>" + std::to_string(r.value("objects", 0)) + "</td></tr>\n";
  return h + "</table></section>\n";
}

}  // namespace telegrasp::report
