// Procedural stand-in meshes for the 30 protocol objects, built from a few generic shapes:
// subdivided box, surface of revolution (lathe), swept tube and extruded 2D outline.
#include "telegrasp/sim/standin_objects.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <map>
#include <numbers>

#include "telegrasp/sim/mesh_loading.h"

namespace telegrasp::sim {
namespace {

using Vec2 = Eigen::Vector2d;
using Vec3 = Eigen::Vector3d;
using Ring = std::vector<Vec3>;
using Triangle = std::array<std::uint32_t, 3>;

constexpr double kPi = std::numbers::pi;
constexpr int kRingSegments = 48;  ///< Vertices per ring of round shapes (multiple of 4).
constexpr double kBoxCell = 0.007;  ///< Box grid cell side, m (cell diagonal < 1 cm).
constexpr double kLayerHeight = 0.01;  ///< Max wall layer height of extrusions, m.

// ---------------------------------------------------------------- generic shape helpers

/// Closes a stack of equally sized rings (each counter-clockwise about the direction from the
/// first ring to the last) with a fan to `start_cap` and a fan to `end_cap`; outward-facing.
TriangleMesh ring_stack(const std::vector<Ring>& rings, const Vec3& start_cap, const Vec3& end_cap) {
  TriangleMesh mesh;
  const auto n = static_cast<std::uint32_t>(rings.front().size());
  const auto ring_count = static_cast<std::uint32_t>(rings.size());
  mesh.vertices.push_back(start_cap);
  for (const Ring& ring : rings) mesh.vertices.insert(mesh.vertices.end(), ring.begin(), ring.end());
  mesh.vertices.push_back(end_cap);
  const std::uint32_t end_index = 1 + ring_count * n;
  auto at = [n](std::uint32_t ring, std::uint32_t i) { return 1 + ring * n + i % n; };
  for (std::uint32_t i = 0; i < n; ++i) {
    mesh.triangles.push_back({0, at(0, i + 1), at(0, i)});
    for (std::uint32_t k = 0; k + 1 < ring_count; ++k) {
      mesh.triangles.push_back({at(k, i), at(k, i + 1), at(k + 1, i + 1)});
      mesh.triangles.push_back({at(k, i), at(k + 1, i + 1), at(k + 1, i)});
    }
    mesh.triangles.push_back({end_index, at(ring_count - 1, i), at(ring_count - 1, i + 1)});
  }
  return mesh;
}

/// Surface of revolution about +z of a profile of (radius, z) points that starts and ends on
/// the axis (radius 0) and runs bottom to top around the outside of the solid.
TriangleMesh lathe(const std::vector<Vec2>& profile_radius_z) {
  std::vector<Ring> rings;
  for (std::size_t k = 1; k + 1 < profile_radius_z.size(); ++k) {
    const double r = profile_radius_z[k].x(), z = profile_radius_z[k].y();
    Ring ring;
    for (int i = 0; i < kRingSegments; ++i) {
      const double phi = 2 * kPi * i / kRingSegments;
      ring.emplace_back(r * std::cos(phi), r * std::sin(phi), z);
    }
    rings.push_back(std::move(ring));
  }
  return ring_stack(rings, Vec3(0, 0, profile_radius_z.front().y()), Vec3(0, 0, profile_radius_z.back().y()));
}

/// A tube of circular section swept along `centres`; an end of radius 0 becomes a pointed
/// tip, otherwise the end is closed flat. `reference_normal` must not be parallel to the path.
TriangleMesh swept_tube(const std::vector<Vec3>& centres, const std::vector<double>& radii,
                        const Vec3& reference_normal, int segments) {
  std::vector<Ring> rings;
  const std::size_t count = centres.size();
  const bool pointed_start = radii.front() == 0;
  const bool pointed_end = radii.back() == 0;
  for (std::size_t k = pointed_start ? 1 : 0; k < (pointed_end ? count - 1 : count); ++k) {
    const Vec3 tangent = (centres[std::min(k + 1, count - 1)] - centres[k > 0 ? k - 1 : 0]).normalized();
    const Vec3 normal = (reference_normal - reference_normal.dot(tangent) * tangent).normalized();
    const Vec3 binormal = tangent.cross(normal);
    Ring ring;
    for (int i = 0; i < segments; ++i) {
      const double phi = 2 * kPi * i / segments;
      ring.push_back(centres[k] + radii[k] * (std::cos(phi) * normal + std::sin(phi) * binormal));
    }
    rings.push_back(std::move(ring));
  }
  return ring_stack(rings, centres.front(), centres.back());
}

/// Box [-x/2, x/2] x [-y/2, y/2] x [0, z] with every face gridded into cells of side <= kBoxCell.
TriangleMesh subdivided_box(const Vec3& extent) {
  std::array<int, 3> divisions{};
  for (int a = 0; a < 3; ++a) divisions[a] = std::max(1, int(std::ceil(extent[a] / kBoxCell - 1e-9)));
  const Vec3 lo(-extent.x() / 2, -extent.y() / 2, 0);
  const Vec3 ex = Vec3::UnitX() * extent.x(), ey = Vec3::UnitY() * extent.y(), ez = Vec3::UnitZ() * extent.z();
  // Each face: origin and two edge vectors u, v with u x v pointing outward.
  const std::array<std::array<Vec3, 3>, 6> faces{{
      {lo + ex, ey, ez},
      {lo, ez, ey},
      {lo + ey, ez, ex},
      {lo, ex, ez},
      {lo + ez, ex, ey},
      {lo, ey, ex},
  }};
  auto axis_of = [](const Vec3& v) {
    int a;
    v.cwiseAbs().maxCoeff(&a);
    return a;
  };
  TriangleMesh soup;
  for (const auto& [origin, u, v] : faces) {
    const int nu = divisions[axis_of(u)], nv = divisions[axis_of(v)];
    const auto base = static_cast<std::uint32_t>(soup.vertices.size());
    for (int j = 0; j <= nv; ++j) {
      for (int i = 0; i <= nu; ++i) soup.vertices.push_back(origin + u * (double(i) / nu) + v * (double(j) / nv));
    }
    auto at = [&](int i, int j) { return base + static_cast<std::uint32_t>(j * (nu + 1) + i); };
    for (int j = 0; j < nv; ++j) {
      for (int i = 0; i < nu; ++i) {
        soup.triangles.push_back({at(i, j), at(i + 1, j), at(i + 1, j + 1)});
        soup.triangles.push_back({at(i, j), at(i + 1, j + 1), at(i, j + 1)});
      }
    }
  }
  // Faces share their border vertices by position only; welding joins them.
  return clean_mesh(soup, 1e-9);
}

/// z component of the 2D cross product.
double cross2(const Vec2& a, const Vec2& b) { return a.x() * b.y() - a.y() * b.x(); }

/// Triangulates a simple counter-clockwise polygon by ear clipping; triangles are CCW.
std::vector<Triangle> ear_clip(const std::vector<Vec2>& polygon) {
  std::vector<std::uint32_t> remaining(polygon.size());
  for (std::uint32_t i = 0; i < remaining.size(); ++i) remaining[i] = i;
  std::vector<Triangle> triangles;
  constexpr double kMinTwiceArea = 4e-14;  // Twice the clean_mesh degenerate area, m^2.
  // strict = reject ears touching another vertex even on their border (avoids T-junctions).
  auto is_ear = [&](std::size_t pos, bool strict) {
    const std::size_t m = remaining.size();
    const std::uint32_t ia = remaining[(pos + m - 1) % m], ib = remaining[pos], ic = remaining[(pos + 1) % m];
    const Vec2 &a = polygon[ia], &b = polygon[ib], &c = polygon[ic];
    if (cross2(b - a, c - b) <= kMinTwiceArea) return false;
    const double slack = strict ? 1e-15 : -1e-15;
    for (std::uint32_t iv : remaining) {
      if (iv == ia || iv == ib || iv == ic) continue;
      const Vec2& p = polygon[iv];
      if (cross2(b - a, p - a) >= -slack && cross2(c - b, p - b) >= -slack && cross2(a - c, p - c) >= -slack) {
        return false;
      }
    }
    return true;
  };
  std::size_t pos = 0;
  while (remaining.size() > 3) {
    const std::size_t m = remaining.size();
    std::size_t found = m;
    for (bool strict : {true, false}) {
      for (std::size_t step = 0; step < m && found == m; ++step) {
        if (is_ear((pos + step) % m, strict)) found = (pos + step) % m;
      }
      if (found != m) break;
    }
    if (found == m) found = pos % m;  // Not a simple polygon; clip anyway rather than loop.
    triangles.push_back({remaining[(found + m - 1) % m], remaining[found], remaining[(found + 1) % m]});
    remaining.erase(remaining.begin() + static_cast<std::ptrdiff_t>(found));
    pos = found % remaining.size();
  }
  triangles.push_back({remaining[0], remaining[1], remaining[2]});
  return triangles;
}

/// Prism from a simple CCW outline (x, y), from z = 0 to z = height, with walls in layers of
/// at most kLayerHeight and outline edges split so the mesh has a moderate triangle count.
TriangleMesh extruded_polygon(const std::vector<Vec2>& outline, double height) {
  const int layers = std::clamp(int(std::ceil(height / kLayerHeight - 1e-9)), 1, 8);
  double perimeter = 0;
  for (std::size_t i = 0; i < outline.size(); ++i) perimeter += (outline[(i + 1) % outline.size()] - outline[i]).norm();
  // Aim for 150..(8000 triangles) outline points: walls 2 n layers, caps 2 (n - 2).
  const double max_points = 8000.0 / (2 * layers + 2);
  const double target_points = std::clamp(perimeter / 0.003, 150.0, max_points - outline.size());
  const double spacing = perimeter / target_points;
  std::vector<Vec2> ring;
  for (std::size_t i = 0; i < outline.size(); ++i) {
    const Vec2& a = outline[i];
    const Vec2& b = outline[(i + 1) % outline.size()];
    const int pieces = std::max(1, int(std::ceil((b - a).norm() / spacing)));
    for (int p = 0; p < pieces; ++p) ring.push_back(a + (b - a) * (double(p) / pieces));
  }
  const auto n = static_cast<std::uint32_t>(ring.size());
  TriangleMesh mesh;
  for (int l = 0; l <= layers; ++l) {
    for (const Vec2& p : ring) mesh.vertices.emplace_back(p.x(), p.y(), height * l / layers);
  }
  auto at = [n](int layer, std::uint32_t i) { return static_cast<std::uint32_t>(layer) * n + i % n; };
  for (int l = 0; l < layers; ++l) {
    for (std::uint32_t i = 0; i < n; ++i) {
      mesh.triangles.push_back({at(l, i), at(l, i + 1), at(l + 1, i + 1)});
      mesh.triangles.push_back({at(l, i), at(l + 1, i + 1), at(l + 1, i)});
    }
  }
  for (const Triangle& t : ear_clip(ring)) {
    mesh.triangles.push_back({at(0, t[0]), at(0, t[2]), at(0, t[1])});  // bottom, -z
    mesh.triangles.push_back({at(layers, t[0]), at(layers, t[1]), at(layers, t[2])});  // top, +z
  }
  return mesh;
}

/// Outline symmetric about the x axis from (x, half width) samples ordered by x; a sample of
/// half width 0 at either end is a point. `tines` > 0 cuts that many prongs of `tine_length`
/// beyond the last sample (fork tines, wrench jaws).
std::vector<Vec2> symmetric_outline(const std::vector<Vec2>& x_half_width, int tines = 0, double tine_length = 0) {
  std::vector<Vec2> lower, upper;
  for (const Vec2& s : x_half_width) {
    lower.emplace_back(s.x(), -s.y());
    if (s.y() > 0) upper.emplace_back(s.x(), s.y());
  }
  std::vector<Vec2> outline(lower.begin(), lower.end());
  if (tines > 0) {
    const double x_tip = x_half_width.back().x(), w = x_half_width.back().y();
    const double tine = 2 * w / (tines + 0.6 * (tines - 1)), gap = 0.6 * tine;
    double y = -w;
    for (int k = 0; k < tines; ++k) {
      outline.emplace_back(x_tip + tine_length, y);
      outline.emplace_back(x_tip + tine_length, y + tine);
      y += tine;
      if (k + 1 < tines) {
        outline.emplace_back(x_tip, y);
        outline.emplace_back(x_tip, y + gap);
        y += gap;
      }
    }
  }
  outline.insert(outline.end(), upper.rbegin(), upper.rend());
  // Drop repeated consecutive points (e.g. a zero half width at an end).
  std::vector<Vec2> unique;
  for (const Vec2& p : outline) {
    if (unique.empty() || (p - unique.back()).norm() > 1e-9) unique.push_back(p);
  }
  while (unique.size() > 1 && (unique.front() - unique.back()).norm() <= 1e-9) unique.pop_back();
  return unique;
}

/// The outline turned by `angle_rad` about the origin (counter-clockwise).
std::vector<Vec2> rotated_outline(std::vector<Vec2> outline, double angle_rad) {
  const Eigen::Rotation2Dd rotation(angle_rad);
  for (Vec2& p : outline) p = rotation * p;
  return outline;
}

/// The mesh with every vertex rotated about the origin.
TriangleMesh rotated(TriangleMesh mesh, const Eigen::Matrix3d& rotation) {
  for (Vec3& v : mesh.vertices) v = rotation * v;
  return mesh;
}

/// Scales each axis and translates so the bounding box is exactly [-x/2, x/2] x [-y/2, y/2] x [0,
/// z].
TriangleMesh fit_to_extent(TriangleMesh mesh, const Vec3& extent) {
  const Vec3 lo = mesh.min_corner(), hi = mesh.max_corner();
  const Vec3 scale = extent.cwiseQuotient(hi - lo);
  const Vec3 anchor(0.5 * (lo.x() + hi.x()), 0.5 * (lo.y() + hi.y()), lo.z());
  for (Vec3& v : mesh.vertices) v = (v - anchor).cwiseProduct(scale);
  return mesh;
}

// ---------------------------------------------------------------- profiles

/// Flat-capped cylinder profile with concentric cap rings and side rings every 1 cm.
std::vector<Vec2> cylinder_profile(double radius, double height) {
  std::vector<Vec2> p{{0, 0}};
  for (int i = 1; i <= 4; ++i) p.emplace_back(radius * i / 4, 0);
  const int sides = std::max(1, int(std::ceil(height / 0.01)));
  for (int i = 1; i <= sides; ++i) p.emplace_back(radius, height * i / sides);
  for (int i = 3; i >= 0; --i) p.emplace_back(radius * i / 4, height);
  return p;
}

/// Profile (radius, z) of a solid of revolution with radius r(t), t in [0, 1] bottom to top.
std::vector<Vec2> revolution_profile(const std::function<double(double)>& radius_of_t, double height, int steps) {
  std::vector<Vec2> p{{0, 0}};
  for (int i = 1; i < steps; ++i) {
    const double t = double(i) / steps;
    p.emplace_back(radius_of_t(t), height * t);
  }
  p.emplace_back(0, height);
  return p;
}

/// Unit sphere-like profile sampled uniformly in polar angle (poles exact).
std::vector<Vec2> sphere_profile(int steps) {
  std::vector<Vec2> p;
  for (int i = 0; i <= steps; ++i) {
    const double theta = kPi * i / steps;
    p.emplace_back(i == 0 || i == steps ? 0.0 : 0.5 * std::sin(theta), 0.5 - 0.5 * std::cos(theta));
  }
  return p;
}

/// Bottle: bevelled flat bottom, straight body, rounded shoulder, neck and a bevelled cap.
std::vector<Vec2> bottle_profile(double body_radius, double body_height, double neck_radius, double total_height) {
  const double bevel = 0.004;
  std::vector<Vec2> p{{0, 0}};
  for (int i = 1; i <= 3; ++i) p.emplace_back((body_radius - bevel) * i / 3, 0);
  const int sides = std::max(1, int(std::ceil((body_height - bevel) / 0.01)));
  for (int i = 0; i <= sides; ++i) p.emplace_back(body_radius, bevel + (body_height - bevel) * i / sides);
  const double shoulder_top = body_height + 0.5 * (total_height - body_height);
  for (int i = 1; i <= 8; ++i) {  // Quarter ellipse from the body to the neck.
    const double a = 0.5 * kPi * i / 8;
    p.emplace_back(neck_radius + (body_radius - neck_radius) * std::cos(a),
                   body_height + (shoulder_top - body_height) * std::sin(a));
  }
  const int neck = std::max(1, int(std::ceil((total_height - bevel - shoulder_top) / 0.01)));
  for (int i = 1; i <= neck; ++i)
    p.emplace_back(neck_radius, shoulder_top + (total_height - bevel - shoulder_top) * i / neck);
  p.emplace_back(neck_radius - bevel, total_height);
  p.emplace_back(0.5 * (neck_radius - bevel), total_height);
  p.emplace_back(0, total_height);
  return p;
}

// ---------------------------------------------------------------- per-object shapes

/// Proper rotation taking +z to +y (about x by -90 degrees).
Eigen::Matrix3d axis_z_to_y() { return Eigen::AngleAxisd(-kPi / 2, Vec3::UnitX()).toRotationMatrix(); }

/// A flat object: `outline` turned by `angle_rad`, extruded to the extent's height.
TriangleMesh flat_tool(const std::vector<Vec2>& outline, double angle_rad, const Vec3& extent) {
  return extruded_polygon(rotated_outline(outline, angle_rad), extent.z());
}

/// Banana: tube along a circular arc, thickest in the middle, pointed ends.
TriangleMesh banana(const Vec3& extent) {
  // Circular arc in the x-y plane, long along y, bulging towards +x, thickest in the middle.
  const double arc_radius = 0.12, half_angle = 0.8;
  const int samples = 41;
  std::vector<Vec3> centres;
  std::vector<double> radii;
  for (int k = 0; k < samples; ++k) {
    const double s = double(k) / (samples - 1);
    const double angle = -half_angle + 2 * half_angle * s;
    centres.emplace_back(arc_radius * std::cos(angle), arc_radius * std::sin(angle), 0);
    const double bulge = std::sin(kPi * s);
    radii.push_back(k == 0 || k == samples - 1 ? 0.0 : 0.5 * extent.z() * (0.3 + 0.7 * std::pow(bulge, 0.5)));
  }
  return swept_tube(centres, radii, Vec3::UnitZ(), 24);
}

using ShapeBuilder = std::function<TriangleMesh(const Vec3& extent)>;

/// The shape class of every protocol object, by id; the result is fitted to the extent later.
const std::map<std::string, ShapeBuilder>& shape_builders() {
  static const std::map<std::string, ShapeBuilder> builders = [] {
    std::map<std::string, ShapeBuilder> b;
    const ShapeBuilder can = [](const Vec3& e) { return lathe(cylinder_profile(0.5 * e.x(), e.z())); };
    const ShapeBuilder box = [](const Vec3& e) { return subdivided_box(e); };
    const ShapeBuilder ellipsoid = [](const Vec3&) { return lathe(sphere_profile(24)); };
    for (const char* id : {"002", "005", "007"}) b[id] = can;
    for (const char* id : {"003", "004", "009", "010"}) b[id] = box;
    for (const char* id : {"013", "014", "015", "017", "018", "055", "056"}) b[id] = ellipsoid;
    b["006"] = [](const Vec3&) { return lathe(bottle_profile(0.045, 0.12, 0.014, 0.191)); };
    b["021"] = [](const Vec3&) { return lathe(bottle_profile(0.05, 0.17, 0.017, 0.251)); };
    b["011"] = banana;
    b["012"] = [](const Vec3& e) {  // Cone-like berry, tip down, rounded top.
      return lathe(revolution_profile([](double t) { return 0.5 * std::pow(t, 0.6) * std::sqrt(1 - std::pow(t, 6)); },
                                      e.z(), 24));
    };
    b["016"] = [](const Vec3& e) {  // Pear lying along y: wide bottom bulb, narrow top.
      auto radius = [](double t) { return std::sqrt(t * (1 - t)) * (1.25 - 0.6 * t); };
      return rotated(lathe(revolution_profile(radius, e.y(), 32)), axis_z_to_y());
    };
    b["040"] = [](const Vec3&) {  // Marker lying along y: cylinder with a conical tip.
      std::vector<Vec2> p{{0, 0}, {0.005, 0}, {0.01, 0}};
      for (int i = 1; i <= 10; ++i) p.emplace_back(0.01, 0.1 * i / 10);
      p.insert(p.end(), {{0.007, 0.11}, {0.004, 0.121}, {0, 0.121}});
      return rotated(lathe(p), axis_z_to_y());
    };
    b["030"] = [](const Vec3& e) {  // Fork: handle, narrow neck, head with four tines.
      return flat_tool(
          symmetric_outline(
              {{0, 0.004}, {0.005, 0.008}, {0.10, 0.009}, {0.13, 0.004}, {0.15, 0.005}, {0.16, 0.012}, {0.165, 0.0135}},
              4, 0.033),
          0, e);
    };
    b["031"] = [](const Vec3& e) {  // Spoon: handle and an oval bowl, lying slightly diagonally.
      std::vector<Vec2> profile{{0, 0.005}, {0.01, 0.008}, {0.10, 0.006}, {0.12, 0.004}};
      for (int i = 0; i <= 12; ++i) {  // Elliptic bowl from x = 0.125 to 0.19.
        const double a = kPi * i / 12;
        profile.emplace_back(0.1575 - 0.0325 * std::cos(a), i == 12 ? 0.0 : std::max(0.004, 0.022 * std::sin(a)));
      }
      return flat_tool(symmetric_outline(profile), 0.21, e);
    };
    b["032"] = [](const Vec3& e) {  // Knife: handle, bolster, blade tapering to a point.
      return flat_tool(
          symmetric_outline(
              {{0, 0.007}, {0.01, 0.0105}, {0.09, 0.0105}, {0.095, 0.006}, {0.10, 0.009}, {0.19, 0.007}, {0.215, 0}}),
          0, e);
    };
    b["033"] = [](const Vec3& e) {  // Spatula: handle, shaft and a wide blade, slightly diagonal.
      return flat_tool(
          symmetric_outline(
              {{0, 0.010}, {0.01, 0.014}, {0.15, 0.013}, {0.17, 0.008}, {0.22, 0.009}, {0.235, 0.03}, {0.33, 0.04}}),
          0.15, e);
    };
    b["035"] = [](const Vec3& e) {  // Pistol drill seen from the side: battery, grip, body, chuck.
      const std::vector<Vec2> outline{{0.030, 0.000}, {0.150, 0.000}, {0.150, 0.040}, {0.105, 0.040}, {0.105, 0.120},
                                      {0.150, 0.120}, {0.150, 0.135}, {0.184, 0.135}, {0.184, 0.170}, {0.150, 0.170},
                                      {0.150, 0.188}, {0.010, 0.188}, {0.000, 0.170}, {0.000, 0.130}, {0.010, 0.120},
                                      {0.060, 0.120}, {0.060, 0.040}, {0.030, 0.040}};
      return flat_tool(outline, 0, e);
    };
    b["037"] = [](const Vec3& e) {  // Scissors along y: closed finger lobes, pivot, blades.
      return flat_tool(symmetric_outline({{0, 0.02},
                                          {0.005, 0.04},
                                          {0.02, 0.048},
                                          {0.05, 0.045},
                                          {0.075, 0.03},
                                          {0.085, 0.012},
                                          {0.10, 0.011},
                                          {0.202, 0}}),
                       kPi / 2, e);
    };
    b["042"] = [](const Vec3& e) {  // Wrench: handle, head with two jaws, lying diagonally.
      return flat_tool(
          symmetric_outline({{0, 0.008}, {0.01, 0.011}, {0.15, 0.011}, {0.165, 0.018}, {0.175, 0.03}, {0.19, 0.03}}, 2,
                            0.02),
          kPi / 2 - 0.45, e);
    };
    b["044"] = [](const Vec3& e) {  // Screwdriver: thick handle, thin shaft, flat tip; diagonal.
      return flat_tool(symmetric_outline({{0, 0.010},
                                          {0.01, 0.015},
                                          {0.09, 0.015},
                                          {0.10, 0.008},
                                          {0.105, 0.004},
                                          {0.20, 0.003},
                                          {0.21, 0.004},
                                          {0.22, 0.0015}}),
                       kPi / 4, e);
    };
    b["048"] = [](const Vec3& e) {  // Hammer along y: handle and a head across it.
      return flat_tool(symmetric_outline({{0, 0.013}, {0.30, 0.012}, {0.30, 0.09}, {0.333, 0.09}}), kPi / 2, e);
    };
    b["072-a"] = [](const Vec3& e) {  // Toy airplane seen from above: tailplane, fuselage, wings, nose.
      return flat_tool(symmetric_outline({{0, 0.06},
                                          {0.03, 0.06},
                                          {0.035, 0.018},
                                          {0.10, 0.02},
                                          {0.10, 0.1275},
                                          {0.16, 0.1275},
                                          {0.17, 0.022},
                                          {0.23, 0.02},
                                          {0.263, 0.008}}),
                       kPi / 2, e);
    };
    return b;
  }();
  return builders;
}

/// ASCII lowercase copy.
std::string lowercase(std::string s) {
  for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

}  // namespace

const std::vector<ProtocolObject>& protocol_objects() {
  // The last column: the object's place in the paper's presentation order (its figures' labels
  // a, b, ... ad), which is not the id order.
  static const std::vector<ProtocolObject> objects{
      {"002", "002_master_chef_can", {0.103, 0.102, 0.140}, 0.414, 11},
      {"003", "003_cracker_box", {0.072, 0.164, 0.213}, 0.411, 1},
      {"004", "004_sugar_box", {0.050, 0.094, 0.176}, 0.514, 2},
      {"005", "005_tomato_soup_can", {0.068, 0.068, 0.102}, 0.349, 3},
      {"006", "006_mustard_bottle", {0.097, 0.067, 0.191}, 0.603, 4},
      {"007", "007_tuna_fish_can", {0.086, 0.086, 0.034}, 0.171, 5},
      {"009", "009_gelatin_box", {0.089, 0.101, 0.030}, 0.097, 6},
      {"010", "010_potted_meat_can", {0.102, 0.060, 0.084}, 0.370, 7},
      {"011", "011_banana", {0.109, 0.178, 0.037}, 0.066, 8},
      {"012", "012_strawberry", {0.045, 0.045, 0.046}, 0.018, 9},
      {"013", "013_apple", {0.075, 0.075, 0.072}, 0.068, 10},
      {"014", "014_lemon", {0.061, 0.059, 0.053}, 0.029, 0},
      {"015", "015_peach", {0.062, 0.063, 0.059}, 0.033, 12},
      {"016", "016_pear", {0.067, 0.101, 0.066}, 0.049, 13},
      {"017", "017_orange", {0.072, 0.074, 0.071}, 0.047, 14},
      {"018", "018_plum", {0.057, 0.055, 0.053}, 0.025, 15},
      {"021", "021_bleach_cleanser", {0.102, 0.068, 0.251}, 1.131, 16},
      {"030", "030_fork", {0.198, 0.027, 0.016}, 0.034, 17},
      {"031", "031_spoon", {0.186, 0.083, 0.021}, 0.030, 18},
      {"032", "032_knife", {0.215, 0.021, 0.023}, 0.031, 19},
      {"033", "033_spatula", {0.306, 0.125, 0.033}, 0.052, 20},
      {"035", "035_power_drill", {0.184, 0.188, 0.057}, 0.895, 21},
      {"037", "037_scissors", {0.096, 0.202, 0.016}, 0.082, 22},
      {"040", "040_large_marker", {0.021, 0.121, 0.019}, 0.016, 23},
      {"042", "042_adjustable_wrench", {0.125, 0.181, 0.015}, 0.252, 24},
      {"044", "044_flat_screwdriver", {0.162, 0.157, 0.035}, 0.098, 25},
      {"048", "048_hammer", {0.182, 0.333, 0.033}, 0.665, 26},
      {"055", "055_baseball", {0.073, 0.074, 0.073}, 0.148, 27},
      {"056", "056_tennis_ball", {0.067, 0.067, 0.067}, 0.058, 28},
      {"072-a", "072-a_toy_airplane", {0.255, 0.263, 0.183}, 0.570, 29},
  };
  return objects;
}

std::vector<ProtocolObject> protocol_objects_in_paper_order() {
  std::vector<ProtocolObject> out = protocol_objects();
  std::sort(out.begin(), out.end(),
            [](const ProtocolObject& a, const ProtocolObject& b) { return a.paper_order < b.paper_order; });
  return out;
}

std::optional<ProtocolObject> find_protocol_object(const std::string& name_or_id) {
  std::string key = lowercase(name_or_id);
  std::replace(key.begin(), key.end(), ' ', '_');
  if (key.empty()) return std::nullopt;
  for (const ProtocolObject& object : protocol_objects()) {
    const std::string name = lowercase(object.name);
    const std::string short_name = name.substr(object.id.size() + 1);
    if (key == name || key == lowercase(object.id) || key == short_name) return object;
  }
  return std::nullopt;
}

TriangleMesh make_standin_mesh(const ProtocolObject& object) {
  const auto& builders = shape_builders();
  const auto it = builders.find(object.id);
  // An object outside the protocol table gets a box of its extent.
  TriangleMesh mesh = it != builders.end() ? it->second(object.extent) : subdivided_box(object.extent);
  return fit_to_extent(std::move(mesh), object.extent);
}

ObjectModelPtr make_standin_model(const ProtocolObject& object) {
  return make_object_model(object.name, make_standin_mesh(object), object.mass_kg, "built-in stand-in");
}

namespace {

// The real mass of the protocol object a file stem names, or 0 (from the volume) if none.
double protocol_mass_kg(const std::string& stem) {
  const auto known = find_protocol_object(stem);
  return known ? known->mass_kg : 0.0;
}

}  // namespace

ObjectModelPtr load_protocol_object_model(const std::string& path, const MeshLoadLimits& limits) {
  return load_object_model(path, protocol_mass_kg(std::filesystem::path(path).stem().string()), limits);
}

std::vector<ObjectModelPtr> load_protocol_object_dir(const std::string& dir, const MeshLoadLimits& limits) {
  return load_object_dir(dir, protocol_mass_kg, limits);
}

}  // namespace telegrasp::sim
