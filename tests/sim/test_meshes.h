// Small closed meshes built inline for tests: boxes and flat prisms (exact), UV spheres and
// cylinders.
#pragma once

#include "telegrasp/sim/triangle_mesh.h"

#include <cmath>
#include <numbers>
#include <vector>

namespace telegrasp::sim::testing {

/// Axis-aligned box with half extents `h`, centred on the origin, outward-facing.
inline TriangleMesh box_mesh(const Eigen::Vector3d& h) {
  TriangleMesh m;
  for (int i = 0; i < 8; ++i)
    m.vertices.emplace_back((i & 1 ? 1 : -1) * h.x(), (i & 2 ? 1 : -1) * h.y(), (i & 4 ? 1 : -1) * h.z());
  // Two triangles per face, counter-clockwise seen from outside.
  m.triangles = {{0, 2, 1}, {1, 2, 3}, {4, 5, 6}, {5, 7, 6}, {0, 1, 4}, {1, 5, 4},
                 {2, 6, 3}, {3, 6, 7}, {0, 4, 2}, {2, 4, 6}, {1, 3, 5}, {3, 7, 5}};
  return m;
}

/// UV sphere of radius r centred on the origin (vertices on the sphere, poles on +-z).
inline TriangleMesh uv_sphere_mesh(double r, int rings, int segments) {
  TriangleMesh m;
  m.vertices.emplace_back(0, 0, r);
  for (int i = 1; i < rings; ++i) {
    const double th = std::numbers::pi * i / rings;
    for (int j = 0; j < segments; ++j) {
      const double ph = 2 * std::numbers::pi * j / segments;
      m.vertices.emplace_back(r * std::sin(th) * std::cos(ph), r * std::sin(th) * std::sin(ph), r * std::cos(th));
    }
  }
  m.vertices.emplace_back(0, 0, -r);
  const auto ring = [&](int i, int j) { return static_cast<std::uint32_t>(1 + (i - 1) * segments + (j % segments)); };
  const auto south = static_cast<std::uint32_t>(m.vertices.size() - 1);
  for (int j = 0; j < segments; ++j) m.triangles.push_back({0, ring(1, j), ring(1, j + 1)});
  for (int i = 1; i < rings - 1; ++i)
    for (int j = 0; j < segments; ++j) {
      m.triangles.push_back({ring(i, j), ring(i + 1, j), ring(i + 1, j + 1)});
      m.triangles.push_back({ring(i, j), ring(i + 1, j + 1), ring(i, j + 1)});
    }
  for (int j = 0; j < segments; ++j) m.triangles.push_back({south, ring(rings - 1, j + 1), ring(rings - 1, j)});
  return m;
}

/// Capped cylinder of radius r and half height hz about the z axis, centred on the origin.
inline TriangleMesh cylinder_mesh(double r, double hz, int segments) {
  TriangleMesh m;
  for (int j = 0; j < segments; ++j) {
    const double ph = 2 * std::numbers::pi * j / segments;
    m.vertices.emplace_back(r * std::cos(ph), r * std::sin(ph), -hz);
    m.vertices.emplace_back(r * std::cos(ph), r * std::sin(ph), hz);
  }
  const auto bottom = static_cast<std::uint32_t>(m.vertices.size());
  m.vertices.emplace_back(0, 0, -hz);
  m.vertices.emplace_back(0, 0, hz);
  for (int j = 0; j < segments; ++j) {
    const auto b0 = static_cast<std::uint32_t>(2 * j), t0 = b0 + 1;
    const auto b1 = static_cast<std::uint32_t>(2 * ((j + 1) % segments)), t1 = b1 + 1;
    m.triangles.push_back({b0, b1, t1});
    m.triangles.push_back({b0, t1, t0});
    m.triangles.push_back({bottom, b1, b0});
    m.triangles.push_back({bottom + 1, t0, t1});
  }
  return m;
}

/// Flat prism: the convex polygon `outline` (x, y, counter-clockwise) from z = -hz to hz.
inline TriangleMesh prism_mesh(const std::vector<Eigen::Vector2d>& outline, double hz) {
  TriangleMesh m;
  for (const Eigen::Vector2d& p : outline) {
    m.vertices.emplace_back(p.x(), p.y(), -hz);
    m.vertices.emplace_back(p.x(), p.y(), hz);
  }
  const auto n = static_cast<std::uint32_t>(outline.size());
  for (std::uint32_t j = 0; j < n; ++j) {
    const std::uint32_t b0 = 2 * j, t0 = b0 + 1, b1 = 2 * ((j + 1) % n), t1 = b1 + 1;
    m.triangles.push_back({b0, b1, t1});
    m.triangles.push_back({b0, t1, t0});
  }
  for (std::uint32_t j = 1; j + 1 < n; ++j) {  // the caps as fans
    m.triangles.push_back({0, 2 * (j + 1), 2 * j});
    m.triangles.push_back({1, 2 * j + 1, 2 * (j + 1) + 1});
  }
  return m;
}

}  // namespace telegrasp::sim::testing
