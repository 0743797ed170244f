// Reading object meshes from files and cleaning them for simulation.
#pragma once

#include "telegrasp/sim/triangle_mesh.h"

#include <cstdint>
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

/// Triangles a mesh file may hold by default: far above any graspable object (the YCB scans have
/// at most ~300,000) and far below what exhausts memory (assimp needs ~100 bytes per triangle).
inline constexpr std::uint64_t kDefaultMaxMeshTriangles = 2'000'000;

/// What load_mesh_file accepts, checked before assimp allocates anything the file declares.
struct MeshLoadLimits {
  /// Most triangles a file may declare (PLY faces, binary STL facets) or contain after
  /// triangulation; a PLY may declare at most three vertices per allowed triangle.
  std::uint64_t max_triangles = kDefaultMaxMeshTriangles;
};

/// Loads every triangle of every mesh in a file assimp reads (PLY, OBJ, STL, glTF, ...),
/// applying node transforms, then clean_mesh. Units are taken as metres.
/// Before assimp reads it, the element counts a PLY header or a binary STL declares are checked
/// against the file's size (each element needs at least its properties' bytes) and `limits`.
/// Throws MeshLoadError for a missing or unreadable file, declared counts the file cannot hold or
/// over the limits (naming the count), a file with no triangles, or non-finite coordinates.
TriangleMesh load_mesh_file(const std::string& path, const MeshLoadLimits& limits = {});

/// True when `path` has an extension assimp can import (used to scan a folder).
bool is_mesh_file(const std::string& path);

}  // namespace telegrasp::sim
