// Validation of controller states arriving from the network: the reasons a sample is dropped.
#pragma once

#include "telegrasp/idl/telegrasp.h"

#include <array>
#include <string_view>

namespace telegrasp::server {

/// Why a controller state was dropped; the names are the keys of ServerStatus.rejected.
enum class RejectReason {
  kEmptyClientId,
  kUnknownHandSide,
  kNonFinite,
  kQuaternionNotUnit,
  kTriggerOutOfRange,
  kCurlsWrongCount,
  kCurlsOutOfRange,
  kStaleSequence,
  kClientIdOwnedByAnotherParticipant,
  kTooManyHands,
  kTooManyHandsForParticipant,
  kRateLimited,
  kPositionOutOfRange,
  kCount,
};

inline constexpr std::array<std::string_view, static_cast<int>(RejectReason::kCount)> kRejectReasonNames = {
    "empty_client_id",
    "unknown_hand_side",
    "non_finite",
    "quaternion_not_unit",
    "trigger_out_of_range",
    "curls_wrong_count",
    "curls_out_of_range",
    "stale_sequence",
    "client_id_owned_by_another_participant",
    "too_many_hands",
    "too_many_hands_for_participant",
    "rate_limited",
    "position_out_of_range"};

inline std::string_view name(RejectReason r) { return kRejectReasonNames[static_cast<int>(r)]; }

/// A palm farther than this from the origin on any axis, m, is refused: a hand kilometres away
/// only costs tick time (the pose resolver sub-steps the whole way back; found by fuzzing).
inline constexpr double kMaxPalmCoordinate = 100.0;

/// A unit quaternion is one whose norm is within this of 1.
inline constexpr double kUnitQuaternionTolerance = 1e-3;

/// True if the pose's numbers are finite and its quaternion is unit within the tolerance.
bool finite_unit_pose(const msg::Pose3& pose);

/// Checks one sample on its own (not its order or sender): client id, hand side, finite
/// numbers, unit quaternion, palm within kMaxPalmCoordinate, trigger in [0, 1], curls empty or one value in [0, 1] per
/// finger of the side's rig (`fingers[side]`). Returns true if valid, else false with `reason` set.
bool validate_controller_state(const msg::ControllerState& state, const std::array<std::size_t, 2>& fingers,
                               RejectReason& reason);

}  // namespace telegrasp::server
