// The exact signed distance of a box (the palm volume) to an object's solid.
#pragma once

#include "telegrasp/sim/object_model.h"

#include <Eigen/Geometry>

namespace telegrasp::sim {

/// Signed distance between the box of `half_extent` centred on the origin of the frame
/// `X_ObjectBox` (in the object frame) and the object's solid: min over box points of the mesh's
/// signed distance, as for capsules. Separated: the exact gap (the closest pair lies on a box edge
/// or at a mesh vertex facing a box face, and both are searched exactly). Overlapping (a box edge
/// meets the surface, a mesh vertex lies in the box, or the centre lies in the solid): minus the
/// depth of the deepest box point, found by projected descent of the signed distance from the
/// lowest of the corners, face centres, centre and contact points: exact for a face, edge or corner
/// pressed into the object, never deeper than the truth, and within about a millimetre of it when
/// an edge of the object cuts deep into the box (the descent stalls on the object's medial ridge).
double box_signed_distance(const ObjectModel& model, const Eigen::Isometry3d& X_ObjectBox,
                           const Eigen::Vector3d& half_extent);

}  // namespace telegrasp::sim
