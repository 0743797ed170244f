// The controller input a headset page sends to telegrasp-view --drive (channel /controller_state,
// schema telegrasp.ControllerInput, JSON; the contract is in README.md, "Driving hands"): parsing
// with an error that names the field, and the grip-to-palm offset that turns a WebXR grip pose
// into the rig's palm pose. Pure functions, no I/O.
#pragma once

#include "telegrasp/client/types.h"

#include <Eigen/Geometry>

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace telegrasp::sim {
class HandRig;
}

namespace telegrasp::view {

/// The schema's version; a page may send "version" and must not send a newer one.
inline constexpr int kControllerInputVersion = 1;
/// A client message larger than this is refused (a sample is about 300 bytes).
inline constexpr std::size_t kMaxControllerInputBytes = 4096;

/// One hand's sample as the page sent it.
struct ControllerInput {
  client::HandSide side = client::HandSide::kRight;
  Eigen::Isometry3d X_WorldGrip = Eigen::Isometry3d::Identity();  ///< WebXR grip pose in the world frame, m.
  double trigger = 0;
  std::vector<double> curls;  ///< Empty or 5 values in [0, 1], thumb first.
  bool tracking = true;
  std::uint64_t seq = 0;  ///< The page's, per hand, increasing.
  std::int64_t stamp_ns = 0;  ///< The page's clock (latency figures only); 0 if not sent.
};

/// Parses one message; on failure nullopt and `error` names the field and what was expected.
/// Limits as the server's: unit quaternion within 1e-3, coordinates within 100 m, values in [0, 1].
std::optional<ControllerInput> parse_controller_input(std::string_view json, std::string& error);

/// X_GripPalm: the rig's palm frame seen from the WebXR grip frame of its side. The grip origin
/// is the rig's grasp_center (where a held handle sits in the palm); grip axes (WebXR): +X out of
/// the back of a right hand (into the palm of a left one), -Z toward the thumb along the handle,
/// Y = Z x X. Rig palm frames: +x to the fingers, +z out of the back, the thumb at +y (right) or
/// -y (left); a rig with no side (a gripper) is taken as a right hand.
Eigen::Isometry3d grip_to_palm(const sim::HandRig& rig, client::HandSide side);

}  // namespace telegrasp::view
