#include "input_validation.h"

#include "telegrasp/idl/topics.h"

#include <cmath>

namespace telegrasp::server {

namespace {

double norm(const msg::Quat& q) { return std::sqrt(q.w() * q.w() + q.x() * q.x() + q.y() * q.y() + q.z() * q.z()); }

bool finite(const msg::Pose3& p) {
  const msg::Vec3& t = p.position();
  const msg::Quat& q = p.orientation();
  for (double v : {t.x(), t.y(), t.z(), q.w(), q.x(), q.y(), q.z()})
    if (!std::isfinite(v)) return false;
  return true;
}

}  // namespace

bool finite_unit_pose(const msg::Pose3& pose) {
  return finite(pose) && std::abs(norm(pose.orientation()) - 1.0) <= kUnitQuaternionTolerance;
}

bool validate_controller_state(const msg::ControllerState& s, const std::array<std::size_t, 2>& fingers,
                               RejectReason& reason) {
  auto reject = [&](RejectReason r) {
    reason = r;
    return false;
  };
  if (s.client_id().size() == 0) return reject(RejectReason::kEmptyClientId);
  if (s.hand_side() != idl::kHandLeft && s.hand_side() != idl::kHandRight)
    return reject(RejectReason::kUnknownHandSide);
  if (!finite(s.palm()) || !std::isfinite(s.trigger())) return reject(RejectReason::kNonFinite);
  for (double c : s.curls())
    if (!std::isfinite(c)) return reject(RejectReason::kNonFinite);
  if (!finite_unit_pose(s.palm())) return reject(RejectReason::kQuaternionNotUnit);
  const msg::Vec3& p = s.palm().position();
  if (std::abs(p.x()) > kMaxPalmCoordinate || std::abs(p.y()) > kMaxPalmCoordinate ||
      std::abs(p.z()) > kMaxPalmCoordinate)
    return reject(RejectReason::kPositionOutOfRange);
  if (s.trigger() < 0 || s.trigger() > 1) return reject(RejectReason::kTriggerOutOfRange);
  if (!s.curls().empty() && s.curls().size() != fingers[s.hand_side()]) return reject(RejectReason::kCurlsWrongCount);
  for (double c : s.curls())
    if (c < 0 || c > 1) return reject(RejectReason::kCurlsOutOfRange);
  return true;
}

}  // namespace telegrasp::server
