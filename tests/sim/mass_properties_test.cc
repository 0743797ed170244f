// Tests compute_mass_properties (volume, centroid, inertia about the centroid) and translated.
#include "telegrasp/sim/mass_properties.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

namespace telegrasp::sim {
namespace {

/// Axis-aligned box [0,a] x [0,b] x [0,c], 12 outward triangles.
TriangleMesh make_box(double a, double b, double c) {
  TriangleMesh mesh;
  for (int i = 0; i < 8; ++i) mesh.vertices.emplace_back((i & 1) ? a : 0, (i & 2) ? b : 0, (i & 4) ? c : 0);
  mesh.triangles = {{0, 2, 1}, {1, 2, 3}, {4, 5, 6}, {5, 7, 6},  // -z, +z
                    {0, 1, 4}, {1, 5, 4}, {2, 6, 3}, {3, 6, 7},  // -y, +y
                    {0, 4, 2}, {2, 4, 6}, {1, 3, 5}, {3, 7, 5}};  // -x, +x
  return mesh;
}

/// Latitude-longitude sphere of radius r centred at the origin.
TriangleMesh make_uv_sphere(double r, int stacks, int slices) {
  TriangleMesh mesh;
  mesh.vertices.emplace_back(0, 0, -r);
  for (int i = 1; i < stacks; ++i) {
    const double theta = std::numbers::pi * i / stacks;
    for (int j = 0; j < slices; ++j) {
      const double phi = 2 * std::numbers::pi * j / slices;
      mesh.vertices.emplace_back(r * std::sin(theta) * std::cos(phi), r * std::sin(theta) * std::sin(phi),
                                 -r * std::cos(theta));
    }
  }
  mesh.vertices.emplace_back(0, 0, r);
  const auto top = static_cast<std::uint32_t>(mesh.vertices.size() - 1);
  auto at = [slices](int ring, int j) { return static_cast<std::uint32_t>(1 + ring * slices + (j % slices)); };
  for (int j = 0; j < slices; ++j) {
    mesh.triangles.push_back({0, at(0, j + 1), at(0, j)});
    for (int i = 0; i + 2 < stacks; ++i) {
      mesh.triangles.push_back({at(i, j), at(i, j + 1), at(i + 1, j + 1)});
      mesh.triangles.push_back({at(i, j), at(i + 1, j + 1), at(i + 1, j)});
    }
    mesh.triangles.push_back({top, at(stacks - 2, j), at(stacks - 2, j + 1)});
  }
  return mesh;
}

void expect_relative(double actual, double expected, double tolerance) {
  EXPECT_NEAR(actual, expected, tolerance * std::abs(expected)) << "expected " << expected;
}

TEST(MassProperties, BoxIsExact) {
  const double a = 0.07, b = 0.16, c = 0.21;
  const MassProperties props = compute_mass_properties(make_box(a, b, c));
  const double volume = a * b * c;
  expect_relative(props.volume, volume, 1e-12);
  expect_relative(props.centroid.x(), a / 2, 1e-12);
  expect_relative(props.centroid.y(), b / 2, 1e-12);
  expect_relative(props.centroid.z(), c / 2, 1e-12);
  expect_relative(props.inertia_per_density(0, 0), volume / 12 * (b * b + c * c), 1e-12);
  expect_relative(props.inertia_per_density(1, 1), volume / 12 * (a * a + c * c), 1e-12);
  expect_relative(props.inertia_per_density(2, 2), volume / 12 * (a * a + b * b), 1e-12);
  const double scale = props.inertia_per_density.diagonal().maxCoeff();
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      if (i != j) {
        EXPECT_NEAR(props.inertia_per_density(i, j), 0.0, 1e-12 * scale);
      }
    }
  }
}

TEST(MassProperties, TranslatedBoxMovesCentroidOnly) {
  const TriangleMesh box = make_box(0.1, 0.2, 0.3);
  const Eigen::Vector3d offset(3.0, -2.0, 0.5);
  const TriangleMesh moved = translated(box, offset);
  ASSERT_EQ(moved.vertices.size(), box.vertices.size());
  EXPECT_EQ(moved.triangles, box.triangles);
  EXPECT_TRUE(moved.vertices[7].isApprox(box.vertices[7] + offset));
  const MassProperties original = compute_mass_properties(box);
  const MassProperties shifted = compute_mass_properties(moved);
  expect_relative(shifted.volume, original.volume, 1e-12);
  EXPECT_LT((shifted.centroid - (original.centroid + offset)).norm(), 1e-12);
  EXPECT_LT((shifted.inertia_per_density - original.inertia_per_density).norm(),
            1e-9 * original.inertia_per_density.norm());
}

TEST(MassProperties, RightTetrahedron) {
  // Corner tetrahedron s*(0, e1, e2, e3): V = s^3/6, centroid s/4, and about the centroid
  // I_xx = s^5/80, I_xy = s^5/480 (from integral x^2 = s^5/60, integral xy = s^5/120).
  const double s = 0.2;
  TriangleMesh tet;
  tet.vertices = {{0, 0, 0}, {s, 0, 0}, {0, s, 0}, {0, 0, s}};
  tet.triangles = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};
  const MassProperties props = compute_mass_properties(tet);
  expect_relative(props.volume, s * s * s / 6, 1e-12);
  EXPECT_LT((props.centroid - Eigen::Vector3d::Constant(s / 4)).norm(), 1e-15);
  const double s5 = std::pow(s, 5);
  for (int i = 0; i < 3; ++i) {
    expect_relative(props.inertia_per_density(i, i), s5 / 80, 1e-12);
    for (int j = 0; j < 3; ++j) {
      if (i != j) {
        expect_relative(props.inertia_per_density(i, j), s5 / 480, 1e-12);
      }
    }
  }
}

TEST(MassProperties, UvSphereApproachesBall) {
  const double r = 0.05;
  const double exact_volume = 4.0 / 3.0 * std::numbers::pi * r * r * r;
  double previous_error = 1.0;
  for (int n : {16, 32, 64}) {
    const MassProperties props = compute_mass_properties(make_uv_sphere(r, n, 2 * n));
    // An inscribed polyhedron: slightly smaller than the ball, error shrinking like 1/n^2.
    const double error = (exact_volume - props.volume) / exact_volume;
    EXPECT_GT(error, 0.0);
    EXPECT_LT(error, 10.0 / (n * n)) << "n = " << n;
    EXPECT_LT(error, previous_error);
    previous_error = error;
    EXPECT_LT(props.centroid.norm(), 1e-12);
    const double ball_inertia = 0.4 * props.volume * r * r;
    for (int i = 0; i < 3; ++i) expect_relative(props.inertia_per_density(i, i), ball_inertia, 20.0 / (n * n));
  }
}

TEST(MassProperties, InvertedWindingGivesNegativeVolume) {
  // Documented behaviour: an inward-facing (clockwise from outside) mesh yields the negated
  // volume; the centroid is still right. A negative volume therefore flags flipped winding.
  TriangleMesh box = make_box(0.1, 0.2, 0.3);
  for (auto& t : box.triangles) std::swap(t[1], t[2]);
  const MassProperties props = compute_mass_properties(box);
  expect_relative(props.volume, -0.1 * 0.2 * 0.3, 1e-12);
  EXPECT_LT((props.centroid - Eigen::Vector3d(0.05, 0.1, 0.15)).norm(), 1e-12);
}

TEST(MassProperties, EmptyMeshIsZero) {
  const MassProperties props = compute_mass_properties(TriangleMesh{});
  EXPECT_EQ(props.volume, 0.0);
  EXPECT_TRUE(props.centroid.isZero());
  EXPECT_TRUE(props.inertia_per_density.isZero());
}

TEST(TriangleMesh, BoundsOfVerticesAndEmpty) {
  EXPECT_TRUE(TriangleMesh{}.min_corner().isZero());
  EXPECT_TRUE(TriangleMesh{}.max_corner().isZero());
  const TriangleMesh box = translated(make_box(0.1, 0.2, 0.3), Eigen::Vector3d(-1, 0, 1));
  EXPECT_TRUE(box.min_corner().isApprox(Eigen::Vector3d(-1, 0, 1)));
  EXPECT_TRUE(box.max_corner().isApprox(Eigen::Vector3d(-0.9, 0.2, 1.3)));
}

}  // namespace
}  // namespace telegrasp::sim
