// Contact: a contact between a blocked phalanx (or the palm) and the grasped object, in world and
// object coordinates (sim/README.md, section 6).
#pragma once

#include "telegrasp/sim/ids.h"

#include <Eigen/Core>

namespace telegrasp::sim {

/// A contact between a blocked phalanx (or the palm) and the grasped object.
struct Contact {
  PhalanxId phalanx;  ///< Invalid for the palm.
  Eigen::Vector3d p_WorldContact{0, 0, 0}, n_World{0, 0, 0};
  Eigen::Vector3d p_ObjectContact{0, 0, 0}, n_Object{0, 0, 0};
  double nd = 0;
  bool nd_hit = false;
};

}  // namespace telegrasp::sim
