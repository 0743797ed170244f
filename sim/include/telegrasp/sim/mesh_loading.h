// Reading object meshes from files and cleaning them for simulation.
#pragma once

#include "telegrasp/sim/triangle_mesh.h"

#include <stdexcept>
#include <string>

namespace telegrasp::sim {

/// A file could not be turned into a usable mesh; what() names the file and the problem.
class MeshLoadError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// What clean_mesh changed, for logs and tests.
struct MeshCleanReport {
  std::size_t vertices_welded = 0;  ///< Vertices merged into an earlier one.
  std::size_t degenerate_dropped = 0;  ///< Triangles with repeated or collinear corners removed.
  std::size_t duplicate_dropped = 0;  ///< Triangles identical to an earlier one removed.
};

/// Merges vertices closer than `weld_tolerance` (metres), drops degenerate and duplicate
/// triangles and unreferenced vertices. Triangle winding is preserved.
/// A back-to-back pair (same corners, opposite winding) bounds no volume: both are dropped and
/// counted in degenerate_dropped.
TriangleMesh clean_mesh(const TriangleMesh& mesh, double weld_tolerance = 1e-7, MeshCleanReport* report = nullptr);

/// Loads every triangle of every mesh in a file assimp reads (PLY, OBJ, STL, glTF, ...),
/// applying node transforms, then clean_mesh. Units are taken as metres.
/// Throws MeshLoadError for a missing or unreadable file, a file with no triangles, or
/// non-finite coordinates.
TriangleMesh load_mesh_file(const std::string& path);

/// True when `path` has an extension assimp can import (used to scan a folder).
bool is_mesh_file(const std::string& path);

}  // namespace telegrasp::sim
