// HandController: the grasp system of sim/README.md (sections 3-6) for one hand, advanced one tick
// at a time. Its inputs, state and outputs have headers of their own: controller_input.h,
// object_view.h, grasp_settings.h, hand_state.h, grasp_metrics.h, contact.h.
#pragma once

#include "telegrasp/sim/contact.h"
#include "telegrasp/sim/controller_input.h"
#include "telegrasp/sim/grasp_metrics.h"
#include "telegrasp/sim/grasp_quality.h"
#include "telegrasp/sim/grasp_settings.h"
#include "telegrasp/sim/hand_rig.h"
#include "telegrasp/sim/hand_state.h"
#include "telegrasp/sim/ids.h"
#include "telegrasp/sim/object_model.h"
#include "telegrasp/sim/object_view.h"
#include "telegrasp/sim/pose_resolver.h"
#include "telegrasp/sim/quality_worker.h"

#include <Eigen/Geometry>

#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace telegrasp::sim {

/// What happened on a tick.
struct HandTickEvents {
  bool grasped = false;  ///< The grasp rule turned true: attach `state().grasped`.
  bool released = false;  ///< The grasp rule turned false: hand `released_object` back to physics.
  ObjectId released_object;
  Eigen::Isometry3d X_WorldReleased = Eigen::Isometry3d::Identity();  ///< Its pose as the hand let go.
};

/// The four components (selection, interaction manager, finger movement, grasping logic)
/// for one hand. Deterministic: equal inputs give bit-identical states.
class HandController {
 public:
  /// Throws std::invalid_argument for a non-positive contact tolerance or speed scale.
  HandController(std::shared_ptr<const HandRig> rig, GraspSettings settings);

  /// Advances one tick of `dt` seconds (dt <= 0: nothing happens). An input that fails
  /// validate_input is ignored (the hand keeps its last pose, trigger and curls). While an object
  /// is grasped its pose is taken as X_WorldPalm * X_PalmObject, not from `objects`.
  HandTickEvents tick(const ControllerInput& input, double dt, std::span<const ObjectView> objects);

  /// Drops any grasp and blocking (e.g. the object was removed); returns the object released.
  ObjectId release();

  const HandState& state() const { return state_; }
  const HandRig& rig() const { return *rig_; }
  const GraspSettings& settings() const { return settings_; }
  /// Metrics of the current grasp (taken on the grasp tick), if an object is grasped; with
  /// defer_grasp_metrics(), empty until set_grasp_metrics() delivers them.
  const std::optional<GraspMetrics>& grasp_metrics() const { return metrics_; }
  /// The grasp tick no longer takes the grasp's metrics (every capsule's ND sweep and exact
  /// signed distance, the palm's: most of that tick's cost); grasp_tick_metrics() takes them
  /// later, on a copy of the hand made right after the grasp tick. The World does this and has
  /// its QualityWorker take them with the grasp's quality.
  void defer_grasp_metrics() { defer_metrics_ = true; }
  /// The metrics of the grasp made on the last tick (measure() against the object as the grasp
  /// tick saw it): bit-identical to those the grasp tick takes without defer_grasp_metrics().
  /// Only on a hand whose last tick grasped (or a copy of it); otherwise empty.
  std::optional<GraspMetrics> grasp_tick_metrics() const;
  /// Delivers the metrics of grasp number `grasp` (grasp_serial()) to grasp_metrics(); ignored
  /// for another grasp than the current one.
  void set_grasp_metrics(std::uint64_t grasp, GraspMetrics metrics);
  /// Contacts of the current grasp at the object's current pose (recomputed in the object frame
  /// only when asked after the hand's shape changed while holding).
  std::vector<Contact> contacts() const;
  /// ND and signed distances of the hand as it is now while holding (the statistics kept while
  /// the object is held; the grasp tick's are in grasp_metrics()); empty when not holding.
  std::optional<GraspMetrics> hold_metrics() const;
  /// Counts the grasps this hand has made: the grasp a quality belongs to (set_quality()).
  std::uint64_t grasp_serial() const { return grasp_serial_; }
  /// The inputs of the grasp quality of the current contacts (QualityJob's contacts, friction:
  /// the held object's, else the rig's; torque scale: its radius; the volume setting), or nothing
  /// when not holding. The World hands them to its QualityWorker.
  std::optional<QualityJob> quality_inputs() const;
  /// Delivers the quality of a contact set of grasp number `grasp` (grasp_serial()): from now on
  /// hold_metrics() carries it, and with `grasp_tick` grasp_metrics() too. A quality of another
  /// grasp than the current one is ignored. Until the first arrives both carry kPendingQuality.
  void set_quality(std::uint64_t grasp, const GraspQuality& quality, bool grasp_tick);
  /// The contacts the grasp quality is taken of (object frame): `contacts` (those of contacts())
  /// less any not finite and those within 1 mm and 2.6 degrees of one kept before them. The
  /// QualityWorker reuses a quality for a later set whose wrenches W are within d = 1e-11 of a
  /// set it computed among the hand's last 8 (same column count, largest distance between
  /// corresponding columns). Bound on a reused quality's error: the two hulls are within
  /// Hausdorff distance d, and epsilon is 1-Lipschitz in it, so epsilon is off by at most d +
  /// 1e-12 (1e-12: the least epsilon reported as closure); the volumes differ by at most kappa6
  /// ((R + d)^6 - R^6) ~ 31 R^5 d (Steiner's formula for V(K + dB), each quermassintegral of K at
  /// most that of the ball B_R holding it; kappa6 = pi^3 / 6, R the largest wrench norm, <=
  /// sqrt(2 (1 + mu^2)) as contacts lie within the torque scale of the centre of mass): about
  /// 1e-8 for mu <= 1. Except where grasp_quality() itself jumps (a set at its flatness threshold
  /// gives all zero). A one-hand hold recomputes a contact set's wrenches bit-identically, so it
  /// reuses exact matches only; d absorbs the rounding of two-hand holds.
  static std::vector<QualityContact> quality_contacts(std::span<const Contact> contacts);
  /// World pose of the grasped object, if any.
  std::optional<Eigen::Isometry3d> grasped_object_pose() const;
  /// Keeps holding the grasped object where it now is (the World moves an object two hands hold):
  /// X_PalmObject = X_WorldPalm^-1 * X_WorldObject. Does nothing when no object is grasped.
  void reattach(const Eigen::Isometry3d& X_WorldObject);

  /// ND and exact signed distances of every capsule against `object` (an analysis tool).
  GraspMetrics measure(const ObjectView& object) const;

 private:
  struct Capsule;  // a capsule placed in the object frame
  Capsule capsule_in_object(PhalanxId id, const Eigen::Isometry3d& X_ObjectPalm) const;
  // Sets the tracked pose, the resolved pose and the hand's velocity from `input`.
  void track(const ControllerInput& input, double dt, std::span<const ObjectView> objects);
  // Recomputes X_PalmPhalanx along one finger from state_.q.
  void update_finger_poses(int finger);
  // The phases of tick(), in order (interaction manager and finger movement in step_finger).
  const ObjectView* choose_object(std::span<const ObjectView> objects, ObjectView& held_view, HandTickEvents& events);
  void select_object(std::span<const ObjectView> objects);
  void choose_type(const ObjectView* object, const Eigen::Isometry3d& X_ObjectPalm);
  // The joints as the hand's grasp type closes them (rig().phalanges(state_.grasp_type)).
  const std::vector<PhalanxSpec>& joints() const { return rig_->phalanges(state_.grasp_type); }
  void carry_gap_bounds(const ObjectView* object, const Eigen::Isometry3d& X_ObjectPalm);
  void step_finger(int finger, double u, double dt, const ObjectView* object, const Eigen::Isometry3d& X_ObjectPalm);
  void apply_grasp_rule(const ObjectView* object, const Eigen::Isometry3d& X_ObjectPalm, HandTickEvents& events);
  // The phases of step_finger(), on one finger's FingerStep.
  struct FingerStep;
  enum class Probe { kFree, kBlocked, kDepenetrated, kOvershot };  // what probe_capsule found
  bool unblock_phalanges(const FingerStep& step);
  bool plan_motion(const FingerStep& step, double dt, int held, bool& closing);
  void block_at_rest(const FingerStep& step);
  bool pushed_into(const FingerStep& step, int id, const Capsule& c) const;
  void close_discrete(const FingerStep& step);
  void close_precise(const FingerStep& step);
  Probe probe_capsule(const FingerStep& step, std::size_t m, double s, double rate, double& ds, double& ds_safe,
                      double certified, bool predicted);
  [[nodiscard]] double predicted_advance(std::size_t m, double s, double certified, double tol) const;
  void set_fraction(const FingerStep& step, double s);
  void forget_bounds(const FingerStep& step);
  void block(int id);
  void refresh_contacts() const;
  // The paper's ND of capsule `id` (the sweep from Sp toward CTc), X_ObjectPalm as measure() takes it.
  struct NdSweep {
    bool hit = false;
    double nd = 0;
    double length = 0;  // |CTc - Sp| in the object frame
  };
  NdSweep nd_midlength(PhalanxId id, const Eigen::Isometry3d& X_ObjectPalm, const ObjectModel& model) const;
  // Exact closest pair between capsule `id`'s segment [a, b] (object frame) and the object's mesh:
  // the cached one while the capsule has not moved since, else searched within `reach` first (a
  // touching capsule's is near), then everywhere.
  SegmentQuery closest_pair(PhalanxId id, ObjectId object, const MeshDistance& mesh, const Eigen::Vector3d& a,
                            const Eigen::Vector3d& b, double reach) const;
  // The hand's shape as the contact and metric caches see it: joint angles, blocks, palm, grasp.
  std::vector<double> shape_key() const;
  // Precise mode: extends a finger the hand pushed into the object until it rests on the surface;
  // false if even the fully extended finger penetrates (the hand itself is inside).
  bool depenetrate(int finger, const Eigen::Isometry3d& X_ObjectPalm, const ObjectView& object);

  std::shared_ptr<const HandRig> rig_;
  GraspSettings settings_;
  HandState state_;
  std::optional<GraspMetrics> metrics_;
  bool defer_metrics_ = false;
  std::optional<ObjectView> grasp_view_;  // the object as the last tick grasped it
  // While grasped: the palm in the object's frame as the fingers use it, X_PalmObject's inverse
  // with the bits of the frame they closed in (or of the last reattach), so that the grasp
  // tick's contacts and every later tick find each capsule's last exact query at the same pose.
  Eigen::Isometry3d X_ObjectPalm_held_ = Eigen::Isometry3d::Identity();
  const ObjectModel* held_model_ = nullptr;
  // Caches keyed on shape_key() (the hand-object pose is fixed while holding).
  mutable std::vector<Contact> contacts_;  // object frame only; world fields filled by contacts()
  mutable std::vector<double> contacts_key_;
  mutable std::optional<GraspMetrics> hold_metrics_;
  mutable std::vector<double> hold_metrics_key_;
  std::uint64_t grasp_serial_ = 0;
  GraspQuality hold_quality_ = kPendingQuality;  // the last delivered by set_quality()
  // reach_[k][m]: bound on the distance from joint k to any point of capsule m's segment.
  std::vector<std::vector<double>> reach_;
  // Per phalanx, the triangle last found nearest to its capsule: a search hint (speed only).
  std::vector<std::uint32_t> hint_;
  // Per phalanx, a lower bound on its capsule's gap to bound_object_ (-inf: unknown), kept
  // across ticks and shrunk by every motion, so far-away capsules need no query.
  std::vector<double> gap_bound_;
  std::vector<double> palm_reach_;  // bound on |p| over the capsule's segment, palm frame
  ObjectId bound_object_;
  Eigen::Isometry3d bound_X_ObjectPalm_ = Eigen::Isometry3d::Identity();
  // The query caches and step_finger's work space (hand_controller.cc), written by const
  // methods too. A copy of the controller copies them: it ticks exactly as the original would.
  struct Scratch;
  struct ScratchHolder {
    ScratchHolder();
    ScratchHolder(const ScratchHolder& other);
    ScratchHolder& operator=(const ScratchHolder& other);
    ScratchHolder(ScratchHolder&& other) noexcept;
    ScratchHolder& operator=(ScratchHolder&& other) noexcept;
    ~ScratchHolder();
    Scratch* operator->() const { return scratch.get(); }
    std::unique_ptr<Scratch> scratch;
  };
  ScratchHolder scratch_;
  // The resolved pose's search, and the hand's volumes it keeps outside (palm, then capsules).
  PoseResolver resolver_;
  std::vector<HandVolume> volumes_;
  std::size_t palm_volume_count_ = 0;
};

}  // namespace telegrasp::sim
