// ScriptedOperator: a model of a person grasping one object with a VR controller.
#pragma once

#include "telegrasp/sim/hand_controller.h"
#include "telegrasp/sim/hand_rig.h"
#include "telegrasp/sim/object_model.h"

#include <Eigen/Geometry>

#include <cstdint>
#include <memory>
#include <optional>
#include <random>
#include <string>
#include <vector>

namespace telegrasp::sim {

/// How well and how fast an operator moves.
struct OperatorSkill {
  std::string name;
  double position_error = 0;     ///< Std dev of the grasp position error per axis, m.
  double orientation_error = 0;  ///< Std dev of the grasp orientation error, rad.
  double reach_speed = 0.5;      ///< Mean hand speed while reaching, m/s.
  double reaction_time = 0.3;    ///< Delay after the object appears, s.
  double squeeze_time = 0.35;    ///< Trigger 0 -> 1, s.
};

/// Built-in skill profiles: "perfect", "experienced", "inexperienced".
/// Throws std::invalid_argument naming the unknown profile.
OperatorSkill skill_profile(const std::string& name);

/// Phases of one trial.
enum class OperatorPhase { kReact, kReach, kSqueeze, kLift, kHold, kRelease, kDone };

/// A hand pose chosen by the planner, with what the offline closing predicted.
struct GraspPlan {
  Eigen::Isometry3d X_WorldPalm = Eigen::Isometry3d::Identity();  ///< Palm pose when closing.
  Eigen::Vector3d approach_World{0, 0, -1};  ///< Unit direction of the final approach.
  int predicted_blocked = 0;                 ///< Capsules blocked in the offline closing.
  bool predicted_grasp = false;              ///< The offline closing grasped, with no penetration.
};

/// Plans a grasp by closing the hand offline (no physics) at candidate poses around the object
/// (top and side approaches, both axes, offsets, heights) with precise closing, and keeping the
/// best: a grasp with no capsule ending inside the object, then opposing contact normals (a pinch
/// or wrap, not a press), then fingers above the table top at `table_height` (the World's is 0),
/// then the most capsules blocked, then the least HandError. Deterministic.
GraspPlan plan_grasp(const std::shared_ptr<const HandRig>& rig, const GraspSettings& settings, const ObjectModel& model,
                     const Eigen::Isometry3d& X_WorldObject, double dt, double table_height = 0.0);

/// Produces controller inputs for one trial: react, reach to a planned grasp pose with the skill's
/// pose error, squeeze until grasped (retrying up to 3 times), lift 10 cm while squeezing fully,
/// hold 1 s, release.
/// Seeded and deterministic; it sees only the object's pose and model and the grasp state.
class ScriptedOperator {
 public:
  ScriptedOperator(std::shared_ptr<const HandRig> rig, OperatorSkill skill, std::uint64_t seed,
                   GraspSettings settings = {}, double dt = 1.0 / 90.0);

  /// Starts a trial at time `t0` for the object at X_WorldObject, the hand at X_WorldPalm.
  void begin(const ObjectModel& model, const Eigen::Isometry3d& X_WorldObject,
             const Eigen::Isometry3d& X_WorldPalm, double t0);
  /// The input for time `t`; `grasped` is whether the hand holds the trial's object now.
  ControllerInput next(double t, bool grasped);

  OperatorPhase phase() const { return phase_; }
  bool done() const { return phase_ == OperatorPhase::kDone; }
  /// True if the object was held through the whole lift and hold.
  bool held_after_lift() const { return held_after_lift_; }
  int attempts() const { return attempts_; }
  const GraspPlan& plan() const { return plan_; }

  static constexpr double kLiftHeight = 0.10;
  static constexpr double kHoldTime = 1.0;
  static constexpr int kMaxAttempts = 3;

 private:
  void start_attempt(double t);
  Eigen::Isometry3d noisy(const Eigen::Isometry3d& X);

  std::shared_ptr<const HandRig> rig_;
  OperatorSkill skill_;
  GraspSettings settings_;
  double dt_;
  std::mt19937_64 rng_;
  GraspPlan plan_;
  OperatorPhase phase_ = OperatorPhase::kDone;
  // Waypoints of the current motion: from -> via -> to, with their times.
  Eigen::Isometry3d X_start_, X_pre_, X_goal_, X_lifted_;
  Eigen::Isometry3d X_last_ = Eigen::Isometry3d::Identity();
  double t_phase_ = 0, t_via_ = 0, t_end_ = 0;
  double trigger_ = 0;
  int attempts_ = 0;
  bool held_after_lift_ = false;
};

}  // namespace telegrasp::sim
