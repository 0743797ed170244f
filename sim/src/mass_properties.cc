// Exact mass properties of a closed triangle mesh by summing signed tetrahedra.
//
// Each triangle (a, b, c) and a reference point r span a tetrahedron whose signed volume is
// det[a-r, b-r, c-r] / 6. With p = a-r etc. and s = p+q+t, its exact moments are
//   integral of 1     = det / 6
//   integral of x     = det / 24 * s
//   integral of x x^T = det / 120 * (p p^T + q q^T + t t^T + s s^T)
// and the sums over a closed surface give the moments of the enclosed solid (divergence
// theorem). The reference point is the bounding-box centre, which keeps the sums well
// conditioned for meshes far from the origin.
#include "telegrasp/sim/mass_properties.h"

#include <Eigen/Dense>

namespace telegrasp::sim {

MassProperties compute_mass_properties(const TriangleMesh& mesh) {
  MassProperties result;
  if (mesh.vertices.empty() || mesh.triangles.empty()) return result;

  const Eigen::Vector3d reference = 0.5 * (mesh.min_corner() + mesh.max_corner());
  double six_volume = 0;  // sum of det
  Eigen::Vector3d first_moment_24 = Eigen::Vector3d::Zero();  // sum of det * s
  Eigen::Matrix3d second_moment_120 = Eigen::Matrix3d::Zero();

  for (const auto& tri : mesh.triangles) {
    const Eigen::Vector3d p = mesh.vertices[tri[0]] - reference;
    const Eigen::Vector3d q = mesh.vertices[tri[1]] - reference;
    const Eigen::Vector3d t = mesh.vertices[tri[2]] - reference;
    const double det = p.dot(q.cross(t));
    const Eigen::Vector3d s = p + q + t;
    six_volume += det;
    first_moment_24 += det * s;
    second_moment_120 += det * (p * p.transpose() + q * q.transpose() + t * t.transpose() + s * s.transpose());
  }

  result.volume = six_volume / 6.0;
  if (result.volume == 0) return result;
  const Eigen::Vector3d centroid_from_reference = (first_moment_24 / 24.0) / result.volume;
  result.centroid = reference + centroid_from_reference;

  // Covariance (integral of x x^T) about the centroid, then I = tr(C) 1 - C.
  const Eigen::Matrix3d covariance_about_centroid =
      second_moment_120 / 120.0 - result.volume * centroid_from_reference * centroid_from_reference.transpose();
  result.inertia_per_density =
      covariance_about_centroid.trace() * Eigen::Matrix3d::Identity() - covariance_about_centroid;
  return result;
}

TriangleMesh translated(const TriangleMesh& mesh, const Eigen::Vector3d& offset) {
  TriangleMesh out = mesh;
  for (Eigen::Vector3d& v : out.vertices) v += offset;
  return out;
}

}  // namespace telegrasp::sim
