// The channels telegrasp-view advertises, with their JSON schemas: foxglove.SceneUpdate and
// foxglove.FrameTransforms from the files the build generated from the npm package
// @foxglove/schemas (share/telegrasp/view/schemas/), and the telegrasp.* schemas written here.
#pragma once

#include "web_server.h"

#include <filesystem>
#include <vector>

namespace telegrasp::view {

enum ChannelId : std::uint32_t {
  kSceneChannel = 1,  ///< /scene, foxglove.SceneUpdate; kept (changes only).
  kTransformsChannel = 2,  ///< /tf, foxglove.FrameTransforms; every frame, latest only.
  kGraspStateChannel = 3,  ///< /grasp_state, telegrasp.GraspState; kept, one per change.
  kGraspEventsChannel = 4,  ///< /grasp_events, telegrasp.GraspEvent; kept.
  kServerStatusChannel = 5,  ///< /server_status, telegrasp.ServerStatus; latest only.
  /// /xr/hands, telegrasp.DrivenHand (--drive only): the skeletons of the hands a connection
  /// drives, to that connection alone, as they arrive; latest only per hand.
  kDrivenHandsChannel = 6,
};

/// The channels, reading the foxglove schemas from `schema_dir`. Throws std::runtime_error
/// naming a missing or unreadable schema file and how to get it.
std::vector<Channel> view_channels(const std::filesystem::path& schema_dir);
/// /xr/hands (kDrivenHandsChannel), advertised with --drive.
Channel driven_hands_channel();

}  // namespace telegrasp::view
