// Tests for MeshDistance (sim/mesh_distance.h): closest point, signed distance, containment,
// segment distance, capsule overlap / signed distance and sphere casts, against analytic
// answers on boxes, a tetrahedron, a capped cylinder and an icosphere, and against an
// independent brute-force reference over all triangles.
#include "telegrasp/sim/mesh_distance.h"

#include "test_meshes.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <map>
#include <random>
#include <stdexcept>
#include <utility>
#include <vector>

namespace telegrasp::sim {
namespace {

using Eigen::Vector3d;

constexpr double kExact = 1e-12;  // planar geometry: exact up to double rounding
constexpr double kPi = 3.14159265358979323846;

// ---------------------------------------------------------------- mesh builders

/// Flips triangles so each normal points away from `centre` (valid for star-shaped meshes).
void orient_outward(TriangleMesh& m, const Vector3d& centre) {
  for (auto& t : m.triangles) {
    const Vector3d& a = m.vertices[t[0]];
    const Vector3d& b = m.vertices[t[1]];
    const Vector3d& c = m.vertices[t[2]];
    const Vector3d n = (b - a).cross(c - a);
    if (n.dot((a + b + c) / 3.0 - centre) < 0) std::swap(t[1], t[2]);
  }
}

/// Axis-aligned box [-h, h] centred at the origin, 12 triangles.
TriangleMesh make_box(const Vector3d& h) {
  TriangleMesh m;
  for (int i = 0; i < 8; ++i) {
    m.vertices.emplace_back((i & 1) ? h.x() : -h.x(), (i & 2) ? h.y() : -h.y(), (i & 4) ? h.z() : -h.z());
  }
  const std::uint32_t quads[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4},
                                     {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  for (const auto& q : quads) {
    m.triangles.push_back({q[0], q[1], q[2]});
    m.triangles.push_back({q[0], q[2], q[3]});
  }
  orient_outward(m, Vector3d::Zero());
  return m;
}

/// The same mesh as an unindexed triangle soup (every triangle has its own three vertices).
TriangleMesh as_soup(const TriangleMesh& in) {
  TriangleMesh m;
  for (const auto& t : in.triangles) {
    const auto base = static_cast<std::uint32_t>(m.vertices.size());
    for (int k = 0; k < 3; ++k) m.vertices.push_back(in.vertices[t[k]]);
    m.triangles.push_back({base, base + 1, base + 2});
  }
  return m;
}

/// Regular tetrahedron with vertices at distance s*sqrt(3) from the origin.
TriangleMesh make_tetrahedron(double s) {
  TriangleMesh m;
  m.vertices = {Vector3d(s, s, s), Vector3d(s, -s, -s), Vector3d(-s, s, -s), Vector3d(-s, -s, s)};
  m.triangles = {{0, 1, 2}, {0, 1, 3}, {0, 2, 3}, {1, 2, 3}};
  orient_outward(m, Vector3d::Zero());
  return m;
}

/// Icosphere of radius r: an icosahedron subdivided `levels` times, vertices on the sphere.
TriangleMesh make_icosphere(double r, int levels) {
  TriangleMesh m;
  const double p = (1.0 + std::sqrt(5.0)) / 2.0;
  const double raw[12][3] = {{-1, p, 0},  {1, p, 0},  {-1, -p, 0}, {1, -p, 0}, {0, -1, p},  {0, 1, p},
                             {0, -1, -p}, {0, 1, -p}, {p, 0, -1},  {p, 0, 1},  {-p, 0, -1}, {-p, 0, 1}};
  for (const auto& v : raw) m.vertices.push_back(r * Vector3d(v[0], v[1], v[2]).normalized());
  m.triangles = {{0, 11, 5},  {0, 5, 1},  {0, 1, 7},  {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
                 {11, 10, 2}, {10, 7, 6}, {7, 1, 8},  {3, 9, 4},  {3, 4, 2},   {3, 2, 6}, {3, 6, 8},
                 {3, 8, 9},   {4, 9, 5},  {2, 4, 11}, {6, 2, 10}, {8, 6, 7},   {9, 8, 1}};
  for (int l = 0; l < levels; ++l) {
    std::map<std::pair<std::uint32_t, std::uint32_t>, std::uint32_t> mid;
    const auto midpoint = [&](std::uint32_t a, std::uint32_t b) {
      const auto key = std::minmax(a, b);
      const auto it = mid.find(key);
      if (it != mid.end()) return it->second;
      const auto idx = static_cast<std::uint32_t>(m.vertices.size());
      m.vertices.push_back(r * (m.vertices[a] + m.vertices[b]).normalized());
      mid.emplace(key, idx);
      return idx;
    };
    std::vector<std::array<std::uint32_t, 3>> next;
    for (const auto& t : m.triangles) {
      const std::uint32_t ab = midpoint(t[0], t[1]);
      const std::uint32_t bc = midpoint(t[1], t[2]);
      const std::uint32_t ca = midpoint(t[2], t[0]);
      next.push_back({t[0], ab, ca});
      next.push_back({t[1], bc, ab});
      next.push_back({t[2], ca, bc});
      next.push_back({ab, bc, ca});
    }
    m.triangles = std::move(next);
  }
  orient_outward(m, Vector3d::Zero());
  return m;
}

/// Capped cylinder (regular n-gon prism) of circumradius r, z in [-h, h], fan-triangulated caps.
TriangleMesh make_cylinder(double r, double h, int n) {
  TriangleMesh m;
  for (int i = 0; i < n; ++i) {
    const double a = 2 * kPi * i / n;
    m.vertices.emplace_back(r * std::cos(a), r * std::sin(a), -h);
    m.vertices.emplace_back(r * std::cos(a), r * std::sin(a), h);
  }
  const auto bottom = static_cast<std::uint32_t>(m.vertices.size());
  m.vertices.emplace_back(0, 0, -h);
  m.vertices.emplace_back(0, 0, h);
  const std::uint32_t top = bottom + 1;
  for (int i = 0; i < n; ++i) {
    const auto b0 = static_cast<std::uint32_t>(2 * i);
    const auto b1 = static_cast<std::uint32_t>(2 * ((i + 1) % n));
    m.triangles.push_back({b0, b1, b1 + 1});
    m.triangles.push_back({b0, b1 + 1, b0 + 1});
    m.triangles.push_back({bottom, b1, b0});
    m.triangles.push_back({top, b0 + 1, b1 + 1});
  }
  orient_outward(m, Vector3d::Zero());
  return m;
}

/// Box [-h, h] with every face split into n x n squares of two triangles: wide flat patches of
/// small triangles, all equally far from a segment running parallel to them.
TriangleMesh make_subdivided_box(const Vector3d& h, int n) {
  TriangleMesh m;
  for (int axis = 0; axis < 3; ++axis) {
    const int u = (axis + 1) % 3;
    const int v = (axis + 2) % 3;
    for (const double side : {-1.0, 1.0}) {
      const auto first = static_cast<std::uint32_t>(m.vertices.size());
      for (int i = 0; i <= n; ++i) {
        for (int j = 0; j <= n; ++j) {
          Vector3d p;
          p[axis] = side * h[axis];
          p[u] = -h[u] + 2 * h[u] * i / n;  // the same expression on every face: shared edges weld
          p[v] = -h[v] + 2 * h[v] * j / n;
          m.vertices.push_back(p);
        }
      }
      const auto at = [&](int i, int j) { return first + static_cast<std::uint32_t>(i * (n + 1) + j); };
      for (int i = 0; i < n; ++i) {
        for (int j = 0; j < n; ++j) {
          m.triangles.push_back({at(i, j), at(i + 1, j), at(i + 1, j + 1)});
          m.triangles.push_back({at(i, j), at(i + 1, j + 1), at(i, j + 1)});
        }
      }
    }
  }
  orient_outward(m, Vector3d::Zero());
  return m;
}

// ---------------------------------------------------------------- independent reference

double ref_point_segment_sq(const Vector3d& p, const Vector3d& a, const Vector3d& b) {
  const Vector3d ab = b - a;
  const double l2 = ab.squaredNorm();
  const double t = l2 > 0 ? std::clamp((p - a).dot(ab) / l2, 0.0, 1.0) : 0.0;
  return (a + t * ab - p).squaredNorm();
}

/// Point-triangle by projection onto the plane, else the nearest of the three edges.
double ref_point_triangle_sq(const Vector3d& p, const Vector3d& a, const Vector3d& b, const Vector3d& c) {
  const Vector3d n = (b - a).cross(c - a);
  const double n2 = n.squaredNorm();
  if (n2 > 0) {
    const Vector3d x = p - ((p - a).dot(n) / n2) * n;
    if ((b - a).cross(x - a).dot(n) >= 0 && (c - b).cross(x - b).dot(n) >= 0 && (a - c).cross(x - c).dot(n) >= 0) {
      return (p - x).squaredNorm();
    }
  }
  return std::min({ref_point_segment_sq(p, a, b), ref_point_segment_sq(p, b, c), ref_point_segment_sq(p, c, a)});
}

/// Segment-segment: the interior critical point of the two lines if admissible, else the best
/// of the four endpoint-to-segment distances.
double ref_segment_segment_sq(const Vector3d& p1, const Vector3d& q1, const Vector3d& p2, const Vector3d& q2) {
  double best = std::min({ref_point_segment_sq(p1, p2, q2), ref_point_segment_sq(q1, p2, q2),
                          ref_point_segment_sq(p2, p1, q1), ref_point_segment_sq(q2, p1, q1)});
  const Vector3d u = q1 - p1;
  const Vector3d v = q2 - p2;
  const Vector3d w = p1 - p2;
  const double a = u.dot(u), b = u.dot(v), c = v.dot(v), d = u.dot(w), e = v.dot(w);
  const double den = a * c - b * b;
  if (den > 1e-12 * a * c) {
    const double s = (b * e - c * d) / den;
    const double t = (a * e - b * d) / den;
    if (s >= 0 && s <= 1 && t >= 0 && t <= 1) best = std::min(best, (w + s * u - t * v).squaredNorm());
  }
  return best;
}

/// Segment-triangle: Moller-Trumbore crossing gives 0, else endpoints and edges.
double ref_segment_triangle_sq(const Vector3d& p, const Vector3d& q, const Vector3d& a, const Vector3d& b,
                               const Vector3d& c) {
  const Vector3d dir = q - p;
  const Vector3d e1 = b - a;
  const Vector3d e2 = c - a;
  const Vector3d h = dir.cross(e2);
  const double det = e1.dot(h);
  if (std::abs(det) > 1e-300) {
    const Vector3d s = p - a;
    const double u = s.dot(h) / det;
    const Vector3d qv = s.cross(e1);
    const double v = dir.dot(qv) / det;
    const double t = e2.dot(qv) / det;
    if (u >= 0 && v >= 0 && u + v <= 1 && t >= 0 && t <= 1) return 0;
  }
  return std::min({ref_point_triangle_sq(p, a, b, c), ref_point_triangle_sq(q, a, b, c),
                   ref_segment_segment_sq(p, q, a, b), ref_segment_segment_sq(p, q, b, c),
                   ref_segment_segment_sq(p, q, c, a)});
}

double brute_point_distance(const TriangleMesh& m, const Vector3d& p) {
  double best = std::numeric_limits<double>::infinity();
  for (const auto& t : m.triangles) {
    best = std::min(best, ref_point_triangle_sq(p, m.vertices[t[0]], m.vertices[t[1]], m.vertices[t[2]]));
  }
  return std::sqrt(best);
}

double brute_segment_distance(const TriangleMesh& m, const Vector3d& a, const Vector3d& b) {
  double best = std::numeric_limits<double>::infinity();
  for (const auto& t : m.triangles) {
    best = std::min(best, ref_segment_triangle_sq(a, b, m.vertices[t[0]], m.vertices[t[1]], m.vertices[t[2]]));
  }
  return std::sqrt(best);
}

/// Exact signed distance of the box [-h, h].
double box_sdf(const Vector3d& h, const Vector3d& p) {
  const Vector3d q = p.cwiseAbs() - h;
  return q.cwiseMax(0.0).norm() + std::min(q.maxCoeff(), 0.0);
}

/// Largest gap between the sphere of radius r and the icosphere's facets (vertices lie on the
/// sphere, facets inside it): the surface lies in the shell [r - error, r].
double tessellation_error(const TriangleMesh& m, double r) { return r - brute_point_distance(m, Vector3d::Zero()); }

/// First t >= 0 at which o + t d comes within `radius` of the origin (d unit), or +inf.
double ray_sphere(const Vector3d& o, const Vector3d& d, double radius) {
  const double b = o.dot(d);
  const double c = o.squaredNorm() - radius * radius;
  const double disc = b * b - c;
  if (disc < 0) return std::numeric_limits<double>::infinity();
  return -b - std::sqrt(disc);
}

Vector3d random_unit(std::mt19937& rng) {
  std::normal_distribution<double> g(0.0, 1.0);
  Vector3d v;
  do {
    v = Vector3d(g(rng), g(rng), g(rng));
  } while (v.norm() < 1e-6);
  return v.normalized();
}

void expect_vec_near(const Vector3d& a, const Vector3d& b, double tol) {
  EXPECT_NEAR((a - b).norm(), 0.0, tol) << "got " << a.transpose() << " expected " << b.transpose();
}

const Vector3d kBoxHalf(0.05, 0.03, 0.02);

// ---------------------------------------------------------------- construction

TEST(MeshDistance, ConstructorRejectsEmptyMeshAndBadIndices) {
  EXPECT_THROW(MeshDistance{TriangleMesh{}}, std::invalid_argument);
  TriangleMesh bad;
  bad.vertices = {Vector3d::Zero(), Vector3d::UnitX(), Vector3d::UnitY()};
  bad.triangles = {{0, 1, 3}};
  EXPECT_THROW(MeshDistance{bad}, std::invalid_argument);
}

TEST(MeshDistance, DefaultConstructedAnswersNothing) {
  const MeshDistance md;
  EXPECT_FALSE(md.closest_point(Vector3d::Zero()).found);
  EXPECT_FALSE(md.closest_to_segment(Vector3d::Zero(), Vector3d::UnitX()).found);
  EXPECT_FALSE(md.contains(Vector3d::Zero()));
  EXPECT_FALSE(md.capsule_overlaps(Vector3d::Zero(), Vector3d::UnitX(), 1.0));
  EXPECT_FALSE(md.sphere_cast(Vector3d::Zero(), Vector3d::UnitX(), 0.1, 1.0).hit);
  EXPECT_EQ(md.triangle_count(), 0u);
}

TEST(MeshDistance, CountsTrianglesAndMemory) {
  const TriangleMesh sphere = make_icosphere(0.04, 3);
  const MeshDistance md(sphere);
  EXPECT_EQ(md.triangle_count(), sphere.triangles.size());
  // At least the triangle corners, normals and indices must be held.
  EXPECT_GT(md.memory_bytes(), sphere.triangles.size() * (9 + 3 + 9) * sizeof(double));
}

// ---------------------------------------------------------------- closest point on a box

// Expects the point of the kBoxHalf box closest to `p` at `on_mesh`, `distance` away (and as
// much outside, if `check_signed`), with normal `normal`.
void expect_box_closest(const Vector3d& p, const Vector3d& on_mesh, double distance, const Vector3d& normal,
                        bool check_signed) {
  const MeshDistance md(make_box(kBoxHalf));
  const PointQuery q = md.closest_point(p);
  ASSERT_TRUE(q.found);
  expect_vec_near(q.point_on_mesh, on_mesh, kExact);
  EXPECT_NEAR(q.distance, distance, kExact);
  if (check_signed) {
    EXPECT_NEAR(q.signed_distance, distance, kExact);
  }
  expect_vec_near(q.normal, normal, kExact);
}

TEST(MeshDistance, BoxClosestPointOnFace) {
  expect_box_closest(Vector3d(0.08, 0.01, -0.005), Vector3d(0.05, 0.01, -0.005), 0.03, Vector3d::UnitX(), true);
}

TEST(MeshDistance, BoxClosestPointOnEdgeUsesEdgePseudoNormal) {
  expect_box_closest(Vector3d(0.07, 0.05, 0.004), Vector3d(0.05, 0.03, 0.004), 0.02 * std::sqrt(2.0),
                     Vector3d(1, 1, 0).normalized(), true);
}

TEST(MeshDistance, BoxClosestPointOnVertexUsesAngleWeightedNormal) {
  expect_box_closest(Vector3d(0.06, 0.04, 0.03), Vector3d(0.05, 0.03, 0.02), 0.01 * std::sqrt(3.0),
                     Vector3d(1, 1, 1).normalized(), false);
}

TEST(MeshDistance, TriangleIndexRefersToInputMesh) {
  const TriangleMesh box = make_box(kBoxHalf);
  const MeshDistance md(box);
  const PointQuery q = md.closest_point(Vector3d(0.01, 0.002, -0.09));
  ASSERT_TRUE(q.found);
  ASSERT_LT(q.triangle, box.triangles.size());
  for (std::uint32_t v : box.triangles[q.triangle]) EXPECT_DOUBLE_EQ(box.vertices[v].z(), -kBoxHalf.z());
}

TEST(MeshDistance, SoupWithDuplicatedVerticesKeepsEdgeAndVertexNormals) {
  const MeshDistance md(as_soup(make_box(kBoxHalf)));
  expect_vec_near(md.closest_point(Vector3d(0.07, 0.05, 0.004)).normal, Vector3d(1, 1, 0).normalized(), kExact);
  expect_vec_near(md.closest_point(Vector3d(-0.06, 0.04, -0.03)).normal, Vector3d(-1, 1, -1).normalized(), kExact);
  EXPECT_TRUE(md.contains(Vector3d(0.0499, 0.0299, 0.0199)));
  EXPECT_FALSE(md.contains(Vector3d(0.0501, 0.0301, 0.0201)));
}

TEST(MeshDistance, BoxSignedDistanceMatchesAnalyticInsideAndOutside) {
  const MeshDistance md(make_box(kBoxHalf));
  EXPECT_NEAR(md.signed_distance(Vector3d(0.01, -0.02, 0.005)), -0.01, kExact);
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1.6, 1.6);
  for (int i = 0; i < 500; ++i) {
    const Vector3d p(u(rng) * kBoxHalf.x(), u(rng) * kBoxHalf.y(), u(rng) * kBoxHalf.z());
    EXPECT_NEAR(md.signed_distance(p), box_sdf(kBoxHalf, p), kExact) << p.transpose();
  }
}

TEST(MeshDistance, BoxContainsInsideOutsideAndNearCorners) {
  const MeshDistance md(make_box(kBoxHalf));
  EXPECT_TRUE(md.contains(Vector3d::Zero()));
  EXPECT_TRUE(md.contains(Vector3d(0.0499, 0.0299, 0.0199)));
  EXPECT_FALSE(md.contains(Vector3d(0.0501, 0.0299, 0.0199)));
  EXPECT_FALSE(md.contains(Vector3d(0.1, 0.0, 0.0)));
  const Vector3d corner = kBoxHalf;
  for (int sx : {-1, 1}) {
    for (int sy : {-1, 1}) {
      for (int sz : {-1, 1}) {
        const Vector3d c(sx * corner.x(), sy * corner.y(), sz * corner.z());
        const Vector3d outward(sx, sy, sz);
        EXPECT_TRUE(md.contains(c - 1e-9 * outward)) << c.transpose();
        EXPECT_FALSE(md.contains(c + 1e-9 * outward)) << c.transpose();
        // Outside along one axis only, inside along the others: still outside.
        EXPECT_FALSE(md.contains(c + Vector3d(sx * 1e-9, -sy * 1e-4, -sz * 1e-4))) << c.transpose();
      }
    }
  }
  // Documented convention: points exactly on the surface count as inside.
  EXPECT_TRUE(md.contains(Vector3d(0.05, 0.0, 0.0)));
  EXPECT_EQ(md.signed_distance(Vector3d(0.05, 0.0, 0.0)), 0.0);
}

// ---------------------------------------------------------------- other closed shapes

TEST(MeshDistance, TetrahedronInradiusAndVertex) {
  const double s = 0.02;
  const MeshDistance md(make_tetrahedron(s));
  // Inradius of a regular tetrahedron = circumradius / 3 = s * sqrt(3) / 3.
  EXPECT_NEAR(md.signed_distance(Vector3d::Zero()), -s * std::sqrt(3.0) / 3.0, kExact);
  const Vector3d far = 3 * s * Vector3d(1, 1, 1);
  const PointQuery q = md.closest_point(far);
  expect_vec_near(q.point_on_mesh, Vector3d(s, s, s), kExact);
  EXPECT_NEAR(q.signed_distance, (far - Vector3d(s, s, s)).norm(), kExact);
  expect_vec_near(q.normal, Vector3d(1, 1, 1).normalized(), kExact);
  EXPECT_TRUE(md.contains(Vector3d(0.3 * s, 0.3 * s, 0.3 * s)));
  EXPECT_FALSE(md.contains(Vector3d(-s, -s, -s)));  // beyond the face opposite to (s, s, s)
}

TEST(MeshDistance, TetrahedronSharpVertexSignNeedsPseudoNormal) {
  // Face normals of a regular tetrahedron are 109.5 degrees apart, so near a vertex, points in its
  // Voronoi cone lie behind the planes of some incident faces: only the vertex pseudo-normal gives
  // the right (outside) sign whichever incident triangle the search reports.
  const double s = 0.02;
  const TriangleMesh tet = make_tetrahedron(s);
  const MeshDistance md(tet);
  for (std::uint32_t vi = 0; vi < 4; ++vi) {
    const Vector3d v = tet.vertices[vi];
    std::vector<Vector3d> normals;
    for (const auto& t : tet.triangles) {
      if (t[0] != vi && t[1] != vi && t[2] != vi) continue;
      const Vector3d& a = tet.vertices[t[0]];
      normals.push_back((tet.vertices[t[1]] - a).cross(tet.vertices[t[2]] - a).normalized());
    }
    ASSERT_EQ(normals.size(), 3u);
    for (int i = 0; i < 3; ++i) {
      // Mostly along one face normal, nudged into the interior of the vertex's normal cone.
      const Vector3d dir = (0.9 * normals[i] + 0.05 * normals[(i + 1) % 3] + 0.05 * normals[(i + 2) % 3]).normalized();
      const Vector3d p = v + 0.001 * dir;
      const PointQuery q = md.closest_point(p);
      expect_vec_near(q.point_on_mesh, v, kExact);
      EXPECT_NEAR(q.signed_distance, 0.001, kExact) << "vertex " << vi << " face " << i;
      EXPECT_FALSE(md.contains(p));
    }
  }
}

TEST(MeshDistance, CappedCylinderSideAndCaps) {
  const double r = 0.03;
  const double h = 0.05;
  const int n = 24;
  const MeshDistance md(make_cylinder(r, h, n));
  const double apothem = r * std::cos(kPi / n);
  // Through the middle of side face i (angle (i + 1/2) * 2 pi / n), at z = 0.01.
  for (int i = 0; i < n; i += 5) {
    const double a = (i + 0.5) * 2 * kPi / n;
    const Vector3d dir(std::cos(a), std::sin(a), 0);
    for (double rho : {0.0, 0.01, 0.045}) {
      const Vector3d p = rho * dir + Vector3d(0, 0, 0.01);
      const double side = rho - apothem;
      const double cap = 0.01 - h;  // inside: distance to the top cap is h - 0.01
      const double expected = side > 0 ? side : std::max(side, cap);
      EXPECT_NEAR(md.signed_distance(p), expected, kExact) << "i=" << i << " rho=" << rho;
    }
  }
  EXPECT_NEAR(md.signed_distance(Vector3d(0.005, -0.004, h + 0.02)), 0.02, kExact);
  EXPECT_NEAR(md.signed_distance(Vector3d(0.005, -0.004, -h + 0.003)), -0.003, kExact);
  EXPECT_TRUE(md.contains(Vector3d(0, 0, h - 1e-6)));
  EXPECT_FALSE(md.contains(Vector3d(0, 0, h + 1e-6)));
}

TEST(MeshDistance, IcosphereDistanceWithinTessellationBound) {
  const double radius = 0.04;
  const TriangleMesh sphere = make_icosphere(radius, 3);
  const double tessellation_tol = tessellation_error(sphere, radius);
  ASSERT_GT(tessellation_tol, 0.0);
  ASSERT_LT(tessellation_tol, 0.001);
  const MeshDistance md(sphere);
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> rho(0.0, 0.08);
  for (int i = 0; i < 300; ++i) {
    const Vector3d dir = random_unit(rng);
    const double r = rho(rng);
    const double sd = md.signed_distance(r * dir);
    // The surface lies in the shell [radius - tol, radius].
    EXPECT_GE(sd, r - radius - 1e-12);
    EXPECT_LE(sd, r - radius + tessellation_tol + 1e-12);
    if (std::abs(r - radius) > tessellation_tol + 1e-9) {
      EXPECT_EQ(md.contains(r * dir), r < radius);
    }
  }
}

// ---------------------------------------------------------------- segments

TEST(MeshDistance, BoxSegmentParallelToFace) {
  const MeshDistance md(make_box(kBoxHalf));
  const SegmentQuery q = md.closest_to_segment(Vector3d(-0.02, 0.0, 0.025), Vector3d(0.02, 0.0, 0.025));
  ASSERT_TRUE(q.found);
  EXPECT_NEAR(q.distance, 0.005, kExact);
  EXPECT_NEAR(q.point_on_mesh.z(), 0.02, kExact);
  EXPECT_NEAR((q.point_on_segment - q.point_on_mesh).norm(), 0.005, kExact);
  expect_vec_near(q.normal, Vector3d::UnitZ(), kExact);
}

TEST(MeshDistance, BoxSegmentCrossingFaceHasZeroDistance) {
  const MeshDistance md(make_box(kBoxHalf));
  const SegmentQuery q = md.closest_to_segment(Vector3d(0.001, 0.002, 0.01), Vector3d(0.001, 0.002, 0.05));
  ASSERT_TRUE(q.found);
  EXPECT_EQ(q.distance, 0.0);
  EXPECT_NEAR(q.segment_t, 0.25, kExact);
  expect_vec_near(q.point_on_mesh, Vector3d(0.001, 0.002, 0.02), kExact);
  expect_vec_near(q.point_on_segment, Vector3d(0.001, 0.002, 0.02), kExact);
}

TEST(MeshDistance, BoxSegmentSkewToEdge) {
  const MeshDistance md(make_box(kBoxHalf));
  // Passes (0.06, 0.04, 0) with direction (1, -1, 1): closest to the z-edge at (0.05, 0.03).
  const Vector3d c(0.06, 0.04, 0.0);
  const Vector3d dir = Vector3d(1, -1, 1).normalized();
  const SegmentQuery q = md.closest_to_segment(c - 0.01 * dir, c + 0.01 * dir);
  ASSERT_TRUE(q.found);
  EXPECT_NEAR(q.distance, 0.01 * std::sqrt(2.0), kExact);
  EXPECT_NEAR(q.segment_t, 0.5, 1e-9);
  expect_vec_near(q.point_on_mesh, Vector3d(0.05, 0.03, 0.0), 1e-9);
  expect_vec_near(q.normal, Vector3d(1, 1, 0).normalized(), kExact);
}

TEST(MeshDistance, MaxDistancePrunesToNotFound) {
  const MeshDistance md(make_box(kBoxHalf));
  const Vector3d p(0.08, 0.0, 0.0);  // 0.03 from the box
  EXPECT_FALSE(md.closest_point(p, 0.029).found);
  const PointQuery q = md.closest_point(p, 0.031);
  ASSERT_TRUE(q.found);
  EXPECT_NEAR(q.distance, 0.03, kExact);
  const Vector3d a(0.07, -0.01, 0.0), b(0.07, 0.01, 0.0);  // 0.02 from the box
  EXPECT_FALSE(md.closest_to_segment(a, b, 0.019).found);
  const SegmentQuery s = md.closest_to_segment(a, b, 0.021);
  ASSERT_TRUE(s.found);
  EXPECT_NEAR(s.distance, 0.02, kExact);
  EXPECT_FALSE(md.closest_point(p, -1.0).found);
}

// The searches prune a node or triangle by the plane through the segment's point closest to its
// centre: a segment lying along a flat patch of many small triangles, each as far as the next,
// is where that bound must neither lose the answer nor let a bounded search miss it.
TEST(MeshDistance, SegmentsAlongFinelyTriangulatedFacesFindTheExactGap) {
  const TriangleMesh mesh = make_subdivided_box(kBoxHalf, 24);  // 6912 triangles of ~2 mm
  const MeshDistance md(mesh);
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (int i = 0; i < 300; ++i) {
    const double height = 0.0005 + 0.015 * u(rng);  // like a finger capsule's radius above the top face
    const double angle = 2 * kPi * u(rng);
    const Vector3d dir(std::cos(angle), std::sin(angle), 0.0);
    const double length = 0.03 * u(rng);
    // Start over the face; the far end may overhang an edge, the closest distance stays `height`.
    const Vector3d a(kBoxHalf.x() * (2 * u(rng) - 1), kBoxHalf.y() * (2 * u(rng) - 1), kBoxHalf.z() + height);
    const Vector3d b = a + length * dir;
    const SegmentQuery q = md.closest_to_segment(a, b);
    ASSERT_TRUE(q.found);
    EXPECT_NEAR(q.distance, height, kExact) << i;
    EXPECT_NEAR(q.point_on_mesh.z(), kBoxHalf.z(), kExact) << i;
    EXPECT_NEAR((q.point_on_segment - q.point_on_mesh).norm(), height, kExact) << i;
    EXPECT_GT(q.normal.z(), 0.0) << i;
    // A search bounded just above the gap finds the same distance, one just below finds nothing.
    const SegmentQuery above = md.closest_to_segment(a, b, height * (1 + 1e-9), q.triangle);
    ASSERT_TRUE(above.found) << i;
    EXPECT_EQ(above.distance, q.distance) << i;
    EXPECT_FALSE(md.closest_to_segment(a, b, height * (1 - 1e-9)).found) << i;
    EXPECT_TRUE(md.capsule_overlaps(a, b, height * (1 + 1e-9))) << i;
    EXPECT_FALSE(md.capsule_overlaps(a, b, height * (1 - 1e-9))) << i;
    EXPECT_NEAR(md.capsule_signed_distance(a, b, 0.008), height - 0.008, kExact) << i;
  }
}

TEST(MeshDistance, SegmentTiltedTowardsAFinelyTriangulatedFaceTouchesWithItsLowEnd) {
  const MeshDistance md(make_subdivided_box(kBoxHalf, 24));
  // The low end is 3 mm over (0.011, -0.007) on the top face, the segment rises away from it.
  const Vector3d low(0.011, -0.007, kBoxHalf.z() + 0.003);
  const Vector3d high = low + Vector3d(-0.02, 0.01, 0.006);
  const SegmentQuery q = md.closest_to_segment(high, low);
  ASSERT_TRUE(q.found);
  EXPECT_NEAR(q.distance, 0.003, kExact);
  EXPECT_NEAR(q.segment_t, 1.0, kExact);
  expect_vec_near(q.point_on_mesh, Vector3d(0.011, -0.007, kBoxHalf.z()), kExact);
  expect_vec_near(q.normal, Vector3d::UnitZ(), kExact);
}

TEST(MeshDistance, SegmentsNearAFinelyTriangulatedBoxMatchBruteForce) {
  const TriangleMesh mesh = make_subdivided_box(kBoxHalf, 12);
  const MeshDistance md(mesh);
  std::mt19937 rng(12);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (int i = 0; i < 300; ++i) {
    // Around the box, out to 15 mm beyond it (edges and corners included), any direction.
    const Vector3d corner = kBoxHalf + Vector3d::Constant(0.015);
    const Vector3d a = corner.cwiseProduct(Vector3d(2 * u(rng) - 1, 2 * u(rng) - 1, 2 * u(rng) - 1));
    const Vector3d b = a + 0.03 * u(rng) * random_unit(rng);
    const SegmentQuery q = md.closest_to_segment(a, b);
    ASSERT_TRUE(q.found);
    EXPECT_NEAR(q.distance, brute_segment_distance(mesh, a, b), kExact) << i;
    EXPECT_NEAR((q.point_on_segment - q.point_on_mesh).norm(), q.distance, kExact) << i;
  }
}

// ---------------------------------------------------------------- capsules

TEST(MeshDistance, CapsuleOverlapsJustInsideAndBeyondRadius) {
  const MeshDistance md(make_box(kBoxHalf));
  const double gap = 0.005;
  const Vector3d a(-0.02, 0.01, kBoxHalf.z() + gap), b(0.03, -0.01, kBoxHalf.z() + gap);
  EXPECT_TRUE(md.capsule_overlaps(a, b, gap + 1e-6));
  EXPECT_FALSE(md.capsule_overlaps(a, b, gap - 1e-6));
  // Near a vertex: closest to the corner (0.05, 0.03, 0.02) at distance 0.01 * sqrt(3).
  const Vector3d c(0.06, 0.04, 0.03);
  const double d = 0.01 * std::sqrt(3.0);
  EXPECT_TRUE(md.capsule_overlaps(c, c + Vector3d(0.01, 0.01, 0.01), d + 1e-6));
  EXPECT_FALSE(md.capsule_overlaps(c, c + Vector3d(0.01, 0.01, 0.01), d - 1e-6));
}

TEST(MeshDistance, CapsuleFullyInsideOverlaps) {
  const MeshDistance md(make_box(kBoxHalf));
  EXPECT_TRUE(md.capsule_overlaps(Vector3d(-0.01, 0, 0), Vector3d(0.01, 0, 0), 0.005));
  EXPECT_FALSE(md.capsule_overlaps(Vector3d(0.1, 0, 0), Vector3d(0.12, 0, 0), 0.005));
}

TEST(MeshDistance, CapsuleSignedDistanceOutsideGap) {
  const MeshDistance md(make_box(kBoxHalf));
  const double r = 0.008;
  EXPECT_NEAR(md.capsule_signed_distance(Vector3d(0.07, -0.01, 0), Vector3d(0.09, 0.01, 0), r), 0.02 - r, kExact);
}

TEST(MeshDistance, CapsuleSignedDistancePenetratingFaceBy3mm) {
  const MeshDistance md(make_box(kBoxHalf));
  const double r = 0.008;
  // Parallel to the top face, surface of the capsule 3 mm below it (segment outside).
  const double z = kBoxHalf.z() + r - 0.003;
  EXPECT_NEAR(md.capsule_signed_distance(Vector3d(-0.02, 0, z), Vector3d(0.02, 0.005, z), r), -0.003, 1e-6);
  // Segment tip 3 mm under the top face (segment crosses the surface).
  const double r2 = 0.002;
  EXPECT_NEAR(md.capsule_signed_distance(Vector3d(0.001, 0.002, 0.04), Vector3d(0.001, 0.002, 0.017), r2), -0.003 - r2,
              1e-6);
}

TEST(MeshDistance, CapsuleSignedDistanceSegmentThroughWholeBox) {
  const MeshDistance md(make_box(kBoxHalf));
  const double r = 0.004;
  // Along x through the box at (y, z) = (0.005, 0.004): deepest signed distance is -(0.02 - 0.004).
  EXPECT_NEAR(md.capsule_signed_distance(Vector3d(-0.1, 0.005, 0.004), Vector3d(0.1, 0.005, 0.004), r), -0.016 - r,
              1e-6);
  // Oblique segment through the box; expectation from the analytic box SDF, densely sampled.
  const Vector3d a(-0.08, -0.04, -0.01), b(0.07, 0.035, 0.03);
  double expected = std::numeric_limits<double>::infinity();
  for (int i = 0; i <= 200000; ++i) expected = std::min(expected, box_sdf(kBoxHalf, a + (i / 200000.0) * (b - a)));
  EXPECT_NEAR(md.capsule_signed_distance(a, b, r), expected - r, 1e-6);
  // Entirely inside without touching: minimum over the segment.
  // Its end points are 0.01 deep, its midpoint 0.02 deep (nearest face z = +-0.02).
  EXPECT_NEAR(md.capsule_signed_distance(Vector3d(-0.01, 0.0, 0.01), Vector3d(0.01, 0.0, -0.01), r), -0.02 - r, 1e-6);
}

TEST(MeshDistance, CapsuleSignedDistanceThroughIcosphereIsConvexMinimum) {
  const double radius = 0.04;
  const TriangleMesh sphere = make_icosphere(radius, 3);
  const double tessellation_tol = tessellation_error(sphere, radius);
  const MeshDistance md(sphere);
  // Chord at offset 0.01 from the centre: the deepest point is at depth radius - 0.01.
  const double v = md.capsule_signed_distance(Vector3d(-0.06, 0.01, 0), Vector3d(0.05, 0.01, 0), 0.0);
  EXPECT_GE(v, 0.01 - radius - 1e-9);
  EXPECT_LE(v, 0.01 - radius + tessellation_tol + 1e-9);
}

// ---------------------------------------------------------------- sphere casts

TEST(MeshDistance, SphereCastHeadOnBoxFace) {
  const MeshDistance md(make_box(kBoxHalf));
  const double r = 0.01;
  const SweepHit h = md.sphere_cast(Vector3d(0.1, 0.01, 0.003), Vector3d(-1, 0, 0), r, 1.0);
  ASSERT_TRUE(h.hit);
  EXPECT_FALSE(h.started_inside);
  EXPECT_NEAR(h.t, (0.1 - 0.05) - r, kExact);
  expect_vec_near(h.point, Vector3d(0.05, 0.01, 0.003), kExact);
  expect_vec_near(h.normal, Vector3d::UnitX(), kExact);
  // max_length is inclusive.
  EXPECT_FALSE(md.sphere_cast(Vector3d(0.1, 0.01, 0.003), Vector3d(-1, 0, 0), r, 0.039).hit);
  EXPECT_TRUE(md.sphere_cast(Vector3d(0.1, 0.01, 0.003), Vector3d(-1, 0, 0), r, 0.04).hit);
}

TEST(MeshDistance, SphereCastGlancingEdge) {
  const MeshDistance md(make_box(kBoxHalf));
  const double r = 0.01;
  const double dy = 0.006;  // centre path 6 mm beyond the face y = 0.03
  const SweepHit h = md.sphere_cast(Vector3d(0.1, 0.03 + dy, 0.0), Vector3d(-1, 0, 0), r, 1.0);
  ASSERT_TRUE(h.hit);
  // Contact with the z-edge capsule at (0.05, 0.03): (x - 0.05)^2 + dy^2 = r^2.
  const double x = 0.05 + std::sqrt(r * r - dy * dy);
  EXPECT_NEAR(h.t, 0.1 - x, kExact);
  expect_vec_near(h.point, Vector3d(0.05, 0.03, 0.0), 1e-9);
  expect_vec_near(h.normal, Vector3d(1, 1, 0).normalized(), kExact);
}

TEST(MeshDistance, SphereCastMissing) {
  const MeshDistance md(make_box(kBoxHalf));
  EXPECT_FALSE(md.sphere_cast(Vector3d(0.1, 0.045, 0.0), Vector3d(-1, 0, 0), 0.01, 1.0).hit);
  EXPECT_FALSE(md.sphere_cast(Vector3d(0.1, 0.0, 0.0), Vector3d(1, 0, 0), 0.01, 1.0).hit);
}

TEST(MeshDistance, SphereCastTouchingAtStart) {
  const MeshDistance md(make_box(kBoxHalf));
  const SweepHit h = md.sphere_cast(Vector3d(0.055, 0.001, 0.0), Vector3d(0, 1, 0), 0.01, 1.0);
  ASSERT_TRUE(h.hit);
  EXPECT_FALSE(h.started_inside);
  EXPECT_EQ(h.t, 0.0);
  expect_vec_near(h.point, Vector3d(0.05, 0.001, 0.0), kExact);
  expect_vec_near(h.normal, Vector3d::UnitX(), kExact);
}

TEST(MeshDistance, SphereCastStartingInsideReportsEntryBehind) {
  const MeshDistance md(make_box(kBoxHalf));
  const double r = 0.01;
  const SweepHit h = md.sphere_cast(Vector3d(0.0, 0.01, 0.0), Vector3d(1, 0, 0), r, 1.0);
  ASSERT_TRUE(h.hit);
  EXPECT_TRUE(h.started_inside);
  // Travelling along +x, the sphere entered through the face x = -0.05 with centre at -0.06.
  EXPECT_NEAR(h.t, -0.06, kExact);
  expect_vec_near(h.point, Vector3d(-0.05, 0.01, 0.0), kExact);
  expect_vec_near(h.normal, -Vector3d::UnitX(), kExact);
  // Oblique start inside, deep enough that the sphere is not yet touching the surface.
  const Vector3d dir = Vector3d(1, 1, 0).normalized();
  const SweepHit g = md.sphere_cast(Vector3d(0.0, 0.0, 0.0), dir, 0.005, 1.0);
  ASSERT_TRUE(g.hit);
  EXPECT_TRUE(g.started_inside);
  // Backwards along (-1, -1): the centre reaches y = -0.03 - 0.005 first (x = -0.035, inside x).
  EXPECT_NEAR(g.t, -0.035 * std::sqrt(2.0), kExact);
  expect_vec_near(g.point, Vector3d(-0.035, -0.03, 0.0), kExact);
  expect_vec_near(g.normal, -Vector3d::UnitY(), kExact);
}

TEST(MeshDistance, SphereCastAgainstIcosphereMatchesAnalyticSphere) {
  const double radius = 0.04;
  const TriangleMesh sphere = make_icosphere(radius, 3);
  const double tessellation_tol = tessellation_error(sphere, radius);
  const MeshDistance md(sphere);
  const double r = 0.008;
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (int i = 0; i < 300; ++i) {
    const Vector3d o = 0.1 * random_unit(rng);
    // Aim at a point offset from the centre by at most what still hits the inner shell.
    Vector3d side = random_unit(rng);
    side = (side - side.dot(o.normalized()) * o.normalized()).normalized();
    const double impact = u(rng) * (radius - tessellation_tol + r - 1e-4);
    const Vector3d dir = (impact * side - o).normalized();
    const SweepHit h = md.sphere_cast(o, dir, r, 1.0);
    ASSERT_TRUE(h.hit) << i;
    EXPECT_FALSE(h.started_inside);
    // Mesh between spheres radius - tol and radius: contact between the two analytic answers.
    EXPECT_GE(h.t, ray_sphere(o, dir, radius + r) - 1e-12) << i;
    EXPECT_LE(h.t, ray_sphere(o, dir, radius - tessellation_tol + r) + 1e-12) << i;
    const Vector3d centre = o + h.t * dir;
    EXPECT_NEAR((centre - h.point).norm(), r, 1e-12);
    EXPECT_GT(h.normal.dot(h.point.normalized()), 0.9);
  }
}

// ---------------------------------------------------------------- brute-force cross-checks

// A capsule from `a`: b up to 30 mm away in a random direction, radius up to 10 mm (drawn in
// that order from `rng`).
struct RandomCapsule {
  Vector3d a, b;
  double r;
};
RandomCapsule random_capsule(const Vector3d& a, std::mt19937& rng) {
  std::uniform_real_distribution<double> len(0.0, 0.03);
  std::uniform_real_distribution<double> rad(0.0, 0.01);
  const Vector3d b = a + len(rng) * random_unit(rng);
  return {a, b, rad(rng)};
}

class IcosphereBruteForce : public ::testing::Test {
 protected:
  static constexpr double kRadius = 0.04;
  TriangleMesh mesh_ = make_icosphere(kRadius, 3);
  MeshDistance md_{mesh_};
  double tessellation_tol_ = tessellation_error(mesh_, kRadius);
  std::mt19937 rng_{1234};

  /// A point within 10 mm of the sphere surface, or occasionally anywhere within 2 radii.
  Vector3d random_point() {
    std::uniform_real_distribution<double> u(0.0, 1.0);
    const double rho = u(rng_) < 0.9 ? kRadius + 0.02 * (u(rng_) - 0.5) : 2 * kRadius * u(rng_);
    return rho * random_unit(rng_);
  }
};

TEST_F(IcosphereBruteForce, ClosestPointMatchesBruteForce) {
  for (int i = 0; i < 2000; ++i) {
    const Vector3d p = random_point();
    const PointQuery q = md_.closest_point(p);
    ASSERT_TRUE(q.found);
    const double expected = brute_point_distance(mesh_, p);
    ASSERT_NEAR(q.distance, expected, 1e-12) << p.transpose();
    EXPECT_NEAR((p - q.point_on_mesh).norm(), expected, 1e-12);
    EXPECT_NEAR(std::abs(q.signed_distance), expected, 1e-12);
    // The reported point lies on the reported triangle.
    const auto& t = mesh_.triangles[q.triangle];
    EXPECT_LT(ref_point_triangle_sq(q.point_on_mesh, mesh_.vertices[t[0]], mesh_.vertices[t[1]], mesh_.vertices[t[2]]),
              1e-24);
    // Sign against the shell [R - tol, R] that holds the surface.
    const double rho = p.norm();
    if (rho > kRadius + 1e-9) {
      EXPECT_GT(q.signed_distance, 0.0);
    }
    if (rho < kRadius - tessellation_tol_ - 1e-9) {
      EXPECT_LT(q.signed_distance, 0.0);
    }
  }
}

TEST_F(IcosphereBruteForce, ClosestToSegmentMatchesBruteForce) {
  std::uniform_real_distribution<double> len(0.0, 0.03);
  for (int i = 0; i < 2000; ++i) {
    const Vector3d a = random_point();
    const Vector3d b = a + len(rng_) * random_unit(rng_);
    const SegmentQuery q = md_.closest_to_segment(a, b);
    ASSERT_TRUE(q.found);
    const double expected = brute_segment_distance(mesh_, a, b);
    ASSERT_NEAR(q.distance, expected, 1e-12) << a.transpose() << " / " << b.transpose();
    EXPECT_NEAR((q.point_on_segment - q.point_on_mesh).norm(), expected, 1e-12);
    EXPECT_GE(q.segment_t, 0.0);
    EXPECT_LE(q.segment_t, 1.0);
  }
}

TEST_F(IcosphereBruteForce, CapsuleOverlapsMatchesBruteForce) {
  int overlaps = 0;
  for (int i = 0; i < 2000; ++i) {
    const auto [a, b, r] = random_capsule(random_point(), rng_);
    const double d = brute_segment_distance(mesh_, a, b);
    if (std::abs(d - r) < 1e-9) continue;  // too close to call
    // With no surface within r the segment is all inside or all outside; decide at a from the
    // shell [R - tol, R] holding the surface (a point inside the shell but not within r of the
    // surface cannot be classified analytically: skip it).
    const double rho = a.norm();
    if (d > r && rho >= kRadius - tessellation_tol_ && rho <= kRadius) continue;
    const bool expected = d <= r || rho < kRadius - tessellation_tol_;
    EXPECT_EQ(md_.capsule_overlaps(a, b, r), expected) << i;
    overlaps += expected;
  }
  EXPECT_GT(overlaps, 200);
  EXPECT_LT(overlaps, 1800);
}

// A zero-length capsule is a ball: it overlaps when the point is within r of the surface or
// inside. A hint triangle (here a random one) changes the speed, never the answer.
TEST_F(IcosphereBruteForce, PointCapsulesAndHintsGiveTheSameAnswers) {
  std::uniform_real_distribution<double> len(0.0, 0.03);
  std::uniform_real_distribution<double> rad(0.0, 0.01);
  std::uniform_int_distribution<std::uint32_t> tri(0, static_cast<std::uint32_t>(mesh_.triangles.size() - 1));
  for (int i = 0; i < 2000; ++i) {
    const Vector3d p = random_point();
    const double r = rad(rng_);
    const PointQuery q = md_.closest_point(p);
    if (std::abs(q.distance - r) < 1e-9) continue;
    EXPECT_EQ(md_.capsule_overlaps(p, p, r), q.distance <= r || q.signed_distance < 0) << i;
    const Vector3d b = p + len(rng_) * random_unit(rng_);
    const std::uint32_t hint = tri(rng_);
    EXPECT_EQ(md_.closest_to_segment(p, b, std::numeric_limits<double>::infinity(), hint).distance,
              md_.closest_to_segment(p, b).distance)
        << i;
    EXPECT_EQ(md_.capsule_overlaps(p, b, r, hint), md_.capsule_overlaps(p, b, r)) << i;
    EXPECT_EQ(md_.capsule_signed_distance(p, b, r, hint), md_.capsule_signed_distance(p, b, r)) << i;
  }
}

// Finger-like segments lying along a finer sphere, 0-15 mm above it: many small triangles are
// nearly as close as the closest, the case the searches' plane bound prunes hardest.
TEST(MeshDistance, SegmentsAlongAFineIcosphereMatchBruteForceAndTheSphere) {
  constexpr double kR = 0.03;
  const TriangleMesh mesh = make_icosphere(kR, 4);  // 5120 triangles
  const MeshDistance md(mesh);
  const double tessellation = tessellation_error(mesh, kR);
  std::mt19937 rng(13);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::uniform_int_distribution<std::uint32_t> tri(0, static_cast<std::uint32_t>(mesh.triangles.size() - 1));
  for (int i = 0; i < 300; ++i) {
    const Vector3d n = random_unit(rng);
    Vector3d t = random_unit(rng);
    t = (t - t.dot(n) * n).normalized();
    const Vector3d dir = (t + 0.3 * (2 * u(rng) - 1) * n).normalized();  // tangent, tilted up to ~17 deg
    const double length = 0.005 + 0.025 * u(rng);
    const Vector3d a = (kR + 0.015 * u(rng)) * n - 0.5 * length * dir;
    const Vector3d b = a + length * dir;
    // Analytic, for a segment outside the sphere: the tessellated surface lies in the shell
    // [R - tessellation, R].
    const double to_sphere = (a + std::clamp(-a.dot(b - a) / (b - a).squaredNorm(), 0.0, 1.0) * (b - a)).norm() - kR;
    const SegmentQuery q = md.closest_to_segment(a, b);
    ASSERT_TRUE(q.found);
    if (to_sphere >= 0) {
      EXPECT_GE(q.distance, to_sphere - 1e-12) << i;
      EXPECT_LE(q.distance, to_sphere + tessellation + 1e-12) << i;
    }
    EXPECT_NEAR(q.distance, brute_segment_distance(mesh, a, b), kExact) << i;
    EXPECT_EQ(md.closest_to_segment(a, b, std::numeric_limits<double>::infinity(), tri(rng)).distance, q.distance) << i;
    EXPECT_EQ(md.closest_to_segment(a, b, q.distance * (1 + 1e-9)).distance, q.distance) << i;
    if (q.distance > 0) {
      EXPECT_FALSE(md.closest_to_segment(a, b, q.distance * (1 - 1e-9)).found) << i;
      EXPECT_TRUE(md.capsule_overlaps(a, b, q.distance * (1 + 1e-9))) << i;
      EXPECT_FALSE(md.capsule_overlaps(a, b, q.distance * (1 - 1e-9))) << i;
    }
  }
}

// Sweeps a sphere of radius r from o along dir for at most max_length and checks it against
// brute force: the swept centre path stays farther than r from every triangle before the hit
// (checked coarsely) and is exactly r away at it; a miss stays clear to the end. True on a hit.
bool expect_first_contact(const TriangleMesh& mesh, const MeshDistance& md, const Vector3d& o, const Vector3d& dir,
                          double r, double max_length) {
  const SweepHit h = md.sphere_cast(o, dir, r, max_length);
  const double t_end = h.hit ? h.t : max_length;
  for (int k = 0; k < 20; ++k) {
    const double t = t_end * k / 20.0;
    EXPECT_GT(brute_point_distance(mesh, o + t * dir), r - 1e-12) << "t=" << t;
  }
  if (h.hit)
    EXPECT_NEAR(brute_point_distance(mesh, o + h.t * dir), r, 1e-12);
  else
    EXPECT_GT(brute_point_distance(mesh, o + max_length * dir), r);
  return h.hit;
}

TEST_F(IcosphereBruteForce, SphereCastIsFirstContact) {
  std::uniform_real_distribution<double> rad(0.001, 0.01);
  int hits = 0;
  for (int i = 0; i < 200; ++i) {
    const Vector3d o = (kRadius + 0.02 + 0.02 * (i % 7) / 7.0) * random_unit(rng_);
    const Vector3d dir = (0.03 * random_unit(rng_) - o).normalized();
    const double r = rad(rng_);
    SCOPED_TRACE(i);
    hits += expect_first_contact(mesh_, md_, o, dir, r, 0.2);
  }
  EXPECT_GT(hits, 50);
}

// A thin plate (an icosphere squashed to 180 x 30 x 3 mm) turned by a random rotation: its BVH
// nodes' axis-aligned boxes are loose, so the oriented boxes do the pruning. Every query must
// still match brute force exactly.
class TiltedThinPlateBruteForce : public ::testing::Test {
 protected:
  static inline const Vector3d kHalf{0.09, 0.015, 0.0015};
  Eigen::Matrix3d R_ = Eigen::Quaterniond(0.3, -0.5, 0.7, 0.4).normalized().toRotationMatrix();
  TriangleMesh mesh_ = tilted_plate();
  MeshDistance md_{mesh_};
  std::mt19937 rng_{777};

  TriangleMesh tilted_plate() const {
    TriangleMesh m = make_icosphere(1.0, 4);  // 5120 triangles
    for (Vector3d& v : m.vertices) v = R_ * kHalf.cwiseProduct(v);
    return m;
  }
  /// A point within about 15 mm of the plate.
  Vector3d random_point() {
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    const Vector3d local(u(rng_) * (kHalf.x() + 0.01), u(rng_) * (kHalf.y() + 0.01), u(rng_) * 0.015);
    return R_ * local;
  }
  /// True when p lies outside the smooth ellipsoid, hence outside the mesh inscribed in it.
  bool outside_ellipsoid(const Vector3d& p) const { return (R_.transpose() * p).cwiseQuotient(kHalf).norm() > 1.0; }
};

TEST_F(TiltedThinPlateBruteForce, ClosestPointMatchesBruteForce) {
  for (int i = 0; i < 1000; ++i) {
    const Vector3d p = random_point();
    const PointQuery q = md_.closest_point(p);
    ASSERT_TRUE(q.found);
    const double expected = brute_point_distance(mesh_, p);
    ASSERT_NEAR(q.distance, expected, 1e-12) << i;
    if (outside_ellipsoid(p)) {
      EXPECT_GT(q.signed_distance, 0.0) << i;
    }
    // Bounded searches find it exactly when it lies within the bound, and nothing beyond.
    EXPECT_TRUE(md_.closest_point(p, expected * (1 + 1e-9) + 1e-12).found) << i;
    EXPECT_FALSE(md_.closest_point(p, expected * (1 - 1e-9) - 1e-12).found) << i;
  }
}

TEST_F(TiltedThinPlateBruteForce, ClosestToSegmentMatchesBruteForce) {
  std::uniform_real_distribution<double> len(0.0, 0.03);
  for (int i = 0; i < 1000; ++i) {
    const Vector3d a = random_point();
    const Vector3d b = a + len(rng_) * random_unit(rng_);
    const double expected = brute_segment_distance(mesh_, a, b);
    const SegmentQuery q = md_.closest_to_segment(a, b);
    ASSERT_TRUE(q.found);
    ASSERT_NEAR(q.distance, expected, 1e-12) << i;
    EXPECT_NEAR((q.point_on_segment - q.point_on_mesh).norm(), expected, 1e-12);
    const SegmentQuery bounded = md_.closest_to_segment(a, b, expected * (1 + 1e-9) + 1e-12, q.triangle);
    ASSERT_TRUE(bounded.found) << i;
    EXPECT_NEAR(bounded.distance, expected, 1e-12) << i;
  }
}

TEST_F(TiltedThinPlateBruteForce, CapsuleOverlapsMatchesBruteForce) {
  int overlaps = 0;
  int checked = 0;
  for (int i = 0; i < 1000; ++i) {
    const auto [a, b, r] = random_capsule(random_point(), rng_);
    const double d = brute_segment_distance(mesh_, a, b);
    if (std::abs(d - r) < 1e-9) continue;  // too close to call
    if (d > r && !outside_ellipsoid(a)) continue;  // not classified analytically
    EXPECT_EQ(md_.capsule_overlaps(a, b, r), d <= r) << i;
    overlaps += d <= r;
    ++checked;
  }
  EXPECT_GT(overlaps, 100);
  EXPECT_GT(checked - overlaps, 100);
}

TEST_F(TiltedThinPlateBruteForce, SphereCastIsFirstContact) {
  std::uniform_real_distribution<double> rad(0.001, 0.01);
  int hits = 0;
  for (int i = 0; i < 200; ++i) {
    Vector3d o = random_point();
    if (!outside_ellipsoid(o)) continue;
    const Vector3d dir = random_unit(rng_);
    const double r = rad(rng_);
    if (brute_point_distance(mesh_, o) <= r) continue;  // touching at the start: not a sweep
    SCOPED_TRACE(i);
    hits += expect_first_contact(mesh_, md_, o, dir, r, 0.1);
  }
  EXPECT_GT(hits, 20);
}

// ---------------------------------------------------------------- long sliver triangles

// A capped cylinder (radius 10 mm, 120 mm long) of 256 sides, whose side triangles are 120 mm
// long and 0.25 mm wide, turned off the axes: segments lying across it, as a finger across a
// thin handle, are where the segment's own frame (its axis and the plane across it) prunes
// triangles that the bounding-sphere and plane bounds let through.
class SliverCylinder : public ::testing::Test {
 protected:
  static constexpr double kRadius = 0.01;
  static TriangleMesh make_mesh() {
    TriangleMesh m = testing::cylinder_mesh(kRadius, 0.06, 256);
    const Eigen::Matrix3d turn =
        Eigen::AngleAxisd(0.7, Vector3d(1, 2, 3).normalized()).toRotationMatrix();
    for (Vector3d& v : m.vertices) v = turn * v;
    return m;
  }
  TriangleMesh mesh_ = make_mesh();
  MeshDistance md_{mesh_};
  Eigen::Matrix3d turn_ = Eigen::AngleAxisd(0.7, Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  std::mt19937 rng_{77};

  /// A segment up to 30 mm long near the side (gap -2 to 12 mm): across the axis, along it, or
  /// any direction; centred on the side or starting there (its end nearest).
  std::pair<Vector3d, Vector3d> random_segment() {
    std::uniform_real_distribution<double> u(0.0, 1.0);
    const double phi = 2 * kPi * u(rng_);
    const Vector3d radial(std::cos(phi), std::sin(phi), 0);
    const Vector3d across(-std::sin(phi), std::cos(phi), 0);
    const Vector3d centre = (kRadius - 0.002 + 0.014 * u(rng_)) * radial + Vector3d(0, 0, 0.1 * (u(rng_) - 0.5));
    const double kind = u(rng_);
    Vector3d dir = kind < 0.5 ? across : kind < 0.7 ? Vector3d::UnitZ() : random_unit(rng_);
    dir = (dir + 0.05 * (u(rng_) - 0.5) * radial).normalized();
    const double len = 0.03 * u(rng_);
    const Vector3d a = u(rng_) < 0.7 ? centre - 0.5 * len * dir : centre;
    return {turn_ * a, turn_ * (a + len * dir)};
  }
};

TEST_F(SliverCylinder, ClosestToSegmentMatchesBruteForceWithAndWithoutHint) {
  std::uint32_t hint = MeshDistance::kNoHint;
  for (int i = 0; i < 3000; ++i) {
    const auto [a, b] = random_segment();
    const double expected = brute_segment_distance(mesh_, a, b);
    const SegmentQuery q = md_.closest_to_segment(a, b);
    ASSERT_TRUE(q.found);
    ASSERT_NEAR(q.distance, expected, kExact) << i;
    // The reported triangle is one of the nearest.
    const auto& t = mesh_.triangles[q.triangle];
    EXPECT_NEAR(std::sqrt(ref_segment_triangle_sq(a, b, mesh_.vertices[t[0]], mesh_.vertices[t[1]], mesh_.vertices[t[2]])),
                expected, kExact)
        << i;
    // A hint (the last answer: usually far) and a tight search radius change nothing.
    const SegmentQuery h = md_.closest_to_segment(a, b, expected * (1 + 1e-6) + 1e-9, hint);
    ASSERT_TRUE(h.found) << i;
    EXPECT_NEAR(h.distance, expected, kExact) << i;
    hint = q.triangle;
    // Capsules just within and just beyond the gap.
    if (expected > 1e-6) {
      EXPECT_TRUE(md_.capsule_overlaps(a, b, expected + 1e-9)) << i;
      EXPECT_EQ(md_.capsule_overlaps(a, b, expected - 1e-9), md_.contains(a)) << i;
    }
  }
}

TEST_F(SliverCylinder, CapsuleOverlapsGivenTheClosestPairAgreesWithTheSearch) {
  int inside = 0, shortcut = 0;
  for (int i = 0; i < 2000; ++i) {
    const auto [a, b] = random_segment();
    const SegmentQuery q = md_.closest_to_segment(a, b);
    ASSERT_TRUE(q.found);
    const double d = q.distance;
    inside += md_.contains(a) && d > 0;
    for (const double r : {0.0, d - 1e-3, d * (1 - 1e-6), d * (1 - 1e-9), d * (1 - 1e-15), d, d * (1 + 1e-15),
                           d * (1 + 1e-9), d * (1 + 1e-6), d + 1e-3}) {
      EXPECT_EQ(md_.capsule_overlaps(a, b, r, q), md_.capsule_overlaps(a, b, r)) << i << " r = " << r;
      shortcut += r < d * (1 - 1e-6);
    }
  }
  EXPECT_GT(inside, 50);  // segments wholly inside: the shortcut's inside test decides them
  EXPECT_GT(shortcut, 2000);
}

TEST(MeshDistance, CapsuleOverlapsGivenTheClosestPairOnABox) {
  const MeshDistance md(make_box(kBoxHalf));
  const double gap = 0.005;
  const Vector3d a(-0.02, 0.01, kBoxHalf.z() + gap), b(0.03, -0.01, kBoxHalf.z() + gap);
  const SegmentQuery q = md.closest_to_segment(a, b);
  ASSERT_TRUE(q.found);
  EXPECT_NEAR(q.distance, gap, kExact);
  EXPECT_FALSE(md.capsule_overlaps(a, b, gap - 1e-6, q));  // decided by the pair: outside
  EXPECT_FALSE(md.capsule_overlaps(a, b, gap * (1 - 1e-10), q));  // too close to call: the full query
  EXPECT_TRUE(md.capsule_overlaps(a, b, gap + 1e-6, q));
  // Wholly inside: no surface within 5 mm, the inside test decides.
  const Vector3d c(-0.01, 0, 0), e(0.01, 0, 0);
  const SegmentQuery in = md.closest_to_segment(c, e);
  ASSERT_TRUE(in.found);
  EXPECT_GT(in.distance, 0.005);
  EXPECT_TRUE(md.capsule_overlaps(c, e, 0.005, in));
  // Not found (searched within 1 mm only): the full query.
  const SegmentQuery none = md.closest_to_segment(a, b, 0.001);
  ASSERT_FALSE(none.found);
  EXPECT_TRUE(md.capsule_overlaps(a, b, gap + 1e-6, none));
}

}  // namespace
}  // namespace telegrasp::sim
