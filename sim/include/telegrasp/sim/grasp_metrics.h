// GraspMetrics: the error metric of a grasp (sim/README.md, section 4): every capsule's ND two
// ways and exact signed distance (CapsuleMetric), the HandError, the palm's distance, the quality.
#pragma once

#include "telegrasp/sim/grasp_quality.h"
#include "telegrasp/sim/ids.h"

#include <cmath>
#include <utility>
#include <vector>

namespace telegrasp::sim {

/// ND of one capsule taken two ways (sim/README.md, section 4), and the exact signed distance of its volume.
struct CapsuleMetric {
  PhalanxId phalanx;
  bool hit = false;  ///< nd_midlength: the sweep toward CTc found the object within its length.
  double nd = 0;  ///< nd_midlength (the paper's ND) in metres (> 0 gap, < 0 penetration); meaningful only if hit.
  bool contact_hit = false;  ///< nd_contact was taken (blocked capsules always have it).
  double nd_contact = 0;  ///< ND toward the axis point nearest the capsule's contact, metres; only if contact_hit.
  double signed_distance = 0;  ///< Exact capsule-to-solid signed distance, metres.
  bool blocked = false;
};

/// ND of every capsule and the HandError, taken on the tick of the grasp.
struct GraspMetrics {
  std::vector<CapsuleMetric> capsules;
  double hand_error_mm = 0;  ///< Sum over fingers of mean |ND| over the finger's capsules that hit.
  int capsules_without_hit = 0;  ///< Capsules whose sweep found nothing (left out of HandError).
  double palm_signed_distance = 0;  ///< Exact signed distance of the palm volume to the object, metres.
  /// Ferrari-Canny epsilon, wrench-space volume, force closure (sim/README.md, section 5);
  /// kPendingQuality until the World delivers it (HandController::set_quality()).
  GraspQuality quality = kPendingQuality;
};

/// The mean |ND| in mm over the capsules whose sweep hit, and how many hit (as telegrasp-eval
/// counts them); 0 and 0 when none hit.
inline std::pair<double, int> mean_abs_nd_mm(const GraspMetrics& metrics) {
  double sum = 0;
  int hits = 0;
  for (const CapsuleMetric& c : metrics.capsules)
    if (c.hit) {
      sum += 1000.0 * std::abs(c.nd);
      ++hits;
    }
  return {hits > 0 ? sum / hits : 0.0, hits};
}

}  // namespace telegrasp::sim
