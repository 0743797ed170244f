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

/// How well and how fast an operator moves. The time to reach a grasp follows Fitts's law (see
/// fitts_time): the transport to the pre-grasp pose and the final approach are each
/// `a + b log2(1 + D / W)` seconds, D the distance and W the target's tolerance; the final
/// approach starts a stand-off away from the grasp that grows with the object's size (the open
/// hand clears it) and takes aperture_time per m of size longer, so larger objects take longer. Practice shortens
/// reaction and movements (see practice_factor). A pose error beyond correction_tolerance is corrected before
/// squeezing. With fitts_slope = 0 the legs take 1.5 D / reach_speed instead (the "perfect" profile, a robot-like
/// operator).
struct OperatorSkill {
  std::string name;
  double position_error = 0;  ///< Std dev of the grasp position error per axis, m.
  double orientation_error = 0;  ///< Std dev of the grasp orientation error, rad.
  double reach_speed = 0.5;  ///< Mean hand speed of the lift (and of reaching when fitts_slope = 0), m/s.
  double reaction_time = 0.3;  ///< Delay after the object appears, s.
  double squeeze_time = 0.35;  ///< Trigger 0 -> 1, s.
  double fitts_intercept = 0;  ///< Fitts's law a: time of a zero-difficulty movement, s.
  double fitts_slope = 0;  ///< Fitts's law b: s per bit of difficulty; 0 = speed-based reach.
  double transport_tolerance = 0.05;  ///< W of the transport to the pre-grasp pose, m.
  double approach_tolerance = 0.02;  ///< W of the final approach to the grasp pose, m.
  double approach_clearance = 0.10;  ///< Stand-off of the pre-grasp pose for a point-sized object, m.
  double size_standoff = 0;  ///< Extra stand-off per m of the object's largest extent.
  /// Opening the hand to the object's size and placing it around it: the final approach takes
  /// this many s longer per m of the object's largest extent (grip aperture grows with size).
  double aperture_time = 0;
  double learning_gain = 0;  ///< Practice: the first grasp is (1 + gain) times slower than a practised one.
  double learning_exponent = 0.5;  ///< Practice: power-law exponent of the slowdown's decay with grasps done.
  /// Seeing the hand arrive off the planned pose, the operator corrects it (a corrective
  /// submovement) until the grasp centre is within this distance of the plan's, taking
  /// fitts_time(a, b, error, tolerance); 0 = no correction.
  double correction_tolerance = 0;
  /// Thin objects are approached more carefully: the correction tolerance is at most this
  /// fraction of the object's smallest extent; 0 = no such bound.
  double thin_tolerance_fraction = 0;

  /// The skill of one person of a group: `speed` multiplies the reach speed and divides the
  /// reaction, squeeze and Fitts times; `precision` multiplies the pose errors.
  OperatorSkill scaled(double speed, double precision) const;
};

/// Built-in skill profiles: "perfect", "experienced", "inexperienced".
/// Throws std::invalid_argument naming the unknown profile.
OperatorSkill skill_profile(const std::string& name);

/// Why `skill` is not usable (a negative or non-finite value, a zero speed, tolerance or squeeze
/// time), or empty if it is.
std::string validate_skill(const OperatorSkill& skill);

/// Skill profiles from text: `[name]` starts a profile, which begins as the built-in profile of
/// that name (or "experienced" for a new name); `key = value` lines set its fields (the names of
/// OperatorSkill's members; angles in degrees as `orientation_error_deg`); `#` starts a comment.
/// Throws std::invalid_argument naming the line on an unknown key, a bad number or a profile that
/// fails validate_skill.
std::vector<OperatorSkill> parse_skill_profiles(const std::string& text);

/// Fitts's law, Shannon form: a + b log2(1 + distance / width), s. Width must be positive.
double fitts_time(double a, double b, double distance, double width);

/// How much slower than practised the operator is after `grasps_done` grasps of the session:
/// 1 + learning_gain (1 + grasps_done)^-learning_exponent, normalised so that a fully practised
/// operator is 1 (the power law of practice).
double practice_factor(const OperatorSkill& skill, int grasps_done);

/// Phases of one trial.
/// kPutDown only with ScriptedOperator::put_down_before_release.
enum class OperatorPhase { kReact, kReach, kSqueeze, kLift, kHold, kPutDown, kRelease, kDone };

/// A hand pose chosen by the planner, with what the offline closing predicted.
struct GraspPlan {
  Eigen::Isometry3d X_WorldPalm = Eigen::Isometry3d::Identity();  ///< Palm pose when closing.
  Eigen::Vector3d approach_World{0, 0, -1};  ///< Unit direction of the final approach.
  int predicted_blocked = 0;  ///< Capsules blocked in the offline closing.
  bool predicted_grasp = false;  ///< The offline closing grasped, with no penetration.
};

/// What closing the hand fully at a fixed palm pose on a static object gave (no physics): the
/// trigger ramps 0 -> 1 over 0.35 s and stays closed for 0.15 s more, or until no joint moves.
struct OfflineClosing {
  HandController hand;  ///< The hand at the end of the close.
  bool grasped = false;  ///< The grasp rule turned true during the close.
  int blocked = 0;  ///< Capsules blocked at the end.
  bool penetrating = false;  ///< A blocked capsule ended below -0.1 mm (the hand started in the object).
  bool below_table = false;  ///< A capsule ended under the table top.
  double closed_table_depth = 0;  ///< How far the closed hand's capsules reach under the table top, m; 0: clear.
  double open_table_depth = 0;  ///< How far the open hand (palm, capsules) reaches under the table top, m; 0: clear.
  bool opposed = false;  ///< Two contact normals oppose (n_i . n_j < -0.5): a pinch or wrap, not a press.
  GraspMetrics metrics{};  ///< ND and exact signed distances at the end.
  /// The same on the tick the grasp rule first turned true (with `measure_grasp_tick`; else empty).
  GraspMetrics grasp_tick_metrics{};
};
/// `measure_grasp_tick`: also measure the grasp tick (one more HandController::measure; the
/// planner's fit needs it, its ranking does not).
OfflineClosing close_offline(const std::shared_ptr<const HandRig>& rig, const GraspSettings& settings,
                             const ObjectModel& model, const Eigen::Isometry3d& X_WorldObject,
                             const Eigen::Isometry3d& X_WorldPalm, double dt, double table_height = 0.0,
                             bool measure_grasp_tick = false);

/// A search for the palm pose whose offline closing gives the lowest ND (see nd_pose_search).
struct NdSearchSettings {
  int random_poses = 400;  ///< Random orientations and grasp-centre positions around the object.
  int refinements = 300;  ///< Small moves (2 mm, 2 deg) from the best pose, kept when better.
  int min_hits = 5;  ///< Capsules whose ND sweep must hit for a grasp to count.
  std::uint64_t seed = 1;
};

/// The pose an ND search kept.
struct NdSearchResult {
  std::optional<OfflineClosing> best;  ///< Empty if no clean grasp was found.
  double nd_mean_mm = 0;  ///< Mean |ND| over the capsules of `best` whose sweep hit.
  int poses_tried = 0, clean_grasps = 0;
};

/// An oracle operator: tries palm poses all around the object (random orientations, grasp centre
/// within ~2 cm of the object's centre, each backed off along the back of the hand until the hand
/// is clear of the object), then refines the best by small random moves, closing the hand offline
/// with precise closing at each. Keeps the clean grasp with the lowest mean |ND|: the grasp rule
/// holds, no blocked capsule ends below -0.1 mm, the palm box is outside the object, no capsule
/// under the table top at `table_height`, and at least `min_hits` capsules whose sweep hits.
/// A random search: its result is an upper estimate of the lowest ND the rig can reach on the
/// object, whoever operates it. Deterministic for a given seed.
NdSearchResult nd_pose_search(const std::shared_ptr<const HandRig>& rig, const ObjectModel& model,
                              const Eigen::Isometry3d& X_WorldObject, const NdSearchSettings& search, double dt,
                              double table_height = 0.0);

/// Whether plan_grasp fits typed plans to the surface: yes unless the environment has
/// TELEGRASP_PLAN_FIT=off (read once). The sanitizer runs set it: under ASan the fit's hundreds of
/// offline closings per plan take seconds, and bots on a free-running server fall behind.
bool plan_fit_enabled();

/// Plans a grasp by closing the hand offline (no physics) at candidate poses around the object
/// (top and side approaches, both axes, offsets, heights) with precise closing, and keeping the
/// best: a grasp with no capsule ending inside the object, then opposing contact normals (a pinch
/// or wrap, not a press), then fingers above the table top at `table_height` (the World's is 0),
/// then the most capsules blocked, then the least HandError. For a rig with grasp types, as people
/// plan: also along the object's box sides, off the centre of a long object and, from the top,
/// 3 cm across the palm either way (the thumb then meets an upright box's face), and closing across
/// the shortest side a hand can reach on the table (closes_across_shortest_side) first, then in
/// force closure by epsilon (0.01 steps), before opposing normals; of the best 16 in force
/// closure, the one that stays so in most of 8 closings with the palm 3 mm or 3 degrees off,
/// unless some of those closings do not grasp at all: then one of the best 8 out of closure
/// grasped in at least 2 more of them replaces it (the one grasped in most). Then, as a person
/// settles the fingers on the surface, the plan is fitted: random moves of the palm (normal, 1 cm
/// and 10 degrees, or a half or a quarter of that) from it and from up to 7 others as robust under the aim errors, 40
/// each and then 200 from the best, keep a move when the closing stays as good (clean, no capsule deeper under the
/// table top, in closure and across if it was, as robust under the aim errors) and lowers the mean |ND| of the closing
/// and its 8 aim errors (not with TELEGRASP_PLAN_FIT=off: plan_fit_enabled()). Deterministic.
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

  /// Starts a trial at time `t0` for the object at X_WorldObject, the hand at X_WorldPalm, after
  /// `grasps_done` grasps of the session (see practice_factor); without it, a practised operator
  /// (factor 1: tools that do not run sessions, such as telegrasp-bot and telegrasp-eval run).
  void begin(const ObjectModel& model, const Eigen::Isometry3d& X_WorldObject, const Eigen::Isometry3d& X_WorldPalm,
             double t0, std::optional<int> grasps_done = std::nullopt);
  /// The same with a plan made beforehand (plan_grasp for the object at its pose now), so that
  /// many operators of one object kind need one plan: plan_grasp of an upright object moved on
  /// the table by d is its plan at the old pose moved by d (telegrasp-bench-scale --active plans
  /// once per model and moves the plan to each object).
  void begin(const GraspPlan& plan, const ObjectModel& model, const Eigen::Isometry3d& X_WorldPalm, double t0,
             std::optional<int> grasps_done = std::nullopt);
  /// The input for time `t`; `grasped` is whether the hand holds the trial's object now.
  ControllerInput next(double t, bool grasped);
  /// What the operator sees of the hand before next(): how far the shown hand (the resolved pose)
  /// stands above the controller, m. A person lifts the hand they see: at the lift the controller
  /// rises kLiftHeight plus this (a hand the table held up rejoins its controller on the way up,
  /// so it and the object still rise kLiftHeight). 0 until told.
  void see_hand_raised(double metres) { hand_raised_ = metres; }
  /// After the hold, lower the object back to where it was grasped (kPutDown) and open there, as
  /// a person tidies a shared table; by default the hand opens at the top and the object drops
  /// (telegrasp-eval removes it after each trial). Call before begin().
  void put_down_before_release(bool on) { put_down_ = on; }

  OperatorPhase phase() const { return phase_; }
  bool done() const { return phase_ == OperatorPhase::kDone; }
  /// True if the object was held through the whole lift and hold.
  bool held_after_lift() const { return held_after_lift_; }
  int attempts() const { return attempts_; }
  const GraspPlan& plan() const { return plan_; }

  static constexpr double kLiftHeight = 0.10;
  static constexpr double kHoldTime = 1.0;
  static constexpr int kMaxAttempts = 3;
  static constexpr double kPutDownClearance = 0.005;  ///< kPutDown ends this far above the grasp pose, m.

 private:
  void start_attempt(double t);
  Eigen::Isometry3d noisy(const Eigen::Isometry3d& X);
  double leg_time(double distance, double width) const;
  Eigen::Isometry3d reach_pose(double t) const;
  double lift_duration() const;  // of the lift, and of the put-down

  std::shared_ptr<const HandRig> rig_;
  OperatorSkill skill_;
  GraspSettings settings_;
  double dt_;
  std::mt19937_64 rng_;
  GraspPlan plan_;
  OperatorPhase phase_ = OperatorPhase::kDone;
  // Waypoints of the current motion: from -> via -> to -> corrected, with their times.
  Eigen::Isometry3d X_start_, X_pre_, X_goal_, X_fixed_, X_lifted_;
  Eigen::Isometry3d X_last_ = Eigen::Isometry3d::Identity();
  double t_phase_ = 0, t_via_ = 0, t_end_ = 0, t_fixed_ = 0;
  double trigger_ = 0;
  double hand_raised_ = 0;  // see_hand_raised
  bool put_down_ = false;  // put_down_before_release
  double practice_ = 1;  // practice_factor of this trial
  double standoff_ = 0.10;  // pre-grasp stand-off of this trial's object, m
  double aperture_s_ = 0;  // extra final-approach time for this trial's object's size, s
  double correction_tolerance_ = 0;  // correction tolerance for this trial's object, m
  int attempts_ = 0;
  bool held_after_lift_ = false;
};

}  // namespace telegrasp::sim
