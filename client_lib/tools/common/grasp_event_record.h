// The one conversion of a server GraspEvent (and the hold's GraspState) into a grasp report
// record, shared by telegrasp-bot and the protocol's participants so that both measure the same thing.
#pragma once

#include "grasp_report.h"
#include "telegrasp/client/types.h"
#include "telegrasp/sim/grasp_quality.h"
#include "telegrasp/sim/hand_rig.h"

#include <optional>

namespace telegrasp::tools {

/// Fills `rec` from the grasp event `e` of one trial: grasped, time to grasp, HandError, the
/// per-capsule metrics (mm) of the grasp tick, and the contacts named by `rig`'s phalanges.
///
/// Time to grasp (README, "time to grasp"): server time from the moment the object was
/// reachable to the grasp tick. The object is reachable from the later of its spawn
/// (`e.object_spawn_time`) and `trial_start_time`, the server time at which the operator's trial
/// began (its hand placed and free to reach).
void record_grasp_event(const client::GraspEvent& e, double trial_start_time, const sim::HandRig& rig,
                        report::Record& rec);

/// The held grasp's quality as the newest GraspState `s` gives it (report::set_hold_quality), if
/// `s` holds `object` and its first quality has arrived (epsilon -1 until then).
std::optional<sim::GraspQuality> hold_quality(const std::optional<client::GraspState>& s, int object);

}  // namespace telegrasp::tools
