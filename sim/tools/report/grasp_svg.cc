// Rendering a grasp snapshot to SVG: the object as depth-shaded raster runs, capsules on top.
#include "grasp_svg.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <sstream>

namespace telegrasp::sim {
namespace {

constexpr int kCells = 180;      // raster cells across the larger side of a view
constexpr double kViewPx = 300;  // view size in pixels
constexpr double kMargin = 0.02; // metres around the scene

struct View {
  const char* name;
  int u, v;       // world axes shown left-right and bottom-up
  int depth;      // world axis toward the viewer
};

std::string fmt(double x) {
  char b[32];
  std::snprintf(b, sizeof b, "%.1f", x);
  return b;
}

}  // namespace

GraspSnapshot snapshot(const HandController& hand, const ObjectView& object, const std::string& title) {
  GraspSnapshot snap;
  snap.title = title;
  snap.model = object.model;
  snap.X_WorldObject = hand.grasped_object_pose().value_or(object.X_WorldObject);
  const HandState& s = hand.state();
  for (PhalanxId id : hand.rig().capsule_phalanges()) {
    const CapsuleSpec& c = *hand.rig().phalanges()[id.value].capsule;
    const Eigen::Isometry3d X = s.X_WorldPalm * s.X_PalmPhalanx[id.value];
    snap.capsules.push_back({X * c.p_PhalanxA, X * c.p_PhalanxB, c.radius, s.blocked[id.value] != 0});
  }
  for (const Contact& c : hand.contacts()) snap.contacts.push_back(c.p_WorldContact);
  return snap;
}

std::string render_svg(const GraspSnapshot& snap) {
  const View views[] = {{"top (x right, y up)", 0, 1, 2}, {"front (x right, z up)", 0, 2, 1}, {"side (y right, z up)", 1, 2, 0}};
  // Scene bounds: object vertices and capsule ends.
  std::vector<Eigen::Vector3d> world_vertices;
  for (const auto& v : snap.model->mesh.vertices) world_vertices.push_back(snap.X_WorldObject * v);
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
  for (const auto& p : world_vertices) { lo = lo.cwiseMin(p); hi = hi.cwiseMax(p); }
  for (const auto& c : snap.capsules)
    for (const auto& p : {c.a, c.b}) {
      lo = lo.cwiseMin(p - Eigen::Vector3d::Constant(c.radius));
      hi = hi.cwiseMax(p + Eigen::Vector3d::Constant(c.radius));
    }
  lo -= Eigen::Vector3d::Constant(kMargin);
  hi += Eigen::Vector3d::Constant(kMargin);

  std::ostringstream svg;
  const double width = 3 * kViewPx + 40, height = kViewPx + 70;
  svg << "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" << width << "\" height=\"" << height
      << "\" font-family=\"sans-serif\" font-size=\"12\">\n<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n"
      << "<text x=\"10\" y=\"18\" font-size=\"14\">" << snap.title << "</text>\n";
  for (int vi = 0; vi < 3; ++vi) {
    const View& view = views[vi];
    const double span = std::max(hi[view.u] - lo[view.u], hi[view.v] - lo[view.v]);
    const double cell = span / kCells;
    const double scale = kViewPx / span;  // px per metre
    const double ox = 10 + vi * (kViewPx + 10), oy = 40;
    auto px = [&](const Eigen::Vector3d& p) {
      return Eigen::Vector2d(ox + (p[view.u] - lo[view.u]) * scale, oy + kViewPx - (p[view.v] - lo[view.v]) * scale);
    };
    svg << "<g>\n<rect x=\"" << ox << "\" y=\"" << oy << "\" width=\"" << kViewPx << "\" height=\"" << kViewPx
        << "\" fill=\"#f7f7f7\" stroke=\"#ccc\"/>\n<text x=\"" << ox << "\" y=\"" << oy + kViewPx + 16 << "\">" << view.name << "</text>\n";
    // Rasterize the object: nearest depth per cell, shaded in four bands.
    std::vector<double> depth(kCells * kCells, -std::numeric_limits<double>::infinity());
    for (const auto& t : snap.model->mesh.triangles) {
      const Eigen::Vector3d& A = world_vertices[t[0]];
      const Eigen::Vector3d& B = world_vertices[t[1]];
      const Eigen::Vector3d& C = world_vertices[t[2]];
      auto uv = [&](const Eigen::Vector3d& p) { return Eigen::Vector2d((p[view.u] - lo[view.u]) / cell, (p[view.v] - lo[view.v]) / cell); };
      const Eigen::Vector2d a = uv(A), b = uv(B), c = uv(C);
      const double area = (b - a).x() * (c - a).y() - (b - a).y() * (c - a).x();
      if (std::abs(area) < 1e-12) continue;
      const int x0 = std::max(0, static_cast<int>(std::floor(std::min({a.x(), b.x(), c.x()}))));
      const int x1 = std::min(kCells - 1, static_cast<int>(std::ceil(std::max({a.x(), b.x(), c.x()}))));
      const int y0 = std::max(0, static_cast<int>(std::floor(std::min({a.y(), b.y(), c.y()}))));
      const int y1 = std::min(kCells - 1, static_cast<int>(std::ceil(std::max({a.y(), b.y(), c.y()}))));
      for (int y = y0; y <= y1; ++y)
        for (int x = x0; x <= x1; ++x) {
          const Eigen::Vector2d p(x + 0.5, y + 0.5);
          const double w0 = ((b - p).x() * (c - p).y() - (b - p).y() * (c - p).x()) / area;
          const double w1 = ((c - p).x() * (a - p).y() - (c - p).y() * (a - p).x()) / area;
          const double w2 = 1 - w0 - w1;
          if (w0 < 0 || w1 < 0 || w2 < 0) continue;
          const double d = w0 * A[view.depth] + w1 * B[view.depth] + w2 * C[view.depth];
          double& cellv = depth[y * kCells + x];
          cellv = std::max(cellv, d);
        }
    }
    const double dlo = lo[view.depth], dhi = hi[view.depth];
    auto shade = [&](double d) { return std::isinf(d) ? -1 : std::clamp(static_cast<int>(4 * (d - dlo) / (dhi - dlo)), 0, 3); };
    const char* greys[] = {"#8a8a8a", "#a2a2a2", "#bababa", "#d2d2d2"};
    for (int y = 0; y < kCells; ++y) {
      for (int x = 0; x < kCells;) {
        const int s = shade(depth[y * kCells + x]);
        int end = x + 1;
        while (end < kCells && shade(depth[y * kCells + end]) == s) ++end;
        if (s >= 0)
          svg << "<rect x=\"" << fmt(ox + x * cell * scale) << "\" y=\"" << fmt(oy + kViewPx - (y + 1) * cell * scale)
              << "\" width=\"" << fmt((end - x) * cell * scale + 0.3) << "\" height=\"" << fmt(cell * scale + 0.3)
              << "\" fill=\"" << greys[s] << "\"/>\n";
        x = end;
      }
    }
    // Capsules (blocked ones darker), then contacts.
    for (const auto& c : snap.capsules) {
      const Eigen::Vector2d a = px(c.a), b = px(c.b);
      svg << "<line x1=\"" << fmt(a.x()) << "\" y1=\"" << fmt(a.y()) << "\" x2=\"" << fmt(b.x()) << "\" y2=\"" << fmt(b.y())
          << "\" stroke=\"" << (c.blocked ? "#c0714f" : "#e8b89a") << "\" stroke-opacity=\"0.75\" stroke-linecap=\"round\" stroke-width=\""
          << fmt(2 * c.radius * scale) << "\"/>\n";
    }
    for (const auto& p : snap.contacts) {
      const Eigen::Vector2d q = px(p);
      svg << "<circle cx=\"" << fmt(q.x()) << "\" cy=\"" << fmt(q.y()) << "\" r=\"3\" fill=\"#d00\"/>\n";
    }
    svg << "</g>\n";
  }
  svg << "<text x=\"10\" y=\"" << height - 8 << "\" fill=\"#555\">capsules: light = free, dark = blocked; red = contacts; grey = object, lighter = nearer</text>\n</svg>\n";
  return svg.str();
}

}  // namespace telegrasp::sim
