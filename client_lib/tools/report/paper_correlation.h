// How well a protocol run's per-object mean times to grasp follow the paper's participants':
// Spearman's rank correlation over the protocol's objects, per mode and group and pooled over both
// groups, beside the mean times (README, "Calibration").
#pragma once

#include "experiment_report.h"

#include <nlohmann/json.hpp>

#include <string>
#include <vector>

namespace telegrasp::report {

/// 1-based ranks of `x`, ties sharing the mean of the ranks they span (x = {10, 20, 20, 5} gives
/// {2, 3.5, 3.5, 1}).
std::vector<double> average_ranks(const std::vector<double>& x);

/// Spearman's rank correlation: the Pearson correlation of the average ranks. NaN when the sizes
/// differ, there are fewer than 2 values, or one side's values are all equal.
double spearman(const std::vector<double>& a, const std::vector<double>& b);

/// Per mode, for "experienced", "inexperienced" and "all" (both groups; the paper's side is its
/// per-object mean over its 4 + 6 participants): {"mode", "group", "objects" (objects with a
/// grasp in the run and a paper time), "spearman" (ours per-object mean time vs the paper's, null
/// if undefined), "time_mean_s" (mean over the run's grasped trials), "paper_time_mean_s" (mean
/// of the paper's per-object means), "time_ratio" (ours / paper)}, as an array.
nlohmann::json paper_correlation_json(const ExperimentRun& run, const std::vector<PaperRow>& paper);

/// The JSON above as console lines ("paper times, precise, experienced: ours 1.31 s, paper 1.30 s
/// (x1.01), Spearman 0.52 over 30 objects").
void print_paper_correlation(const nlohmann::json& correlation);

/// The JSON above as an HTML section (a table), for html_report.
std::string paper_correlation_html(const nlohmann::json& correlation);

}  // namespace telegrasp::report
