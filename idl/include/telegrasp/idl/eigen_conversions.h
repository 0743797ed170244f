// Eigen <-> IDL geometry (Vec3, Pose3): shared by the server's and the client library's
// conversions so both sides read and write poses the same way.
#pragma once

#include "telegrasp/idl/telegrasp.h"

#include <Eigen/Geometry>

namespace telegrasp::idl {

/// A vector as an IDL Vec3 (x, y, z).
inline msg::Vec3 to_msg(const Eigen::Vector3d& v) {
  msg::Vec3 m;
  m.x(v.x());
  m.y(v.y());
  m.z(v.z());
  return m;
}

/// An IDL Vec3 as a vector.
inline Eigen::Vector3d to_eigen(const msg::Vec3& v) { return {v.x(), v.y(), v.z()}; }

/// X_AB as an IDL Pose3: position p_AB, orientation (w, x, y, z) of R_AB. Not normalized: a
/// scaled or sheared linear part gives a non-unit quaternion, which the server rejects.
inline msg::Pose3 to_msg(const Eigen::Isometry3d& X_AB) {
  const Eigen::Quaterniond q_AB(X_AB.linear());
  msg::Pose3 m;
  m.position(to_msg(Eigen::Vector3d(X_AB.translation())));
  m.orientation().w(q_AB.w());
  m.orientation().x(q_AB.x());
  m.orientation().y(q_AB.y());
  m.orientation().z(q_AB.z());
  return m;
}

/// An IDL Pose3 as X_AB; the quaternion is normalized first, so the rotation is exact.
inline Eigen::Isometry3d to_eigen(const msg::Pose3& pose) {
  const msg::Quat& q = pose.orientation();
  Eigen::Isometry3d X_AB = Eigen::Isometry3d::Identity();
  X_AB.linear() = Eigen::Quaterniond(q.w(), q.x(), q.y(), q.z()).normalized().toRotationMatrix();
  X_AB.translation() = to_eigen(pose.position());
  return X_AB;
}

}  // namespace telegrasp::idl
