// Shape classes from an oriented bounding box about the principal axes and how much of it the
// solid fills.
#include "telegrasp/sim/object_shape.h"

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numbers>

namespace telegrasp::sim {

const char* shape_class_name(ShapeClass shape) {
  switch (shape) {
    case ShapeClass::kSphere: return "sphere";
    case ShapeClass::kCylinder: return "cylinder";
    case ShapeClass::kBox: return "box";
    case ShapeClass::kThin: return "thin";
    case ShapeClass::kOther: break;
  }
  return "other";
}

std::optional<ShapeClass> parse_shape_class(std::string_view name) {
  for (ShapeClass s : {ShapeClass::kSphere, ShapeClass::kCylinder, ShapeClass::kBox, ShapeClass::kThin, ShapeClass::kOther})
    if (name == shape_class_name(s)) return s;
  return std::nullopt;
}

namespace {

// The box with axes R's columns holding every vertex: its centre (object frame) and half extents.
void box_along(const TriangleMesh& mesh, const Eigen::Matrix3d& R, Eigen::Vector3d& centre, Eigen::Vector3d& half) {
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
  for (const Eigen::Vector3d& v : mesh.vertices) {
    const Eigen::Vector3d p = R.transpose() * v;
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  centre = R * (0.5 * (lo + hi));
  half = 0.5 * (hi - lo);
}

}  // namespace

ObjectShape classify_shape(const TriangleMesh& mesh, const MassProperties& mass, const ShapeRules& rules) {
  ObjectShape out;
  if (mesh.vertices.empty()) return out;
  // Principal axes: of the solid's inertia, or of the vertices' spread for an open mesh.
  Eigen::Matrix3d spread = mass.inertia_per_density;
  if (!(mass.volume > 0) || !spread.allFinite()) {
    Eigen::Vector3d mean = Eigen::Vector3d::Zero();
    for (const Eigen::Vector3d& v : mesh.vertices) mean += v;
    mean /= static_cast<double>(mesh.vertices.size());
    spread.setZero();
    for (const Eigen::Vector3d& v : mesh.vertices) spread += (v - mean) * (v - mean).transpose();
  }
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen(spread);
  Eigen::Matrix3d axes = eigen.eigenvectors();
  if (axes.determinant() < 0) axes.col(2) = -axes.col(2);

  double best_volume = std::numeric_limits<double>::infinity();
  Eigen::Matrix3d best_R = axes;
  Eigen::Vector3d best_centre = Eigen::Vector3d::Zero(), best_half = Eigen::Vector3d::Zero();
  constexpr int kSteps = 45;  // 2 degrees over a quarter turn
  for (int k = 0; k < 3; ++k) {
    for (int s = 0; s < kSteps; ++s) {
      const double angle = (std::numbers::pi / 2) * s / kSteps;
      const Eigen::Matrix3d R = Eigen::AngleAxisd(angle, axes.col(k)).toRotationMatrix() * axes;
      Eigen::Vector3d centre, half;
      box_along(mesh, R, centre, half);
      const double volume = half.prod();
      if (volume < best_volume * (1 - 1e-9)) {
        best_volume = volume;
        best_R = R;
        best_centre = centre;
        best_half = half;
      }
    }
  }
  // Sides ascending, axes with them, kept right-handed.
  std::array<int, 3> order{0, 1, 2};
  std::sort(order.begin(), order.end(), [&](int a, int b) { return best_half[a] < best_half[b]; });
  Eigen::Matrix3d R;
  for (int i = 0; i < 3; ++i) {
    R.col(i) = best_R.col(order[i]);
    out.half_extent[i] = best_half[order[i]];
  }
  if (R.determinant() < 0) R.col(0) = -R.col(0);
  out.X_ObjectBox.linear() = R;
  out.X_ObjectBox.translation() = best_centre;
  if (!(mass.volume > 0)) return out;  // open: no fill, no thickness
  const double box_volume = 8 * out.half_extent.prod();
  out.fill = box_volume > 0 ? mass.volume / box_volume : 0.0;
  double area = 0;
  for (const auto& t : mesh.triangles)
    area += 0.5 * (mesh.vertices[t[1]] - mesh.vertices[t[0]]).cross(mesh.vertices[t[2]] - mesh.vertices[t[0]]).norm();
  out.thickness = area > 0 ? 2 * mass.volume / area : 0.0;

  const Eigen::Vector3d& h = out.half_extent;
  const auto within = [](double v, double lo, double hi) { return v >= lo && v <= hi; };
  const bool round01 = h[0] >= rules.round_ratio * h[1], round12 = h[1] >= rules.round_ratio * h[2];
  if (round01 && round12 && within(out.fill, rules.sphere_fill_min, rules.sphere_fill_max)) {
    out.shape = ShapeClass::kSphere;
  } else if ((round01 || round12) && within(out.fill, rules.cylinder_fill_min, rules.cylinder_fill_max)) {
    out.shape = ShapeClass::kCylinder;
    // The round cross-section is across the two similar sides; with all three similar, the pair
    // nearer equal.
    out.axis = round01 && (!round12 || h[0] / h[1] >= h[1] / h[2]) ? 2 : 0;
  } else if (out.fill >= rules.box_fill_min) {
    out.shape = ShapeClass::kBox;
  } else if (out.thickness <= rules.thin_thickness) {
    out.shape = ShapeClass::kThin;
  }
  return out;
}

}  // namespace telegrasp::sim
