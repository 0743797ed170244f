// Mesh cleaning (welding, degenerate and duplicate removal) and file import through assimp.
#include "telegrasp/sim/mesh_loading.h"

#include <assimp/config.h>
#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <assimp/Importer.hpp>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <limits>
#include <unordered_map>
#include <unordered_set>

namespace telegrasp::sim {
namespace {

/// Triangles smaller than this (m^2) count as degenerate.
constexpr double kMinTriangleArea = 1e-14;

struct CellKey {
  std::int64_t x, y, z;
  bool operator==(const CellKey&) const = default;
};

struct CellKeyHash {
  std::size_t operator()(const CellKey& k) const noexcept {
    std::uint64_t h = static_cast<std::uint64_t>(k.x) * 0x9E3779B97F4A7C15ull;
    h ^= static_cast<std::uint64_t>(k.y) * 0xC2B2AE3D27D4EB4Full + (h << 6) + (h >> 2);
    h ^= static_cast<std::uint64_t>(k.z) * 0x165667B19E3779F9ull + (h << 6) + (h >> 2);
    return static_cast<std::size_t>(h);
  }
};

std::int64_t cell_coordinate(double value, double cell_size) {
  const double c = std::floor(value / cell_size);
  constexpr double kLimit = 4.0e18;
  return static_cast<std::int64_t>(std::clamp(c, -kLimit, kLimit));
}

/// Maps every vertex to the first earlier vertex within `tolerance` (itself if none).
std::vector<std::uint32_t> weld_map(const std::vector<Eigen::Vector3d>& vertices, double tolerance,
                                    std::size_t* welded) {
  std::vector<std::uint32_t> representative(vertices.size());
  std::unordered_map<CellKey, std::vector<std::uint32_t>, CellKeyHash> grid;
  grid.reserve(vertices.size());
  // With a zero tolerance only bit-identical positions merge; cell size is then irrelevant.
  const double cell_size = tolerance > 0 ? tolerance : 1.0;
  const double tolerance_sq = tolerance * tolerance;
  *welded = 0;
  for (std::uint32_t i = 0; i < vertices.size(); ++i) {
    const Eigen::Vector3d& p = vertices[i];
    representative[i] = i;
    if (!p.allFinite()) continue;  // Never merge non-finite points; they stay as they are.
    const CellKey home{cell_coordinate(p.x(), cell_size), cell_coordinate(p.y(), cell_size),
                       cell_coordinate(p.z(), cell_size)};
    bool found = false;
    for (int dx = -1; dx <= 1 && !found; ++dx) {
      for (int dy = -1; dy <= 1 && !found; ++dy) {
        for (int dz = -1; dz <= 1 && !found; ++dz) {
          auto it = grid.find(CellKey{home.x + dx, home.y + dy, home.z + dz});
          if (it == grid.end()) continue;
          for (std::uint32_t j : it->second) {
            if ((vertices[j] - p).squaredNorm() <= tolerance_sq) {
              representative[i] = j;
              found = true;
              break;
            }
          }
        }
      }
    }
    if (found) {
      ++*welded;
    } else {
      grid[home].push_back(i);
    }
  }
  return representative;
}

/// Same triangle up to a cyclic rotation (which keeps the winding).
std::array<std::uint32_t, 3> canonical_rotation(const std::array<std::uint32_t, 3>& t) {
  if (t[1] < t[0] && t[1] < t[2]) return {t[1], t[2], t[0]};
  if (t[2] < t[0] && t[2] < t[1]) return {t[2], t[0], t[1]};
  return t;
}

struct TriangleHash {
  std::size_t operator()(const std::array<std::uint32_t, 3>& t) const noexcept {
    std::uint64_t h = t[0];
    h = h * 0x9E3779B97F4A7C15ull + t[1];
    h = h * 0x9E3779B97F4A7C15ull + t[2];
    return static_cast<std::size_t>(h ^ (h >> 29));
  }
};

std::string describe(const std::string& path) { return "mesh file '" + path + "': "; }

/// Appends the triangles of `node` and its children, in scene coordinates.
void collect_node(const aiScene& scene, const aiNode& node, const aiMatrix4x4& parent_transform, TriangleMesh& out) {
  const aiMatrix4x4 transform = parent_transform * node.mTransformation;
  for (unsigned m = 0; m < node.mNumMeshes; ++m) {
    const aiMesh& mesh = *scene.mMeshes[node.mMeshes[m]];
    // Keep only triangles (points and lines are not surfaces); remember which vertices are used.
    const std::size_t base = out.vertices.size();
    for (unsigned v = 0; v < mesh.mNumVertices; ++v) {
      const aiVector3D p = transform * mesh.mVertices[v];
      out.vertices.emplace_back(p.x, p.y, p.z);
    }
    for (unsigned f = 0; f < mesh.mNumFaces; ++f) {
      const aiFace& face = mesh.mFaces[f];
      if (face.mNumIndices != 3) continue;
      out.triangles.push_back({static_cast<std::uint32_t>(base + face.mIndices[0]),
                               static_cast<std::uint32_t>(base + face.mIndices[1]),
                               static_cast<std::uint32_t>(base + face.mIndices[2])});
    }
  }
  for (unsigned c = 0; c < node.mNumChildren; ++c) {
    collect_node(scene, *node.mChildren[c], transform, out);
  }
}

}  // namespace

TriangleMesh clean_mesh(const TriangleMesh& mesh, double weld_tolerance, MeshCleanReport* report) {
  MeshCleanReport local;
  const std::vector<std::uint32_t> representative =
      weld_map(mesh.vertices, std::max(weld_tolerance, 0.0), &local.vertices_welded);

  std::vector<std::array<std::uint32_t, 3>> kept;  // In original vertex numbering.
  std::vector<bool> alive;  // False once cancelled by a back-to-back twin.
  kept.reserve(mesh.triangles.size());
  alive.reserve(mesh.triangles.size());
  std::unordered_set<std::array<std::uint32_t, 3>, TriangleHash> seen;  // Every winding met.
  std::unordered_map<std::array<std::uint32_t, 3>, std::size_t, TriangleHash> live;  // -> kept index
  seen.reserve(mesh.triangles.size());
  live.reserve(mesh.triangles.size());
  for (const auto& original : mesh.triangles) {
    if (original[0] >= mesh.vertices.size() || original[1] >= mesh.vertices.size() ||
        original[2] >= mesh.vertices.size()) {
      ++local.degenerate_dropped;  // An index past the end cannot form a triangle.
      continue;
    }
    const std::array<std::uint32_t, 3> t{representative[original[0]], representative[original[1]],
                                         representative[original[2]]};
    if (t[0] == t[1] || t[1] == t[2] || t[2] == t[0]) {
      ++local.degenerate_dropped;
      continue;
    }
    const Eigen::Vector3d& a = mesh.vertices[t[0]];
    const double twice_area = (mesh.vertices[t[1]] - a).cross(mesh.vertices[t[2]] - a).norm();
    if (!(0.5 * twice_area >= kMinTriangleArea)) {  // Also catches NaN.
      ++local.degenerate_dropped;
      continue;
    }
    const std::array<std::uint32_t, 3> key = canonical_rotation(t);
    if (!seen.insert(key).second) {
      ++local.duplicate_dropped;
      continue;
    }
    // Same corners, opposite winding: a zero-volume fin (welding two touching scan sheets
    // makes these); neither side bounds the solid, so both go.
    const auto twin = live.find(canonical_rotation({t[0], t[2], t[1]}));
    if (twin != live.end()) {
      alive[twin->second] = false;
      live.erase(twin);
      local.degenerate_dropped += 2;
      continue;
    }
    live.emplace(key, kept.size());
    kept.push_back(t);
    alive.push_back(true);
  }
  std::size_t write = 0;
  for (std::size_t i = 0; i < kept.size(); ++i) {
    if (alive[i]) kept[write++] = kept[i];
  }
  kept.resize(write);

  // Compact: keep referenced vertices in their original order.
  constexpr std::uint32_t kUnused = std::numeric_limits<std::uint32_t>::max();
  std::vector<std::uint32_t> new_index(mesh.vertices.size(), kUnused);
  for (const auto& t : kept) {
    for (std::uint32_t v : t) new_index[v] = 0;
  }
  TriangleMesh out;
  for (std::uint32_t v = 0; v < mesh.vertices.size(); ++v) {
    if (new_index[v] == kUnused) continue;
    new_index[v] = static_cast<std::uint32_t>(out.vertices.size());
    out.vertices.push_back(mesh.vertices[v]);
  }
  out.triangles.reserve(kept.size());
  for (const auto& t : kept) out.triangles.push_back({new_index[t[0]], new_index[t[1]], new_index[t[2]]});

  if (report != nullptr) *report = local;
  return out;
}

TriangleMesh load_mesh_file(const std::string& path) {
  std::error_code ec;
  if (!std::filesystem::exists(path, ec)) throw MeshLoadError(describe(path) + "file not found");
  if (!std::filesystem::is_regular_file(path, ec)) {
    throw MeshLoadError(describe(path) + "not a regular file");
  }
  Assimp::Importer importer;
  // No JoinIdenticalVertices: clean_mesh does all welding, so its report counts every
  // coincident vertex the file contains. Points and lines are skipped in collect_node.
  // Keep coordinates as written (the simulation is +Z up): no Collada Z-up to Y-up rotation.
  importer.SetPropertyBool(AI_CONFIG_IMPORT_COLLADA_IGNORE_UP_DIRECTION, true);
  const aiScene* scene = importer.ReadFile(path, aiProcess_Triangulate);
  if (scene == nullptr) {
    throw MeshLoadError(describe(path) + "assimp could not read it: " + importer.GetErrorString());
  }
  TriangleMesh raw;
  if (scene->mRootNode != nullptr) collect_node(*scene, *scene->mRootNode, aiMatrix4x4(), raw);
  if (raw.triangles.empty()) throw MeshLoadError(describe(path) + "contains no triangle mesh");
  std::vector<bool> referenced(raw.vertices.size(), false);
  for (const auto& triangle : raw.triangles) {
    for (std::uint32_t v : triangle) referenced[v] = true;
  }
  for (std::size_t v = 0; v < raw.vertices.size(); ++v) {
    if (referenced[v] && !raw.vertices[v].allFinite()) {
      throw MeshLoadError(describe(path) + "non-finite vertex coordinate at vertex " + std::to_string(v));
    }
  }
  TriangleMesh cleaned = clean_mesh(raw);
  if (cleaned.triangles.empty()) {
    throw MeshLoadError(describe(path) + "contains no triangle mesh (all triangles degenerate)");
  }
  return cleaned;
}

bool is_mesh_file(const std::string& path) {
  const std::string extension = std::filesystem::path(path).extension().string();
  if (extension.empty()) return false;
  Assimp::Importer importer;
  return importer.IsExtensionSupported(extension);
}

}  // namespace telegrasp::sim
