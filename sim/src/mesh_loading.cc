// Mesh cleaning (welding, degenerate and duplicate removal) and file import through assimp.
#include "telegrasp/sim/mesh_loading.h"

#include <assimp/config.h>
#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <assimp/Importer.hpp>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <optional>
#include <sstream>
#include <string_view>
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

/// The weld grid's cell of `value` on one axis. Beyond +-4e18 cells (|value| above 4e11 m at the
/// 1e-7 m tolerance) neighbouring doubles lie hundreds of tolerances apart, so no two distinct
/// values there can weld: such a value gets a cell of its own from its bits, above the grid's
/// range (clamping them all into one cell made the weld quadratic: 16,300 such vertices in a
/// 64 KB PLY took 10 s, found by telegrasp-fuzz-mesh).
std::int64_t cell_coordinate(double value, double cell_size) {
  const double c = std::floor(value / cell_size);
  constexpr double kLimit = 4.0e18;
  if (std::abs(c) <= kLimit) return static_cast<std::int64_t>(c);
  std::uint64_t bits = 0;
  std::memcpy(&bits, &value, sizeof bits);
  const auto cell = static_cast<std::int64_t>(kLimit) + 2 + static_cast<std::int64_t>(bits & ((1ull << 62) - 1));
  return c > 0 ? cell : -cell;
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

constexpr std::uint64_t kU64Max = std::numeric_limits<std::uint64_t>::max();

std::uint64_t saturating_mul(std::uint64_t a, std::uint64_t b) {
  if (a != 0 && b > kU64Max / a) return kU64Max;
  return a * b;
}

std::uint64_t saturating_add(std::uint64_t a, std::uint64_t b) { return b > kU64Max - a ? kU64Max : a + b; }

/// Up to `max_bytes` from the start of the file.
std::string read_prefix(const std::string& path, std::size_t max_bytes) {
  std::ifstream in(path, std::ios::binary);
  std::string bytes(max_bytes, '\0');
  in.read(bytes.data(), static_cast<std::streamsize>(max_bytes));
  bytes.resize(static_cast<std::size_t>(std::max<std::streamsize>(in.gcount(), 0)));
  return bytes;
}

/// Bytes one binary PLY scalar of `type` takes (1 for a type assimp does not know either).
std::uint64_t ply_scalar_bytes(std::string_view type) {
  if (type == "short" || type == "ushort" || type == "int16" || type == "uint16") return 2;
  if (type == "int" || type == "uint" || type == "float" || type == "int32" || type == "uint32" || type == "float32")
    return 4;
  if (type == "double" || type == "float64") return 8;
  return 1;  // char, uchar, int8, uint8, unknown
}

/// The longest PLY header read; real ones are a few hundred bytes.
constexpr std::size_t kMaxPlyHeaderBytes = 64 * 1024;

/// A PLY file's header: every element's declared count must fit in the bytes after the header
/// (each element needs at least one byte per binary scalar, two per ascii value: a digit and a
/// separator), faces are capped at limits.max_triangles and vertices at three per triangle.
/// Throws MeshLoadError naming the element and its count. A file that is not a PLY is left alone.
/// `head`: the file's first kMaxPlyHeaderBytes. Returns where a binary PLY's data starts, 0 for an
/// ascii PLY or another file.
std::size_t check_ply_header(const std::string& path, const std::string& head, std::uint64_t file_size,
                             const MeshLoadLimits& limits) {
  std::string extension = std::filesystem::path(path).extension().string();
  std::transform(extension.begin(), extension.end(), extension.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  if (extension != ".ply" && head.compare(0, 3, "ply") != 0) return 0;  // not read as a PLY
  // assimp takes any file starting "ply" as one, and its header parser looped forever on a
  // ".ply" starting "plymat" (found by telegrasp-fuzz-mesh): the first line must be "ply".
  if (head.size() < 4 || head.compare(0, 3, "ply") != 0 || (head[3] != '\n' && head[3] != '\r')) {
    throw MeshLoadError(describe(path) + "not a PLY file: its first line must be 'ply'");
  }
  struct Element {
    std::string name;
    std::uint64_t count = 0;
    std::uint64_t binary_bytes = 0, ascii_bytes = 0;  // at least, per element
    int line = 0;
  };
  std::vector<Element> elements;
  bool ascii = true, header_ended = false;
  std::size_t pos = 0, body_start = head.size();
  int line_number = 0;
  while (pos < head.size()) {
    std::size_t end = head.find('\n', pos);
    if (end == std::string::npos) end = head.size();
    // assimp splits a header's words at spaces, tabs and line ends only, where the stream below
    // also splits at a vertical tab or form feed: "end_header\v" passed here and made assimp's
    // header parser loop for ever (found by telegrasp-fuzz-mesh). A header is plain text.
    for (std::size_t i = pos; i < end; ++i) {
      const auto c = static_cast<unsigned char>(head[i]);
      if ((c < 0x20 && c != '\t' && c != '\r') || c == 0x7f) {
        char code[8];
        std::snprintf(code, sizeof code, "0x%02x", c);
        throw MeshLoadError(describe(path) + "PLY header line " + std::to_string(line_number + 1) +
                            ": control character " + code + " (a header is plain text)");
      }
    }
    std::istringstream line(head.substr(pos, end - pos));
    pos = end + 1;
    ++line_number;
    std::string keyword;
    line >> keyword;
    if (keyword == "end_header") {
      header_ended = true;
      body_start = std::min(pos, head.size());
      break;
    }
    if (keyword == "format") {
      std::string format;
      line >> format;
      ascii = format == "ascii";
    } else if (keyword == "element") {
      Element e;
      std::string count;
      line >> e.name >> count;
      e.line = line_number;
      // assimp freed memory it had not allocated on a header declaring "face" twice (found by
      // telegrasp-fuzz-mesh): every element once.
      for (const Element& before : elements)
        if (before.name == e.name)
          throw MeshLoadError(describe(path) + "PLY header line " + std::to_string(line_number) + ": element '" +
                              e.name + "' is declared twice (first on line " + std::to_string(before.line) + ")");
      const auto [rest, error] = std::from_chars(count.data(), count.data() + count.size(), e.count);
      if (count.empty() || error != std::errc() || rest != count.data() + count.size()) {
        throw MeshLoadError(describe(path) + "PLY header line " + std::to_string(line_number) + ": element '" + e.name +
                            "' has count '" + count + "', not a non-negative integer");
      }
      elements.push_back(e);
    } else if (keyword == "property" && !elements.empty()) {
      std::string type;
      line >> type;
      // A list costs at least its length (an empty list); a scalar its size.
      if (type == "list") line >> type;
      elements.back().binary_bytes += ply_scalar_bytes(type);
      elements.back().ascii_bytes += 2;
    } else if (!keyword.empty() && keyword != "comment" && keyword != "obj_info" && keyword != "property" &&
               !(keyword == "ply" && line_number == 1)) {
      throw MeshLoadError(describe(path) + "PLY header line " + std::to_string(line_number) + ": unknown keyword '" +
                          keyword.substr(0, 32) + "'");
    }
  }
  if (!header_ended) {
    throw MeshLoadError(describe(path) + "PLY header has no end_header line in its first " +
                        std::to_string(kMaxPlyHeaderBytes) + " bytes");
  }
  const std::uint64_t body_bytes = file_size > body_start ? file_size - body_start : 0;
  std::uint64_t needed = 0;
  for (const Element& e : elements) {
    const std::string declares = "the PLY header declares " + std::to_string(e.count) + " " + e.name + " elements";
    if (e.name == "face" && e.count > limits.max_triangles) {
      throw MeshLoadError(describe(path) + declares + ", more than the limit of " +
                          std::to_string(limits.max_triangles) + " triangles");
    }
    if (e.name == "vertex" && e.count > saturating_mul(3, limits.max_triangles)) {
      throw MeshLoadError(describe(path) + declares + ", more than the limit of " +
                          std::to_string(saturating_mul(3, limits.max_triangles)) +
                          " (three per triangle of the limit of " + std::to_string(limits.max_triangles) +
                          " triangles)");
    }
    // An element with no property still takes a line (ascii) or is refused (binary, 1 byte).
    const std::uint64_t per_element = std::max<std::uint64_t>(ascii ? e.ascii_bytes : e.binary_bytes, 1);
    const std::uint64_t element_bytes = saturating_mul(e.count, per_element);
    needed = saturating_add(needed, element_bytes);
    // Ascii: the last value of the file needs no separator after it.
    if (needed > saturating_add(body_bytes, ascii ? 1 : 0)) {
      throw MeshLoadError(describe(path) + declares + " (line " + std::to_string(e.line) + "), which need at least " +
                          std::to_string(element_bytes) + " bytes, but the file has " + std::to_string(body_bytes) +
                          " bytes after its header in all");
    }
  }
  return ascii ? 0 : body_start;
}

/// assimp skips a line end after a binary PLY's "end_header\n" even when it is the data's first
/// byte (assimp issue 5341), and then reads the file one byte off: it refused or, worse, misread
/// the 1 in 256 binary PLYs whose data starts with the byte 0x0a, such as those whose first float's
/// lowest byte it is. It reads "end_header\r\n" right. Returns such a file with its end_header
/// line ended so, nothing for any other file. `head` and `binary_data_start` as check_ply_header.
std::optional<std::string> ply_for_assimp(const std::string& path, const std::string& head,
                                          std::size_t binary_data_start) {
  if (binary_data_start < 2) return std::nullopt;  // not a binary PLY
  if (head.size() <= binary_data_start || head[binary_data_start] != '\n' || head[binary_data_start - 2] == '\r')
    return std::nullopt;
  std::ifstream in(path, std::ios::binary);
  std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  bytes.insert(binary_data_start - 1, 1, '\r');
  return bytes;
}

/// A binary STL's facet count (at byte 80) against the file's size (50 bytes a facet after an
/// 84-byte header) and limits.max_triangles. Ascii STL (starting "solid", of a size that is not
/// exactly a binary one's) and other files are left alone. `head`: the file's first bytes (84 or more).
void check_stl_header(const std::string& path, const std::string& head, std::uint64_t file_size,
                      const MeshLoadLimits& limits) {
  std::string extension = std::filesystem::path(path).extension().string();
  std::transform(extension.begin(), extension.end(), extension.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  if (extension != ".stl" || file_size < 84) return;
  if (head.size() < 84) return;
  std::uint64_t facets = 0;
  for (int i = 3; i >= 0; --i) facets = (facets << 8) | static_cast<unsigned char>(head[80 + i]);
  const std::uint64_t binary_size = 84 + 50 * facets;
  if (head.compare(0, 5, "solid") == 0 && binary_size != file_size) return;  // ascii
  if (facets > limits.max_triangles) {
    throw MeshLoadError(describe(path) + "the binary STL declares " + std::to_string(facets) +
                        " facets, more than the limit of " + std::to_string(limits.max_triangles) + " triangles");
  }
  if (binary_size > file_size) {
    throw MeshLoadError(describe(path) + "the binary STL declares " + std::to_string(facets) + " facets, which need " +
                        std::to_string(binary_size) + " bytes, but the file has " + std::to_string(file_size));
  }
}

/// Appends the triangles of `node` and its children, in scene coordinates. Throws MeshLoadError
/// naming `path` once the faces (a mesh counts once per node that places it) pass `max_triangles`.
void collect_node(const aiScene& scene, const aiNode& node, const aiMatrix4x4& parent_transform,
                  std::uint64_t max_triangles, const std::string& path, TriangleMesh& out) {
  const aiMatrix4x4 transform = parent_transform * node.mTransformation;
  for (unsigned m = 0; m < node.mNumMeshes; ++m) {
    const aiMesh& mesh = *scene.mMeshes[node.mMeshes[m]];
    if (out.triangles.size() + mesh.mNumFaces > max_triangles) {
      throw MeshLoadError(describe(path) + "holds at least " + std::to_string(out.triangles.size() + mesh.mNumFaces) +
                          " faces, over the limit of " + std::to_string(max_triangles) + " triangles");
    }
    // Keep only triangles (points and lines are not surfaces); remember which vertices are used.
    const std::size_t base = out.vertices.size();
    for (unsigned v = 0; v < mesh.mNumVertices; ++v) {
      const aiVector3D p = transform * mesh.mVertices[v];
      out.vertices.emplace_back(p.x, p.y, p.z);
    }
    for (unsigned f = 0; f < mesh.mNumFaces; ++f) {
      const aiFace& face = mesh.mFaces[f];
      // Points and lines are not surfaces. ValidateDataStructure refuses an index past the mesh
      // (it would point into another); skipped here too.
      bool in_range = face.mNumIndices >= 3;
      for (unsigned k = 0; k < face.mNumIndices && in_range; ++k) in_range = face.mIndices[k] < mesh.mNumVertices;
      if (!in_range) continue;
      // A polygon as a fan from its first corner (exact for the convex faces exporters write).
      for (unsigned k = 1; k + 1 < face.mNumIndices; ++k) {
        if (out.triangles.size() >= max_triangles) {
          throw MeshLoadError(describe(path) + "holds more than " + std::to_string(max_triangles) +
                              " triangles, over the limit of " + std::to_string(max_triangles) + " triangles");
        }
        out.triangles.push_back({static_cast<std::uint32_t>(base + face.mIndices[0]),
                                 static_cast<std::uint32_t>(base + face.mIndices[k]),
                                 static_cast<std::uint32_t>(base + face.mIndices[k + 1])});
      }
    }
  }
  for (unsigned c = 0; c < node.mNumChildren; ++c) {
    collect_node(scene, *node.mChildren[c], transform, max_triangles, path, out);
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

TriangleMesh load_mesh_file(const std::string& path, const MeshLoadLimits& limits) {
  std::error_code ec;
  if (!std::filesystem::exists(path, ec)) throw MeshLoadError(describe(path) + "file not found");
  if (!std::filesystem::is_regular_file(path, ec)) {
    throw MeshLoadError(describe(path) + "not a regular file");
  }
  const std::uint64_t file_size = std::filesystem::file_size(path, ec);
  if (ec) throw MeshLoadError(describe(path) + "cannot read its size: " + ec.message());
  // Declared counts first: assimp reserves what a header declares before reading the data.
  const std::string head = read_prefix(path, kMaxPlyHeaderBytes);
  const std::size_t ply_binary_data = check_ply_header(path, head, file_size, limits);
  check_stl_header(path, head, file_size, limits);
  Assimp::Importer importer;
  // No JoinIdenticalVertices: clean_mesh does all welding, so its report counts every
  // coincident vertex the file contains. Points and lines are skipped in collect_node.
  // Keep coordinates as written (the simulation is +Z up): no Collada Z-up to Y-up rotation.
  importer.SetPropertyBool(AI_CONFIG_IMPORT_COLLADA_IGNORE_UP_DIRECTION, true);
  // Only ValidateDataStructure: a face index past its mesh's vertices (a hostile PLY) made
  // assimp's Triangulate read out of bounds (SEGV), another PLY made it abort; validation
  // refuses such files and collect_node triangulates.
  const std::optional<std::string> ply = ply_for_assimp(path, head, ply_binary_data);
  const aiScene* scene =
      ply ? importer.ReadFileFromMemory(ply->data(), ply->size(), aiProcess_ValidateDataStructure, "ply")
          : importer.ReadFile(path, aiProcess_ValidateDataStructure);
  if (scene == nullptr) {
    throw MeshLoadError(describe(path) + "assimp could not read it: " + importer.GetErrorString());
  }
  TriangleMesh raw;
  if (scene->mRootNode != nullptr)
    collect_node(*scene, *scene->mRootNode, aiMatrix4x4(), limits.max_triangles, path, raw);
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
