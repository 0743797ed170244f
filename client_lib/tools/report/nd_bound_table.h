// A run's ND beside the nd-bound oracle's: which objects the rig's geometry lets reach the paper's
// figure, and the run's mean over those.
#pragma once

#include "grasp_report.h"

#include <nlohmann/json.hpp>

#include <map>
#include <optional>
#include <string>
#include <vector>

namespace telegrasp::report {

/// The paper's mean |ND| for its experienced group (mm): the mean over its 30 objects of
/// paper_results_per_object.csv's err_experienced (1.1215).
inline constexpr double kPaperNdExperiencedMm = 1.12;

/// telegrasp-eval nd-bound's `--json` file: per object the lowest mean |ND| of a clean grasp the
/// oracle found, none when it found no clean grasp; and the rig it ran ("" if the file does not say).
struct NdBounds {
  std::string rig;
  std::map<std::string, std::optional<double>> nd_mean_mm;
};

/// Reads an nd-bound `--json` file; throws std::runtime_error naming the file and what is wrong.
NdBounds read_nd_bounds(const std::string& path);

/// Prints per object the grasp tick's mean |ND| over the capsules that hit, how many hit, the grasps
/// where none hit and the oracle's figure; then the grasp tick's pooled mean |ND| over every object,
/// over the objects the oracle takes to kPaperNdExperiencedMm or below, and names the others (the
/// oracle above it or without a clean grasp) and those the file does not have. Returns the same as
/// JSON: {"paper_nd_mm", "oracle_rig", "grasp_tick_nd_abs_mean_mm", "reachable":
/// {"grasp_tick_nd_abs_mean_mm", "capsules_hit", "objects": [names]}, "beyond": [names],
/// "unknown": [names]}.
nlohmann::json print_nd_bound_table(const std::vector<ObjectRows>& objects, const NdBounds& bounds);

}  // namespace telegrasp::report
