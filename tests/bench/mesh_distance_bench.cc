// Microbenchmarks for MeshDistance (sim/mesh_distance.h) on a ~10k-triangle geodesic sphere of
// radius 4 cm, with queries near the surface (finger-capsule-like: radius 8 mm, length 25 mm).
#include "telegrasp/sim/mesh_distance.h"

#include <benchmark/benchmark.h>

#include <Eigen/Geometry>

#include <array>
#include <cmath>
#include <cstdint>
#include <map>
#include <random>
#include <utility>
#include <vector>

namespace telegrasp::sim {
namespace {

using Eigen::Vector3d;

constexpr double kRadius = 0.04;  // object radius [m]
constexpr double kCapsuleRadius = 0.008;  // finger capsule radius [m]
constexpr double kCapsuleLength = 0.025;  // finger capsule segment length [m]
constexpr int kQueries = 1024;  // distinct queries cycled through

/// Geodesic sphere: each icosahedron face split into freq^2 triangles, projected to the
/// sphere; freq = 22 gives 9680 triangles.
TriangleMesh make_geodesic_sphere(double radius, int freq) {
  const double p = (1.0 + std::sqrt(5.0)) / 2.0;
  const double raw[12][3] = {{-1, p, 0},  {1, p, 0},  {-1, -p, 0}, {1, -p, 0}, {0, -1, p},  {0, 1, p},
                             {0, -1, -p}, {0, 1, -p}, {p, 0, -1},  {p, 0, 1},  {-p, 0, -1}, {-p, 0, 1}};
  const int faces[20][3] = {{0, 11, 5},  {0, 5, 1},  {0, 1, 7},  {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
                            {11, 10, 2}, {10, 7, 6}, {7, 1, 8},  {3, 9, 4},  {3, 4, 2},   {3, 2, 6}, {3, 6, 8},
                            {3, 8, 9},   {4, 9, 5},  {2, 4, 11}, {6, 2, 10}, {8, 6, 7},   {9, 8, 1}};
  TriangleMesh m;
  std::map<std::array<long long, 3>, std::uint32_t> index;  // welds points shared by faces
  const auto vertex = [&](const Vector3d& q) {
    const Vector3d v = radius * q.normalized();
    const std::array<long long, 3> key = {std::llround(v.x() * 1e9), std::llround(v.y() * 1e9),
                                          std::llround(v.z() * 1e9)};
    const auto [it, inserted] = index.emplace(key, static_cast<std::uint32_t>(m.vertices.size()));
    if (inserted) m.vertices.push_back(v);
    return it->second;
  };
  for (const auto& f : faces) {
    const Vector3d a(raw[f[0]][0], raw[f[0]][1], raw[f[0]][2]);
    const Vector3d b(raw[f[1]][0], raw[f[1]][1], raw[f[1]][2]);
    const Vector3d c(raw[f[2]][0], raw[f[2]][1], raw[f[2]][2]);
    const auto at = [&](int i, int j) { return vertex(a + (b - a) * i / freq + (c - a) * j / freq); };
    for (int i = 0; i < freq; ++i) {
      for (int j = 0; i + j < freq; ++j) {
        m.triangles.push_back({at(i, j), at(i + 1, j), at(i, j + 1)});
        if (i + j + 2 <= freq) m.triangles.push_back({at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)});
      }
    }
  }
  for (auto& t : m.triangles) {  // outward orientation
    const Vector3d& x = m.vertices[t[0]];
    if ((m.vertices[t[1]] - x).cross(m.vertices[t[2]] - x).dot(x) < 0) std::swap(t[1], t[2]);
  }
  return m;
}

const TriangleMesh& object_mesh() {
  static const TriangleMesh mesh = make_geodesic_sphere(kRadius, 22);
  return mesh;
}

const MeshDistance& object() {
  static const MeshDistance md(object_mesh());
  return md;
}

Vector3d random_unit(std::mt19937& rng) {
  std::normal_distribution<double> g(0.0, 1.0);
  return Vector3d(g(rng), g(rng), g(rng)).normalized();
}

/// A unit vector perpendicular to n, tilted towards n by up to ~20 degrees.
Vector3d roughly_tangent(std::mt19937& rng, const Vector3d& n) {
  std::uniform_real_distribution<double> tilt(-0.35, 0.35);
  Vector3d t = random_unit(rng);
  t = (t - t.dot(n) * n).normalized();
  return (t + tilt(rng) * n).normalized();
}

/// Points within 3 mm of the surface, inside and outside.
std::vector<Vector3d> near_points() {
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> off(-0.003, 0.003);
  std::vector<Vector3d> out;
  for (int i = 0; i < kQueries; ++i) out.push_back((kRadius + off(rng)) * random_unit(rng));
  return out;
}

/// Finger-like capsule segments whose surface lies within +-3 mm of the object's surface.
std::vector<std::pair<Vector3d, Vector3d>> near_segments() {
  std::mt19937 rng(2);
  std::uniform_real_distribution<double> off(-0.003, 0.003);
  std::vector<std::pair<Vector3d, Vector3d>> out;
  for (int i = 0; i < kQueries; ++i) {
    const Vector3d n = random_unit(rng);
    const Vector3d tangent = roughly_tangent(rng, n);
    const Vector3d a = (kRadius + kCapsuleRadius + off(rng)) * n;  // one end (the fingertip) near the surface
    out.emplace_back(a, a + kCapsuleLength * tangent);
  }
  return out;
}

/// Sphere casts starting 10-20 mm from the surface, heading roughly towards the object.
std::vector<std::pair<Vector3d, Vector3d>> casts() {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> off(0.01, 0.02);
  std::vector<std::pair<Vector3d, Vector3d>> out;
  for (int i = 0; i < kQueries; ++i) {
    const Vector3d n = random_unit(rng);
    const Vector3d o = (kRadius + off(rng)) * n;
    const Vector3d target = 0.03 * random_unit(rng);
    out.emplace_back(o, (target - o).normalized());
  }
  return out;
}

void BM_MeshDistance_build(benchmark::State& state) {
  const TriangleMesh& mesh = object_mesh();
  for (auto _ : state) {
    MeshDistance md(mesh);
    benchmark::DoNotOptimize(md);
  }
  state.counters["triangles"] = static_cast<double>(mesh.triangles.size());
  state.counters["bytes"] = static_cast<double>(MeshDistance(mesh).memory_bytes());
}
BENCHMARK(BM_MeshDistance_build)->Unit(benchmark::kMillisecond);

// Runs `query` on each of `inputs` in turn, one per iteration; how many iterations ran.
template <class T, class Query>
std::size_t each_in_turn(benchmark::State& state, const std::vector<T>& inputs, Query query) {
  std::size_t i = 0;
  for (auto _ : state) query(inputs[i++ % inputs.size()]);
  return i;
}

// The share of `iterations` that hit.
double hit_ratio(std::size_t hits, std::size_t iterations) {
  return static_cast<double>(hits) / static_cast<double>(std::max<std::size_t>(iterations, 1));
}

void BM_MeshDistance_closest_point(benchmark::State& state) {
  const MeshDistance& md = object();
  each_in_turn(state, near_points(), [&](const auto& p) { benchmark::DoNotOptimize(md.closest_point(p)); });
}
BENCHMARK(BM_MeshDistance_closest_point);

void BM_MeshDistance_closest_to_segment(benchmark::State& state) {
  const MeshDistance& md = object();
  each_in_turn(state, near_segments(),
               [&](const auto& s) { benchmark::DoNotOptimize(md.closest_to_segment(s.first, s.second)); });
}
BENCHMARK(BM_MeshDistance_closest_to_segment);

void BM_MeshDistance_capsule_overlaps(benchmark::State& state) {
  const MeshDistance& md = object();
  std::size_t hits = 0;
  const std::size_t n = each_in_turn(state, near_segments(), [&](const auto& s) {
    const bool hit = md.capsule_overlaps(s.first, s.second, kCapsuleRadius);
    hits += hit;
    benchmark::DoNotOptimize(hit);
  });
  state.counters["overlap_ratio"] = hit_ratio(hits, n);
}
BENCHMARK(BM_MeshDistance_capsule_overlaps);

void BM_MeshDistance_capsule_signed_distance(benchmark::State& state) {
  const MeshDistance& md = object();
  each_in_turn(state, near_segments(), [&](const auto& s) {
    benchmark::DoNotOptimize(md.capsule_signed_distance(s.first, s.second, kCapsuleRadius));
  });
}
BENCHMARK(BM_MeshDistance_capsule_signed_distance);

void BM_MeshDistance_sphere_cast(benchmark::State& state) {
  const MeshDistance& md = object();
  std::size_t hits = 0;
  const std::size_t n = each_in_turn(state, casts(), [&](const auto& r) {
    const SweepHit h = md.sphere_cast(r.first, r.second, kCapsuleRadius, 0.05);
    hits += h.hit;
    benchmark::DoNotOptimize(h);
  });
  state.counters["hit_ratio"] = hit_ratio(hits, n);
}
BENCHMARK(BM_MeshDistance_sphere_cast);

void BM_MeshDistance_contains(benchmark::State& state) {
  const MeshDistance& md = object();
  each_in_turn(state, near_points(), [&](const auto& p) { benchmark::DoNotOptimize(md.contains(p)); });
}
BENCHMARK(BM_MeshDistance_contains);

}  // namespace
}  // namespace telegrasp::sim
