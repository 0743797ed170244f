// Forward kinematics of a hand rig.
#include "telegrasp/sim/hand_kinematics.h"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <limits>

namespace telegrasp::sim {

Eigen::Isometry3d phalanx_pose(const PhalanxSpec& phalanx, const Eigen::Isometry3d& X_PalmParent, double q) {
  Eigen::Isometry3d X = X_PalmParent * phalanx.X_ParentJoint;
  X.linear() = X.linear() * Eigen::AngleAxisd(q, phalanx.axis).toRotationMatrix();
  return X;
}

void forward_kinematics(const HandRig& rig, const std::vector<double>& q,
                        std::vector<Eigen::Isometry3d>* X_PalmPhalanx) {
  const auto& phalanges = rig.phalanges();
  assert(q.size() == phalanges.size());
  X_PalmPhalanx->resize(phalanges.size());
  for (std::size_t i = 0; i < phalanges.size(); ++i) {
    const int parent = phalanges[i].parent;
    const Eigen::Isometry3d X_PalmParent = parent < 0 ? Eigen::Isometry3d::Identity() : (*X_PalmPhalanx)[parent];
    (*X_PalmPhalanx)[i] = phalanx_pose(phalanges[i], X_PalmParent, q[i]);
  }
}

double target_angle(const PhalanxSpec& phalanx, double u) {
  // The default range [0, 1] gives t = u exactly.
  const double t = std::clamp((u - phalanx.closes_from) / (phalanx.closes_until - phalanx.closes_from), 0.0, 1.0);
  return std::clamp(phalanx.open + t * (phalanx.closed - phalanx.open), phalanx.min, phalanx.max);
}

double certified_advance(double rate, double turn, double reach, double radius, double graze) {
  // r - sqrt(r^2 - c^2 / 4) = (c^2 / 4) / (r + sqrt(r^2 - c^2 / 4)) <= c^2 / (4 (1 + sqrt(3) / 2) r) for c <= r.
  const double per_h2 = rate * rate / (7.4 * radius) + turn * turn * reach / 8;
  if (!(per_h2 > 0)) return std::numeric_limits<double>::infinity();
  const double h = std::sqrt(std::max(graze, 0.0) / per_h2);
  return rate > 0 ? std::min(h, radius / rate) : h;
}

}  // namespace telegrasp::sim
