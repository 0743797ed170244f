// HandRig: the immutable description of a hand, loaded from a protobuf text file.
#pragma once

#include "telegrasp/sim/grasp_type.h"
#include "telegrasp/sim/ids.h"

#include <Eigen/Geometry>

#include <array>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

namespace telegrasp::sim {

enum class HandSide { kUnspecified, kLeft, kRight };

/// A rig file is missing, unreadable or invalid; what() names the file and the field.
class RigError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Capsule trigger on a phalanx, in the phalanx frame, with the ND metric points.
struct CapsuleSpec {
  Eigen::Vector3d p_PhalanxA, p_PhalanxB;  ///< Segment end points.
  double radius = 0;
  Eigen::Vector3d p_PhalanxCTc;  ///< Centre point on the palmar skin at mid-length.
  Eigen::Vector3d p_PhalanxSp;  ///< Sweep start inside the finger.
};

/// One phalanx: a revolute joint at its frame origin, and an optional capsule.
struct PhalanxSpec {
  std::string name;
  int finger = 0;  ///< Index into HandRig::fingers().
  int parent = -1;  ///< Phalanx index of the parent, -1 for the palm.
  Eigen::Isometry3d X_ParentJoint = Eigen::Isometry3d::Identity();  ///< Joint frame at angle 0.
  Eigen::Vector3d axis = Eigen::Vector3d::UnitY();  ///< Unit axis in the joint frame.
  double open = 0, closed = 0;  ///< Radians at trigger 0 and 1.
  double closes_from = 0, closes_until = 1;  ///< The closing input's range over which it goes from open to closed.
  double min = 0, max = 0;  ///< Radian limits.
  double max_speed = 0;  ///< rad/s.
  double length = 0;  ///< Display length along +x; 0 for an extra axis of the next phalanx's joint.
  std::optional<CapsuleSpec> capsule;
};

/// One finger: its phalanges, proximal first.
struct FingerSpec {
  std::string name;
  std::vector<PhalanxId> phalanges;
};

/// A sphere in the palm frame.
struct PalmSphere {
  Eigen::Vector3d p_PalmCenter{0, 0, 0};
  double radius = 0;
};

/// One member of a grasp-rule group: a phalanx, or the palm contact volume.
struct GraspTerm {
  bool palm = false;
  PhalanxId phalanx;
};

/// Immutable hand description: skeleton, joints, trigger volumes, metric points, grasp rule.
class HandRig {
 public:
  /// Loads and validates a rig text file; throws RigError naming the file and field.
  static HandRig load(const std::string& path);
  /// Parses and validates rig text; `source` names it in errors.
  static HandRig parse(const std::string& text, const std::string& source);
  /// Path of a rig shipped with telegrasp ("human_right", "human_left", "human_right_opposable",
  /// "human_left_opposable", "gripper3").
  static std::string builtin_path(const std::string& name);
  /// Name of the built-in human hand a server, bot or eval uses when no rig is given: the hand
  /// with the opposable thumb and grasp types ("human_right_opposable", "human_left_opposable").
  static std::string default_human(HandSide side);

  /// This rig reflected through the palm's x-z plane: a right hand becomes a left hand.
  [[nodiscard]] HandRig mirrored() const;

  const std::string& name() const { return name_; }
  HandSide side() const { return side_; }
  const std::vector<PhalanxSpec>& phalanges() const { return phalanges_; }
  const std::vector<FingerSpec>& fingers() const { return fingers_; }
  /// Grasped = AND over groups of (OR over terms).
  const std::vector<std::vector<GraspTerm>>& grasp_rule() const { return grasp_rule_; }
  const PalmSphere& selection_sphere() const { return selection_sphere_; }
  const PalmSphere& palm_contact() const { return palm_contact_; }
  double nd_sweep_radius() const { return nd_sweep_radius_; }
  double nd_sweep_beyond() const { return nd_sweep_beyond_; }
  const Eigen::Vector3d& palm_half_extent() const { return palm_half_extent_; }
  const Eigen::Vector3d& p_PalmGraspCenter() const { return p_PalmGraspCenter_; }
  /// Coulomb friction coefficient of the hand's contacts (grasp quality; an object may set its own).
  double friction() const { return friction_; }
  /// Phalanges that carry a capsule, in rig order.
  const std::vector<PhalanxId>& capsule_phalanges() const { return capsule_phalanges_; }
  /// Phalanx by name, or an invalid id.
  PhalanxId find(const std::string& name) const;
  /// Whether the rig lists grasp type `type` (its own closing and rule); kOther: always.
  bool has_grasp_type(GraspType type) const;
  /// Whether the rig lists any grasp type.
  bool has_grasp_types() const;
  /// The phalanges as grasp type `type` closes them: phalanges() with the type's open and closed
  /// angles and closing ranges; phalanges() itself for kOther or a type the rig does not list.
  const std::vector<PhalanxSpec>& phalanges(GraspType type) const;
  /// The grasp rule of type `type`: its own if it has one, else grasp_rule().
  const std::vector<std::vector<GraspTerm>>& grasp_rule(GraspType type) const;

 private:
  HandRig() = default;
  void finish(const std::string& source);
  // A joint's closing under one grasp type.
  struct JointClosing {
    double open = 0, closed = 0, closes_from = 0, closes_until = 1;
  };
  // A listed grasp type: per phalanx, its closing; its own rule (empty: the rig's).
  struct TypeClosing {
    std::vector<JointClosing> joints;
    std::vector<std::vector<GraspTerm>> grasp_rule;
    std::vector<PhalanxSpec> phalanges;  // phalanges_ with `joints` applied (finish())
  };

  std::string name_;
  HandSide side_ = HandSide::kUnspecified;
  std::vector<PhalanxSpec> phalanges_;
  std::vector<FingerSpec> fingers_;
  std::vector<std::vector<GraspTerm>> grasp_rule_;
  PalmSphere selection_sphere_, palm_contact_;
  double nd_sweep_radius_ = 0, nd_sweep_beyond_ = 0;
  Eigen::Vector3d palm_half_extent_{0, 0, 0};
  Eigen::Vector3d p_PalmGraspCenter_{0, 0, 0};
  double friction_ = 0.5;
  std::vector<PhalanxId> capsule_phalanges_;
  std::array<std::optional<TypeClosing>, kGraspTypeCount> types_;  // by GraspType
};

}  // namespace telegrasp::sim
