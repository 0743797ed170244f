// The data a telegrasp client sends and receives, in Eigen and std types (no Fast DDS here).
// Mirrors idl/telegrasp.idl; units SI, poses named with their frames.
#pragma once

#include <Eigen/Geometry>

#include <array>
#include <compare>
#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

namespace telegrasp::client {

enum class HandSide : std::uint8_t { kLeft = 0, kRight = 1 };

/// "left" / "right" (or "side<N>" for a value that is neither).
std::string to_string(HandSide side);

/// One hand of one client: the key of every per-hand topic.
struct HandKey {
  std::string client_id;
  HandSide side = HandSide::kRight;
  auto operator<=>(const HandKey&) const = default;
};

/// One controller sample for one hand.
struct ControllerSample {
  HandSide side = HandSide::kRight;
  Eigen::Isometry3d X_WorldPalm = Eigen::Isometry3d::Identity();
  double trigger = 0;  ///< 0 open .. 1 closed.
  std::vector<double> curls;  ///< Empty, or five values in [0, 1] (thumb first).
  std::uint32_t buttons = 0;  ///< BUTTON_* bits of the IDL.
  bool tracking_valid = true;  ///< False: the server keeps the last pose.
  std::uint64_t sequence_number = 0;  ///< 0: Client::publish numbers the hand's samples 1, 2, 3 ...
  std::int64_t client_time_ns = 0;  ///< 0: Client::publish stamps steady_clock now.
  /// For a server in lockstep: the tick of the newest SceneState this sample answers (the server's
  /// next tick waits for it). Client::publish adds how many commands this client sent before it.
  std::uint64_t lockstep_tick = 0;
};

struct HandSkeleton {
  HandKey hand;
  std::string rig;
  std::uint64_t tick = 0;
  double time = 0;
  std::uint64_t input_sequence = 0;  ///< Newest controller sample this skeleton reflects.
  std::int64_t input_client_time_ns = 0;
  bool late_latched = false;  ///< Re-posed on that sample's arrival, fingers of the last tick.
  bool frozen = false;  ///< The client went silent; the hand keeps its last input.
  Eigen::Isometry3d X_WorldPalm = Eigen::Isometry3d::Identity();  ///< Resolved: the pose that grasps and is shown.
  std::vector<Eigen::Isometry3d> X_WorldPhalanx;  ///< Rig order.
  std::vector<double> joint_angles;  ///< rad, rig order.
  Eigen::Isometry3d X_WorldTracked = Eigen::Isometry3d::Identity();  ///< The controller's pose.
  Eigen::Vector3d resolve_offset{0, 0, 0};  ///< X_WorldPalm minus X_WorldTracked position, world frame, m.
  double resolve_angle = 0;  ///< Rotation from the tracked to the resolved pose, rad.
};

struct GraspState {
  HandKey hand;
  std::uint64_t tick = 0;
  double time = 0;
  int selected_object = -1;  ///< -1: none.
  int grasped_object = -1;  ///< -1: none.
  double trigger = 0;
  std::vector<bool> blocked;  ///< Per phalanx, rig order.
  bool palm_contact = false;
  double epsilon = 0;  ///< Held grasp's Ferrari-Canny epsilon (sim/README.md, section 5); 0 when not holding.
  double volume = 0;  ///< Held grasp's wrench-space volume.
  bool force_closure = false;  ///< epsilon > 0.
  std::string grasp_type;  ///< How the hand closes ("other" for a rig that lists no grasp types).
};

struct ContactPoint {
  int phalanx = -1;  ///< Rig index; -1 for the palm.
  Eigen::Vector3d p_WorldContact{0, 0, 0}, n_World{0, 0, 0};
  Eigen::Vector3d p_ObjectContact{0, 0, 0}, n_Object{0, 0, 0};
  double nd = 0;  ///< The paper's ND, m; meaningful only if nd_hit.
  bool nd_hit = false;
};

struct ContactSet {
  HandKey hand;
  std::uint64_t tick = 0;
  double time = 0;
  int object_id = -1;
  Eigen::Isometry3d X_WorldObject = Eigen::Isometry3d::Identity();
  std::vector<ContactPoint> contacts;
};

/// One capsule's metrics on the grasp tick: sim::CapsuleMetric as the server publishes it, with the
/// phalanx's rig name (lengths in metres).
struct CapsuleMetric {
  int phalanx = -1;
  std::string phalanx_name;
  bool hit = false;  ///< nd_midlength: false: "no hit", kept apart from nd = 0.
  double nd = 0;  ///< nd_midlength, the paper's ND (sweep toward mid-length CTc), m
  double signed_distance = 0;  ///< m
  bool blocked = false;
  bool contact_hit = false;  ///< nd_contact was taken (every blocked capsule has it).
  double nd_contact = 0;  ///< ND toward the axis point nearest the contact, m; only if contact_hit.
};

/// The name of the previous release; goes in the next.
using CapsuleReport [[deprecated("use CapsuleMetric")]] = CapsuleMetric;

struct GraspEvent {
  enum class Kind { kGrasp, kRelease };
  std::uint64_t event_id = 0;  ///< Unique and increasing per server run.
  Kind kind = Kind::kGrasp;
  HandKey hand;
  int object_id = -1;
  std::string object_name;
  std::uint64_t tick = 0;
  double time = 0;
  double object_spawn_time = 0;
  Eigen::Isometry3d X_WorldObject = Eigen::Isometry3d::Identity();
  std::uint64_t input_sequence = 0;
  double hand_error_mm = 0;  ///< Grasp events.
  int capsules_without_hit = 0;  ///< Grasp events.
  std::vector<CapsuleMetric> capsules;  ///< Grasp events.
  std::vector<ContactPoint> contacts;  ///< Grasp events.
  double palm_signed_distance = 0;  ///< Grasp events: exact palm-box signed distance to the object, m.
  double epsilon = 0, volume = 0;  ///< Grasp events: Ferrari-Canny epsilon, wrench-space volume.
  bool force_closure = false;  ///< Grasp events: epsilon > 0.
  Eigen::Vector3d v_WorldObject{0, 0, 0};  ///< Release events: velocity handed to physics.
  Eigen::Vector3d w_WorldObject{0, 0, 0};
  std::string grasp_type;  ///< Grasp events: the hand's grasp type (GraspState::grasp_type).
  /// Not on the wire: the incarnation of the server run that sent it, as the client library knows
  /// it (Client::server_incarnation() of its sender; 0 if none was known yet).
  std::uint64_t server_incarnation = 0;
};

struct ObjectState {
  int id = -1;
  std::string name;
  Eigen::Isometry3d X_WorldObject = Eigen::Isometry3d::Identity();
  Eigen::Vector3d v_WorldObject{0, 0, 0};
  bool held = false;
  HandKey holder;  ///< When held: the first hand holding it (holders.front()).
  std::vector<HandKey> holders;  ///< Every hand holding it, in grasp order (two may share it); empty when free.
  double spawn_time = 0;
};

struct SceneState {
  std::uint64_t tick = 0;
  double time = 0;
  std::vector<ObjectState> objects;
  /// The server run that published it (random, nonzero, new after each restart): object ids, ticks
  /// and times of different incarnations are not comparable.
  std::uint64_t incarnation = 0;
};

struct SceneCommand {
  enum class Kind { kSpawn, kRemove, kReset };
  Kind kind = Kind::kSpawn;
  std::string model;  ///< kSpawn: a name from ServerStatus::models.
  int object_id = -1;  ///< kRemove.
  bool on_table = true;  ///< kSpawn: rest on the table at (x, y, yaw), else at X_WorldObject.
  double x = 0.45, y = 0, yaw = 0;
  Eigen::Isometry3d X_WorldObject = Eigen::Isometry3d::Identity();
};

struct ServerStatus {
  std::uint64_t tick = 0;
  double time = 0;
  double tick_rate_hz = 0;
  int clients = 0, hands = 0, objects = 0;
  double tick_us_p50 = 0, tick_us_p99 = 0, tick_us_max = 0;
  std::uint64_t missed_ticks = 0;
  std::uint64_t inputs_accepted = 0, inputs_rejected = 0;
  std::map<std::string, std::uint64_t> rejected;  ///< Per reason, since the server started.
  std::uint64_t commands_accepted = 0, commands_rejected = 0;
  std::vector<std::string> models;  ///< Model names a spawn command accepts.
  std::uint64_t incarnation = 0;  ///< The server run, as in SceneState::incarnation.
  std::map<std::string, std::uint64_t> commands_rejected_by_reason;  ///< Per reason, since the server started.
  std::uint64_t notices_sent = 0;  ///< Refusals told to their clients (Notice), since the server started.
  std::uint64_t rss_kib = 0;   ///< The server process's resident set, KiB.
  std::uint64_t heap_kib = 0;  ///< Its heap in use (malloc'd, not freed), KiB: what a leak makes grow.
  std::uint64_t quality_late = 0;  ///< Ticks that waited for the grasp-quality worker, since start.
};

/// Why the server refused this client's input or command (ClientNotice): the client learns it
/// instead of being ignored. Input refusals come at most once a second per reason.
struct Notice {
  enum class Kind { kInputRejected, kCommandRejected };
  std::string client_id;  ///< The refused client: this one, or one its relay_prefix covers.
  Kind kind = Kind::kInputRejected;
  std::string reason;  ///< A key of ServerStatus::rejected or commands_rejected_by_reason, e.g. "rate_limited".
  std::string detail;  ///< For people: what was wrong.
  std::uint64_t command_id = 0;  ///< kCommandRejected: the refused command's id (send_command's return).
  std::uint64_t count = 0;  ///< This client's refusals for this reason, since the server started.
  double time = 0;  ///< Scene time of a command the scene refused; 0 otherwise.
};

/// A server run as it announces itself on the scene directory (Client::scenes()): one per live
/// server, every scene.
struct SceneInfo {
  std::string scene;  ///< The scene it serves (ClientOptions::scene).
  std::string host;  ///< The server's host name.
  std::string version;  ///< Its telegrasp version.
  std::uint64_t incarnation = 0;  ///< The server run (ServerStatus::incarnation).
  double started = 0;  ///< Unix time, s.
  bool serving = false;  ///< False while it still waits out its claim on the scene name.
  int clients = 0, hands = 0, objects = 0;
  double tick_rate_hz = 0;
  double tick_us_p99 = 0;  ///< Tick work over the last second.
  std::uint64_t missed_ticks = 0;
  double cpu_percent = 0;  ///< The server process, over the last second, % of one core.
  int host_cores = 0;
  double host_load = 0;  ///< The host's 1-minute load average per core.
};

/// Where to start a server for a new scene: the host of `scenes` with the lowest load per core
/// (the highest its servers report; ties: fewer hands served there, then the name); none when
/// `scenes` is empty.
std::optional<std::string> least_loaded_host(const std::vector<SceneInfo>& scenes);

/// A restarted server, noticed by its new incarnation (Client::on_server_restart).
struct ServerRestart {
  std::uint64_t previous_incarnation = 0;
  std::uint64_t incarnation = 0;
};

/// One model's shape and mass as the server publishes it (ObjectGeometry), so a client needs no
/// mesh files. The frame is the model's own: origin at its centre of mass, the frame of
/// ObjectState::X_WorldObject and ContactPoint::p_ObjectContact. Client::object_geometry shares
/// one immutable copy per mesh.
struct ObjectGeometry {
  std::string model;  ///< The model name, as in ObjectState::name.
  std::uint64_t content_hash = 0;  ///< FNV-1a 64 of the mesh as published (see telegrasp.idl); checked on arrival.
  std::vector<Eigen::Vector3f> vertices;  ///< m, model frame.
  std::vector<std::array<std::uint32_t, 3>> triangles;  ///< Vertex indices, counter-clockwise seen from outside.
  std::uint32_t vertex_count = 0;  ///< Of the whole mesh, also when it is omitted.
  std::uint32_t triangle_count = 0;
  bool mesh_omitted = false;  ///< Over the server's size limit: vertices and triangles are empty.
  Eigen::Vector3d p_ObjectMin{0, 0, 0}, p_ObjectMax{0, 0, 0};  ///< Bounds of the mesh, model frame.
  double mass_kg = 0;
  double volume_m3 = 0;  ///< Enclosed by the mesh.
  Eigen::Vector3d inertia_diagonal{0, 0, 0};  ///< kg m^2, about the centre of mass along the model axes.
  Eigen::Vector3d p_ObjectSourceOrigin{0, 0, 0};  ///< Where the source mesh file's origin lies, model frame.
};

}  // namespace telegrasp::client
