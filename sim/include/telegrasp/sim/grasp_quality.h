// Grasp quality for robots (../shared/docs/GRASPING.md section 4b): the grasp wrench space of a
// set of frictional point contacts, its Ferrari-Canny epsilon and its volume, as GraspIt! computes them.
#pragma once

#include <Eigen/Core>

#include <span>

namespace telegrasp::sim {

/// One point contact on the object, in the object frame.
struct QualityContact {
  Eigen::Vector3d p{0, 0, 0};  ///< Contact point, relative to the object's centre of mass, m.
  Eigen::Vector3d n{0, 0, 0};  ///< Unit surface normal at p, pointing out of the object.
};

/// Quality of one grasp. All zero (and no closure) for degenerate inputs.
struct GraspQuality {
  double epsilon = 0;  ///< Radius of the largest origin-centred ball inside the wrench hull (0: origin not strictly inside).
  double volume = 0;  ///< Volume of the 6-D wrench hull.
  bool force_closure = false;  ///< epsilon > 0.
};

/// Quality of `contacts` with Coulomb friction `mu` (>= 0; 0 is frictionless), each friction cone
/// linearised with `cone_edges` unit-normal-force edges, torques divided by `torque_scale` (the
/// object's radius about its centre of mass, > 0). Never throws; degenerate inputs give all zero.
GraspQuality grasp_quality(std::span<const QualityContact> contacts, double mu, double torque_scale,
                           int cone_edges = 8);

}  // namespace telegrasp::sim
