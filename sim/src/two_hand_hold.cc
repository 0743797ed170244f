// The pose of an object held by two hands (definition in two_hand_hold.h).
#include "telegrasp/sim/two_hand_hold.h"

namespace telegrasp::sim {
namespace {

// The unit direction from a to b, or zero when they (nearly) coincide.
Eigen::Vector3d direction(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  const Eigen::Vector3d span = b - a;
  const double length = span.norm();
  return length < kTwoHandMinSpan ? Eigen::Vector3d::Zero() : Eigen::Vector3d(span / length);
}

// The twist of `q` about the unit `axis` (swing-twist decomposition); identity when q has none
// (a half turn about an axis perpendicular to `axis`).
Eigen::Quaterniond twist_about(const Eigen::Quaterniond& q, const Eigen::Vector3d& axis) {
  const Eigen::Vector3d along = q.vec().dot(axis) * axis;
  Eigen::Quaterniond twist(q.w(), along.x(), along.y(), along.z());
  const double norm = twist.norm();
  if (norm < 1e-12) return Eigen::Quaterniond::Identity();
  twist.coeffs() /= norm;
  return twist;
}

// R_B: the swing taking the join's direction to the current one, then the first hand's twist
// about the join's direction; the first hand's rotation alone when there is no direction.
Eigen::Matrix3d hold_rotation(const TwoHandHold& hold, const Eigen::Matrix3d& dR1, const Eigen::Vector3d& d) {
  if (hold.d_World.isZero() || d.isZero()) return dR1;
  const Eigen::Quaterniond swing = Eigen::Quaterniond::FromTwoVectors(hold.d_World, d);
  const Eigen::Quaterniond rest = swing.conjugate() * Eigen::Quaterniond(dR1);
  return (swing * twist_about(rest, hold.d_World)).toRotationMatrix();
}

}  // namespace

TwoHandHold start_two_hand_hold(const Eigen::Isometry3d& X_WorldPalm1, const Eigen::Vector3d& p_Palm1Attach,
                                const Eigen::Isometry3d& X_WorldPalm2, const Eigen::Vector3d& p_Palm2Attach,
                                const Eigen::Isometry3d& X_WorldObject) {
  TwoHandHold hold;
  hold.p_Palm1Attach = p_Palm1Attach;
  hold.p_Palm2Attach = p_Palm2Attach;
  hold.R_WorldPalm1 = X_WorldPalm1.linear();
  const Eigen::Vector3d a1 = X_WorldPalm1 * p_Palm1Attach;
  const Eigen::Vector3d a2 = X_WorldPalm2 * p_Palm2Attach;
  hold.d_World = direction(a1, a2);
  hold.X_MidObject = X_WorldObject;
  hold.X_MidObject.translation() -= 0.5 * (a1 + a2);
  return hold;
}

Eigen::Isometry3d two_hand_object_pose(const TwoHandHold& hold, const Eigen::Isometry3d& X_WorldPalm1,
                                       const Eigen::Isometry3d& X_WorldPalm2) {
  const Eigen::Vector3d a1 = X_WorldPalm1 * hold.p_Palm1Attach;
  const Eigen::Vector3d a2 = X_WorldPalm2 * hold.p_Palm2Attach;
  const Eigen::Matrix3d dR1 = X_WorldPalm1.linear() * hold.R_WorldPalm1.transpose();
  Eigen::Isometry3d X_WorldMid = Eigen::Isometry3d::Identity();
  X_WorldMid.linear() = hold_rotation(hold, dR1, direction(a1, a2));
  X_WorldMid.translation() = 0.5 * (a1 + a2);
  return X_WorldMid * hold.X_MidObject;
}

}  // namespace telegrasp::sim
