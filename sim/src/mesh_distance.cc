// MeshDistance: exact point / segment / capsule / swept-sphere queries on a triangle mesh.
//
// Structure: a binned-SAH BVH of axis-aligned boxes in a flat vector (children adjacent, at most
// four triangles per leaf where SAH agrees), an oriented box (principal axes) beside the nodes
// where it is markedly tighter (thin or flat patches of a tilted mesh), triangle data stored in
// leaf order, and the angle-weighted pseudo-normals of Baerentzen & Aanaes (2005) for the sign of
// the distance.
// Traversals are iterative with a fixed stack, nearest child first, pruned by the current best.
// Segment searches prune a box or triangle by the plane through the segment point nearest its
// centre (separated_beyond): a finger capsule lies along the surface, many millimetres above many
// small triangles, where bounding balls or inflated boxes let almost every nearby one through.
//
// Conventions:
//  * A point exactly on the surface (distance 0) has signed distance 0 and counts as inside
//    (the solid is a closed set); contains(p) == (signed_distance(p) <= 0).
//  * The mesh is treated as a triangle soup for distances and sweeps; pseudo-normals use
//    vertices welded by exact position, so duplicated vertices do not create false boundaries.
#include "telegrasp/sim/mesh_distance.h"

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>

#include <algorithm>
#include <cassert>
#include <cmath>
#include <cstring>
#include <optional>
#include <stdexcept>
#include <tuple>
#include <unordered_map>
#include <utility>

namespace telegrasp::sim {
namespace {

using Eigen::Vector3d;

constexpr int kStackSize = 64;
constexpr int kMaxDepth = 60;  // < kStackSize: a traversal holds at most one pending node per level
constexpr std::uint32_t kLeafSize = 4;
constexpr std::uint32_t kMaxSahLeafSize = 8;
constexpr int kBins = 16;
constexpr double kInf = std::numeric_limits<double>::infinity();

/// Closest feature of a triangle: its face, one of its vertices, or one of its edges.
enum Feature : int { kFace = 0, kVertex0 = 1, kVertex1 = 2, kVertex2 = 3, kEdge01 = 4, kEdge12 = 5, kEdge20 = 6 };

using Corners = std::array<Vector3d, 3>;

/// Closest point on segment a + s*ab (s in [0, 1]) to p, as the parameter s.
inline double segment_param(const Vector3d& p, const Vector3d& a, const Vector3d& ab, double ab2) {
  if (!(ab2 > 0)) return 0;
  return std::clamp((p - a).dot(ab) / ab2, 0.0, 1.0);
}

/// Closest point on triangle (a, b, c) to p, with the feature it lies on (Ericson 5.1.5).
Vector3d closest_on_triangle(const Vector3d& p, const Corners& v, int& feature) {
  const Vector3d& a = v[0];
  const Vector3d& b = v[1];
  const Vector3d& c = v[2];
  const Vector3d ab = b - a;
  const Vector3d ac = c - a;
  const Vector3d ap = p - a;
  const double d1 = ab.dot(ap);
  const double d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0) {
    feature = kVertex0;
    return a;
  }
  const Vector3d bp = p - b;
  const double d3 = ab.dot(bp);
  const double d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) {
    feature = kVertex1;
    return b;
  }
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) {
    const double den = d1 - d3;
    feature = kEdge01;
    return den > 0 ? Vector3d(a + (d1 / den) * ab) : a;
  }
  const Vector3d cp = p - c;
  const double d5 = ab.dot(cp);
  const double d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) {
    feature = kVertex2;
    return c;
  }
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) {
    const double den = d2 - d6;
    feature = kEdge20;
    return den > 0 ? Vector3d(a + (d2 / den) * ac) : a;
  }
  const double va = d3 * d6 - d5 * d4;
  const double e1 = d4 - d3;
  const double e2 = d5 - d6;
  if (va <= 0 && e1 >= 0 && e2 >= 0) {
    const double den = e1 + e2;
    feature = kEdge12;
    return den > 0 ? Vector3d(b + (e1 / den) * (c - b)) : b;
  }
  const double denom = va + vb + vc;
  if (denom > 0) {
    feature = kFace;
    return a + (vb / denom) * ab + (vc / denom) * ac;
  }
  // Degenerate (collinear) triangle: the closest point lies on one of its edges.
  double best = kInf;
  Vector3d best_q = a;
  feature = kEdge01;
  for (int k = 0; k < 3; ++k) {
    const Vector3d& s = v[k];
    const Vector3d e = v[(k + 1) % 3] - s;
    const Vector3d q = s + segment_param(p, s, e, e.squaredNorm()) * e;
    const double d = (p - q).squaredNorm();
    if (d < best) {
      best = d;
      best_q = q;
      feature = kEdge01 + k;
    }
  }
  return best_q;
}

/// True when x (assumed in the plane of the triangle with unit normal n) lies inside it.
inline bool inside_triangle(const Vector3d& x, const Corners& v, const Vector3d& n) {
  return (v[1] - v[0]).cross(x - v[0]).dot(n) >= 0 && (v[2] - v[1]).cross(x - v[1]).dot(n) >= 0 &&
         (v[0] - v[2]).cross(x - v[2]).dot(n) >= 0;
}

/// Squared distance between segment a + s*d (s in [0, 1], b = a + d) and a triangle with unit
/// normal n (zero when degenerate). Returns +inf early when the plane alone proves the distance
/// exceeds sqrt(cutoff_sq). Outputs the segment parameter and the closest triangle point.
double segment_triangle_sq(const Vector3d& a, const Vector3d& b, const Vector3d& d, double dd, const Corners& v,
                           const Vector3d& n, double cutoff_sq, double& s_out, Vector3d& q_out) {
  const bool planar = n.squaredNorm() > 0;
  if (planar) {
    const double da = n.dot(a - v[0]);
    const double db = n.dot(b - v[0]);
    if (da > 0 && db > 0) {
      const double m = std::min(da, db);
      if (m * m > cutoff_sq) return kInf;
    } else if (da < 0 && db < 0) {
      const double m = std::max(da, db);
      if (m * m > cutoff_sq) return kInf;
    } else if (da != db) {
      // The segment meets the plane: test whether it meets the triangle there.
      const double s = da / (da - db);
      const Vector3d x = a + s * d;
      if (inside_triangle(x, v, n)) {
        s_out = s;
        q_out = x;
        return 0;
      }
    }
  }
  // No crossing: the minimum is at an endpoint vs the triangle, a vertex vs the segment, or an
  // interior-interior pair of the segment and an edge.
  int feature = 0;
  Vector3d q = closest_on_triangle(a, v, feature);
  double best = (a - q).squaredNorm();
  s_out = 0;
  q_out = q;
  q = closest_on_triangle(b, v, feature);
  double d2 = (b - q).squaredNorm();
  if (d2 < best) {
    best = d2;
    s_out = 1;
    q_out = q;
  }
  for (int k = 0; k < 3; ++k) {
    const double s = segment_param(v[k], a, d, dd);
    d2 = (a + s * d - v[k]).squaredNorm();
    if (d2 < best) {
      best = d2;
      s_out = s;
      q_out = v[k];
    }
  }
  for (int k = 0; k < 3; ++k) {
    const Vector3d& p = v[k];
    const Vector3d e = v[(k + 1) % 3] - p;
    const double ee = e.squaredNorm();
    const double de = d.dot(e);
    const double den = dd * ee - de * de;
    if (!(den > 1e-14 * dd * ee)) continue;  // parallel: covered by endpoint/vertex candidates
    const Vector3d r = a - p;
    const double c = d.dot(r);
    const double f = e.dot(r);
    const double s = (de * f - c * ee) / den;
    const double t = (dd * f - de * c) / den;
    if (s > 0 && s < 1 && t > 0 && t < 1) {
      const Vector3d y = p + t * e;
      d2 = (a + s * d - y).squaredNorm();
      if (d2 < best) {
        best = d2;
        s_out = s;
        q_out = y;
      }
    }
  }
  return best;
}

/// Roots t0 <= t1 of A t^2 + 2 B t + C = 0 (A > 0), computed without cancellation.
inline bool solve_quadratic(double A, double B, double C, double& t0, double& t1) {
  const double disc = B * B - A * C;
  if (disc < 0 || !(A > 0)) return false;
  const double q = -(B + std::copysign(std::sqrt(disc), B));
  if (q == 0) {
    t0 = t1 = 0;
    return true;
  }
  t0 = q / A;
  t1 = C / q;
  if (t0 > t1) std::swap(t0, t1);
  return true;
}

/// Interval [t0, t1] of the line o + t d (d unit) inside the cylinder of radius sqrt(r2) around
/// the edge from p to p + e, between the planes through its end points; false if none.
inline bool line_edge_cylinder(const Vector3d& o, const Vector3d& d, const Vector3d& p, const Vector3d& e, double r2,
                               double& t0, double& t1) {
  const double ee = e.squaredNorm();
  if (!(ee > 0)) return false;
  const Vector3d m = o - p;
  const double md = m.dot(e);
  const double nd = d.dot(e);
  const double A = ee - nd * nd;
  if (!(A > 1e-14 * ee)) return false;  // parallel to the edge: the vertex spheres bound the interval
  if (!solve_quadratic(A, ee * m.dot(d) - nd * md, ee * (m.squaredNorm() - r2) - md * md, t0, t1)) return false;
  if (nd != 0) {
    double u0 = -md / nd;
    double u1 = (ee - md) / nd;
    if (u0 > u1) std::swap(u0, u1);
    t0 = std::max(t0, u0);
    t1 = std::min(t1, u1);
    return t0 <= t1;
  }
  return md >= 0 && md <= ee;
}

/// Interval [t0, t1] of the line o + t d (d unit) inside the Minkowski sum of the triangle and
/// a ball of radius r (face slab inside the triangle's prism, edge cylinders, vertex spheres).
bool line_triangle_minkowski(const Vector3d& o, const Vector3d& d, const Corners& v, const Vector3d& n, double r,
                             double& t0, double& t1) {
  double lo = kInf;
  double hi = -kInf;
  const auto add = [&](double x, double y) {
    if (x <= y) {
      lo = std::min(lo, x);
      hi = std::max(hi, y);
    }
  };
  const double r2 = r * r;
  for (int k = 0; k < 3; ++k) {
    const Vector3d m = o - v[k];
    double x = 0;
    double y = 0;
    if (solve_quadratic(1.0, m.dot(d), m.squaredNorm() - r2, x, y)) add(x, y);
  }
  for (int k = 0; k < 3; ++k) {
    double x = 0;
    double y = 0;
    if (line_edge_cylinder(o, d, v[k], v[(k + 1) % 3] - v[k], r2, x, y)) add(x, y);
  }
  if (n.squaredNorm() > 0) {
    const double s0 = n.dot(o - v[0]);
    const double sd = n.dot(d);
    double fa = -kInf;
    double fb = kInf;
    bool ok = true;
    if (sd != 0) {
      fa = (-r - s0) / sd;
      fb = (r - s0) / sd;
      if (fa > fb) std::swap(fa, fb);
    } else if (std::abs(s0) > r) {
      ok = false;
    }
    for (int k = 0; ok && k < 3; ++k) {
      const Vector3d w = n.cross(v[(k + 1) % 3] - v[k]);  // inward in-plane edge normal
      const double g0 = w.dot(o - v[k]);
      const double gd = w.dot(d);
      if (gd == 0) {
        ok = g0 >= 0;
      } else if (gd > 0) {
        fa = std::max(fa, -g0 / gd);
      } else {
        fb = std::min(fb, -g0 / gd);
      }
    }
    if (ok) add(fa, fb);
  }
  t0 = lo;
  t1 = hi;
  return lo <= hi;
}

/// First contact t in [0, t_max] of a sphere of radius r whose centre moves along o + t d (d unit)
/// with the triangle; false if none. The Minkowski sum of triangle and ball is the prism slab over
/// the face plus the edge capsules; when the centre starts outside the slab and first reaches it
/// over the face interior that is the contact, otherwise the slab's side walls lie inside the
/// capsules, so the capsule (edge cylinder or vertex sphere) entries decide.
inline bool sweep_triangle(const Vector3d& o, const Vector3d& d, const Corners& v, const Vector3d& n, double r,
                           double t_max, double& t_out) {
  double best = t_max;
  bool found = false;
  const auto take = [&](double t) {
    t = std::max(t, 0.0);
    if (t <= best) {
      best = t;
      found = true;
    }
  };
  if (n.squaredNorm() > 0) {
    const double s0 = n.dot(o - v[0]);
    const double sd = n.dot(d);
    if (std::abs(s0) <= r) {
      if (inside_triangle(o - s0 * n, v, n)) {  // already within r of the face
        t_out = 0;
        return true;
      }
    } else {
      const double target = s0 > 0 ? r : -r;
      if (!(s0 > 0 ? sd < 0 : sd > 0)) return false;  // never reaches the plane
      const double t = (target - s0) / sd;
      if (t > best) return false;
      if (inside_triangle(o + t * d - target * n, v, n)) {
        t_out = t;
        return true;
      }
    }
  }
  const double r2 = r * r;
  for (int k = 0; k < 3; ++k) {
    const Vector3d m = o - v[k];
    const double c = m.squaredNorm() - r2;
    if (c <= 0) {
      t_out = 0;
      return true;
    }
    const double b = m.dot(d);
    if (b >= 0 || -b - r > best) continue;
    const double disc = b * b - c;
    if (disc < 0) continue;
    take(c / (-b + std::sqrt(disc)));
  }
  for (int k = 0; k < 3; ++k) {
    double ta = 0;
    double tb = 0;
    if (line_edge_cylinder(o, d, v[k], v[(k + 1) % 3] - v[k], r2, ta, tb) && tb >= 0) take(ta);
  }
  if (found) t_out = best;
  return found;
}

/// Float rounded towards -inf / +inf, so that a float box contains the double box.
inline float round_down(double x) {
  float f = static_cast<float>(x);
  if (static_cast<double>(f) > x) f = std::nextafter(f, -std::numeric_limits<float>::infinity());
  return f;
}
inline float round_up(double x) {
  float f = static_cast<float>(x);
  if (static_cast<double>(f) < x) f = std::nextafter(f, std::numeric_limits<float>::infinity());
  return f;
}

inline Vector3d box_centre(const float* lo, const float* hi) {
  return Vector3d(0.5 * (double{lo[0]} + hi[0]), 0.5 * (double{lo[1]} + hi[1]), 0.5 * (double{lo[2]} + hi[2]));
}

/// Squared distance from p to box [lo, hi].
inline double point_box_sq(const Vector3d& p, const float* lo, const float* hi) {
  double s = 0;
  for (int i = 0; i < 3; ++i) {
    const double x = std::max(std::max(lo[i] - p[i], p[i] - hi[i]), 0.0);
    s += x * x;
  }
  return s;
}

/// Squared distance between boxes [alo, ahi] and [blo, bhi].
inline double box_box_sq(const Vector3d& alo, const Vector3d& ahi, const float* blo, const float* bhi) {
  double s = 0;
  for (int i = 0; i < 3; ++i) {
    const double x = std::max(std::max(blo[i] - ahi[i], alo[i] - bhi[i]), 0.0);
    s += x * x;
  }
  return s;
}

/// Componentwise reciprocal of a direction, +inf marking axes the direction is parallel to.
inline Vector3d safe_inverse(const Vector3d& d) {
  Vector3d inv;
  for (int i = 0; i < 3; ++i) inv[i] = std::abs(d[i]) > 1e-300 ? 1.0 / d[i] : kInf;
  return inv;
}

/// Slab test: does o + t d, t in [t0, t1], meet box [lo - e, hi + e]? Outputs the entry t.
/// The box inflated by e in every axis contains every point within e of the box, so a miss
/// proves the distance exceeds e (a conservative, never over-estimating bound).
inline bool ray_hits_box(const Vector3d& o, const Vector3d& inv, const float* lo, const float* hi, double e, double t0,
                         double t1, double& t_enter) {
  e = e * (1 + 1e-12) + 1e-15;  // absorb the rounding of the slab arithmetic
  for (int i = 0; i < 3; ++i) {
    if (std::isinf(inv[i])) {
      if (o[i] < lo[i] - e || o[i] > hi[i] + e) return false;
      continue;
    }
    double ta = (lo[i] - e - o[i]) * inv[i];
    double tb = (hi[i] + e - o[i]) * inv[i];
    if (ta > tb) std::swap(ta, tb);
    t0 = std::max(t0, ta);
    t1 = std::min(t1, tb);
    if (t0 > t1) return false;
  }
  t_enter = t0;
  return true;
}

/// First t in [0, t_max] where o + t d (d unit) is within `radius` of c; false if none.
inline bool ray_ball_entry(const Vector3d& o, const Vector3d& d, const Vector3d& c, double radius, double t_max,
                           double& t_enter) {
  const double R = radius * (1 + 1e-12) + 1e-15;
  const Vector3d m = o - c;
  const double cc = m.squaredNorm() - R * R;
  t_enter = 0;
  if (cc <= 0) return true;  // starts inside the ball
  const double b = m.dot(d);
  if (b >= 0) return false;
  const double disc = b * b - cc;
  if (disc < 0) return false;
  t_enter = cc / (-b + std::sqrt(disc));  // = -b - sqrt(disc), without cancellation
  return t_enter <= t_max;
}

/// Largest w.(q - c) over the points q of the box [lo, hi] centred on c.
inline double box_support(const Vector3d& w, const float* lo, const float* hi) {
  return 0.5 * ((double{hi[0]} - lo[0]) * std::abs(w[0]) + (double{hi[1]} - lo[1]) * std::abs(w[1]) +
                (double{hi[2]} - lo[2]) * std::abs(w[2]));
}

/// True when a set whose points q all have w.(q - c) <= support is provably farther than e from a
/// convex query (point or segment), where w = p* - c points from c to the query's closest point p*
/// (w2 = |w|^2): the whole query lies beyond the plane through p* normal to w, and the set reaches
/// at most support / |w| from c toward it, so the gap is at least (w2 - support) / |w|. The
/// tolerance absorbs the rounding of p*.
inline bool separated_beyond(double w2, double support, double e) {
  const double g = w2 - support - 1e-14 * w2;  // gap * |w|, less the tolerance's share
  const double reach = e * (1 + 1e-12) + 1e-15;
  return g > 0 && g * g > reach * reach * w2;
}

/// Largest w.(q - c) over the points q of the triangle with corners v.
inline double triangle_support(const Vector3d& w, const Corners& v, const Vector3d& c) {
  return std::max({w.dot(v[0] - c), w.dot(v[1] - c), w.dot(v[2] - c)});
}

/// The float axes are orthonormal only to float precision: a relative slack this size covers it.
constexpr double kAxisSlack = 1e-5;

/// An oriented box {x : u_i . (x - c) in [lo_i, hi_i]} (rows u_i of `axes`, c the node's box
/// centre) and the lower bounds on distances to it.
struct OrientedBox {
  const float (*axes)[3];
  const float* lo;
  const float* hi;
  double radius;  // of the node's box: |x - c| <= radius for every x inside

  [[nodiscard]] double along(int i, const Vector3d& v) const {
    return double{axes[i][0]} * v[0] + double{axes[i][1]} * v[1] + double{axes[i][2]} * v[2];
  }

  /// Largest w . (q - c) over the points q of the box, rounded up (w = any direction).
  [[nodiscard]] double support(const Vector3d& w) const {
    double s = 0;
    for (int i = 0; i < 3; ++i) {
      const double a = along(i, w);
      s += a >= 0 ? a * hi[i] : a * lo[i];
    }
    // x - c = sum_i y_i u_i + residual, |residual| <= 3 kAxisSlack radius for nearly orthonormal u_i.
    return s + 3 * kAxisSlack * radius * (std::abs(w[0]) + std::abs(w[1]) + std::abs(w[2]));
  }

  /// True when p (given as p - c) is provably farther than e from the box.
  [[nodiscard]] bool point_beyond(const Vector3d& pc, double e) const {
    double g2 = 0;
    for (int i = 0; i < 3; ++i) {
      const double y = along(i, pc);
      const double g = std::max({lo[i] - y, y - hi[i], 0.0});
      g2 += g * g;
    }
    const double reach = e * (1 + kAxisSlack) + 1e-12;
    return g2 > reach * reach;
  }

  /// False when a ball of radius e centred on o + t d, t in [0, t_max], provably never touches
  /// the box (oc = o - c).
  [[nodiscard]] bool ray_meets(const Vector3d& oc, const Vector3d& d, double e, double t_max) const {
    const double m = e * (1 + kAxisSlack) + 1e-12;
    double t0 = 0;
    double t1 = t_max;
    for (int i = 0; i < 3; ++i) {
      const double y = along(i, oc);
      const double v = along(i, d);
      const double l = lo[i] - m;
      const double h = hi[i] + m;
      if (v == 0) {
        if (y < l || y > h) return false;
        continue;
      }
      double ta = (l - y) / v;
      double tb = (h - y) / v;
      if (ta > tb) std::swap(ta, tb);
      t0 = std::max(t0, ta);
      t1 = std::min(t1, tb);
      if (t0 > t1) return false;
    }
    return true;
  }
};

/// A segment a + s d (s in [0, 1]) with the quantities its box tests reuse.
struct SegmentProbe {
  SegmentProbe(const Vector3d& a_in, const Vector3d& b_in)
      : a(a_in), b(b_in), d(b_in - a_in), dd(d.squaredNorm()), lo(a_in.cwiseMin(b_in)), hi(a_in.cwiseMax(b_in)) {}
  Vector3d a, b, d;
  double dd;
  Vector3d lo, hi;

  /// The closest point of the segment to c, minus c.
  [[nodiscard]] Vector3d offset_from(const Vector3d& c) const { return a + segment_param(c, a, d, dd) * d - c; }

  /// False when the box [lo, hi] or the oriented box is provably farther than e from the segment; `key` gets the
  /// squared centre distance for ordering.
  bool may_reach(const float* blo, const float* bhi, const OrientedBox* obb, double e, double& key) const {
    if (!std::isinf(e) && box_box_sq(lo, hi, blo, bhi) > e * e) return false;
    const Vector3d w = offset_from(box_centre(blo, bhi));
    key = w.squaredNorm();
    if (std::isinf(e)) return true;
    if (separated_beyond(key, box_support(w, blo, bhi), e)) return false;
    return !obb || !separated_beyond(key, obb->support(w), e);
  }
};

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

/// A node's oriented box, for the bounds of OrientedBox.
template <class Node, class Data>
OrientedBox oriented_box(const Node& n, const std::vector<Data>& boxes) {
  const Data& o = boxes[n.oriented];
  return {o.axes, o.lo, o.hi, n.radius};
}

/// SegmentProbe::may_reach with the node's boxes.
template <class Node, class Data>
bool segment_may_reach(const SegmentProbe& seg, const Node& n, const std::vector<Data>& boxes, double e, double& key) {
  if (n.oriented == MeshDistance::kNoHint) return seg.may_reach(n.lo, n.hi, nullptr, e, key);
  const OrientedBox obb = oriented_box(n, boxes);
  return seg.may_reach(n.lo, n.hi, &obb, e, key);
}

}  // namespace

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

std::size_t MeshDistance::triangle_count() const { return triangles_.size(); }

std::size_t MeshDistance::memory_bytes() const {
  return nodes_.capacity() * sizeof(Node) + oriented_boxes_.capacity() * sizeof(OrientedBoxData) +
         vertices_.capacity() * sizeof(Eigen::Vector3d) + triangles_.capacity() * sizeof(triangles_[0]) +
         face_normals_.capacity() * sizeof(Eigen::Vector3d) + vertex_normals_.capacity() * sizeof(Eigen::Vector3d) +
         edge_normals_.capacity() * sizeof(edge_normals_[0]) + corners_.capacity() * sizeof(corners_[0]) +
         triangle_ids_.capacity() * sizeof(std::uint32_t) + slot_of_triangle_.capacity() * sizeof(std::uint32_t) +
         bounding_spheres_.capacity() * sizeof(bounding_spheres_[0]);
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
               const auto& bs = bounding_spheres_[s];
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
  // No surface within the radius: the capsule overlaps the solid only if it lies entirely inside.
  // a is farther than r from the surface, so a ray-parity test is well conditioned; it falls back
  // to the pseudo-normal test (contains) whenever the ray passes near an edge or grazes a plane.
  bool decided = false;
  const bool inside = inside_by_ray_parity(a, decided);
  return decided ? inside : contains(a);
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
