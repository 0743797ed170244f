// A ControllerState carrying a sim::ControllerInput, for the server tests.
#pragma once

#include "conversions.h"
#include "telegrasp/sim/hand_controller.h"

#include <cstdint>
#include <string>

namespace telegrasp::server {

/// `in` as the wire sample of hand (`client`, `side`) with sequence number `seq` (client time
/// seq microseconds), tracking valid.
inline msg::ControllerState to_state(const std::string& client, std::uint8_t side, std::uint64_t seq,
                                     const sim::ControllerInput& in) {
  msg::ControllerState s;
  s.client_id(client);
  s.hand_side(side);
  s.sequence_number(seq);
  s.client_time_ns(static_cast<std::int64_t>(seq) * 1000);
  s.palm(to_msg(in.X_WorldPalm));
  s.trigger(in.trigger);
  s.tracking_valid(true);
  return s;
}

}  // namespace telegrasp::server
