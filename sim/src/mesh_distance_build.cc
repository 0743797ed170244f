// MeshDistance's construction: the binned-SAH BVH of axis-aligned boxes in a flat vector
// (children adjacent, at most four triangles per leaf where SAH agrees), an oriented box
// (principal axes) beside the nodes where it is markedly tighter (thin or flat patches of a
// tilted mesh), triangle data stored in leaf order, and the angle-weighted pseudo-normals of
// Baerentzen & Aanaes (2005) for the sign of the distance (vertices welded by exact position, so
// duplicated vertices do not create false boundaries). The queries are in mesh_distance.cc.
#include "telegrasp/sim/mesh_distance.h"

#include "mesh_primitives.h"

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <optional>
#include <stdexcept>
#include <tuple>
#include <unordered_map>
#include <utility>

namespace telegrasp::sim {
using namespace mesh_detail;
namespace {

/// Exact-bit key of a position, for welding duplicated vertices.
struct PositionKey {
  std::uint64_t bits[3];
  bool operator==(const PositionKey& o) const {
    return bits[0] == o.bits[0] && bits[1] == o.bits[1] && bits[2] == o.bits[2];
  }
};
struct PositionKeyHash {
  std::size_t operator()(const PositionKey& k) const {
    std::uint64_t h = 1469598103934665603ULL;
    for (std::uint64_t b : k.bits) h = (h ^ b) * 1099511628211ULL + (h >> 29);
    return static_cast<std::size_t>(h);
  }
};
PositionKey position_key(const Vector3d& p) {
  PositionKey k{};
  for (int i = 0; i < 3; ++i) {
    const double x = p[i] + 0.0;  // folds -0 onto +0
    std::memcpy(&k.bits[i], &x, sizeof(double));
  }
  return k;
}

Vector3d normalized_or(const Vector3d& v, const Vector3d& fallback) {
  const double n = v.norm();
  return n > 0 ? Vector3d(v / n) : fallback;
}

double half_area(const Vector3d& lo, const Vector3d& hi) {
  const Vector3d e = (hi - lo).cwiseMax(0.0);
  return e.x() * e.y() + e.y() * e.z() + e.z() * e.x();
}

/// Throws std::invalid_argument unless `mesh` has triangles, all indexing its vertices.
void check_mesh(const TriangleMesh& mesh) {
  if (mesh.triangles.empty()) throw std::invalid_argument("MeshDistance: mesh has no triangles");
  const std::size_t nv = mesh.vertices.size();
  for (const auto& t : mesh.triangles) {
    for (std::uint32_t i : t) {
      if (i >= nv) throw std::invalid_argument("MeshDistance: triangle index out of range");
    }
  }
  if (mesh.triangles.size() >= std::numeric_limits<std::uint32_t>::max() / 2) {
    throw std::invalid_argument("MeshDistance: too many triangles");
  }
}

/// Per input triangle: its box and centroid, what the BVH build sorts.
struct TriangleBounds {
  std::vector<Vector3d> lo, hi, centroid;
};

TriangleBounds triangle_bounds(const TriangleMesh& mesh) {
  const std::size_t nt = mesh.triangles.size();
  TriangleBounds out{std::vector<Vector3d>(nt), std::vector<Vector3d>(nt), std::vector<Vector3d>(nt)};
  for (std::size_t i = 0; i < nt; ++i) {
    const auto& t = mesh.triangles[i];
    const Vector3d& a = mesh.vertices[t[0]];
    const Vector3d& b = mesh.vertices[t[1]];
    const Vector3d& c = mesh.vertices[t[2]];
    out.lo[i] = a.cwiseMin(b).cwiseMin(c);
    out.hi[i] = a.cwiseMax(b).cwiseMax(c);
    out.centroid[i] = (a + b + c) / 3.0;
  }
  return out;
}

/// The box of a range of triangles and the box of their centroids.
struct RangeBounds {
  Vector3d lo{kInf, kInf, kInf}, hi{-kInf, -kInf, -kInf};
  Vector3d centroid_lo{kInf, kInf, kInf}, centroid_hi{-kInf, -kInf, -kInf};
};

RangeBounds range_bounds(const TriangleBounds& bounds, const std::vector<std::uint32_t>& order, std::uint32_t begin,
                         std::uint32_t end) {
  RangeBounds r;
  for (std::uint32_t i = begin; i < end; ++i) {
    const std::uint32_t t = order[i];
    r.lo = r.lo.cwiseMin(bounds.lo[t]);
    r.hi = r.hi.cwiseMax(bounds.hi[t]);
    r.centroid_lo = r.centroid_lo.cwiseMin(bounds.centroid[t]);
    r.centroid_hi = r.centroid_hi.cwiseMax(bounds.centroid[t]);
  }
  return r;
}

/// Stores box [lo, hi] rounded outwards to float in flo / fhi; returns the rounded-up half
/// diagonal of the float box (a node's `radius`).
float store_rounded_box(const Vector3d& lo, const Vector3d& hi, float* flo, float* fhi) {
  Vector3d dlo, dhi;
  for (int i = 0; i < 3; ++i) {
    flo[i] = round_down(lo[i]);
    fhi[i] = round_up(hi[i]);
    dlo[i] = flo[i];
    dhi[i] = fhi[i];
  }
  return round_up(0.5 * (dhi - dlo).norm() * (1 + 1e-9) + 1e-12);
}

/// The principal axes of a range's triangle corners (their covariance's eigenvectors, as rows),
/// or the coordinate axes when that fails.
Eigen::Matrix3d principal_axes(const TriangleMesh& mesh, const std::vector<std::uint32_t>& order, std::uint32_t begin,
                               std::uint32_t end) {
  Vector3d mean = Vector3d::Zero();
  for (std::uint32_t i = begin; i < end; ++i)
    for (std::uint32_t v : mesh.triangles[order[i]]) mean += mesh.vertices[v];
  mean /= 3.0 * (end - begin);
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  for (std::uint32_t i = begin; i < end; ++i)
    for (std::uint32_t v : mesh.triangles[order[i]]) {
      const Vector3d d = mesh.vertices[v] - mean;
      cov += d * d.transpose();
    }
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(cov);
  if (eig.info() != Eigen::Success || !eig.eigenvectors().allFinite()) return Eigen::Matrix3d::Identity();
  return eig.eigenvectors().transpose();
}

/// Stores a range's oriented box: float axes (principal axes) and the extents of its corners'
/// projections relative to `centre`, rounded outwards.
void store_oriented_box(const TriangleMesh& mesh, const std::vector<std::uint32_t>& order, std::uint32_t begin,
                        std::uint32_t end, const Vector3d& centre, float (*axes)[3], float* lo, float* hi) {
  const Eigen::Matrix3d u = principal_axes(mesh, order, begin, end);
  for (int i = 0; i < 3; ++i) {
    for (int k = 0; k < 3; ++k) axes[i][k] = static_cast<float>(u(i, k));
    double l = kInf;
    double h = -kInf;
    for (std::uint32_t t = begin; t < end; ++t)
      for (std::uint32_t v : mesh.triangles[order[t]]) {
        const Vector3d x = mesh.vertices[v] - centre;
        const double y = double{axes[i][0]} * x[0] + double{axes[i][1]} * x[1] + double{axes[i][2]} * x[2];
        l = std::min(l, y);
        h = std::max(h, y);
      }
    lo[i] = round_down(l);
    hi[i] = round_up(h);
  }
}

/// An oriented box is worth testing beside the axis-aligned one when this much smaller.
constexpr double kOrientedGain = 0.5;

/// Volume of box [lo, hi], each side taken at least 1e-6 of the largest (flat boxes compare by area).
double volume_with_floor(const float* lo, const float* hi) {
  const Vector3d e(double{hi[0]} - lo[0], double{hi[1]} - lo[1], double{hi[2]} - lo[2]);
  const Vector3d f = e.cwiseMax(1e-6 * e.maxCoeff());
  return f.x() * f.y() * f.z();
}

/// kBins equal slices of a range's centroid extent along one axis.
struct CentroidBins {
  int axis;
  double origin;  // lowest centroid coordinate
  double scale;  // kBins / extent
  [[nodiscard]] int operator()(const Vector3d& centroid) const {
    return std::min(kBins - 1, static_cast<int>((centroid[axis] - origin) * scale));
  }
};

/// The cheapest SAH split between centroid bins: left = bins below `bin` (-1: none splits).
struct SahSplit {
  double cost = kInf;
  int bin = -1;
};

SahSplit best_sah_split(const TriangleBounds& bounds, const std::vector<std::uint32_t>& order, std::uint32_t begin,
                        std::uint32_t end, const CentroidBins& bin_of) {
  struct Bin {
    Vector3d lo{kInf, kInf, kInf};
    Vector3d hi{-kInf, -kInf, -kInf};
    std::uint32_t count = 0;
  };
  Bin bins[kBins];
  for (std::uint32_t i = begin; i < end; ++i) {
    const std::uint32_t t = order[i];
    Bin& b = bins[bin_of(bounds.centroid[t])];
    b.lo = b.lo.cwiseMin(bounds.lo[t]);
    b.hi = b.hi.cwiseMax(bounds.hi[t]);
    ++b.count;
  }
  double right_cost[kBins];
  {
    Vector3d rlo(kInf, kInf, kInf), rhi(-kInf, -kInf, -kInf);
    std::uint32_t rc = 0;
    for (int i = kBins - 1; i > 0; --i) {
      rlo = rlo.cwiseMin(bins[i].lo);
      rhi = rhi.cwiseMax(bins[i].hi);
      rc += bins[i].count;
      right_cost[i] = rc > 0 ? rc * half_area(rlo, rhi) : 0.0;
    }
  }
  const std::uint32_t count = end - begin;
  SahSplit best;
  Vector3d llo(kInf, kInf, kInf), lhi(-kInf, -kInf, -kInf);
  std::uint32_t lc = 0;
  for (int i = 1; i < kBins; ++i) {
    llo = llo.cwiseMin(bins[i - 1].lo);
    lhi = lhi.cwiseMax(bins[i - 1].hi);
    lc += bins[i - 1].count;
    if (lc == 0 || lc == count) continue;
    const double cost = lc * half_area(llo, lhi) + right_cost[i];
    if (cost < best.cost) {
      best.cost = cost;
      best.bin = i;
    }
  }
  return best;
}

/// Where to split order[begin, end) in two, reordering it: at the cheapest binned-SAH plane
/// along the centroids' widest axis, else at the median; nullopt (make a leaf) when the range is
/// small enough and SAH finds no split cheaper than a leaf.
std::optional<std::uint32_t> split_point(const TriangleBounds& bounds, const RangeBounds& range,
                                         std::vector<std::uint32_t>& order, std::uint32_t begin, std::uint32_t end) {
  const std::uint32_t count = end - begin;
  const Vector3d cext = range.centroid_hi - range.centroid_lo;
  int axis = 0;
  if (cext[1] > cext[axis]) axis = 1;
  if (cext[2] > cext[axis]) axis = 2;
  std::uint32_t mid = begin + count / 2;
  if (!(cext[axis] > 0)) return mid;  // all centroids coincide: any split is as good
  const CentroidBins bin_of{axis, range.centroid_lo[axis], kBins / cext[axis]};
  const SahSplit sah = best_sah_split(bounds, order, begin, end, bin_of);
  const double leaf_cost = count * half_area(range.lo, range.hi);
  if (count <= kMaxSahLeafSize && sah.cost >= leaf_cost) return std::nullopt;
  if (sah.bin > 0) {
    auto* it = std::partition(order.data() + begin, order.data() + end,
                              [&](std::uint32_t t) { return bin_of(bounds.centroid[t]) < sah.bin; });
    mid = static_cast<std::uint32_t>(it - order.data());
  }
  if (mid == begin || mid == end) {
    mid = begin + count / 2;
    std::nth_element(
        order.begin() + begin, order.begin() + mid, order.begin() + end,
        [&](std::uint32_t x, std::uint32_t y) { return bounds.centroid[x][axis] < bounds.centroid[y][axis]; });
  }
  return mid;
}

/// For each vertex, the first vertex at its exact position (welding duplicated vertices).
std::vector<std::uint32_t> weld_vertices(const std::vector<Vector3d>& vertices) {
  const std::size_t nv = vertices.size();
  std::vector<std::uint32_t> weld(nv);
  std::unordered_map<PositionKey, std::uint32_t, PositionKeyHash> first_of;
  first_of.reserve(nv);
  for (std::size_t i = 0; i < nv; ++i) {
    weld[i] = first_of.emplace(position_key(vertices[i]), static_cast<std::uint32_t>(i)).first->second;
  }
  return weld;
}

}  // namespace

MeshDistance::MeshDistance(const TriangleMesh& mesh) {
  check_mesh(mesh);
  vertices_ = mesh.vertices;
  const std::vector<std::uint32_t> order = build_bvh(mesh);
  store_in_leaf_order(mesh, order);
  build_pseudo_normals();
  vertices_.shrink_to_fit();
}

/// BVH over triangle boxes (binned SAH), leaves referencing ranges of the returned order: a work
/// list of node ranges, each made a leaf or split in two children appended next to each other.
std::vector<std::uint32_t> MeshDistance::build_bvh(const TriangleMesh& mesh) {
  const std::size_t nt = mesh.triangles.size();
  const TriangleBounds bounds = triangle_bounds(mesh);
  std::vector<std::uint32_t> order(nt);
  for (std::size_t i = 0; i < nt; ++i) order[i] = static_cast<std::uint32_t>(i);

  struct Task {
    std::uint32_t node, begin, end;
    int depth;
  };
  std::vector<Task> tasks;
  nodes_.reserve(2 * nt / kLeafSize + 1);
  nodes_.emplace_back();
  tasks.push_back({0, 0, static_cast<std::uint32_t>(nt), 0});
  while (!tasks.empty()) {
    const Task task = tasks.back();
    tasks.pop_back();
    const RangeBounds range = range_bounds(bounds, order, task.begin, task.end);
    {
      Node& n = nodes_[task.node];
      n.radius = store_rounded_box(range.lo, range.hi, n.lo, n.hi);
      OrientedBoxData o;
      store_oriented_box(mesh, order, task.begin, task.end, box_centre(n.lo, n.hi), o.axes, o.lo, o.hi);
      if (volume_with_floor(o.lo, o.hi) < kOrientedGain * volume_with_floor(n.lo, n.hi)) {
        n.oriented = static_cast<std::uint32_t>(oriented_boxes_.size());
        oriented_boxes_.push_back(o);
      }
    }
    const std::uint32_t count = task.end - task.begin;
    const std::optional<std::uint32_t> mid = count <= kLeafSize || task.depth >= kMaxDepth
                                                 ? std::nullopt
                                                 : split_point(bounds, range, order, task.begin, task.end);
    if (!mid) {
      nodes_[task.node].first = task.begin;
      nodes_[task.node].count = count;
      continue;
    }
    const auto left = static_cast<std::uint32_t>(nodes_.size());
    nodes_.emplace_back();
    nodes_.emplace_back();
    nodes_[task.node].first = left;
    nodes_[task.node].count = 0;
    tasks.push_back({left + 1, *mid, task.end, task.depth + 1});
    tasks.push_back({left, task.begin, *mid, task.depth + 1});
  }
  nodes_.shrink_to_fit();
  oriented_boxes_.shrink_to_fit();
  return order;
}

/// Per-triangle data in leaf order: indices, corners, face normals and bounding spheres by slot.
void MeshDistance::store_in_leaf_order(const TriangleMesh& mesh, const std::vector<std::uint32_t>& order) {
  const std::size_t nt = order.size();
  triangle_ids_ = order;
  slot_of_triangle_.assign(order.size(), 0);
  for (std::uint32_t s = 0; s < order.size(); ++s) slot_of_triangle_[order[s]] = s;
  triangles_.resize(nt);
  corners_.resize(nt);
  face_normals_.resize(nt);
  bounding_spheres_.resize(nt);
  for (std::size_t s = 0; s < nt; ++s) {
    const auto& t = mesh.triangles[order[s]];
    triangles_[s] = t;
    corners_[s] = {vertices_[t[0]], vertices_[t[1]], vertices_[t[2]]};
    face_normals_[s] =
        normalized_or((corners_[s][1] - corners_[s][0]).cross(corners_[s][2] - corners_[s][0]), Vector3d::Zero());
    const Vector3d centroid = (corners_[s][0] + corners_[s][1] + corners_[s][2]) / 3.0;
    double rad = 0;
    for (const Vector3d& c : corners_[s]) rad = std::max(rad, (c - centroid).norm());
    bounding_spheres_[s] = {centroid.x(), centroid.y(), centroid.z(), rad * (1 + 1e-9) + 1e-15};
  }
}

/// Pseudo-normals over welded vertices: a vertex's is the angle-weighted sum of its faces'
/// normals, an edge's the sum of its two faces' (Baerentzen & Aanaes), normalized.
void MeshDistance::build_pseudo_normals() {
  const std::size_t nv = vertices_.size();
  const std::size_t nt = triangles_.size();
  const std::vector<std::uint32_t> weld = weld_vertices(vertices_);
  std::vector<Vector3d> vsum(nv, Vector3d::Zero());
  std::unordered_map<std::uint64_t, Vector3d> esum;
  esum.reserve(nt * 2);
  const auto edge_key = [&](std::uint32_t i, std::uint32_t j) {
    std::uint64_t a = weld[i];
    std::uint64_t b = weld[j];
    if (a > b) std::swap(a, b);
    return (a << 32) | b;
  };
  for (std::size_t s = 0; s < nt; ++s) {
    const auto& t = triangles_[s];
    const Corners& v = corners_[s];
    const Vector3d& n = face_normals_[s];
    for (int k = 0; k < 3; ++k) {
      const Vector3d u = v[(k + 1) % 3] - v[k];
      const Vector3d w = v[(k + 2) % 3] - v[k];
      const double angle = std::atan2(u.cross(w).norm(), u.dot(w));
      vsum[weld[t[k]]] += angle * n;
      auto [it, inserted] = esum.try_emplace(edge_key(t[k], t[(k + 1) % 3]), Vector3d::Zero());
      it->second += n;
    }
  }
  vertex_normals_.resize(nv);
  for (std::size_t i = 0; i < nv; ++i) vertex_normals_[i] = normalized_or(vsum[weld[i]], Vector3d::Zero());
  edge_normals_.resize(nt);
  for (std::size_t s = 0; s < nt; ++s) {
    const auto& t = triangles_[s];
    for (int k = 0; k < 3; ++k) {
      edge_normals_[s][k] = normalized_or(esum.at(edge_key(t[k], t[(k + 1) % 3])), face_normals_[s]);
    }
  }
}

std::size_t MeshDistance::memory_bytes() const {
  return nodes_.capacity() * sizeof(Node) + oriented_boxes_.capacity() * sizeof(OrientedBoxData) +
         vertices_.capacity() * sizeof(Eigen::Vector3d) + triangles_.capacity() * sizeof(triangles_[0]) +
         face_normals_.capacity() * sizeof(Eigen::Vector3d) + vertex_normals_.capacity() * sizeof(Eigen::Vector3d) +
         edge_normals_.capacity() * sizeof(edge_normals_[0]) + corners_.capacity() * sizeof(corners_[0]) +
         triangle_ids_.capacity() * sizeof(std::uint32_t) + slot_of_triangle_.capacity() * sizeof(std::uint32_t) +
         bounding_spheres_.capacity() * sizeof(bounding_spheres_[0]);
}

}  // namespace telegrasp::sim
