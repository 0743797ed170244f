// Hands that grasp, for telegrasp-bench-scale --active: one object per hand on a grid over the
// server's table, and per hand the sim's ScriptedOperator approaching its object, closing until the
// server reports the grasp (GraspEvent), lifting, holding, releasing, and again. The grasp is planned
// once per rig on the model at the origin (sim::plan_grasp, the bot's planner) and moved onto each
// object's pose as the server last published it (SceneState), as telegrasp-bot corrects its plan
// when an object moves. After the hold the bench lowers the object back onto the table (0.4 s)
// before the operator opens the hand, so that objects stay upright trial after trial.
#pragma once

#include "telegrasp/idl/telegrasp.h"
#include "telegrasp/sim/hand_rig.h"
#include "telegrasp/sim/object_model.h"
#include "telegrasp/sim/scripted_operator.h"

#include <fastdds/dds/subscriber/DataReader.hpp>
#include <fastdds/dds/subscriber/DataReaderListener.hpp>

#include <Eigen/Geometry>

#include <array>
#include <atomic>
#include <cstdint>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

namespace telegrasp::bench {

/// The object grid: hand h (client h / 2, side h % 2) has object h, at active_object_xy(h).
/// 11 columns 0.35 m apart by 12 rows 0.30 m apart, inside the server's 4 x 4 m table: room for
/// the scene's 128 objects (the SceneState bound).
constexpr int kMaxActiveHands = 128;
Eigen::Vector2d active_object_xy(int hand);

/// Whether `model` names a built-in stand-in (the objects --active can put in the scene).
bool is_active_model(const std::string& model);

/// The server configuration lines of the grid's first `hands` objects of `model`.
std::string active_objects_config(int hands, const std::string& model);

/// What the active hands did, since the start (counters only grow).
struct ActiveCounts {
  std::uint64_t grasps = 0, releases = 0;  ///< GraspEvents of the bench's hands.
  std::uint64_t cycles = 0, cycles_held = 0;  ///< Operator trials finished, and of those held through lift and hold.
  /// Trials not begun: the object was not in the newest SceneState within 0.12 m of its place,
  /// or had fallen over (tilted more than 0.3 rad).
  std::uint64_t objects_missing = 0, objects_fallen = 0;
  std::vector<std::uint64_t> grasps_per_hand;
};

/// The per-hand operators and the server's answers they need. Publisher threads call sample() for
/// the hands they own (one thread per hand); the GraspEvent listener and SceneState reader are
/// the main participant's.
class ActiveHands : public eprosima::fastdds::dds::DataReaderListener {
 public:
  /// `model`: the built-in stand-in the scene's objects are (throws std::runtime_error if unknown).
  ActiveHands(const std::string& model, int max_hands, double sample_hz);

  /// The SceneState reader to take object poses from (no listener; newest sample taken when needed).
  void set_scene_reader(eprosima::fastdds::dds::DataReader* reader) { scene_reader_ = reader; }
  /// GraspEvent reader listener: takes every event to on_grasp_event().
  void on_data_available(eprosima::fastdds::dds::DataReader* reader) override;
  /// Counts a GraspEvent of a "scale-<c>" hand and tracks whether that hand holds (others ignored).
  void on_grasp_event(const msg::GraspEvent& event);
  /// Takes the object poses of a SceneState: each object within 0.12 m of a grid place is that
  /// place's hand's. (With a scene reader set, the newest SceneState is taken when needed.)
  void on_scene_state(const msg::SceneState& scene, double t);

  /// Idle: every hand hovers 0.3 m above its object, wobbling, trigger oscillating (as the idle
  /// bench's hands, closing on nothing). Active: each hand runs grasp trials on its object.
  void set_active(bool active) { active_.store(active); }
  bool active() const { return active_.load(); }

  /// Controller sample `seq` of hand `side` of client `client` at `t` s into the run.
  msg::ControllerState sample(const std::string& client_id, int client, int side, std::uint64_t seq, double t);

  ActiveCounts counts() const;
  /// Hands holding an object now, by the events.
  int holding() const;
  /// Mean duration of a finished trial (begin to done), s; 0 before any.
  double mean_cycle_s() const;

 private:
  struct Hand {
    std::unique_ptr<sim::ScriptedOperator> op;
    double t_begin = 0, t_next = -1;  // current trial's start; when the next may start (-1: unset)
    Eigen::Isometry3d X_WorldPalm = Eigen::Isometry3d::Identity();  // the last commanded palm pose
  };
  /// The pose of object `hand` as last published, if it stands upright within 0.12 m of its place.
  std::optional<Eigen::Isometry3d> object_pose(int hand, double t);
  void take_poses(const msg::SceneState& scene, double t);  // with mutex_ held
  Eigen::Isometry3d hover_pose(int hand, int side) const;

  std::string model_name_;
  sim::ObjectModelPtr model_;
  double sample_hz_;
  std::array<std::shared_ptr<const sim::HandRig>, 2> rigs_;  // by side: left 0, right 1
  std::array<sim::GraspPlan, 2> plans_;  // by side, for the object at X_WorldObject0_
  Eigen::Isometry3d X_WorldObject0_ = Eigen::Isometry3d::Identity();
  std::vector<Hand> hands_;
  std::unique_ptr<std::atomic<bool>[]> grasped_;
  std::atomic<bool> active_{false};

  mutable std::mutex mutex_;  // guards everything below
  eprosima::fastdds::dds::DataReader* scene_reader_ = nullptr;
  std::map<int, Eigen::Isometry3d> object_poses_;  // by hand, from the newest SceneState taken
  double poses_taken_t_ = -1e9;
  ActiveCounts counts_;
  double cycle_s_sum_ = 0;
};

}  // namespace telegrasp::bench
