#include "input_validation.h"

#include "telegrasp/idl/topics.h"

#include <cmath>

namespace telegrasp::server {

bool validate_controller_state(const msg::ControllerState& s, const std::array<std::size_t, 2>& fingers,
                               RejectReason& reason) {
  auto reject = [&](RejectReason r) {
    reason = r;
    return false;
  };
  if (s.client_id().size() == 0) return reject(RejectReason::kEmptyClientId);
  if (s.hand_side() != idl::kHandLeft && s.hand_side() != idl::kHandRight) return reject(RejectReason::kUnknownHandSide);
  const msg::Vec3& p = s.palm().position();
  const msg::Quat& q = s.palm().orientation();
  for (double v : {p.x(), p.y(), p.z(), q.w(), q.x(), q.y(), q.z(), s.trigger()})
    if (!std::isfinite(v)) return reject(RejectReason::kNonFinite);
  for (double c : s.curls())
    if (!std::isfinite(c)) return reject(RejectReason::kNonFinite);
  const double norm = std::sqrt(q.w() * q.w() + q.x() * q.x() + q.y() * q.y() + q.z() * q.z());
  if (std::abs(norm - 1.0) > kUnitQuaternionTolerance) return reject(RejectReason::kQuaternionNotUnit);
  if (s.trigger() < 0 || s.trigger() > 1) return reject(RejectReason::kTriggerOutOfRange);
  if (!s.curls().empty() && s.curls().size() != fingers[s.hand_side()]) return reject(RejectReason::kCurlsWrongCount);
  for (double c : s.curls())
    if (c < 0 || c > 1) return reject(RejectReason::kCurlsOutOfRange);
  return true;
}

}  // namespace telegrasp::server
