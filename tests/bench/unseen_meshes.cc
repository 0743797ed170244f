// Generated stand-ins for unseen meshes: every shape is one or more closed "tubes", a grid of
// rings between two poles, f(u, v) with u in [0, 1] from pole to pole and v around.
#include "unseen_meshes.h"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <functional>
#include <numbers>
#include <random>

namespace telegrasp::sim::bench {
namespace {

using Eigen::Vector2d;
using Eigen::Vector3d;

constexpr double kPi = std::numbers::pi;

/// A closed surface: point at (u, v), u in [0, 1] (poles at 0 and 1), v in [0, 2 pi).
using Surface = std::function<Vector3d(double u, double v)>;

/// How a tube's grid is laid out: regular, or uneven (slivers) with random quad diagonals.
struct Grid {
  int rings = 100;  // rings between the poles, plus one: 2 * segments * (rings - 1) triangles
  int segments = 50;
  bool slivers = false;
  unsigned seed = 1;
};

/// Signed volume of a closed mesh (positive when outward-facing).
double signed_volume(const TriangleMesh& m) {
  double v = 0;
  for (const auto& t : m.triangles) v += m.vertices[t[0]].dot(m.vertices[t[1]].cross(m.vertices[t[2]]));
  return v / 6;
}

/// Rings at u_k (k = 1 .. rings - 1) of `segments` points, fans to the poles; outward-facing.
TriangleMesh tube(const Surface& f, const Grid& g) {
  std::mt19937 rng(g.seed);
  std::uniform_real_distribution<double> jitter(-0.49, 0.49);
  std::bernoulli_distribution coin(0.5);
  TriangleMesh m;
  m.vertices.push_back(f(0, 0));
  for (int k = 1; k < g.rings; ++k) {
    const double u = (k + (g.slivers ? jitter(rng) : 0.0)) / g.rings;
    const double twist = g.slivers ? jitter(rng) : 0.0;
    for (int j = 0; j < g.segments; ++j) m.vertices.push_back(f(u, 2 * kPi * (j + twist) / g.segments));
  }
  m.vertices.push_back(f(1, 0));
  const auto at = [&](int k, int j) { return static_cast<std::uint32_t>(1 + (k - 1) * g.segments + j % g.segments); };
  const auto last = static_cast<std::uint32_t>(m.vertices.size() - 1);
  for (int j = 0; j < g.segments; ++j) {
    m.triangles.push_back({0, at(1, j + 1), at(1, j)});
    for (int k = 1; k + 1 < g.rings; ++k) {
      if (g.slivers && coin(rng)) {
        m.triangles.push_back({at(k, j), at(k, j + 1), at(k + 1, j)});
        m.triangles.push_back({at(k, j + 1), at(k + 1, j + 1), at(k + 1, j)});
      } else {
        m.triangles.push_back({at(k, j), at(k, j + 1), at(k + 1, j + 1)});
        m.triangles.push_back({at(k, j), at(k + 1, j + 1), at(k + 1, j)});
      }
    }
    m.triangles.push_back({last, at(g.rings - 1, j), at(g.rings - 1, j + 1)});
  }
  if (signed_volume(m) < 0)
    for (auto& t : m.triangles) std::swap(t[1], t[2]);
  return m;
}

/// Appends `part` to `whole` as one more shell.
void append(TriangleMesh& whole, const TriangleMesh& part) {
  const auto base = static_cast<std::uint32_t>(whole.vertices.size());
  whole.vertices.insert(whole.vertices.end(), part.vertices.begin(), part.vertices.end());
  for (const auto& t : part.triangles) whole.triangles.push_back({t[0] + base, t[1] + base, t[2] + base});
}

/// A (radius, axial) polyline from pole to pole, walked at constant speed as u goes 0 -> 1.
Vector2d along_profile(const std::vector<Vector2d>& profile, double u) {
  std::vector<double> length{0};
  for (std::size_t i = 1; i < profile.size(); ++i)
    length.push_back(length.back() + (profile[i] - profile[i - 1]).norm());
  const double s = std::clamp(u, 0.0, 1.0) * length.back();
  const auto it = std::upper_bound(length.begin(), length.end(), s);
  const std::size_t i = std::clamp<std::size_t>(it - length.begin(), 1, profile.size() - 1);
  const double w = (s - length[i - 1]) / std::max(length[i] - length[i - 1], 1e-15);
  return profile[i - 1] + std::clamp(w, 0.0, 1.0) * (profile[i] - profile[i - 1]);
}

/// Elliptic rounding of a flat part's ends: 0 at an end, 1 once `round` inside.
double end_rounding(double d, double round) {
  const double x = 1 - std::clamp(d / round, 0.0, 1.0);
  return std::sqrt(std::max(0.0, 1 - x * x));
}

/// A thin flat part along `span` (length L, centred) whose section at span s is an ellipse of
/// half chord c(s) along `chord` and half thickness t(s) along the third axis, around `centre`.
Surface flat_part(const Vector3d& centre, const Vector3d& span, const Vector3d& chord, double L,
                  std::function<double(double)> c, std::function<double(double)> t, double round) {
  const Vector3d thick = span.cross(chord);
  return [=](double u, double v) {
    const double s = (u - 0.5) * L;
    const double e = end_rounding(std::min(u, 1 - u) * L, round);
    return Vector3d(centre + s * span + e * c(s) * std::cos(v) * chord + e * t(s) * std::sin(v) * thick);
  };
}

/// Marker: a 0.12 m x 0.018 m cylinder along z, flat rounded base, a conical tip.
TriangleMesh marker(const Grid& g) {
  const double R = 0.009;
  const double h = 0.06;
  const std::vector<Vector2d> profile{{0, -h},
                                      {R - 0.001, -h},
                                      {R - 0.0003, -h + 0.0003},
                                      {R, -h + 0.001},
                                      {R, h - 0.022},
                                      {R - 0.001, h - 0.018},
                                      {0.004, h - 0.012},
                                      {0.0035, h - 0.004},
                                      {0.002, h - 0.0005},
                                      {0, h}};
  return tube(
      [&](double u, double v) {
        const Vector2d p = along_profile(profile, u);
        return Vector3d(p.x() * std::cos(v), p.x() * std::sin(v), p.y());
      },
      g);
}

/// Spoon along x: a thin handle bending up, a thin shallow bowl (8 mm deep) at the far end.
TriangleMesh spoon(const Grid& g) {
  const double L = 0.186;
  const double bowl_start = 0.05;  // x where the bowl widens (x in [-L/2, L/2])
  const auto half_width = [=](double x) {
    if (x < bowl_start) return 0.0055 - 0.0015 * (x + L / 2) / (L / 2 + bowl_start);
    const double b = (x - bowl_start) / (L / 2 - bowl_start);  // 0 .. 1 over the bowl
    return 0.004 + 0.018 * std::sqrt(std::max(0.0, 1 - (1 - 2 * b) * (1 - 2 * b)));
  };
  const auto half_thickness = [=](double x) { return std::clamp(0.002 - 0.1 * (x - bowl_start), 0.001, 0.002); };
  const auto centre_height = [=](double x, double y, double w) {
    if (x < bowl_start) return 0.012 * std::pow((bowl_start - x) / (L / 2 + bowl_start), 2);  // handle bends up
    const double b = (x - bowl_start) / (L / 2 - bowl_start);
    const double across = w > 0 ? std::min(1.0, std::abs(y) / w) : 1.0;
    return -0.008 * std::sin(kPi * b) * (1 - across * across);
  };
  return tube(
      [=](double u, double v) {
        const double x = (u - 0.5) * L;
        const double e = end_rounding(std::min(u, 1 - u) * L, 0.006);
        const double w = e * half_width(x);
        const double y = w * std::cos(v);
        return Vector3d(x, y, centre_height(x, y, w) + e * half_thickness(x) * std::sin(v));
      },
      g);
}

/// Toy airplane: fuselage along x, low wing and tailplane below it, fin above; shells 1 mm apart.
TriangleMesh airplane(Grid g) {
  const double Rf = 0.02;
  const std::vector<Vector2d> body{{0, -0.12}, {0.012, -0.117}, {0.018, -0.108}, {Rf, -0.095},
                                   {Rf, 0.03}, {0.012, 0.10},   {0.006, 0.122},  {0, 0.125}};
  TriangleMesh m;
  g.rings = 81;
  g.segments = 25;  // 4,000 triangles
  append(m, tube(
                [&](double u, double v) {
                  const Vector2d p = along_profile(body, u);
                  return Vector3d(p.y(), p.x() * std::cos(v), p.x() * std::sin(v));
                },
                g));
  g.rings = 61;
  g.segments = 30;  // 3,600 triangles
  ++g.seed;
  append(m, tube(flat_part(
                     {-0.01, 0, -Rf - 0.004}, Vector3d::UnitY(), Vector3d::UnitX(), 0.26,
                     [](double s) { return 0.028 - 0.04 * std::abs(s); }, [](double) { return 0.003; }, 0.008),
                 g));
  g.rings = 41;
  g.segments = 20;  // 1,600 triangles
  ++g.seed;
  append(m, tube(flat_part(
                     {0.1, 0, -0.018}, Vector3d::UnitY(), Vector3d::UnitX(), 0.09,
                     [](double s) { return 0.015 - 0.06 * std::abs(s); }, [](double) { return 0.002; }, 0.006),
                 g));
  g.rings = 21;
  g.segments = 20;  // 800 triangles
  ++g.seed;
  append(m, tube(flat_part(
                     {0.105, 0, 0.046}, Vector3d::UnitZ(), Vector3d::UnitX(), 0.06,
                     [](double s) { return 0.014 + 0.1 * s; }, [](double) { return 0.002; }, 0.006),
                 g));
  return m;
}

}  // namespace

TriangleMesh randomly_rotated(const TriangleMesh& mesh, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> normal;
  Eigen::Quaterniond q(normal(rng), normal(rng), normal(rng), normal(rng));  // uniform on SO(3)
  q.normalize();
  Vector3d centre = Vector3d::Zero();
  for (const Vector3d& v : mesh.vertices) centre += v;
  centre /= std::max<std::size_t>(1, mesh.vertices.size());
  TriangleMesh out = mesh;
  for (Vector3d& v : out.vertices) v = centre + q * (v - centre);
  return out;
}

std::vector<NamedMesh> procedural_unseen_meshes() {
  std::vector<NamedMesh> out;
  const Grid regular{101, 50, false, 11};
  const Grid slivers{51, 100, true, 12};  // 10,000 triangles, uneven rings, twisted, random diagonals
  const auto add = [&](const std::string& name, const TriangleMesh& m, unsigned seed) {
    out.push_back({name, m});
    out.push_back({name + "_rotated", randomly_rotated(m, seed)});
  };
  add("gen_marker", marker(regular), 101);
  add("gen_marker_slivers", marker(slivers), 102);
  add("gen_spoon", spoon(regular), 103);
  add("gen_spoon_slivers", spoon(slivers), 104);
  add("gen_airplane", airplane(regular), 105);
  add("gen_airplane_slivers", airplane(slivers), 106);
  return out;
}

}  // namespace telegrasp::sim::bench
