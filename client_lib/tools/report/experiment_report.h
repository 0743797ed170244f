// Reports of a protocol run (the paper's experiment, sim/README.md section 10):
// aggregates per mode, operator group and object as JSON; the per-grasp and per-object CSV
// tables; and one self-contained HTML page (inline CSS and SVG, nothing fetched) with a picture of
// one grasp per object, the paper's bar charts, the paper's published per-object numbers beside
// ours, and the questionnaire's scores.
//
// Which numbers: every error metric here is taken at the grasp tick (the moment the paper measures
// "for each grasping", and what a GraspEvent carries), i.e. Record::grasp_tick_capsules and
// Record::grasp_tick_hand_error_mm. A grasp's |ND| is the mean |ND| over its capsules that hit;
// per object and group, "nd_abs_mean_mm" is the mean of those per-grasp values (every grasp weighs
// the same, as each of the paper's grasps gives one error), and the charts plot that. The pooled
// mean over all hit capsules is in the JSON too ("nd_abs_pooled_mean_mm"). HandError, like |ND|,
// exists only for a grasp with a capsule that hit (a grasp without one has no value, not zero).
// Times are the mean over grasped trials of spawn-to-grasp seconds; sd is the sample sd (n - 1),
// null/empty for n < 2. Undefined values are null in JSON, empty in CSV, "no data" in HTML.
#pragma once

#include "grasp_report.h"
#include "questionnaire.h"
#include "telegrasp/sim/hand_rig.h"
#include "telegrasp/sim/object_model.h"

#include <nlohmann/json.hpp>

#include <cstdint>
#include <map>
#include <memory>
#include <string>
#include <vector>

namespace telegrasp::report {

/// One protocol run, as the protocol runner collected it.
struct ExperimentRun {
  std::string protocol;  ///< "paper".
  std::string command_line;
  std::uint64_t seed = 0;
  double wall_seconds = 0;
  std::string created;  ///< ISO 8601 date-time.
  std::vector<std::string> modes;  ///< "precise", "discrete", in run order.
  std::vector<std::string> objects;  ///< The protocol's objects, in order.
  std::vector<std::string> standin_objects;  ///< Objects that fell back to a built-in stand-in.
  std::map<std::string, int> participants;  ///< Group -> number of participants.
  std::vector<Record> records;  ///< With group, participant and mode set.
};

/// One object of the paper's published results (time in s, error as the paper plotted it, mm).
struct PaperRow {
  std::string label;  ///< The paper's object letter, a..ad.
  std::string object;  ///< YCB name, e.g. "014_lemon".
  double time_experienced = 0, time_inexperienced = 0, err_experienced = 0, err_inexperienced = 0;
};

/// The shipped paper_results_per_object.csv, in the data folder (sim::data_dir()).
std::string default_paper_results_path();

/// Reads label,object,time_s_experienced,time_s_inexperienced,err_experienced,err_inexperienced
/// (header row required). Throws std::runtime_error naming the file, line and column on a missing
/// column or a bad number.
std::vector<PaperRow> load_paper_results(const std::string& path);

/// Aggregates: {"run":{...},"metrics":{...notes},"by_mode_group_object":[...],"by_mode_group":[...],
/// "by_mode_object":[...] (group "all"),"worst_objects":[{"mode","by_time":[...],"by_nd":[...]}]}.
/// Each aggregate: n, grasped, held_after_lift, time_to_grasp_mean_s/_sd_s, nd_abs_mean_mm/_sd_mm,
/// nd_abs_pooled_mean_mm, capsules_hit, hand_error_mean_mm/_sd_mm (NaN as null).
nlohmann::json aggregate_json(const ExperimentRun& run);

/// Writes `path` (one row per grasp: mode, group, participant, object, trial, grasped,
/// held_after_lift, attempts, time_to_grasp_s, hand_error_mm, nd_abs_mean_mm, capsules_hit,
/// min_signed_distance_mm, contacts) and `<stem>_by_object.csv` next to it (one row per mode,
/// group, object, plus group "all" for both groups together). Returns the second file's path.
/// Throws std::runtime_error naming the file if it cannot be written.
std::string write_csv(const ExperimentRun& run, const std::string& path);

/// What the report draws the grasps with: the hand's rig and the models the run loaded, by name.
struct GraspPictureInputs {
  std::shared_ptr<const sim::HandRig> rig;
  std::map<std::string, sim::ObjectModelPtr> models;
};

/// The record whose grasp the report draws for `object`: among the records with the hand at the
/// grasp tick (Record::grasp_tick_hand), held after the lift before merely grasped, precise mode
/// before the others, experienced before the other groups, then the lowest participant and trial;
/// null when no record has the hand.
const Record* representative_grasp(const ExperimentRun& run, const std::string& object);

/// The full report as one HTML page. `paper` may be empty (no paper bars); `questionnaire` may be
/// null (no questionnaire section); `pictures` may be null (no pictures section), else one
/// picture per object (see representative_grasp), drawn by grasp_svg.h in its readable view.
/// Every bar is an SVG
/// `<rect class="bar" data-chart=".." data-mode=".." data-group=".." data-object=".." data-value="..">`
/// (data-mode "paper" for the paper's bars; data-group "all" for both groups together; data-value
/// empty when the value is undefined, e.g. no grasp succeeded: then the bar is a hatched slot of
/// the plot's height marked "no data"). A series with no trials of an object (or a paper without
/// the object) gets a hatched `<rect class="nodata">` slot instead of a bar.
std::string html_report(const ExperimentRun& run, const std::vector<PaperRow>& paper,
                        const QuestionnaireSummary* questionnaire, const GraspPictureInputs* pictures = nullptr);

/// A page with only the questionnaire section (telegrasp-eval questionnaire --report).
std::string questionnaire_html_report(const QuestionnaireSummary& questionnaire);

/// Writes `text` to `path`; throws std::runtime_error naming the file on failure.
void write_text_file(const std::string& path, const std::string& text);

}  // namespace telegrasp::report
