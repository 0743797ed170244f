// Grasp types from shape classes.
#include "telegrasp/sim/grasp_type.h"

#include <algorithm>
#include <array>
#include <cmath>

namespace telegrasp::sim {
namespace {

constexpr double kCos45 = 0.7071067811865476;

constexpr std::array<const char*, kGraspTypeCount> kNames = {
    "other", "power_sphere", "tripod", "small_wrap", "medium_wrap", "large_wrap", "disk", "prismatic", "lateral_pinch"};

}  // namespace

const char* grasp_type_name(GraspType type) {
  const auto i = static_cast<std::size_t>(type);
  return i < kNames.size() ? kNames[i] : "other";
}

std::optional<GraspType> parse_grasp_type(std::string_view name) {
  for (std::size_t i = 0; i < kNames.size(); ++i)
    if (name == kNames[i]) return static_cast<GraspType>(i);
  return std::nullopt;
}

double box_width_along(const ObjectShape& shape, const Eigen::Vector3d& d_Object) {
  const Eigen::Matrix3d& R = shape.X_ObjectBox.linear();
  double w = 0;
  for (int i = 0; i < 3; ++i) w += shape.half_extent[i] * std::abs(R.col(i).dot(d_Object));
  return 2 * w;
}

bool closes_across_shortest_side(const ObjectShape& shape, const Eigen::Isometry3d& X_ObjectPalm,
                                 const ShapeRules& rules, const std::optional<Eigen::Vector3d>& up_Object) {
  const Eigen::Matrix3d& R = shape.X_ObjectBox.linear();
  const Eigen::Vector3d& h = shape.half_extent;  // ascending
  // A side within 45 degrees of the table's normal cannot be closed across while the object lies
  // there (the thumb would go under it): with a table, the shortest side is the shortest of the rest.
  int shortest = 0;
  while (up_Object && shortest < 2 && std::abs(R.col(shortest).dot(*up_Object)) >= kCos45) ++shortest;
  // The shortest side and the sides as long as it (within the rules' round ratio: a ball's three,
  // a can's two across its axis) span where closing counts as across the smallest dimension.
  const Eigen::Vector3d across = X_ObjectPalm.linear().col(0);
  double in_span_sq = 0;
  for (int i = 0; i < 3; ++i) {
    const bool tied = std::min(h[i], h[shortest]) >= rules.round_ratio * std::max(h[i], h[shortest]);
    if (tied) in_span_sq += R.col(i).dot(across) * R.col(i).dot(across);
  }
  return in_span_sq >= 0.5;
}

GraspType choose_grasp_type(const ObjectShape& shape, const Eigen::Isometry3d& X_ObjectPalm,
                            const GraspTypeRules& rules) {
  const Eigen::Vector3d across = X_ObjectPalm.linear().col(0);  // palm +x, the thumb-to-fingers line
  switch (shape.shape) {
    case ShapeClass::kSphere:
      return box_width_along(shape, across) <= rules.tripod_max_width ? GraspType::kTripod : GraspType::kPowerSphere;
    case ShapeClass::kCylinder: {
      if (shape.axis < 0) return GraspType::kOther;
      const Eigen::Vector3d axis = shape.X_ObjectBox.linear().col(shape.axis);
      if (std::abs(axis.dot(X_ObjectPalm.linear().col(2))) >= rules.disk_min_cos) return GraspType::kDisk;
      const double diameter = 2 * shape.half_extent[shape.axis == 0 ? 2 : 0];
      if (diameter <= rules.small_wrap_max_width) return GraspType::kSmallWrap;
      return diameter <= rules.medium_wrap_max_width ? GraspType::kMediumWrap : GraspType::kLargeWrap;
    }
    case ShapeClass::kBox:
      return GraspType::kPrismatic;
    case ShapeClass::kThin:
      // Across its thickness: between the thumb's pad and the index finger's side. Across its
      // width, as a thin object lying flat on a table must be closed: a flat box between the
      // thumb and four fingers.
      return std::abs(shape.X_ObjectBox.linear().col(0).dot(across)) >= rules.pinch_min_cos ? GraspType::kLateralPinch
                                                                                              : GraspType::kPrismatic;
    case ShapeClass::kOther:
      break;
  }
  return GraspType::kOther;
}

}  // namespace telegrasp::sim
