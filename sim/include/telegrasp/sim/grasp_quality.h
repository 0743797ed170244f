// Grasp quality for robots (sim/README.md, section 5 Grasp quality): the grasp wrench space of a
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

/// GraspQuality::volume when it was not asked for (QualityVolume::kSkip).
inline constexpr double kVolumeNotComputed = -1;

/// Quality of one grasp. All zero (and no closure) for degenerate inputs.
struct GraspQuality {
  double epsilon = 0;  ///< Radius of the largest origin-centred ball inside the wrench hull (0: origin not strictly inside).
  double volume = 0;  ///< Volume of the 6-D wrench hull; kVolumeNotComputed (< 0) when not asked for.
  bool force_closure = false;  ///< epsilon > 0.
};

/// A quality not computed yet (a HandController's until its World delivers one): epsilon and
/// volume -1, no closure.
inline constexpr GraspQuality kPendingQuality{-1, -1, false};

/// Whether a quality includes the hull's volume: epsilon takes tens to hundreds of microseconds
/// (wrench_epsilon), the volume needs the full hull (Qhull: milliseconds to tens of them).
enum class QualityVolume { kSkip, kCompute };

/// 6-D wrenches, one per column: force (3), then torque divided by the torque scale (3).
using Wrenches = Eigen::Matrix<double, 6, Eigen::Dynamic>;

/// Quality of `contacts` with Coulomb friction `mu` (>= 0; 0 is frictionless), each friction cone
/// linearised with `cone_edges` unit-normal-force edges, torques divided by `torque_scale` (the
/// object's radius about its centre of mass, > 0). Never throws; degenerate inputs give all zero.
/// Equals wrench_quality(contact_wrenches(contacts, mu, torque_scale, cone_edges), volume) bit for bit.
GraspQuality grasp_quality(std::span<const QualityContact> contacts, double mu, double torque_scale, int cone_edges = 8,
                           QualityVolume volume = QualityVolume::kSkip);

/// The wrenches grasp_quality() takes the hull of: column k * edges + e is edge e of contact k's
/// cone (edges = cone_edges, or 1 when mu = 0). No columns for degenerate inputs (grasp_quality
/// gives all zero for them, as wrench_quality does for no columns). Cheap: no hull.
Wrenches contact_wrenches(std::span<const QualityContact> contacts, double mu, double torque_scale, int cone_edges = 8);

/// Epsilon (wrench_epsilon()) and, if asked, the volume (qhull_wrench_quality()) of the convex
/// hull of `wrenches`. A pure function of the wrenches: equal wrenches give equal qualities.
GraspQuality wrench_quality(const Wrenches& wrenches, QualityVolume volume = QualityVolume::kSkip);

/// What wrench_epsilon() found, with its certificate.
struct EpsilonResult {
  double epsilon = 0;  ///< As GraspQuality::epsilon: 0 unless the origin is strictly inside.
  bool force_closure = false;  ///< epsilon > 0.
  /// Unit 6-D direction. Closure: the normal of the hull's facet nearest the origin (every wrench
  /// lies at most epsilon + tol along it). No closure: a separating direction (every wrench lies
  /// at most tol along it). Zero for degenerate inputs and when the full hull was used.
  Eigen::Matrix<double, 6, 1> direction = Eigen::Matrix<double, 6, 1>::Zero();
  double support = 0;  ///< The largest wrench . direction: epsilon <= exact <= support <= epsilon + tol.
  int added = 0;  ///< Wrenches added to the first simplex.
  int facets = 0;  ///< Facets built in all (the full hull has 1,000-15,000 on grasps).
  bool full_hull = false;  ///< Numerically degenerate on the way: the value is Qhull's.
};

/// Ferrari-Canny epsilon of the convex hull of `wrenches` without the full hull: the expanding
/// polytope of Y. Zheng (IEEE T-RO 29(2), 2013), exact to tol = 1e-11 x the largest wrench norm;
/// its first phase is the exact force-closure test. Flat (rank < 6) or non-finite sets and fewer
/// than 7 wrenches give 0. Debug builds check the certificate on exit.
EpsilonResult wrench_epsilon(const Wrenches& wrenches);

/// Epsilon and volume from Qhull's full hull of `wrenches`: the reference for wrench_epsilon()
/// (the tests hold it to this) and the only source of the volume.
GraspQuality qhull_wrench_quality(const Wrenches& wrenches);

}  // namespace telegrasp::sim
