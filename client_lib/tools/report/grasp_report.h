// Grasp records and how they are reported: the per-object table, the summary line and the JSON
// records, shared by telegrasp-eval (in-process) and telegrasp-bot (over DDS) so both print and
// write the same thing.
#pragma once

#include "telegrasp/sim/hand_controller.h"
#include "telegrasp/sim/hand_rig.h"
#include "telegrasp/sim/world.h"

#include <nlohmann/json.hpp>

#include <limits>
#include <optional>
#include <string>
#include <vector>

namespace telegrasp::report {

/// One capsule's metrics as a report writes them: sim::CapsuleMetric (client::CapsuleMetric over
/// DDS) with the phalanx's rig name, in millimetres. `hit`/`nd_midlength_mm`: the paper's ND at
/// mid-length; `contact_hit`/`nd_contact_mm`: ND toward the contact (blocked capsules).
struct CapsuleMetricRecord {
  std::string phalanx;
  bool hit = false, blocked = false;
  double nd_midlength_mm = 0, signed_distance_mm = 0;
  bool contact_hit = false;
  double nd_contact_mm = 0;
};

/// A grasp's hand-level figures (sim/README.md, sections 4 and 5): the palm volume's exact signed
/// distance to the object (mm), Ferrari-Canny epsilon, the wrench hull's volume, force closure.
struct GraspFigures {
  double palm_signed_distance_mm = 0;
  double epsilon = 0, volume = 0;
  bool force_closure = false;
};

/// A contact of a grasp as a report writes it: sim::Contact (client::ContactPoint over DDS) with
/// the phalanx's rig name; in world and object coordinates (m; unit normals).
struct ContactPointRecord {
  std::string phalanx;  ///< "palm" for the palm.
  Eigen::Vector3d p_WorldContact{0, 0, 0}, n_World{0, 0, 0}, p_ObjectContact{0, 0, 0}, n_Object{0, 0, 0};
};

/// A frame of the hand ("palm" or a rig phalanx) in the grasped object's frame.
struct HandFrameRecord {
  std::string frame;  ///< "palm" or the phalanx's rig name.
  Eigen::Isometry3d X_ObjectFrame = Eigen::Isometry3d::Identity();
};

/// One grasp trial.
struct Record {
  std::string object;
  std::string mode;  ///< Closing mode; "" if unknown (written as null).
  double speed_scale = 1;  ///< Written as null when `mode` is "".
  int trial = 0, attempts = 0;
  bool grasped = false, held_after_lift = false;
  double time_to_grasp_s = 0;
  double hand_error_mm = 0;  ///< The settled hand while held (end of the hold), else the grasp tick's.
  std::vector<CapsuleMetricRecord> capsules;
  /// Of the same hand as hand_error_mm; protocol runs' and telegrasp-bot's keep the grasp tick's
  /// palm distance and take the settled hold's quality only (set_hold_quality).
  GraspFigures figures;
  double grasp_tick_hand_error_mm = 0;  ///< The tick the grasp rule turned true.
  std::vector<CapsuleMetricRecord> grasp_tick_capsules;
  GraspFigures grasp_tick_figures;
  // Protocol runs (telegrasp-eval --protocol) only; written when `group` is not empty.
  std::string group;  ///< Operator group, e.g. "experienced".
  int participant = 0;  ///< 1-based, unique in a run.
  std::vector<ContactPointRecord> contacts;  ///< At the grasp tick.
  /// The hand at the grasp tick (palm, then every phalanx in rig order) in the object's frame,
  /// from the server's HandSkeleton of that tick; empty when unknown. Written when not empty.
  std::vector<HandFrameRecord> grasp_tick_hand;
  Eigen::Isometry3d grasp_tick_X_WorldObject = Eigen::Isometry3d::Identity();  ///< With grasp_tick_hand.
  /// The hand's grasp type at the grasp tick (sim::grasp_type_name); "" unknown (not written).
  std::string grasp_type;
  /// Grasp tick: opposition_deg() of its contacts; NaN without (not written).
  double opposition_deg = std::numeric_limits<double>::quiet_NaN();
  /// Grasp tick: sim::closes_across_shortest_side() with the table (the smallest side a hand can
  /// close across on it), and ignoring it (the box's shortest side); unknown: not written.
  std::optional<bool> across_smallest;
  std::optional<bool> across_smallest_ignoring_table;
};

/// The angle (degrees) between the mean contact normal of the rig's finger named "thumb" and the
/// mean of the other fingers' contact normals (the palm left out): 180 when the thumb pushes
/// straight against the fingers. NaN when the thumb or the other fingers touch nothing, or the
/// rig has no thumb.
double opposition_deg(const std::vector<sim::Contact>& contacts, const sim::HandRig& rig);

/// Prints one row per grasp type among `records` that have one: grasps, held after lift, force
/// closure share, median opposition, mean |ND| at mid-length, closing across the shortest side.
/// Prints nothing when every type is "other" (a rig that lists no types).
void print_type_table(const std::vector<const Record*>& records);

/// The capsule metrics of a grasp, named by the rig's phalanges, in mm.
std::vector<CapsuleMetricRecord> capsule_records(const sim::GraspMetrics& metrics, const sim::HandRig& rig);

/// The hand-level figures of a grasp, palm distance in mm.
GraspFigures grasp_figures(const sim::GraspMetrics& metrics);

/// Fills `rec`'s grasp-tick figures from an in-process grasp event with metrics: HandError, the
/// per-capsule metrics and the hand-level figures (also as the record's own until a hold replaces
/// them), the grasp type and the thumb's opposition. The in-process twin of
/// tools::record_grasp_event; time to grasp and contacts are the caller's.
void record_grasp_tick(const sim::GraspEvent& e, const sim::HandRig& rig, Record& rec);

/// A record's force closure, epsilon and volume from the settled hold of a run over DDS or its
/// in-process twin (the last quality while the object was held up), as telegrasp-eval run's
/// records have them: the grasp rule fires on the first contacts that hold, and the other fingers
/// close after it. The grasp_tick figures keep the grasp tick's. Nothing changes for a record not
/// grasped or a hold that had no quality yet (`hold` empty).
void set_hold_quality(Record& rec, const std::optional<sim::GraspQuality>& hold);

/// The capsules as a JSON array of {"phalanx","hit","blocked","nd_midlength_mm" (null without hit),
/// "nd_mm" (the same: an alias kept for one release),"contact_hit","nd_contact_mm" (null without
/// contact_hit),"signed_distance_mm"}.
nlohmann::json capsule_json(const std::vector<CapsuleMetricRecord>& capsules);

/// Success counts and metric statistics over `records` (keys as in telegrasp-eval's JSON summary).
nlohmann::json summarize(const std::vector<const Record*>& records);

/// The p-quantile of `v` (p in [0, 1]), interpolated linearly between the closest ranks; NaN
/// for no values.
double percentile(std::vector<double> v, double p);

/// `v` with `prec` decimals, "-" if not finite.
std::string fmt(double v, int prec = 2);

/// The trials of one object, for one row of the table.
struct ObjectRows {
  std::string object;
  std::vector<const Record*> records;
};

/// Prints the per-object table to stdout: held after lift, grasped, mean time to grasp, |ND|
/// median and 95th percentile, the minimum signed distance of blocked capsules, mean HandError.
void print_object_table(const std::vector<ObjectRows>& objects);

/// One grasp record as JSON: {"object","trial","mode","speed_scale","grasped","held_after_lift",
/// "attempts","time_to_grasp_s","hand_error_mm","palm_signed_distance_mm","epsilon","volume",
/// "force_closure","capsules":[...],"grasp_tick":{the same metrics at the grasp tick}} (metrics
/// null when not grasped), plus
/// "group","participant","contacts":[{"phalanx","p_WorldContact_m","n_World","p_ObjectContact_m","n_Object"}] for
/// protocol runs, and "grasp_tick_hand":{"X_WorldObject":{"p","q_wxyz"},"frames":[{"frame","p","q_wxyz"}]}
/// (X_ObjectFrame; m, unit quaternion w,x,y,z; rounded to 1e-6) when a protocol record has it.
nlohmann::json record_json(const Record& record);

/// The inverse of record_json (protocol runs read their participants' records back with it).
/// Throws nlohmann::json::exception naming a missing or mistyped key.
Record record_from_json(const nlohmann::json& j);

}  // namespace telegrasp::report
