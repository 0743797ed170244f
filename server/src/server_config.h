// ServerSettings: the server's configuration, from a protobuf text file plus command-line flags.
#pragma once

#include "telegrasp/sim/hand_controller.h"
#include "telegrasp/sim/object_shape.h"
#include "telegrasp/sim/world.h"

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace telegrasp::server {

namespace proto {
class ServerConfig;
}

/// One object of the initial scene, resting on the table at (x, y) turned by yaw.
struct SceneObjectSpec {
  std::string model;
  double x = 0, y = 0, yaw = 0;
  std::optional<double> friction{};  ///< Coulomb mu of hand contacts on it (grasp quality); unset: the rig's.
  std::optional<sim::ShapeClass> shape{};  ///< Its shape class; unset: the one read from its mesh.
};

/// A relay: one DDS participant that forwards many remote users' inputs (telegrasp-view --drive
/// forwards browser connections). It owns every client id that starts with `prefix`: the first
/// participant (with DDS Security, the first identity) to drive or command one holds the prefix
/// until it leaves the domain, and nobody else drives an id under it. Its hands under the prefix
/// count against `max_hands`, not against the per-participant limit.
struct Relay {
  std::string prefix;  ///< 1..32 characters.
  int max_hands = 64;  ///< 1..4096.
};

/// An object placed at an exact pose (a restored snapshot's), kept as read so that a recording's
/// replay rebuilds the very same pose.
struct PlacedObject {
  std::string model;
  Eigen::Vector3d p_WorldObject{0, 0, 0};
  Eigen::Quaterniond q_WorldObject{1, 0, 0, 0};  ///< Unit within a tolerance; normalized by X_WorldObject().
  Eigen::Isometry3d X_WorldObject() const {
    Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
    X.linear() = q_WorldObject.normalized().toRotationMatrix();
    X.translation() = p_WorldObject;
    return X;
  }
};

/// Everything the server needs to start; defaults are the built-in demo scene on loopback.
struct ServerSettings {
  int domain = 0;
  std::string profile = "loopback";
  std::string profiles_file;
  /// The scene (DDS partition) served; "": $TELEGRASP_SCENE, else "default" (idl/network.h).
  std::string scene;
  /// Fast DDS discovery servers, HOST[:PORT] in server-id order; empty: $TELEGRASP_DISCOVERY_SERVERS,
  /// else the profile's discovery.
  std::vector<std::string> discovery_servers;
  /// Seconds the server waits, announcing its claim on the scene name, before it serves: a live
  /// server with an older claim on the same scene makes it refuse to start.
  double claim_wait_s = 1.5;
  double tick_hz = 90;
  std::string objects_dir;
  /// With objects_dir: also the built-in stand-in of every protocol object that has no mesh there
  /// (protocol runs with a partial mesh set).
  bool fill_standins = false;
  std::vector<SceneObjectSpec> objects;  ///< Empty and !empty_scene: every model in a grid.
  bool empty_scene = false;
  std::string right_rig, left_rig;  ///< "": the built-in human rigs.
  sim::ClosingMode closing_mode = sim::ClosingMode::kPrecise;
  /// A grasp on an object another hand holds: both hold it (share) or it takes it over (takeover).
  sim::TwoHandMode two_hand_mode = sim::TwoHandMode::kShare;
  double freeze_after_s = 0.25;
  double remove_after_s = 0.5;
  bool late_latch = true;
  /// Grasp qualities include the wrench hull's volume (sim::GraspSettings::quality_volume).
  bool quality_volume = false;
  /// The grasp quality of the contacts of tick t is computed on a worker thread and published at
  /// tick t + this (GraspEvents wait as long, all of them, so their order is kept); 0: computed
  /// within the tick on the simulation thread (sim::WorldSettings::quality_delay_ticks).
  int quality_delay_ticks = 2;
  double status_period_s = 1.0;
  int max_hands = 256;
  /// Tick as soon as every hand has answered the last tick (ControllerState.lockstep_tick) instead
  /// of on the wall clock: deterministic, faster than real time. With no hands the scene waits.
  bool lockstep = false;
  /// Write a recording of the run here (recording.h); "": none.
  std::string record_path;
  /// Client ids that may remove any object and reset the scene (others: only what they spawned
  /// or hold); open_scene makes every client an operator.
  std::vector<std::string> operators;
  bool open_scene = false;
  int max_objects_per_client = 16;  ///< Objects a non-operator may have spawned at once.
  int max_hands_per_participant = 16;
  std::vector<Relay> relays;  ///< Prefixes no two of which start one another.
  double max_input_rate_hz = 250;  ///< Per hand.
  double max_command_rate_hz = 20;  ///< Per client.
  /// Write the objects' last published poses here about once a second and on a clean stop, and
  /// start from them when the file exists (snapshot.h); "": none.
  std::string snapshot_path;

  // Facts of one run, not configuration (not in the configuration file; a recording's header keeps them).
  /// SceneState/ServerStatus.incarnation: the server sets a random one at start (new_incarnation()).
  std::uint64_t incarnation = 0;
  /// The objects to start with, at these poses, instead of the configured scene (a restored
  /// snapshot); unset: the configured scene. SCENE_RESET always goes back to the configured scene.
  std::optional<std::vector<PlacedObject>> restored_objects;
};

/// Reads a protobuf text file onto `settings` (fields present in the file replace the defaults).
/// Throws std::runtime_error naming the file and the field that is wrong.
void load_server_config(const std::string& path, ServerSettings& settings);

/// Checks ranges and combinations; throws std::runtime_error naming the field (`origin` says
/// where the value came from, e.g. the file name or "command line").
void validate_settings(const ServerSettings& settings, const std::string& origin);

/// The settings as a configuration message with every field set (a recording's header).
proto::ServerConfig to_proto(const ServerSettings& settings);
/// Default settings with the fields present in `config` applied, then validated. Throws
/// std::runtime_error starting with `origin` and naming the field that is wrong.
ServerSettings settings_from_proto(const proto::ServerConfig& config, const std::string& origin);

}  // namespace telegrasp::server
