// MeshDistance's queries: exact point / segment / capsule / swept-sphere queries on a triangle mesh
// (the structure they walk is built in mesh_distance_build.cc).
// Traversals are iterative with a fixed stack, nearest child first, pruned by the current best.
// Segment searches prune a box or triangle by the plane through the segment point nearest its
// centre (separated_beyond): a finger capsule lies along the surface, many millimetres above many
// small triangles, where bounding balls or inflated boxes let almost every nearby one through.
// A triangle large against the distance searched is first bounded in the segment's own frame
// (SegmentFrame: the 2-D distance across the segment's axis, with the gap along it), which is
// exact for a segment lying across long sliver triangles, where the plane bound is loose by
// about the sliver's length squared over twice the distance.
//
// Conventions:
//  * A point exactly on the surface (distance 0) has signed distance 0 and counts as inside
//    (the solid is a closed set); contains(p) == (signed_distance(p) <= 0).
//  * The mesh is treated as a triangle soup for distances and sweeps.
#include "telegrasp/sim/mesh_distance.h"

#include "mesh_primitives.h"

#include <Eigen/Geometry>

#include <algorithm>
#include <cassert>
#include <cmath>
#include <utility>

namespace telegrasp::sim {
using namespace mesh_detail;

/// Depth-first walk of the BVH, nearer child first. `reach(node, key)` says whether a node may
/// hold an answer and sets its ordering key (smaller first). A deferred node is not asked again
/// when resumed: most still pass, and its children are asked with the tightened reach anyway.
/// `leaf(node)` handles a leaf's triangles and returns true to end the walk.
template <class Reach, class Leaf>
void MeshDistance::traverse(Reach&& reach, Leaf&& leaf) const {
  double key0 = 0;
  double key1 = 0;
  if (nodes_.empty() || !reach(nodes_[0], key0)) return;
  std::uint32_t stack[kStackSize];
  int top = 0;
  std::uint32_t node = 0;
  for (;;) {
    const Node& nd = nodes_[node];
    if (nd.count > 0) {
      if (leaf(nd)) return;
    } else {
      std::uint32_t c0 = nd.first;
      std::uint32_t c1 = c0 + 1;
      const bool r0 = reach(nodes_[c0], key0);
      const bool r1 = reach(nodes_[c1], key1);
      if (r0 && r1) {
        if (key1 < key0) std::swap(c0, c1);
        assert(top < kStackSize);
        stack[top++] = c1;
        node = c0;
        continue;
      }
      if (r0 || r1) {
        node = r0 ? c0 : c1;
        continue;
      }
    }
    if (top == 0) return;
    node = stack[--top];
  }
}

namespace {
// A triangle whose bounding radius exceeds this fraction of the distance searched is "large".
constexpr double kLargeTriangle = 0.15;
}  // namespace

std::size_t MeshDistance::triangle_count() const { return triangles_.size(); }

double MeshDistance::coordinate_extent(const Eigen::Vector3d& a, const Eigen::Vector3d& b) const {
  double e = std::max(a.cwiseAbs().maxCoeff(), b.cwiseAbs().maxCoeff());
  if (!nodes_.empty())
    for (int i = 0; i < 3; ++i) e = std::max({e, std::abs(double{nodes_[0].lo[i]}), std::abs(double{nodes_[0].hi[i]})});
  return e;
}

Eigen::Vector3d MeshDistance::feature_normal(std::uint32_t slot, int feature) const {
  switch (feature) {
    case kVertex0:
    case kVertex1:
    case kVertex2:
      return vertex_normals_[triangles_[slot][feature - kVertex0]];
    case kEdge01:
    case kEdge12:
    case kEdge20:
      return edge_normals_[slot][feature - kEdge01];
    default:
      return face_normals_[slot];
  }
}

MeshDistance::Candidate MeshDistance::nearest_to_point(const Eigen::Vector3d& p, double max_distance) const {
  Candidate best;
  if (nodes_.empty() || !(max_distance >= 0)) return best;
  best.distance_sq = max_distance * max_distance;
  double best_d = max_distance;
  // Nearest box first; boxes holding p (distance 0) by nearer centre.
  const auto reach = [&](const Node& n, double& key) {
    const double d = point_box_sq(p, n.lo, n.hi);
    if (d > best.distance_sq) return false;
    if (n.oriented != kNoHint && std::isfinite(best_d) &&
        oriented_box(n, oriented_boxes_).point_beyond(p - box_centre(n.lo, n.hi), best_d))
      return false;
    key = d > 0 ? d : -1.0 / (1.0 + (p - box_centre(n.lo, n.hi)).squaredNorm());
    return true;
  };
  traverse(reach, [&](const Node& nd) {
    for (std::uint32_t s = nd.first; s < nd.first + nd.count; ++s) {
      const auto& bs = bounding_spheres_[s];
      const double sphere_reach = best_d + bs[3];
      if ((p - Vector3d(bs[0], bs[1], bs[2])).squaredNorm() > sphere_reach * sphere_reach) continue;
      int feature = 0;
      const Vector3d q = closest_on_triangle(p, corners_[s], feature);
      const double d2 = (p - q).squaredNorm();
      if (d2 < best.distance_sq || (!best.found && d2 <= best.distance_sq)) {
        best.distance_sq = d2;
        best.point = q;
        best.slot = s;
        best.found = true;
        best_d = std::sqrt(d2);
      }
    }
    return false;
  });
  return best;
}

PointQuery MeshDistance::closest_point(const Eigen::Vector3d& p, double max_distance) const {
  PointQuery out;
  const Candidate c = nearest_to_point(p, max_distance);
  if (!c.found) return out;
  int feature = 0;
  out.found = true;
  out.point_on_mesh = closest_on_triangle(p, corners_[c.slot], feature);
  out.normal = feature_normal(c.slot, feature);
  out.distance = std::sqrt(c.distance_sq);
  out.signed_distance = (p - out.point_on_mesh).dot(out.normal) >= 0 ? out.distance : -out.distance;
  out.triangle = triangle_ids_[c.slot];
  return out;
}

double MeshDistance::signed_distance(const Eigen::Vector3d& p) const {
  const PointQuery q = closest_point(p);
  return q.found ? q.signed_distance : kInf;
}

bool MeshDistance::contains(const Eigen::Vector3d& p) const {
  const PointQuery q = closest_point(p);
  return q.found && q.signed_distance <= 0;
}

MeshDistance::Candidate MeshDistance::nearest_to_segment(const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                                                         double max_distance, std::uint32_t hint) const {
  Candidate best;
  if (nodes_.empty() || !(max_distance >= 0)) return best;
  best.distance_sq = max_distance * max_distance;
  double best_d = max_distance;
  const SegmentProbe seg(a, b);
  SegmentFrame frame(a, seg.d, seg.dd, coordinate_extent(a, b));
  if (hint < slot_of_triangle_.size()) {  // a near triangle first: a tight bound prunes the tree
    const std::uint32_t s = slot_of_triangle_[hint];
    double t = 0;
    Vector3d q;
    const double d2 = segment_triangle_sq(a, b, seg.d, seg.dd, corners_[s], face_normals_[s], best.distance_sq, t, q);
    if (d2 <= best.distance_sq) {
      best = {d2, t, q, s, true};
      best_d = std::sqrt(d2);
    }
  }
  traverse([&](const Node& n, double& key) { return segment_may_reach(seg, n, oriented_boxes_, best_d, key); },
           [&](const Node& nd) {
             for (std::uint32_t s = nd.first; s < nd.first + nd.count; ++s) {
               // The frame's bound, first, for a triangle large against the distance (a sliver:
               // the centroid's bounds are loose by about its size squared over the distance);
               // for the others the centroid's bounds are nearly as tight and cheaper.
               const auto& bs = bounding_spheres_[s];
               if (bs[3] > kLargeTriangle * best_d && frame.beyond(corners_[s], best_d)) continue;
               const Vector3d centroid(bs[0], bs[1], bs[2]);
               const Vector3d w = seg.offset_from(centroid);
               const double w2 = w.squaredNorm();
               const double reach = best_d + bs[3];
               if (w2 > reach * reach) continue;
               if (separated_beyond(w2, triangle_support(w, corners_[s], centroid), best_d)) continue;
               double t = 0;
               Vector3d q;
               const double d2 =
                   segment_triangle_sq(a, b, seg.d, seg.dd, corners_[s], face_normals_[s], best.distance_sq, t, q);
               if (d2 < best.distance_sq || (!best.found && d2 <= best.distance_sq)) {
                 best.distance_sq = d2;
                 best.segment_t = t;
                 best.point = q;
                 best.slot = s;
                 best.found = true;
                 best_d = std::sqrt(d2);
               }
             }
             return best.found && best.distance_sq == 0;  // cannot get closer
           });
  return best;
}

SegmentQuery MeshDistance::closest_to_segment(const Eigen::Vector3d& a, const Eigen::Vector3d& b, double max_distance,
                                              std::uint32_t hint) const {
  SegmentQuery out;
  const Candidate c = nearest_to_segment(a, b, max_distance, hint);
  if (!c.found) return out;
  out.found = true;
  out.distance = std::sqrt(c.distance_sq);
  out.segment_t = c.segment_t;
  out.point_on_segment = a + c.segment_t * (b - a);
  int feature = 0;
  out.point_on_mesh = closest_on_triangle(out.point_on_segment, corners_[c.slot], feature);
  out.normal = feature_normal(c.slot, feature);
  out.triangle = triangle_ids_[c.slot];
  return out;
}

bool MeshDistance::capsule_overlaps(const Eigen::Vector3d& a, const Eigen::Vector3d& b, double radius,
                                    std::uint32_t hint) const {
  if (nodes_.empty()) return false;
  const double r = std::max(radius, 0.0);
  const double r2 = r * r;
  const SegmentProbe seg(a, b);
  if (hint < slot_of_triangle_.size()) {
    const std::uint32_t s = slot_of_triangle_[hint];
    double t = 0;
    Vector3d q;
    if (segment_triangle_sq(a, b, seg.d, seg.dd, corners_[s], face_normals_[s], r2, t, q) <= r2) return true;
  }
  bool overlaps = false;
  traverse([&](const Node& n, double& key) { return segment_may_reach(seg, n, oriented_boxes_, r, key); },
           [&](const Node& nd) {
             for (std::uint32_t s = nd.first; s < nd.first + nd.count; ++s) {
               const auto& bs = bounding_spheres_[s];
               const Vector3d centroid(bs[0], bs[1], bs[2]);
               const Vector3d w = seg.offset_from(centroid);
               const double c2 = w.squaredNorm();
               const double reach = r + bs[3];
               if (c2 > reach * reach) continue;
               // The centroid lies on the triangle, so c2 <= r2 settles it without the exact test.
               if (c2 > r2) {
                 if (separated_beyond(c2, triangle_support(w, corners_[s], centroid), r)) continue;
                 double t = 0;
                 Vector3d q;
                 if (segment_triangle_sq(a, b, seg.d, seg.dd, corners_[s], face_normals_[s], r2, t, q) > r2) continue;
               }
               overlaps = true;
               return true;
             }
             return false;
           });
  if (overlaps) return true;
  return segment_inside(a);
}

bool MeshDistance::segment_inside(const Eigen::Vector3d& a) const {
  // No surface within the radius: the capsule overlaps the solid only if it lies entirely inside.
  // a is farther than r from the surface, so a ray-parity test is well conditioned; it falls back
  // to the pseudo-normal test (contains) whenever the ray passes near an edge or grazes a plane.
  bool decided = false;
  const bool inside = inside_by_ray_parity(a, decided);
  return decided ? inside : contains(a);
}

bool MeshDistance::capsule_overlaps(const Eigen::Vector3d& a, const Eigen::Vector3d& b, double radius,
                                    const SegmentQuery& nearest, std::uint32_t hint) const {
  if (nodes_.empty()) return false;
  // The search that found `nearest` tested every triangle its sound bounds did not exclude, so no
  // triangle's computed distance lies below nearest.distance by more than rounding (far below
  // 1e-9 relative, or 1e-9 of the coordinates' size): capsule_overlaps' triangle phase, whose
  // tests (the exact one and the centroid shortcut) pass only within the radius, finds nothing.
  const double r = std::max(radius, 0.0);
  const double slack = 1e-9 * (coordinate_extent(a, b) + (b - a).norm());
  if (nearest.found && nearest.distance > r * (1 + 1e-8) + slack) return segment_inside(a);
  return capsule_overlaps(a, b, radius, hint);
}

bool MeshDistance::inside_by_ray_parity(const Eigen::Vector3d& p, bool& decided) const {
  decided = false;
  if (nodes_.empty()) return false;
  const Node& root = nodes_[0];
  const double eps = 1e-9 * root.radius;
  // Shoot away from the box centre (short exit for star-shaped solids); slightly skewed off axes.
  Vector3d u = p - box_centre(root.lo, root.hi) + Vector3d(0.61e-3, 0.37e-3, 0.17e-3) * root.radius;
  if (!(u.norm() > 0)) return false;
  u.normalize();
  const Vector3d inv = safe_inverse(u);
  int crossings = 0;
  bool undecided = false;  // the ray grazes an edge or a plane, or p is on the surface
  traverse([&](const Node& n, double& key) { return ray_hits_box(p, inv, n.lo, n.hi, 0.0, 0.0, kInf, key); },
           [&](const Node& nd) {
             for (std::uint32_t s = nd.first; s < nd.first + nd.count; ++s) {
               const Corners& v = corners_[s];
               const Vector3d& n = face_normals_[s];
               const double s0 = n.dot(p - v[0]);
               const double sd = n.dot(u);
               if (std::abs(sd) < 1e-9) {
                 if (std::abs(s0) <= eps) return undecided = true;  // ray (nearly) in the plane
                 continue;
               }
               const double t = -s0 / sd;
               if (t < -eps) continue;
               const Vector3d x = p + t * u;
               bool in = true;
               for (int k = 0; k < 3; ++k) {
                 const Vector3d e = v[(k + 1) % 3] - v[k];
                 const double g = e.cross(x - v[k]).dot(n);  // = |e| * signed in-plane distance
                 if (g < 0 && g * g > eps * eps * e.squaredNorm()) {
                   in = false;
                   break;
                 }
                 if (g * g <= eps * eps * e.squaredNorm()) return undecided = true;  // near an edge
               }
               if (!in) continue;
               if (t <= eps) return undecided = true;  // p (nearly) on the surface
               ++crossings;
             }
             return false;
           });
  if (undecided) return false;
  decided = true;
  return (crossings & 1) != 0;
}

double MeshDistance::min_signed_distance_on_segment(const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                                                    double hint_t) const {
  constexpr int kSamples = 32;
  constexpr double kStep = 1.0 / (kSamples - 1);
  const Vector3d d = b - a;
  const auto f = [&](double t) { return signed_distance(a + t * d); };
  double best_t = std::clamp(hint_t, 0.0, 1.0);
  double best_f = f(best_t);
  for (int i = 0; i < kSamples; ++i) {
    const double t = i * kStep;
    const double v = f(t);
    if (v < best_f) {
      best_f = v;
      best_t = t;
    }
  }
  if (!(d.squaredNorm() > 0)) return best_f;
  // Golden-section search on the bracket around the best sample (exact for convex solids, whose
  // signed distance is convex along a line).
  double lo = std::max(0.0, best_t - kStep);
  double hi = std::min(1.0, best_t + kStep);
  constexpr double kInvPhi = 0.6180339887498949;
  double x1 = hi - kInvPhi * (hi - lo);
  double x2 = lo + kInvPhi * (hi - lo);
  double f1 = f(x1);
  double f2 = f(x2);
  while (hi - lo > 1e-12) {
    if (f1 <= f2) {
      hi = x2;
      x2 = x1;
      f2 = f1;
      x1 = hi - kInvPhi * (hi - lo);
      f1 = f(x1);
    } else {
      lo = x1;
      x1 = x2;
      f1 = f2;
      x2 = lo + kInvPhi * (hi - lo);
      f2 = f(x2);
    }
  }
  return std::min({best_f, f1, f2});
}

double MeshDistance::capsule_signed_distance(const Eigen::Vector3d& a, const Eigen::Vector3d& b, double radius,
                                             std::uint32_t hint) const {
  if (nodes_.empty()) return kInf;
  const SegmentQuery q = closest_to_segment(a, b, kInf, hint);
  // A segment that does not touch the surface lies wholly outside or wholly inside; the
  // pseudo-normal at the closest point tells which.
  if (q.distance > 0 && (q.point_on_segment - q.point_on_mesh).dot(q.normal) > 0) return q.distance - radius;
  return min_signed_distance_on_segment(a, b, q.segment_t) - radius;
}

bool MeshDistance::sweep_forward(const Eigen::Vector3d& origin, const Eigen::Vector3d& dir, double radius,
                                 double max_length, double& t_hit, std::uint32_t& slot) const {
  if (nodes_.empty() || !(max_length >= 0)) return false;
  const double r = std::max(radius, 0.0);
  const Vector3d inv = safe_inverse(dir);
  double best_t = max_length;
  bool found = false;
  // Ball around the node's box inflated by r, then the slab test; entry parameter for ordering.
  const auto reach = [&](const Node& n, double& t_enter) {
    double ts = 0;
    double tb = 0;
    if (!ray_hits_box(origin, inv, n.lo, n.hi, r, 0.0, best_t, tb)) return false;
    if (!ray_ball_entry(origin, dir, box_centre(n.lo, n.hi), n.radius + r, best_t, ts)) return false;
    if (n.oriented != kNoHint &&
        !oriented_box(n, oriented_boxes_).ray_meets(origin - box_centre(n.lo, n.hi), dir, r, best_t))
      return false;
    t_enter = std::max(ts, tb);
    return true;
  };
  traverse(reach, [&](const Node& nd) {
    for (std::uint32_t s = nd.first; s < nd.first + nd.count; ++s) {
      const auto& bs = bounding_spheres_[s];
      double tb = 0;
      if (!ray_ball_entry(origin, dir, Vector3d(bs[0], bs[1], bs[2]), bs[3] + r, best_t, tb)) continue;
      double t = 0;
      if (!sweep_triangle(origin, dir, corners_[s], face_normals_[s], r, best_t, t)) continue;
      if (t < best_t || (!found && t <= best_t)) {
        best_t = t;
        slot = s;
        found = true;
      }
    }
    return false;
  });
  if (found) t_hit = best_t;
  return found;
}

bool MeshDistance::sweep_exit(const Eigen::Vector3d& origin, const Eigen::Vector3d& dir, double radius, double& s,
                              std::uint32_t& slot) const {
  // Walks the connected set {s : the sphere at origin + s dir touches the surface} to its far end:
  // repeatedly jumps to the largest exit of the per-triangle intervals containing the current s.
  const double r = std::max(radius, 0.0);
  const double r_tol = r * (1 + 1e-12) + 1e-15;
  const double r_tol2 = r_tol * r_tol;
  bool moved = false;
  for (int iter = 0; iter < 256; ++iter) {
    const Vector3d x = origin + s * dir;
    double best_exit = s;
    std::uint32_t best_slot = slot;
    const auto touches = [&](const Node& n, double& key) { return (key = point_box_sq(x, n.lo, n.hi)) <= r_tol2; };
    double key = 0;
    if (!touches(nodes_[0], key)) break;
    traverse(touches, [&](const Node& nd) {
      for (std::uint32_t k = nd.first; k < nd.first + nd.count; ++k) {
        int feature = 0;
        if ((x - closest_on_triangle(x, corners_[k], feature)).squaredNorm() > r_tol2) continue;
        double t0 = 0;
        double t1 = 0;
        if (line_triangle_minkowski(origin, dir, corners_[k], face_normals_[k], r, t0, t1) && t1 > best_exit) {
          best_exit = t1;
          best_slot = k;
        }
      }
      return false;
    });
    if (!(best_exit > s)) break;
    s = best_exit;
    slot = best_slot;
    moved = true;
  }
  return moved;
}

SweepHit MeshDistance::sphere_cast(const Eigen::Vector3d& origin, const Eigen::Vector3d& direction, double radius,
                                   double max_length) const {
  SweepHit hit;
  if (nodes_.empty()) return hit;
  const double len = direction.norm();
  if (!(len > 0) || !std::isfinite(len)) return hit;
  const Vector3d dir = direction / len;
  const double r = std::max(radius, 0.0);

  const auto fill = [&](const Vector3d& centre, std::uint32_t slot, double t) {
    int feature = 0;
    hit.hit = true;
    hit.t = t;
    hit.point = closest_on_triangle(centre, corners_[slot], feature);
    hit.normal = feature_normal(slot, feature);
  };

  bool inside = false;
  if (r > 0) {
    const PointQuery near = closest_point(origin, r);
    if (near.found) {
      if (near.signed_distance > 0) {  // already touching from outside
        hit.hit = true;
        hit.t = 0;
        hit.point = near.point_on_mesh;
        hit.normal = near.normal;
        return hit;
      }
      inside = true;
    } else {
      double t = 0;
      std::uint32_t slot = 0;
      if (sweep_forward(origin, dir, r, max_length, t, slot)) {
        // The centre never came within r of the surface before t, so it is on the origin's side.
        const Vector3d centre = origin + t * dir;
        int feature = 0;
        const Vector3d q = closest_on_triangle(centre, corners_[slot], feature);
        const double side = (centre - q).dot(feature_normal(slot, feature));
        if (side > 0 || (side == 0 && !contains(origin))) {
          fill(centre, slot, t);
          return hit;
        }
        inside = true;
      } else {
        // No surface within r of the origin: the ray-parity test is well conditioned there (and
        // falls back to the pseudo-normal test when the ray grazes an edge or a plane).
        bool decided = false;
        const bool parity = inside_by_ray_parity(origin, decided);
        inside = decided ? parity : contains(origin);
        if (!inside) return hit;
      }
    }
  } else {
    inside = contains(origin);
    if (!inside) {
      double t = 0;
      std::uint32_t slot = 0;
      if (sweep_forward(origin, dir, 0.0, max_length, t, slot)) fill(origin + t * dir, slot, t);
      return hit;
    }
  }

  // Started inside: sweep backwards to the last position where the sphere touched the surface
  // from outside, i.e. where it would have entered the solid when travelling along +dir.
  assert(inside);
  hit.started_inside = true;
  const Vector3d back = -dir;
  double s = 0;
  std::uint32_t slot = 0;
  bool have = false;
  for (int round = 0; round < 16; ++round) {
    const double step = round == 0 ? 0.0 : 1e-9;
    double t = 0;
    std::uint32_t sl = 0;
    if (!sweep_forward(origin + (s + step) * back, back, r, kInf, t, sl)) break;
    s += step + t;
    slot = sl;
    have = true;
    (void)sweep_exit(origin, back, r, s, slot);
    if (r <= 0) break;
    const Vector3d centre = origin + s * back;
    int feature = 0;
    const Vector3d q = closest_on_triangle(centre, corners_[slot], feature);
    if ((centre - q).dot(feature_normal(slot, feature)) > 0) break;  // outside: this is the entry
  }
  if (have) fill(origin + s * back, slot, -s);
  return hit;
}

}  // namespace telegrasp::sim
