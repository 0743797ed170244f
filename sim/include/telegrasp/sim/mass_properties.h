// Volume, centre of mass and inertia of a closed triangle mesh of uniform density.
#pragma once

#include "telegrasp/sim/triangle_mesh.h"

#include <Eigen/Core>

namespace telegrasp::sim {

/// Mass properties of a solid bounded by a closed, outward-facing mesh.
struct MassProperties {
  double volume = 0;  ///< m^3, > 0 for a valid closed mesh.
  Eigen::Vector3d centroid{0, 0, 0};  ///< Centre of mass, mesh frame.
  Eigen::Matrix3d inertia_per_density =
      Eigen::Matrix3d::Zero();  ///< About the centroid, mesh axes; times density = kg m^2.
};

/// Exact polyhedral mass properties (divergence theorem over the triangles).
/// An inward-facing (clockwise) mesh gives negated volume and inertia; the centroid stays right.
MassProperties compute_mass_properties(const TriangleMesh& mesh);

/// Returns `mesh` translated by `offset` (every vertex + offset).
TriangleMesh translated(const TriangleMesh& mesh, const Eigen::Vector3d& offset);

}  // namespace telegrasp::sim
