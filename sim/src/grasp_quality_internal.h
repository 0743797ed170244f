// What grasp_quality.cc (the Qhull hull) and wrench_epsilon.cc (the expanding polytope) share.
#pragma once

#include "telegrasp/sim/grasp_quality.h"

namespace telegrasp::sim {

/// The origin counts as strictly inside only when every facet is farther than this (wrench units).
inline constexpr double kMinEpsilon = 1e-12;

/// The affine dimension of the wrenches (the columns) is 6: their smallest singular value after
/// removing the centroid exceeds 1e-10 of their largest. A flat set's hull has no interior
/// (epsilon 0) and no 6-D volume.
bool full_dimensional(const Wrenches& w);

}  // namespace telegrasp::sim
