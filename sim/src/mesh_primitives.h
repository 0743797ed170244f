// The geometry MeshDistance's queries and BVH build share: exact closest points between points,
// segments and triangles, sphere sweeps against a triangle, and the conservative bounds of boxes,
// oriented boxes and triangles that prune a traversal. Internal to sim (src/, not installed),
// included by mesh_distance.cc (queries) and mesh_distance_build.cc (construction) only. Its
// functions have internal linkage (an unnamed namespace) so that each file's optimizer treats
// them as it did when they were one file's statics: as inline functions with external linkage
// the segment searches ran 10-20 % slower (BM_HandTick).
#pragma once

#include "telegrasp/sim/mesh_distance.h"

#include <Eigen/Geometry>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

namespace telegrasp::sim::mesh_detail {
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
inline Vector3d closest_on_triangle(const Vector3d& p, const Corners& v, int& feature) {
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
inline double segment_triangle_sq(const Vector3d& a, const Vector3d& b, const Vector3d& d, double dd, const Corners& v,
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
inline bool line_triangle_minkowski(const Vector3d& o, const Vector3d& d, const Corners& v, const Vector3d& n, double r,
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

/// A lower bound on the distance between a segment and triangles, from the segment's own frame:
/// unit axis u along the segment and e1, e2 across it. Every point x of the segment has
/// u.(x - a) in [0, len] and projects onto the same point across (a), so for a triangle point y
///   |x - y|^2 = |across(y - a)|^2 + (u.(y - a) - u.(x - a))^2
/// and the distance to the triangle is at least sqrt(A^2 + G^2): A the 2-D distance from the
/// origin to the triangle projected across the axis (a convex polygon: the projected triangle),
/// G the gap between [0, len] and the corners' range along it. Exact when the closest pair is
/// interior to the segment (a finger lying across a thin part), where the bounding-sphere and
/// plane tests are loose by the triangle's spread squared over twice the distance. A triangle
/// reaching past an end's plane (G = 0) is still bounded by A, its distance from the segment's
/// line: on a coarse mesh of large facets that rejects most of what the exact test would
/// otherwise take (the hammer stand-in's grasp tick: 562 exact tests -> 19).
struct SegmentFrame {
  /// The frame is set up on the first test (most queries end on their hint or test no triangle).
  SegmentFrame(const Vector3d& a_in, const Vector3d& d_in, double dd_in, double extent_in)
      : a(a_in), d(d_in), dd(dd_in), extent(extent_in) {}

  Vector3d a, d;
  double dd, extent;
  bool ready = false, valid = false;
  Vector3d u, e1, e2;
  double len = 0;
  double slack = 0;  // absolute rounding allowance: 1e-9 of the largest coordinate in play

  void prepare() {
    ready = true;
    if (!(dd > 0) || !std::isfinite(dd)) return;
    len = std::sqrt(dd);
    u = d / len;
    // e1: u crossed with the coordinate axis it is least aligned with.
    int k = 0;
    if (std::abs(u[1]) < std::abs(u[k])) k = 1;
    if (std::abs(u[2]) < std::abs(u[k])) k = 2;
    e1 = u.cross(Vector3d::Unit(k)).normalized();
    e2 = u.cross(e1);
    slack = 1e-9 * (extent + len);
    valid = std::isfinite(slack);
  }

  /// True when the triangle is provably farther than e from the segment: its computed exact
  /// distance would exceed e as well (the slack covers the rounding of both computations).
  [[nodiscard]] bool beyond(const Corners& v, double e) {
    if (!ready) prepare();
    if (!valid) return false;
    const Vector3d z[3] = {v[0] - a, v[1] - a, v[2] - a};
    double lo = kInf, hi = -kInf;
    for (int k = 0; k < 3; ++k) {
      const double ax = u.dot(z[k]);
      lo = std::min(lo, ax);
      hi = std::max(hi, ax);
    }
    const double g = std::max({lo - len, -hi, 0.0});
    const double reach = e * (1 + 1e-9) + slack;
    const double reach2 = reach * reach;
    const double g2 = g * g;
    if (g2 > reach2) return true;
    double px[3], py[3];
    for (int k = 0; k < 3; ++k) {
      px[k] = e1.dot(z[k]);
      py[k] = e2.dot(z[k]);
    }
    // Every point of the projected triangle must lie farther than sqrt(rest) from the origin:
    // its corners, the origin outside it, and each edge's interior (the squared distance to an
    // edge's line is cross^2 / |edge|^2, compared without dividing).
    const double rest = reach2 - g2;
    for (int k = 0; k < 3; ++k)
      if (px[k] * px[k] + py[k] * py[k] <= rest) return false;
    bool pos = false, neg = false;
    for (int k = 0; k < 3; ++k) {
      const int j = k == 2 ? 0 : k + 1;
      const double ex = px[j] - px[k];
      const double ey = py[j] - py[k];
      const double cr = px[k] * ey - py[k] * ex;  // sign: which side of the edge the origin lies
      pos |= cr > 0;
      neg |= cr < 0;
      const double along = -(px[k] * ex + py[k] * ey);  // the origin's foot on the edge, times |edge|^2
      const double ee = ex * ex + ey * ey;
      if (along > 0 && along < ee && !(cr * cr > rest * ee)) return false;
    }
    return pos && neg;  // else the origin is inside (or on) the projected triangle
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

/// A node's oriented box, for the bounds of OrientedBox.
template <class Node, class Data>
inline OrientedBox oriented_box(const Node& n, const std::vector<Data>& boxes) {
  const Data& o = boxes[n.oriented];
  return {o.axes, o.lo, o.hi, n.radius};
}

/// SegmentProbe::may_reach with the node's boxes.
template <class Node, class Data>
inline bool segment_may_reach(const SegmentProbe& seg, const Node& n, const std::vector<Data>& boxes, double e, double& key) {
  if (n.oriented == MeshDistance::kNoHint) return seg.may_reach(n.lo, n.hi, nullptr, e, key);
  const OrientedBox obb = oriented_box(n, boxes);
  return seg.may_reach(n.lo, n.hi, &obb, e, key);
}

}  // namespace
}  // namespace telegrasp::sim::mesh_detail
