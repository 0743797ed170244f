// Bounding box of a triangle mesh.
#include "telegrasp/sim/triangle_mesh.h"

namespace telegrasp::sim {

Eigen::Vector3d TriangleMesh::min_corner() const {
  if (vertices.empty()) return Eigen::Vector3d::Zero();
  Eigen::Vector3d lo = vertices.front();
  for (const Eigen::Vector3d& v : vertices) lo = lo.cwiseMin(v);
  return lo;
}

Eigen::Vector3d TriangleMesh::max_corner() const {
  if (vertices.empty()) return Eigen::Vector3d::Zero();
  Eigen::Vector3d hi = vertices.front();
  for (const Eigen::Vector3d& v : vertices) hi = hi.cwiseMax(v);
  return hi;
}

}  // namespace telegrasp::sim
