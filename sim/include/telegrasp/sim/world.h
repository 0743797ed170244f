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
#include <vector>

namespace telegrasp::sim {

/// Fixed parameters of a world.
struct WorldSettings {
  double dt = 1.0 / 90.0;  ///< Fixed tick, seconds.
  Eigen::Vector3d gravity{0, 0, -9.81};
  double table_half_extent = 1.0;  ///< The table top is [-this, this]^2 at z = 0, m.
  GraspSettings grasp;
};

/// A grasp or release, with the grasp's metrics and contacts.
struct GraspEvent {
  enum class Kind { kGrasp, kRelease };
  Kind kind = Kind::kGrasp;
  HandId hand;
  ObjectId object;
  std::uint64_t tick = 0;
  double time = 0;  ///< Seconds since the world started.
  std::optional<GraspMetrics> metrics;  ///< Grasp events.
  std::vector<Contact> contacts;  ///< Grasp events.
  Eigen::Vector3d v_WorldObject{0, 0, 0};  ///< Release events: velocity handed to physics.
  Eigen::Vector3d w_WorldObject{0, 0, 0};
};

/// One physics scene with a table top at z = 0 (square, see WorldSettings), dynamic objects and hands. One thread owns
/// it. Deterministic: the same calls in the same order give bit-identical results.
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
  /// Removes a hand; an object it holds is dropped to physics at rest where it is (a release event
  /// comes with the next step). Unknown ids are ignored. Ids are never reused.
  void remove_hand(HandId id);
  /// Sets a hand's input for the next step; returns "" or the reason the input was rejected
  /// (the hand then keeps its previous input).
  std::string set_input(HandId hand, const ControllerInput& input);

  /// Advances one tick: every hand in id order, grasp attachment, then physics.
  void step();

  double dt() const;
  double time() const;
  std::uint64_t tick() const;
  std::vector<ObjectId> objects() const;
  std::vector<HandId> hands() const;
  const ObjectModel& object_model(ObjectId id) const;
  Eigen::Isometry3d object_pose(ObjectId id) const;
  Eigen::Vector3d object_velocity(ObjectId id) const;
  /// The hand holding `id`, or an invalid id.
  HandId holder(ObjectId id) const;
  const HandController& hand(HandId id) const;
  /// Events of the last step, in order (a release caused by remove_object between steps comes first).
  const std::vector<GraspEvent>& events() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace telegrasp::sim
