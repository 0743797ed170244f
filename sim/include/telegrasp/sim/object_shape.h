// ObjectShape: what kind of solid an object is (sphere, cylinder, box, thin, other), from its
// mesh alone, for choosing how a hand closes on it.
#pragma once

#include "telegrasp/sim/mass_properties.h"
#include "telegrasp/sim/triangle_mesh.h"

#include <Eigen/Geometry>

#include <optional>
#include <string_view>

namespace telegrasp::sim {

enum class ShapeClass { kSphere, kCylinder, kBox, kThin, kOther };

/// "sphere", "cylinder", "box", "thin" or "other" (as configuration files write it).
const char* shape_class_name(ShapeClass shape);
/// The class named `name` (shape_class_name's); nothing for any other name.
std::optional<ShapeClass> parse_shape_class(std::string_view name);

/// An object's oriented bounding box and the class read from it.
struct ObjectShape {
  ShapeClass shape = ShapeClass::kOther;
  /// The box's frame in the object frame: its x, y, z axes along the box's shortest, middle
  /// and longest sides (right-handed), its origin at the box's centre.
  Eigen::Isometry3d X_ObjectBox = Eigen::Isometry3d::Identity();
  Eigen::Vector3d half_extent{0, 0, 0};  ///< Ascending: x <= y <= z, m.
  double fill = 0;  ///< The solid's volume over the box's (1 box, pi/4 cylinder, pi/6 sphere).
  double thickness = 0;  ///< Mean thickness 2 V / A (volume over surface area), m.
  int axis = -1;  ///< kCylinder: the box axis (0 a disk, 2 a rod) along the cylinder's axis; else -1.
};

/// Thresholds of classify_shape(), in metres and ratios.
struct ShapeRules {
  double round_ratio = 0.88;  ///< Two sides this close (shorter / longer) make a round cross-section.
  double sphere_fill_min = 0.42, sphere_fill_max = 0.62;  ///< Around pi/6 = 0.524.
  double cylinder_fill_min = 0.66, cylinder_fill_max = 0.84;  ///< Around pi/4 = 0.785 (scanned cans: 0.69-0.72).
  double box_fill_min = 0.82;  ///< Scanned boxes with rounded edges: 0.86-0.89.
  /// Thin: mean thickness 2 V / A at most this (a plate's thickness; a long rod's radius), m.
  /// YCB flatware and tools 3.2-5.6 mm, the banana 15.8, the hammer 12.6.
  double thin_thickness = 0.008;
};

/// The smallest box about the solid's principal axes of inertia (each axis in turn kept, the box
/// turned about it in 2-degree steps), and the class its sides, fill and thickness say, in this
/// order: a sphere (all sides within round_ratio, sphere fill); a cylinder (two sides within
/// round_ratio, cylinder fill; its axis the third); a box (box fill); thin; else other. `mass` is
/// the mesh's (compute_mass_properties); an open mesh (volume <= 0) is other.
ObjectShape classify_shape(const TriangleMesh& mesh, const MassProperties& mass, const ShapeRules& rules = {});

}  // namespace telegrasp::sim
