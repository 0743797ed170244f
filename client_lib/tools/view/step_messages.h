// The messages of one step of telegrasp-view, serialized once and shared by the viewers (web
// server) and the MCAP recording, in the order they go out.
#pragma once

#include "view_model.h"

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace telegrasp::view {

/// One message on one of the view's channels (channels.h), as JSON text.
struct StepMessage {
  std::uint32_t channel = 0;
  std::shared_ptr<const std::string> payload;
};

/// The messages of `update` in sending order: /scene first (a viewer knows an entity before the
/// frames that move it), then /tf, /grasp_state, /grasp_events (arrival order), /server_status.
std::vector<StepMessage> step_messages(const ViewUpdate& update);

/// `message` as the JSON text sent on a channel.
std::shared_ptr<const std::string> payload(const Json& message);

}  // namespace telegrasp::view
