// Drawing a grasp snapshot as SVG with a painter's algorithm: hidden hand parts, the object's
// visible faces far to near, then the hand parts in front, then the contacts.
#include "grasp_svg.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <map>
#include <sstream>
#include <unordered_map>

namespace telegrasp::sim {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kNormalTick = 0.010;  // m: the drawn length of a contact normal
constexpr int kCapsuleSamples = 5;  // points along a capsule tested for being behind the object

std::string f1(double x) {
  char b[32];
  std::snprintf(b, sizeof b, "%.1f", x);
  return std::string(b) == "-0.0" ? "0.0" : b;
}

// `s` as SVG text content.
std::string esc(const std::string& s) {
  std::string out;
  for (char c : s) {
    if (c == '<')
      out += "&lt;";
    else if (c == '&')
      out += "&amp;";
    else
      out += c;
  }
  return out;
}

std::string hex(const Eigen::Vector3d& rgb) {
  char b[8];
  auto c = [](double v) { return static_cast<int>(std::lround(std::clamp(v, 0.0, 255.0))); };
  std::snprintf(b, sizeof b, "#%02x%02x%02x", c(rgb.x()), c(rgb.y()), c(rgb.z()));
  return b;
}

const Eigen::Vector3d kObjectRgb(196, 202, 214), kPalmRgb(236, 200, 172);

// Flat shading seen along `view`: ambient plus a light from the viewer's upper left, in 32 steps
// (so neighbouring faces of one plane share a colour and merge into one path).
Eigen::Vector3d shade(const Eigen::Vector3d& rgb, const Eigen::Vector3d& n, const View& view) {
  const Eigen::Vector3d light = (-0.35 * view.right + 0.55 * view.up + 0.76 * view.toward).normalized();
  const double lambert = std::max(0.0, n.dot(light));
  return rgb * (std::round((0.5 + 0.5 * lambert) * 32) / 32);
}

// The object's triangles as one view sees them, for the "is this point behind the object" test.
class Occluder {
 public:
  Occluder(const std::vector<Eigen::Vector3d>& world_vertices, const TriangleMesh& mesh, const View& view, double eps)
      : eps_(eps) {
    for (const auto& t : mesh.triangles) {
      Tri tri;
      for (int k = 0; k < 3; ++k) {
        const Eigen::Vector3d& p = world_vertices[t[k]];
        tri.u[k] = p.dot(view.right);
        tri.v[k] = p.dot(view.up);
        tri.d[k] = p.dot(view.toward);
      }
      tri.area = (tri.u[1] - tri.u[0]) * (tri.v[2] - tri.v[0]) - (tri.v[1] - tri.v[0]) * (tri.u[2] - tri.u[0]);
      if (std::abs(tri.area) < 1e-14) continue;
      tris_.push_back(tri);
    }
    view_ = view;
  }

  // True when the object covers `p` on the way to the viewer (by more than eps).
  bool hides(const Eigen::Vector3d& p) const {
    const double u = p.dot(view_.right), v = p.dot(view_.up), d = p.dot(view_.toward);
    for (const Tri& t : tris_) {
      if (u < std::min({t.u[0], t.u[1], t.u[2]}) || u > std::max({t.u[0], t.u[1], t.u[2]}) ||
          v < std::min({t.v[0], t.v[1], t.v[2]}) || v > std::max({t.v[0], t.v[1], t.v[2]}))
        continue;
      const double w0 = ((t.u[1] - u) * (t.v[2] - v) - (t.v[1] - v) * (t.u[2] - u)) / t.area;
      const double w1 = ((t.u[2] - u) * (t.v[0] - v) - (t.v[2] - v) * (t.u[0] - u)) / t.area;
      const double w2 = 1 - w0 - w1;
      if (w0 < 0 || w1 < 0 || w2 < 0) continue;
      if (w0 * t.d[0] + w1 * t.d[1] + w2 * t.d[2] > d + eps_) return true;
    }
    return false;
  }

 private:
  struct Tri {
    double u[3], v[3], d[3], area;
  };
  std::vector<Tri> tris_;
  View view_;
  double eps_;
};

// How far in front of a surface a point must be not to count as hidden by it: decimation moves
// the drawn surface by up to about a grid cell.
double occlusion_eps(const TriangleMesh& drawn) {
  if (drawn.vertices.empty()) return 1e-3;
  return std::max(1e-3, 0.02 * (drawn.max_corner() - drawn.min_corner()).maxCoeff());
}

// The points of a capsule tested for visibility: along its axis, on its side toward the viewer.
std::array<Eigen::Vector3d, kCapsuleSamples> capsule_samples(const GraspSnapshot::Capsule& c, const View& view) {
  std::array<Eigen::Vector3d, kCapsuleSamples> out;
  for (int i = 0; i < kCapsuleSamples; ++i) {
    const double s = static_cast<double>(i) / (kCapsuleSamples - 1);
    out[i] = c.a + s * (c.b - c.a) + c.radius * view.toward;
  }
  return out;
}

// True when a capsule covers `p` on the way to the viewer: `p` projects well inside the capsule's
// outline and the capsule's axis there is nearer the viewer. A contact seen along its finger's
// side is not covered by that finger.
bool capsule_hides(const std::vector<GraspSnapshot::Capsule>& capsules, const Eigen::Vector3d& p, const View& view) {
  const Eigen::Vector2d q(p.dot(view.right), p.dot(view.up));
  for (const auto& c : capsules) {
    const Eigen::Vector2d a(c.a.dot(view.right), c.a.dot(view.up)), b(c.b.dot(view.right), c.b.dot(view.up));
    const Eigen::Vector2d ab = b - a;
    const double s = ab.squaredNorm() > 1e-18 ? std::clamp((q - a).dot(ab) / ab.squaredNorm(), 0.0, 1.0) : 0.0;
    if ((a + s * ab - q).norm() > 0.8 * c.radius) continue;
    if ((c.a + s * (c.b - c.a)).dot(view.toward) > p.dot(view.toward) + 0.2 * c.radius) return true;
  }
  return false;
}

std::vector<Eigen::Vector3d> palm_corners(const GraspSnapshot::Palm& palm) {
  std::vector<Eigen::Vector3d> out;
  const Eigen::Vector3d& h = palm.half_extent;
  for (int k = 0; k < 8; ++k)
    out.push_back(palm.X_WorldPalm *
                  Eigen::Vector3d(k & 1 ? h.x() : -h.x(), k & 2 ? h.y() : -h.y(), k & 4 ? h.z() : -h.z()));
  return out;
}

// One hand part, drawn before the object if the object hides it, else after it.
struct Part {
  double depth = 0;  // toward the viewer: larger is nearer
  bool hidden = false;
  std::string svg, outline;  // outline: drawn over the object when hidden
};

// Maps the world to one panel of the picture: scaled to fit everything, centred.
struct Screen {
  View view;
  double scale = 1, x0 = 0, y0 = 0, u_min = 0, v_max = 0;
  Eigen::Vector2d operator()(const Eigen::Vector3d& p) const {
    return {x0 + (p.dot(view.right) - u_min) * scale, y0 + (v_max - p.dot(view.up)) * scale};
  }
};

std::string point(const Eigen::Vector2d& p) { return f1(p.x()) + " " + f1(p.y()); }

// A capsule's outline on the screen: the stadium of its two end circles.
std::string stadium_path(const Eigen::Vector2d& a, const Eigen::Vector2d& b, double r) {
  const Eigen::Vector2d d = b - a;
  if (d.norm() < 1e-6)
    return "M" + point(a + Eigen::Vector2d(r, 0)) + "A" + f1(r) + " " + f1(r) + " 0 1 0 " +
           point(a - Eigen::Vector2d(r, 0)) + "A" + f1(r) + " " + f1(r) + " 0 1 0 " + point(a + Eigen::Vector2d(r, 0)) +
           "Z";
  const Eigen::Vector2d n = Eigen::Vector2d(-d.y(), d.x()).normalized() * r;
  const std::string arc = "A" + f1(r) + " " + f1(r) + " 0 0 0 ";
  return "M" + point(a + n) + "L" + point(b + n) + arc + point(b - n) + "L" + point(a - n) + arc + point(a + n) + "Z";
}

// The picture's elements inside the panel (x, y, w, h): everything of `snap` seen along `view`.
std::string draw_view(const GraspSnapshot& snap, const DrawingMesh& object, const View& view, double x, double y,
                      double w, double h) {
  const TriangleMesh& drawn = object.mesh;
  std::vector<Eigen::Vector3d> world_vertices;
  for (const auto& v : drawn.vertices) world_vertices.push_back(snap.X_WorldObject * v);

  // Fit the object, the hand and the contacts' normal ticks into the panel, 4 % margin.
  double u_lo = std::numeric_limits<double>::infinity(), u_hi = -u_lo, v_lo = u_lo, v_hi = -u_lo;
  auto fit = [&](const Eigen::Vector3d& p, double r) {
    u_lo = std::min(u_lo, p.dot(view.right) - r);
    u_hi = std::max(u_hi, p.dot(view.right) + r);
    v_lo = std::min(v_lo, p.dot(view.up) - r);
    v_hi = std::max(v_hi, p.dot(view.up) + r);
  };
  for (const auto& p : world_vertices) fit(p, 0);
  for (const auto& c : snap.capsules) fit(c.a, c.radius), fit(c.b, c.radius);
  for (const auto& bone : snap.bones) fit(bone.a, bone.radius), fit(bone.b, bone.radius);
  if (snap.palm)
    for (const auto& p : palm_corners(*snap.palm)) fit(p, 0);
  for (const auto& c : snap.contacts) fit(c.p, 0), fit(c.p + kNormalTick * c.n, 0);
  if (!(u_hi > u_lo)) u_lo = -0.05, u_hi = 0.05, v_lo = -0.05, v_hi = 0.05;
  const double span_u = std::max(u_hi - u_lo, 1e-3), span_v = std::max(v_hi - v_lo, 1e-3);
  Screen screen;
  screen.view = view;
  screen.scale = 0.92 * std::min(w / span_u, h / span_v);
  screen.u_min = u_lo;
  screen.v_max = v_hi;
  screen.x0 = x + (w - span_u * screen.scale) / 2;
  screen.y0 = y + (h - span_v * screen.scale) / 2;

  const Occluder occluder(world_vertices, drawn, view, occlusion_eps(drawn));
  std::vector<Part> parts;

  // The palm box: its faces toward the viewer, shaded and see-through (it is context, and large);
  // hidden when most of its corners are.
  if (snap.palm) {
    const auto corners = palm_corners(*snap.palm);
    Part part;
    int hidden = 0;
    Eigen::Vector3d centre = Eigen::Vector3d::Zero();
    for (const auto& p : corners) {
      hidden += occluder.hides(p);
      centre += p / 8;
    }
    part.hidden = hidden > 4;
    part.depth = centre.dot(view.toward);
    static const int faces[6][4] = {{0, 2, 6, 4}, {1, 5, 7, 3}, {0, 4, 5, 1}, {2, 3, 7, 6}, {0, 1, 3, 2}, {4, 6, 7, 5}};
    for (const auto& f : faces) {
      const Eigen::Vector3d n = (corners[f[1]] - corners[f[0]]).cross(corners[f[3]] - corners[f[0]]).normalized();
      const Eigen::Vector3d outward = (corners[f[0]] + corners[f[2]]) / 2 - centre;
      const Eigen::Vector3d n_out = n.dot(outward) < 0 ? -n : n;
      if (n_out.dot(view.toward) <= 0) continue;
      part.svg += "<path class=\"palm\" d=\"M" + point(screen(corners[f[0]]));
      for (int k = 1; k < 4; ++k) part.svg += "L" + point(screen(corners[f[k]]));
      part.svg += "Z\" fill=\"" + hex(shade(kPalmRgb, n_out, view)) +
                  "\" fill-opacity=\"0.45\" stroke=\"#8a6a55\" stroke-opacity=\"0.6\" stroke-width=\"0.5\"/>\n";
    }
    parts.push_back(std::move(part));
  }
  // Phalanges without a capsule: light, see-through, as thick as their finger.
  for (const auto& bone : snap.bones) {
    Part part;
    part.hidden =
        occluder.hides(bone.a + bone.radius * view.toward) && occluder.hides(bone.b + bone.radius * view.toward);
    part.depth = ((bone.a + bone.b) / 2).dot(view.toward);
    const Eigen::Vector2d p = screen(bone.a), q = screen(bone.b);
    part.svg = "<line class=\"bone\" x1=\"" + f1(p.x()) + "\" y1=\"" + f1(p.y()) + "\" x2=\"" + f1(q.x()) + "\" y2=\"" +
               f1(q.y()) + "\" stroke=\"#e3b896\" stroke-opacity=\"0.6\" stroke-width=\"" +
               f1(std::max(2.0, 2 * bone.radius * screen.scale)) + "\" stroke-linecap=\"round\"/>\n";
    parts.push_back(std::move(part));
  }
  // Capsules: hidden when the object covers most of their samples.
  for (const auto& c : snap.capsules) {
    Part part;
    int hidden = 0;
    for (const auto& p : capsule_samples(c, view)) hidden += occluder.hides(p);
    part.hidden = 2 * hidden > kCapsuleSamples;
    part.depth = ((c.a + c.b) / 2).dot(view.toward);
    const std::string d = stadium_path(screen(c.a), screen(c.b), c.radius * screen.scale);
    part.svg = std::string("<path class=\"capsule") + (c.blocked ? " blocked" : "") + "\" d=\"" + d + "\" fill=\"" +
               (c.blocked ? "#b8653c" : "#f2cdb0") + "\" stroke=\"#6b3a22\" stroke-width=\"0.7\"/>\n";
    part.outline = "<path class=\"capsule-hidden\" d=\"" + d +
                   "\" fill=\"none\" stroke=\"#6b3a22\" stroke-width=\"0.9\" stroke-dasharray=\"3 2\"/>\n";
    parts.push_back(std::move(part));
  }
  std::stable_sort(parts.begin(), parts.end(), [](const Part& a, const Part& b) { return a.depth < b.depth; });

  std::ostringstream o;
  for (const Part& p : parts)
    if (p.hidden) o << p.svg;
  // The object: faces toward the viewer, far to near, flat shaded; runs of one colour in one path.
  struct Face {
    double depth;
    std::string d, fill;
  };
  std::vector<Face> faces;
  // Facing and shade come from the original surface the triangle stands for (object.normals).
  for (std::size_t i = 0; i < drawn.triangles.size(); ++i) {
    const auto& t = drawn.triangles[i];
    const Eigen::Vector3d &A = world_vertices[t[0]], &B = world_vertices[t[1]], &C = world_vertices[t[2]];
    const Eigen::Vector3d n = snap.X_WorldObject.linear() * object.normals[i];
    if (n.dot(view.toward) <= 0) continue;
    faces.push_back({(A + B + C).dot(view.toward) / 3,
                     "M" + point(screen(A)) + "L" + point(screen(B)) + "L" + point(screen(C)) + "Z",
                     hex(shade(kObjectRgb, n, view))});
  }
  std::stable_sort(faces.begin(), faces.end(), [](const Face& a, const Face& b) { return a.depth < b.depth; });
  o << "<g class=\"object\" stroke-width=\"0.4\" stroke-linejoin=\"round\">\n";
  for (std::size_t i = 0; i < faces.size();) {
    std::size_t j = i;
    o << "<path d=\"";
    for (; j < faces.size() && faces[j].fill == faces[i].fill; ++j) o << faces[j].d;
    o << "\" fill=\"" << faces[i].fill << "\" stroke=\"" << faces[i].fill << "\"/>\n";
    i = j;
  }
  o << "</g>\n";
  for (const Part& p : parts)
    if (!p.hidden) o << p.svg;
  for (const Part& p : parts)
    if (p.hidden) o << p.outline;
  // Contacts with their normal tick; hollow and dashed when behind the object.
  for (const auto& c : snap.contacts) {
    const bool hidden = occluder.hides(c.p);
    const Eigen::Vector2d p = screen(c.p), q = screen(c.p + kNormalTick * c.n);
    o << "<line class=\"normal\" x1=\"" << f1(p.x()) << "\" y1=\"" << f1(p.y()) << "\" x2=\"" << f1(q.x()) << "\" y2=\""
      << f1(q.y()) << "\" stroke=\"#d00000\" stroke-width=\"1.4\"" << (hidden ? " stroke-dasharray=\"2 1.5\"" : "")
      << "/>\n<circle class=\"contact" << (hidden ? " hidden" : "") << "\" cx=\"" << f1(p.x()) << "\" cy=\""
      << f1(p.y()) << "\" r=\"3\" fill=\"" << (hidden ? "#ffffff" : "#d00000") << "\" stroke=\""
      << (hidden ? "#d00000" : "#ffffff") << "\" stroke-width=\"" << (hidden ? "1.4" : "0.8") << "\"/>\n";
  }
  return o.str();
}

}  // namespace

void add_hand(GraspSnapshot& snap, const HandRig& rig, const Eigen::Isometry3d& X_WorldPalm,
              const std::vector<Eigen::Isometry3d>& X_WorldPhalanx, const std::vector<bool>& blocked) {
  // A phalanx without a capsule is drawn as thick as the first capsule of its finger.
  auto finger_radius = [&](int finger) {
    for (PhalanxId id : rig.capsule_phalanges())
      if (rig.phalanges()[id.value].finger == finger) return rig.phalanges()[id.value].capsule->radius;
    return 0.008;
  };
  for (std::size_t i = 0; i < rig.phalanges().size() && i < X_WorldPhalanx.size(); ++i) {
    const PhalanxSpec& spec = rig.phalanges()[i];
    const Eigen::Isometry3d& X = X_WorldPhalanx[i];
    if (spec.capsule)
      snap.capsules.push_back({X * spec.capsule->p_PhalanxA, X * spec.capsule->p_PhalanxB, spec.capsule->radius,
                               i < blocked.size() && blocked[i]});
    else
      snap.bones.push_back({X.translation(), X * Eigen::Vector3d(spec.length, 0, 0), finger_radius(spec.finger)});
  }
  snap.palm = GraspSnapshot::Palm{X_WorldPalm, rig.palm_half_extent()};
}

GraspSnapshot snapshot(const HandController& hand, const ObjectView& object, const std::string& title) {
  GraspSnapshot snap;
  snap.title = title;
  snap.model = object.model;
  snap.X_WorldObject = hand.grasped_object_pose().value_or(object.X_WorldObject);
  const HandState& s = hand.state();
  std::vector<Eigen::Isometry3d> X_WorldPhalanx;
  std::vector<bool> blocked;
  for (std::size_t i = 0; i < s.X_PalmPhalanx.size(); ++i) {
    X_WorldPhalanx.push_back(s.X_WorldPalm * s.X_PalmPhalanx[i]);
    blocked.push_back(i < s.blocked.size() && s.blocked[i] != 0);
  }
  add_hand(snap, hand.rig(), s.X_WorldPalm, X_WorldPhalanx, blocked);
  for (const Contact& c : hand.contacts()) snap.contacts.push_back({c.p_WorldContact, c.n_World});
  return snap;
}

View orbit_view(double azimuth_deg, double elevation_deg) {
  const double az = azimuth_deg * kPi / 180, el = elevation_deg * kPi / 180;
  View v;
  char name[64];
  std::snprintf(name, sizeof name, "azimuth %.0f\u00b0, elevation %.0f\u00b0", azimuth_deg, elevation_deg);
  v.name = name;
  v.toward = Eigen::Vector3d(std::cos(az) * std::cos(el), std::sin(az) * std::cos(el), std::sin(el));
  v.right = Eigen::Vector3d::UnitZ().cross(v.toward).normalized();
  v.up = v.toward.cross(v.right);
  return v;
}

View readable_view(const GraspSnapshot& snap) {
  const TriangleMesh drawn =
      snap.model ? decimate_for_drawing(snap.model->mesh, PictureOptions{}.max_triangles).mesh : TriangleMesh{};
  std::vector<Eigen::Vector3d> world_vertices;
  for (const auto& v : drawn.vertices) world_vertices.push_back(snap.X_WorldObject * v);
  View best;
  int best_score = -1;
  for (int az = 0; az < 360; az += 45)
    for (const double el : {20.0, 50.0}) {
      const View view = orbit_view(az, el);
      const Occluder occluder(world_vertices, drawn, view, occlusion_eps(drawn));
      int score = 0;
      for (const auto& c : snap.capsules)
        for (const auto& p : capsule_samples(c, view)) score += !occluder.hides(p);
      for (const auto& c : snap.contacts)
        score += 4 * !(occluder.hides(c.p) || capsule_hides(snap.capsules, c.p, view));
      if (score > best_score) best_score = score, best = view;
    }
  return best;
}

DrawingMesh decimate_for_drawing(const TriangleMesh& mesh, int max_triangles) {
  // Each original triangle's area-weighted normal (its cross product), summed into the drawn
  // triangle it becomes: a clustered triangle can fold over, its source cannot.
  auto cross = [&](const std::array<std::uint32_t, 3>& t) {
    return Eigen::Vector3d(
        (mesh.vertices[t[1]] - mesh.vertices[t[0]]).cross(mesh.vertices[t[2]] - mesh.vertices[t[0]]));
  };
  auto finish = [](DrawingMesh& out) {
    for (Eigen::Vector3d& n : out.normals) n = n.norm() > 0 ? Eigen::Vector3d(n.normalized()) : Eigen::Vector3d::Zero();
  };
  DrawingMesh out;
  if (static_cast<int>(mesh.triangles.size()) <= max_triangles || mesh.vertices.empty()) {
    out.mesh = mesh;
    for (const auto& t : mesh.triangles) out.normals.push_back(cross(t));
    finish(out);
    return out;
  }
  const Eigen::Vector3d lo = mesh.min_corner();
  const double extent = std::max((mesh.max_corner() - lo).maxCoeff(), 1e-9);
  for (double cells = 128; cells >= 2; cells *= 0.8) {
    const double size = extent / cells;
    const std::int64_t n = static_cast<std::int64_t>(cells) + 2;
    std::unordered_map<std::int64_t, std::uint32_t> cluster_of_cell;
    std::vector<std::uint32_t> cluster(mesh.vertices.size());
    std::vector<Eigen::Vector3d> sum;
    std::vector<int> count;
    for (std::size_t i = 0; i < mesh.vertices.size(); ++i) {
      const Eigen::Vector3d c = ((mesh.vertices[i] - lo) / size).array().floor();
      const std::int64_t key = (static_cast<std::int64_t>(c.x()) * n + static_cast<std::int64_t>(c.y())) * n +
                               static_cast<std::int64_t>(c.z());
      const auto [it, added] = cluster_of_cell.emplace(key, static_cast<std::uint32_t>(sum.size()));
      if (added) sum.emplace_back(Eigen::Vector3d::Zero()), count.push_back(0);
      cluster[i] = it->second;
      sum[it->second] += mesh.vertices[i];
      ++count[it->second];
    }
    out = {};
    for (std::size_t k = 0; k < sum.size(); ++k) out.mesh.vertices.push_back(sum[k] / count[k]);
    // A triangle and its reverse both stay (the two sides of a collapsed sheet); repeats merge.
    std::map<std::array<std::uint32_t, 3>, std::size_t> index_of;
    for (const auto& t : mesh.triangles) {
      std::array<std::uint32_t, 3> c = {cluster[t[0]], cluster[t[1]], cluster[t[2]]};
      if (c[0] == c[1] || c[1] == c[2] || c[0] == c[2]) continue;
      std::rotate(c.begin(), std::min_element(c.begin(), c.end()), c.end());
      const auto [it, added] = index_of.emplace(c, out.mesh.triangles.size());
      if (added) {
        out.mesh.triangles.push_back(c);
        out.normals.emplace_back(Eigen::Vector3d::Zero());
      }
      out.normals[it->second] += cross(t);
    }
    if (static_cast<int>(out.mesh.triangles.size()) <= max_triangles) break;
  }
  finish(out);
  return out;
}

std::string render_view_svg(const GraspSnapshot& snap, const View& view, const PictureOptions& options) {
  const DrawingMesh drawn = snap.model ? decimate_for_drawing(snap.model->mesh, options.max_triangles) : DrawingMesh{};
  std::ostringstream svg;
  // No xmlns: inline SVG in HTML needs none, and the page names no URL at all.
  svg << "<svg class=\"grasp\" viewBox=\"0 0 " << f1(options.width_px) << " " << f1(options.height_px) << "\" width=\""
      << f1(options.width_px) << "\" height=\"" << f1(options.height_px) << "\" role=\"img\"><title>"
      << esc(snap.title + " (" + view.name + ")")
      << "</title>\n<rect width=\"100%\" height=\"100%\" fill=\"#fbfbfb\"/>\n"
      << draw_view(snap, drawn, view, 0, 0, options.width_px, options.height_px) << "</svg>\n";
  return svg.str();
}

std::string render_svg(const GraspSnapshot& snap) {
  constexpr double kViewPx = 300;
  const View views[] = {
      {"top (x right, y up)", Eigen::Vector3d::UnitX(), Eigen::Vector3d::UnitY(), Eigen::Vector3d::UnitZ()},
      {"front (x right, z up)", Eigen::Vector3d::UnitX(), Eigen::Vector3d::UnitZ(), -Eigen::Vector3d::UnitY()},
      {"side (y right, z up)", Eigen::Vector3d::UnitY(), Eigen::Vector3d::UnitZ(), Eigen::Vector3d::UnitX()}};
  const DrawingMesh drawn =
      snap.model ? decimate_for_drawing(snap.model->mesh, PictureOptions{}.max_triangles) : DrawingMesh{};
  std::ostringstream svg;
  const double width = 3 * kViewPx + 40, height = kViewPx + 84;
  svg << "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" << width << "\" height=\"" << height
      << "\" font-family=\"sans-serif\" font-size=\"12\">\n<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n"
      << "<text x=\"10\" y=\"18\" font-size=\"14\">" << esc(snap.title) << "</text>\n";
  for (int vi = 0; vi < 3; ++vi) {
    const double ox = 10 + vi * (kViewPx + 10), oy = 40;
    svg << "<g>\n<rect x=\"" << ox << "\" y=\"" << oy << "\" width=\"" << kViewPx << "\" height=\"" << kViewPx
        << "\" fill=\"#f7f7f7\" stroke=\"#ccc\"/>\n<text x=\"" << ox << "\" y=\"" << oy + kViewPx + 16 << "\">"
        << views[vi].name << "</text>\n"
        << draw_view(snap, drawn, views[vi], ox, oy, kViewPx, kViewPx) << "</g>\n";
  }
  svg << "<text x=\"10\" y=\"" << height - 8
      << "\" fill=\"#555\">capsules: light = free, dark = blocked, dashed = behind the object; red = contacts and "
         "their "
         "normals (hollow = behind); grey = object</text>\n</svg>\n";
  return svg.str();
}

}  // namespace telegrasp::sim
