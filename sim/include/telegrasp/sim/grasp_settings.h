// GraspSettings: the tunables of the grasp system (closing mode, selection, tolerance, speed,
// the resolved pose), the same for every hand of a World.
#pragma once

#include "telegrasp/sim/grasp_quality.h"

#include <optional>
#include <string_view>

namespace telegrasp::sim {

/// How a closing finger finds the surface.
enum class ClosingMode {
  kPrecise,  ///< Conservative advancement within each step: contact within the tolerance, no tunnelling.
  kDiscrete,  ///< The paper's: move a whole step, then test overlap (may sink by up to one step).
};

/// The mode named "precise" or "discrete" (as configuration files, flags and records write it);
/// nothing for any other name.
std::optional<ClosingMode> parse_closing_mode(std::string_view name);
/// The name parse_closing_mode reads: "precise" or "discrete".
const char* closing_mode_name(ClosingMode mode);

/// How "nearest object" is measured for object selection.
enum class SelectionMetric {
  kSurface,  ///< Distance from the selection sphere's centre to the object's surface (default).
  kOrigin,  ///< Distance to the object's origin (centre of mass), as in the paper.
};

/// Tunables of the grasp system (not of the hand: those live in the HandRig).
struct GraspSettings {
  ClosingMode mode = ClosingMode::kPrecise;
  SelectionMetric selection = SelectionMetric::kSurface;
  double contact_tolerance = 0.05e-3;  ///< Precise mode: a blocked capsule's gap lies in [0, this] (m).
  double speed_scale = 1.0;  ///< Multiplies every joint's max speed.
  /// Keep the resolved pose (HandState::X_WorldPalm) outside every object and the table while the
  /// tracked pose goes through them (pose_resolver.h); false: the resolved pose is the tracked one.
  bool resolve_pose = true;
  double table_half_extent = 0;  ///< > 0: the table top z = 0 over [-this, this]^2 is an obstacle (m).
  double rejoin_speed = 1.0;  ///< The resolved pose closes its offset to the tracked one at most this fast (m/s).
  double rejoin_turn = 6.283185307179586;  ///< ... and its turn at most this fast (rad/s).
  /// A hand holding nothing whose resolved pose is more than this (m) from the tracked one, caught
  /// behind an object, jumps to the tracked pose when every volume is clear there; 0: never.
  double snap_distance = 0.2;
  /// Whether grasp qualities include the wrench hull's volume (the full Qhull hull: milliseconds
  /// per contact set); kSkip: GraspQuality::volume is kVolumeNotComputed.
  QualityVolume quality_volume = QualityVolume::kSkip;
};

}  // namespace telegrasp::sim
