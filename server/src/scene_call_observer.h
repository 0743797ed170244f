// SceneCallObserver: told of every call the simulation thread makes into the SceneServer, just
// before it is made, with the same arguments (the Recorder writes them; replay checks them).
#pragma once

#include "input_mailbox.h"

#include <cstdint>
#include <vector>

namespace telegrasp::server {

class SceneCallObserver {
 public:
  virtual ~SceneCallObserver() = default;
  /// Before SceneServer::on_inputs(samples, now_ns).
  virtual void inputs(const std::vector<InputSample>& samples, std::int64_t now_ns) = 0;
  /// Before SceneServer::apply_command(command), in an iteration at now_ns.
  virtual void command(const msg::SceneCommand& command, std::int64_t now_ns) = 0;
  /// Before SceneServer::tick(now_ns).
  virtual void tick(std::int64_t now_ns) = 0;
};

}  // namespace telegrasp::server
