// GraspType: how a hand closes on an object, chosen from the object's shape class and its width
// across the hand, after Miller et al., "Automatic Grasp Planning Using Shape Primitives" (ICRA
// 2003) and the grasp taxonomy of Feix et al. (2016).
#pragma once

#include "telegrasp/sim/object_shape.h"

#include <Eigen/Geometry>

#include <optional>
#include <string_view>

namespace telegrasp::sim {

enum class GraspType {
  kOther,  ///< The rig's own closing (its joints' open and closed angles, its grasp rule).
  kPowerSphere,  ///< A ball in the whole hand.
  kTripod,  ///< A small ball between thumb, index and middle finger.
  kSmallWrap,  ///< A thin cylinder (a handle) in the fist, the thumb over the fingers.
  kMediumWrap,  ///< A cylinder (a can) in the hand.
  kLargeWrap,  ///< A wide cylinder, fingers and thumb spread around it.
  kDisk,  ///< A cylinder from its end, fingers around the rim.
  kPrismatic,  ///< A box between the thumb and four fingers.
  kLateralPinch,  ///< A thin object between the thumb and the side of the index finger.
};
inline constexpr int kGraspTypeCount = 9;

/// "other", "power_sphere", "tripod", "small_wrap", "medium_wrap", "large_wrap", "disk",
/// "prismatic", "lateral_pinch" (as rig files and records write it).
const char* grasp_type_name(GraspType type);
/// The type named `name` (grasp_type_name's); nothing for any other name.
std::optional<GraspType> parse_grasp_type(std::string_view name);

/// Thresholds of choose_grasp_type(), m.
struct GraspTypeRules {
  double tripod_max_width = 0.05;  ///< Balls up to this across the hand: tripod, larger: power sphere.
  double small_wrap_max_width = 0.03;  ///< Cylinders up to this across: small wrap ...
  double medium_wrap_max_width = 0.07;  ///< ... up to this: medium (Feix: 96 % of grasps under 7 cm), larger: large.
  double disk_min_cos = 0.7071067811865476;  ///< A cylinder whose axis is within 45 degrees of the palm normal: disk.
  double pinch_min_cos = 0.7071067811865476;  ///< A thin object closed within 45 degrees of across its thickness: lateral pinch.
};

/// Width of `shape`'s box along the unit direction `d` (object frame): 2 sum_i h_i |b_i . d|.
double box_width_along(const ObjectShape& shape, const Eigen::Vector3d& d_Object);

/// Whether a hand at X_ObjectPalm closes across the object's smallest dimension: its +x (from the
/// thumb to the fingers) within 45 degrees of the span of the shortest side of `shape`'s box and
/// of every side as short (shorter / longer >= rules.round_ratio, as a round cross-section): a
/// ball is closed across whatever the direction, a can across any line square to its axis.
/// With `up_Object` (the table's normal in the object frame, the object lying on it) the smallest
/// dimension is the smallest a hand can close across there: a side within 45 degrees of the
/// normal does not count unless it is as long as that one (a knife lying flat is closed across
/// its width, not its upright thickness; a ball still from any direction).
bool closes_across_shortest_side(const ObjectShape& shape, const Eigen::Isometry3d& X_ObjectPalm,
                                 const ShapeRules& rules = {},
                                 const std::optional<Eigen::Vector3d>& up_Object = std::nullopt);

/// The grasp type for a hand at X_ObjectPalm (palm frame: +x to the fingers, -z the palm normal)
/// about to close on an object of `shape`: sphere -> tripod or power sphere by its width across
/// the palm (along palm x); cylinder -> disk when its axis is near the palm normal, else a small,
/// medium or large wrap by its diameter; box -> prismatic; thin -> lateral pinch when the palm's
/// +x is near its thickness, else prismatic (a knife lying flat, closed across its width); other ->
/// kOther. Constant time.
GraspType choose_grasp_type(const ObjectShape& shape, const Eigen::Isometry3d& X_ObjectPalm,
                            const GraspTypeRules& rules = {});

}  // namespace telegrasp::sim
