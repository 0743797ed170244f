// Exact distance, containment and sweep queries against one triangle mesh, accelerated by a BVH.
#pragma once

#include "telegrasp/sim/triangle_mesh.h"

#include <Eigen/Core>

#include <array>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <vector>

namespace telegrasp::sim {

/// Closest point on the mesh surface to a query point.
struct PointQuery {
  bool found = false;  ///< False when nothing lies within max_distance.
  Eigen::Vector3d point_on_mesh{0, 0, 0};
  Eigen::Vector3d normal{0, 0, 0};  ///< Outward unit angle-weighted pseudo-normal at point_on_mesh.
  double distance = 0;  ///< Unsigned distance, >= 0.
  double signed_distance = 0;  ///< Negative inside the (closed) mesh.
  std::uint32_t triangle = 0;
};

/// Closest pair between a segment and the mesh surface.
struct SegmentQuery {
  bool found = false;  ///< False when nothing lies within max_distance.
  double distance = 0;  ///< Unsigned distance between segment and surface, >= 0.
  double segment_t = 0;  ///< Closest point on the segment = a + t (b - a), t in [0, 1].
  Eigen::Vector3d point_on_segment{0, 0, 0};
  Eigen::Vector3d point_on_mesh{0, 0, 0};
  Eigen::Vector3d normal{0, 0, 0};  ///< Outward unit pseudo-normal at point_on_mesh.
  std::uint32_t triangle = 0;
};

/// First contact of a sphere swept along a ray.
struct SweepHit {
  bool hit = false;  ///< False when no contact within max_length.
  bool started_inside = false;  ///< The sweep origin lies inside the closed mesh.
  /// Travel of the sphere centre along the direction at first contact: in [0, max_length], or,
  /// when started_inside, <= 0 (the entry lies behind the origin, at any distance).
  double t = 0;
  Eigen::Vector3d point{0, 0, 0};  ///< Contact point on the mesh surface.
  Eigen::Vector3d normal{0, 0, 0};  ///< Outward surface normal at the contact point.
};

/// Immutable acceleration structure over a closed, outward-facing triangle mesh.
/// All queries are exact up to floating point, const, thread-safe and allocation-free.
class MeshDistance {
 public:
  MeshDistance() = default;
  /// Builds the BVH and per-vertex/edge pseudo-normals; `mesh` must have >= 1 triangle.
  explicit MeshDistance(const TriangleMesh& mesh);

  /// Closest surface point to `p`, searching only within `max_distance`.
  [[nodiscard]] PointQuery closest_point(const Eigen::Vector3d& p,
                                         double max_distance = std::numeric_limits<double>::infinity()) const;

  /// Signed distance from `p` to the surface (negative inside).
  [[nodiscard]] double signed_distance(const Eigen::Vector3d& p) const;

  /// "No hint" for the queries below that take a triangle hint.
  static constexpr std::uint32_t kNoHint = std::numeric_limits<std::uint32_t>::max();

  /// Closest pair between segment [a, b] and the surface, searching only within `max_distance`.
  /// `hint` names a triangle likely to be near (e.g. the previous answer's `triangle`): it only
  /// tightens the search's first bound, so it changes the speed, never the distance.
  [[nodiscard]] SegmentQuery closest_to_segment(const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                                                double max_distance = std::numeric_limits<double>::infinity(),
                                                std::uint32_t hint = kNoHint) const;

  /// True when the segment [a, b] comes within `radius` of the surface or lies inside the mesh
  /// (the capsule overlaps the solid). Early-outs, trying the `hint` triangle first.
  [[nodiscard]] bool capsule_overlaps(const Eigen::Vector3d& a, const Eigen::Vector3d& b, double radius,
                                      std::uint32_t hint = kNoHint) const;

  /// capsule_overlaps(a, b, radius, hint) for a segment whose closest pair with the surface is
  /// known: `nearest`, a found answer of closest_to_segment for this very a and b. When its distance
  /// exceeds the radius by more than the searches' rounding, no triangle comes within the radius and
  /// only the inside test is left; otherwise (or when not found) it is capsule_overlaps itself. The
  /// same answer as capsule_overlaps, bit for bit.
  [[nodiscard]] bool capsule_overlaps(const Eigen::Vector3d& a, const Eigen::Vector3d& b, double radius,
                                      const SegmentQuery& nearest, std::uint32_t hint = kNoHint) const;
  /// capsule_overlaps' answer once no triangle lies within the radius of a segment from a: whether
  /// the segment lies inside the solid (it then does entirely).
  [[nodiscard]] bool segment_inside(const Eigen::Vector3d& a) const;

  /// Exact signed distance between the capsule (segment [a, b], `radius`) and the solid:
  /// min over segment points of signed_distance, minus radius. Positive = gap, negative = depth.
  [[nodiscard]] double capsule_signed_distance(const Eigen::Vector3d& a, const Eigen::Vector3d& b, double radius,
                                               std::uint32_t hint = kNoHint) const;

  /// Sweeps a sphere of `radius` from `origin` along unit `direction` for at most `max_length`
  /// and returns the first contact with the surface. If `origin` starts inside the solid, the
  /// result has started_inside set and reports the surface found by sweeping backwards instead
  /// (t is then <= 0: the entry point lies behind the origin).
  [[nodiscard]] SweepHit sphere_cast(const Eigen::Vector3d& origin, const Eigen::Vector3d& direction, double radius,
                                     double max_length) const;

  /// True when `p` lies inside the closed mesh.
  [[nodiscard]] bool contains(const Eigen::Vector3d& p) const;

  [[nodiscard]] std::size_t triangle_count() const;
  /// Heap bytes held by this structure (BVH, triangle data, normals).
  [[nodiscard]] std::size_t memory_bytes() const;

 private:
  // Implementation-defined; see mesh_distance.cc.
  /// One BVH node: a bounding box and either two adjacent children or a triangle range, and
  /// maybe an oriented box. Box corners are rounded outwards to float, so every bound derived from
  /// them stays conservative.
  struct Node {
    float lo[3] = {0, 0, 0};
    float hi[3] = {0, 0, 0};
    float radius = 0;  // rounded-up half diagonal: the box lies in this ball around its centre
    std::uint32_t first = 0;  // leaf: first triangle (BVH order); inner: left child (right = first + 1)
    std::uint32_t count = 0;  // leaf: number of triangles (> 0); inner: 0
    std::uint32_t oriented = kNoHint;  // index in oriented_boxes_, or kNoHint when it has none
  };
  /// A node's oriented box: its triangles lie where u_i . (x - c) is in [lo[i], hi[i]] for the rows
  /// u_i of `axes` (its triangles' principal axes) and c the node's box centre. It stays tight on a
  /// thin or nearly flat patch however the mesh is turned, where the axis-aligned box of a tilted
  /// patch is loose; kept only for nodes where it is markedly smaller. Bounds are rounded outwards
  /// and the queries allow for the axes being orthonormal only to float precision.
  struct OrientedBoxData {
    float axes[3][3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
    float lo[3] = {0, 0, 0};
    float hi[3] = {0, 0, 0};
  };
  /// Squared distance, parameter and feature of the best triangle found by a traversal.
  struct Candidate {
    double distance_sq = std::numeric_limits<double>::infinity();
    double segment_t = 0;
    Eigen::Vector3d point{0, 0, 0};
    std::uint32_t slot = 0;  // triangle slot in BVH order
    bool found = false;
  };

  // Construction phases, in the constructor's order.
  [[nodiscard]] std::vector<std::uint32_t> build_bvh(const TriangleMesh& mesh);
  void store_in_leaf_order(const TriangleMesh& mesh, const std::vector<std::uint32_t>& order);
  void build_pseudo_normals();

  template <class Reach, class Leaf>
  void traverse(Reach&& reach, Leaf&& leaf) const;
  [[nodiscard]] Candidate nearest_to_point(const Eigen::Vector3d& p, double max_distance) const;
  [[nodiscard]] Candidate nearest_to_segment(const Eigen::Vector3d& a, const Eigen::Vector3d& b, double max_distance,
                                             std::uint32_t hint = kNoHint) const;
  [[nodiscard]] Eigen::Vector3d feature_normal(std::uint32_t slot, int feature) const;
  /// Largest absolute coordinate of the mesh's box and of a and b (the scale of rounding errors).
  [[nodiscard]] double coordinate_extent(const Eigen::Vector3d& a, const Eigen::Vector3d& b) const;
  [[nodiscard]] bool sweep_forward(const Eigen::Vector3d& origin, const Eigen::Vector3d& dir, double radius,
                                   double max_length, double& t, std::uint32_t& slot) const;
  [[nodiscard]] bool sweep_exit(const Eigen::Vector3d& origin, const Eigen::Vector3d& dir, double radius, double& s,
                                std::uint32_t& slot) const;
  [[nodiscard]] bool inside_by_ray_parity(const Eigen::Vector3d& p, bool& decided) const;
  [[nodiscard]] double min_signed_distance_on_segment(const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                                                      double hint_t) const;

  std::vector<Node> nodes_;
  std::vector<OrientedBoxData> oriented_boxes_;
  std::vector<Eigen::Vector3d> vertices_;
  std::vector<std::array<std::uint32_t, 3>> triangles_;
  std::vector<Eigen::Vector3d> face_normals_;
  std::vector<Eigen::Vector3d> vertex_normals_;  // angle-weighted
  std::vector<std::array<Eigen::Vector3d, 3>> edge_normals_;  // per triangle edge (v0v1, v1v2, v2v0)
  // Per-triangle arrays (triangles_, face_normals_, edge_normals_, corners_) are stored in BVH
  // leaf order; triangle_ids_ maps a slot back to the input triangle index.
  std::vector<std::array<Eigen::Vector3d, 3>> corners_;  // triangle corner positions
  std::vector<std::uint32_t> triangle_ids_;
  std::vector<std::uint32_t> slot_of_triangle_;  // inverse of triangle_ids_
  std::vector<std::array<double, 4>> bounding_spheres_;  // per triangle: centroid and radius
};

}  // namespace telegrasp::sim
