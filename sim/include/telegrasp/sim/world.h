// World: the physics scene (table, dynamic objects) and the hands grasping in it.
#pragma once

#include "telegrasp/sim/hand_controller.h"
#include "telegrasp/sim/ids.h"
#include "telegrasp/sim/object_model.h"

#include <Eigen/Geometry>

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace telegrasp::sim {

/// What a hand's grasp on an object another hand holds does.
enum class TwoHandMode {
  kShare,  ///< Both hold it and it follows both hands (two_hand_hold.h); a third grasp replaces the first holder.
  kTakeover,  ///< The newest grasp takes it and the previous holder lets go (the original's hand-to-hand takeover).
};

/// The mode named "share" or "takeover" (as configuration files and flags write it); nothing for any other name.
std::optional<TwoHandMode> parse_two_hand_mode(std::string_view name);
/// The name parse_two_hand_mode reads: "share" or "takeover".
const char* two_hand_mode_name(TwoHandMode mode);

/// Fixed parameters of a world.
struct WorldSettings {
  double dt = 1.0 / 90.0;  ///< Fixed tick, seconds.
  Eigen::Vector3d gravity{0, 0, -9.81};
  double table_half_extent = 1.0;  ///< The table top is [-this, this]^2 at z = 0, m.
  GraspSettings grasp;
  TwoHandMode two_hand_mode = TwoHandMode::kShare;
  /// Grasp qualities: 0 computes each within the step that took its contacts, on the calling
  /// thread; k > 0 on a QualityWorker thread, delivered exactly k steps later (the step waits for
  /// the worker if it is late, and counts it: quality_late()). Either way deterministic.
  int quality_delay_ticks = 0;
};

/// A grasp or release, with the grasp's metrics and contacts.
struct GraspEvent {
  enum class Kind { kGrasp, kRelease };
  Kind kind = Kind::kGrasp;
  HandId hand;
  ObjectId object;
  std::uint64_t tick = 0;
  double time = 0;  ///< Seconds since the world started.
  /// Grasp events: the grasp tick's metrics, taken by the QualityWorker with the grasp's quality
  /// (see quality_job). With quality_delay_ticks 0 they are here, quality included; with k > 0
  /// this is empty and they come k steps later in quality_results() (QualityResult::metrics).
  std::optional<GraspMetrics> metrics;
  /// Grasp events: the QualityJob whose result holds this grasp's metrics and quality.
  std::uint64_t quality_job = 0;
  std::vector<Contact> contacts;  ///< Grasp events.
  GraspType grasp_type = GraspType::kOther;  ///< Grasp events: the hand's grasp type (HandState::grasp_type).
  Eigen::Vector3d v_WorldObject{0, 0, 0};  ///< Release events: velocity handed to physics.
  Eigen::Vector3d w_WorldObject{0, 0, 0};
};

/// One physics scene with a table top at z = 0 (square, see WorldSettings), dynamic objects and hands. One thread owns
/// it. Deterministic: the same calls in the same order give bit-identical results.
///
/// An object has up to two holders. One holder carries it at its grasp's relative pose. With
/// TwoHandMode::kShare, a second hand whose grasp rule turns true on it joins: from then on the
/// object follows two_hand_object_pose() of the first and second holder (the attach points are
/// the centres of the rigs' palm contact spheres), and after every tick both hands are re-attached
/// at the object's new pose (HandController::reattach), so each hand's fingers work against the
/// object where it is. When one of two holders lets go (release event with zero velocity), the
/// other keeps it at its current relative pose; the object goes back to physics, with the
/// velocity of its last holder, only when the last holder lets go.
class World {
 public:
  explicit World(WorldSettings settings = {});
  ~World();
  World(const World&) = delete;
  World& operator=(const World&) = delete;

  /// Adds a dynamic object at `X_WorldObject`. The world shares ownership of `model`, so the model
  /// outlives the object and any hand's grasp of it: the caller need not keep it.
  ObjectId add_object(ObjectModelPtr model, const Eigen::Isometry3d& X_WorldObject);
  /// Removes an object; a hand holding it lets go. Unknown ids are ignored.
  void remove_object(ObjectId id);
  /// Puts a free (not held) object at `X_WorldObject` at rest; false if it is held or unknown.
  bool place_object(ObjectId id, const Eigen::Isometry3d& X_WorldObject);
  /// Pose at which `model` rests on the table at (x, y) with yaw about +z.
  static Eigen::Isometry3d resting_pose(const ObjectModel& model, double x, double y, double yaw);

  /// Adds a hand driven by a rig; it starts open, at the origin, until its first input.
  HandId add_hand(std::shared_ptr<const HandRig> rig);
  /// Removes a hand; an object only it holds is dropped to physics at rest where it is (a release
  /// event comes with the next step; another holder keeps it). Unknown ids are ignored. Ids are never reused.
  void remove_hand(HandId id);
  /// Sets a hand's input for the next step; returns "" or the reason the input was rejected
  /// (the hand then keeps its previous input).
  std::string set_input(HandId hand, const ControllerInput& input);

  /// Advances one tick: every hand in id order (its release, then its grasp), held objects follow
  /// their holders, then physics.
  void step();

  double dt() const;
  double time() const;
  std::uint64_t tick() const;
  std::vector<ObjectId> objects() const;
  bool has_object(ObjectId id) const;
  std::vector<HandId> hands() const;
  const ObjectModel& object_model(ObjectId id) const;
  Eigen::Isometry3d object_pose(ObjectId id) const;
  Eigen::Vector3d object_velocity(ObjectId id) const;
  /// The first hand holding `id` (the earliest grasp), or an invalid id.
  HandId holder(ObjectId id) const;
  /// Every hand holding `id`, in the order they grasped it (at most two); empty when it is free.
  std::vector<HandId> holders(ObjectId id) const;
  const HandController& hand(HandId id) const;
  /// Events of the last step, in order (a release caused by remove_object between steps comes first).
  const std::vector<GraspEvent>& events() const;
  /// The grasp qualities the last step delivered, in job order: those of the contact sets of the
  /// step quality_delay_ticks before it (each holding hand's, when its contacts changed or it
  /// grasped; a grasp's first also carries the grasp's metrics, their quality set). Each is also
  /// in its hand's hold_metrics() (and, with the metrics, grasp_metrics() for a grasp's first) if
  /// the hand still holds that grasp.
  const std::vector<QualityResult>& quality_results() const;
  /// Steps that had to wait for the quality worker (0 when it keeps up).
  std::uint64_t quality_late() const;
  /// Qualities computed (not reused from the hand's last 8 wrench sets) for `hand` so far, as
  /// delivered.
  std::uint64_t quality_computations(HandId hand) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace telegrasp::sim
