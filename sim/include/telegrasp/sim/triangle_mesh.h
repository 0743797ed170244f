// Triangle meshes: the one geometry type shared by loading, distance queries and physics.
#pragma once

#include <Eigen/Core>

#include <array>
#include <cstdint>
#include <vector>

namespace telegrasp::sim {

/// An indexed triangle mesh in metres, in its own (object) frame.
struct TriangleMesh {
  std::vector<Eigen::Vector3d> vertices;
  std::vector<std::array<std::uint32_t, 3>> triangles;  ///< Counter-clockwise seen from outside.

  /// Axis-aligned bounds of the vertices; {0,0} for an empty mesh.
  [[nodiscard]] Eigen::Vector3d min_corner() const;
  [[nodiscard]] Eigen::Vector3d max_corner() const;
};

}  // namespace telegrasp::sim
