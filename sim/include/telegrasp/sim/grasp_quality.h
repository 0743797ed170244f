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

/// 6-D wrenches, one per column: force (3), then torque divided by the torque scale (3).
using Wrenches = Eigen::Matrix<double, 6, Eigen::Dynamic>;

/// Quality of `contacts` with Coulomb friction `mu` (>= 0; 0 is frictionless), each friction cone
/// linearised with `cone_edges` unit-normal-force edges, torques divided by `torque_scale` (the
/// object's radius about its centre of mass, > 0). Never throws; degenerate inputs give all zero.
/// Equals wrench_quality(contact_wrenches(contacts, mu, torque_scale, cone_edges)) bit for bit.
GraspQuality grasp_quality(std::span<const QualityContact> contacts, double mu, double torque_scale,
                           int cone_edges = 8);

/// The wrenches grasp_quality() takes the hull of: column k * edges + e is edge e of contact k's
/// cone (edges = cone_edges, or 1 when mu = 0). No columns for degenerate inputs (grasp_quality
/// gives all zero for them, as wrench_quality does for no columns). Cheap: no hull.
Wrenches contact_wrenches(std::span<const QualityContact> contacts, double mu, double torque_scale, int cone_edges = 8);

/// Epsilon and volume of the convex hull of `wrenches` (the Qhull part of grasp_quality(), which
/// costs milliseconds). A pure function of the wrenches: equal wrenches give equal qualities.
GraspQuality wrench_quality(const Wrenches& wrenches);

}  // namespace telegrasp::sim
