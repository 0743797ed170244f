// OutputSink: where the simulation thread sends what it publishes (DDS in the server, a
// recorder in tests). Building a message is separate from sending it.
#pragma once

#include "conversions.h"
#include "telegrasp/idl/telegrasp.h"

namespace telegrasp::server {

class OutputSink {
 public:
  virtual ~OutputSink() = default;
  virtual void publish(const msg::HandSkeleton& skeleton) = 0;
  virtual void publish(const msg::GraspState& state) = 0;
  virtual void publish(const msg::ContactSet& contacts) = 0;
  virtual void publish(const msg::GraspEvent& event) = 0;
  virtual void publish(const msg::SceneState& scene) = 0;
  virtual void publish(const msg::ServerStatus& status) = 0;
  /// Why a client's command or input was refused, for that client (default: nowhere).
  virtual void publish(const msg::ClientNotice& notice) { (void)notice; }
  /// The hand left the scene: its per-hand instances are disposed.
  virtual void hand_removed(const HandAddress& hand) = 0;
};

}  // namespace telegrasp::server
