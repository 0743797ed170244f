// ServerSettings: the server's configuration, from a protobuf text file plus command-line flags.
#pragma once

#include "telegrasp/sim/hand_controller.h"

#include <string>
#include <vector>

namespace telegrasp::server {

/// One object of the initial scene, resting on the table at (x, y) turned by yaw.
struct SceneObjectSpec {
  std::string model;
  double x = 0, y = 0, yaw = 0;
};

/// Everything the server needs to start; defaults are the built-in demo scene on loopback.
struct ServerSettings {
  int domain = 0;
  std::string profile = "loopback";
  std::string profiles_file;
  double tick_hz = 90;
  std::string objects_dir;
  std::vector<SceneObjectSpec> objects;  ///< Empty and !empty_scene: every model in a grid.
  bool empty_scene = false;
  std::string right_rig, left_rig;       ///< "": the built-in human rigs.
  sim::ClosingMode closing_mode = sim::ClosingMode::kPrecise;
  double freeze_after_s = 0.25;
  double remove_after_s = 0.5;
  bool late_latch = true;
  double status_period_s = 1.0;
  int max_hands = 256;
  /// Tick as soon as every hand has answered the last tick (ControllerState.lockstep_tick) instead
  /// of on the wall clock: deterministic, faster than real time. With no hands the scene waits.
  bool lockstep = false;
};

/// Reads a protobuf text file onto `settings` (fields present in the file replace the defaults).
/// Throws std::runtime_error naming the file and the field that is wrong.
void load_server_config(const std::string& path, ServerSettings& settings);

/// Checks ranges and combinations; throws std::runtime_error naming the field (`origin` says
/// where the value came from, e.g. the file name or "command line").
void validate_settings(const ServerSettings& settings, const std::string& origin);

}  // namespace telegrasp::server
