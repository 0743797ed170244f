// Internal to the experiment report (experiment_aggregate.cc, experiment_writers.cc,
// experiment_html.cc); the public API is experiment_report.h. The statistics of a set of grasp
// records, and what a run contains in a stable order.
#pragma once

#include "experiment_report.h"

#include <cmath>
#include <string>
#include <vector>

namespace telegrasp::report {

struct Stat {
  int n = 0;
  double mean = NAN, sd = NAN;  // sd: sample sd (n - 1), NaN for n < 2.
};

Stat stat(const std::vector<double>& v);

// A grasp's mean |ND| over the capsules that hit at the grasp tick; NaN when none hit.
double grasp_nd_abs_mean(const Record& r, int* hits = nullptr);

// The smallest exact signed distance of a blocked capsule at the grasp tick; NaN when none is.
double grasp_min_signed_distance(const Record& r);

// The fidelity figures of some grasps at the grasp tick (sim/README.md, section 4): nd_contact and
// the exact signed distances of the blocked capsules, the palm's exact signed distance.
struct Fidelity {
  std::vector<double> nd_contact_abs;  // |nd_contact| of every blocked capsule that has one, mm
  int blocked = 0, blocked_without_contact = 0, blocked_below = 0;  // below: signed distance < -0.1 mm
  double min_signed_distance = NAN;  // of a blocked capsule, mm
  int palms = 0, palm_below = 0;
  double palm_min = NAN;  // mm
};

// Adds one grasp's blocked capsules and palm at the grasp tick to `f`.
void add_fidelity(Fidelity& f, const Record& r);

// The aggregate of some trials (one mode, group and object, or wider).
struct Aggregate {
  int n = 0, grasped = 0, held = 0, capsules_hit = 0;
  Stat time, nd, hand_error;  // over grasped trials (nd, hand_error: those with a hit capsule)
  double nd_pooled = NAN;  // mean |ND| over every hit capsule of those trials
  Fidelity fidelity;  // over grasped trials
  int held_force_closure = 0;  // held trials whose grasp is in force closure
};

Aggregate aggregate(const std::vector<const Record*>& records);

// The run's modes in run order, then any mode only the records name.
std::vector<std::string> modes_of(const ExperimentRun& run);

// The paper's two groups first (its charts put experienced first), then the others by name.
std::vector<std::string> groups_of(const ExperimentRun& run);

// The objects that have records: the protocol's order, then objects only the records name.
std::vector<std::string> objects_of(const ExperimentRun& run);

// Records of one mode, group ("" = every group) and object ("" = every object).
std::vector<const Record*> select(const ExperimentRun& run, const std::string& mode, const std::string& group,
                                  const std::string& object);

// A bar chart's y axis from 0: a nice step (1, 2 or 5 x 10^k, the smallest at least a fifth of
// the largest value), the axis top (the first multiple of the step at or above that value), and a
// label per tick (0, step, 2 step, ... top) with exactly the decimals the step needs. No positive
// finite value: 0 to 1 in steps of 0.2.
struct AxisTicks {
  double top = 1, step = 0.2;
  std::vector<double> values;
  std::vector<std::string> labels;
};
AxisTicks axis_ticks(double largest_value);

// `v` with `prec` decimals; "" when undefined (NaN), as a CSV cell or data attribute wants it.
inline std::string number(double v, int prec = 3) { return std::isfinite(v) ? fmt(v, prec) : ""; }

}  // namespace telegrasp::report
