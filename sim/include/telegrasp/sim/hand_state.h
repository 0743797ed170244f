// HandState: the mutable per-tick state of one hand (resolved and tracked pose, velocities,
// joint angles and their poses, blocked phalanges, selection, grasp type, the grasped object).
#pragma once

#include "telegrasp/sim/grasp_type.h"
#include "telegrasp/sim/ids.h"

#include <Eigen/Geometry>

#include <cstdint>
#include <vector>

namespace telegrasp::sim {

/// The mutable per-tick state of one hand.
struct HandState {
  Eigen::Isometry3d X_WorldPalm = Eigen::Isometry3d::Identity();  ///< Resolved: the pose that grasps and is shown.
  Eigen::Isometry3d X_WorldTracked = Eigen::Isometry3d::Identity();  ///< The controller's pose, as last tracked.
  Eigen::Vector3d v_WorldPalm{0, 0, 0};  ///< Linear velocity, m/s.
  Eigen::Vector3d w_WorldPalm{0, 0, 0};  ///< Angular velocity, rad/s.
  bool has_pose = false;
  double trigger = 0;
  std::vector<double> curls;
  std::vector<double> q;  ///< Joint angle per phalanx, rad.
  std::vector<Eigen::Isometry3d> X_PalmPhalanx;  ///< Forward kinematics of q.
  std::vector<std::uint8_t> blocked;  ///< Per phalanx.
  std::vector<double> blocked_angle;  ///< Joint angle when it blocked.
  bool palm_contact = false;
  ObjectId selected;
  /// How the fingers close: chosen from the selected object's shape and the hand's pose while no
  /// phalanx is blocked (kOther with no object, or a type the rig does not list), then kept until
  /// every phalanx has let go.
  GraspType grasp_type = GraspType::kOther;
  ObjectId grasped;
  Eigen::Isometry3d X_PalmObject = Eigen::Isometry3d::Identity();  ///< While grasped.

  /// X_WorldPalm minus X_WorldTracked position, world frame, m (what a person sees of the resolve).
  [[nodiscard]] Eigen::Vector3d resolve_offset() const { return X_WorldPalm.translation() - X_WorldTracked.translation(); }
};

}  // namespace telegrasp::sim
