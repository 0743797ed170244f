// InputMailbox: where DDS listener threads leave controller states for the simulation thread.
#pragma once

#include "conversions.h"
#include "input_validation.h"

#include <array>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <functional>
#include <map>
#include <mutex>
#include <set>
#include <string>
#include <vector>

namespace telegrasp::server {

/// The DDS participant that wrote a sample (its GUID prefix).
using ParticipantKey = std::array<std::uint8_t, 12>;

/// An accepted controller state, as the simulation thread takes it.
struct InputSample {
  HandAddress hand;
  msg::ControllerState state;
  std::int64_t received_ns = 0;  ///< steady_clock time of arrival.
};

/// Keeps the newest valid sample per hand until the simulation thread drains it. Every offered
/// sample is validated on its own, then against its hand's history: a client id belongs to the
/// first participant that drives it until all its hands are forgotten, and sequence numbers must
/// grow. A dropped sample is counted per reason and logged once per client and reason.
/// Thread-safe: offer() from any thread; the rest from the simulation thread.
class InputMailbox {
 public:
  /// `fingers[side]`: finger count of the rig driving that side. `log`: where the one-time
  /// messages go (default stderr).
  InputMailbox(std::array<std::size_t, 2> fingers, int max_hands, std::function<void(const std::string&)> log = {});

  /// Validates and stores `state` from participant `writer`; false if it was dropped.
  bool offer(const msg::ControllerState& state, const ParticipantKey& writer, std::int64_t received_ns);
  /// Counts and logs (as offer() does) a sample of `client_id` dropped before it was offered, e.g.
  /// because another authenticated identity owns the client id (identity.h). Returns false.
  bool refuse(RejectReason reason, const std::string& client_id);

  /// Blocks until a sample is pending, wake() is called, or `deadline` passes. True if woken (a
  /// sample or wake()) before the deadline, false if the deadline came first.
  bool wait(std::chrono::steady_clock::time_point deadline);
  /// Wakes wait(), or the next wait() if none is waiting (a command arrived, or shutdown).
  void wake();
  /// Takes the pending samples, the newest per hand, in hand order.
  std::vector<InputSample> drain();
  /// The hand is gone: its sequence history is dropped, and a client with no hands left no longer
  /// belongs to its participant.
  void forget_hand(const HandAddress& hand);

  std::uint64_t accepted() const;
  /// Drops per reason since construction.
  std::array<std::uint64_t, static_cast<int>(RejectReason::kCount)> rejected() const;

 private:
  bool reject(RejectReason reason, const std::string& client_id);

  const std::array<std::size_t, 2> fingers_;
  const int max_hands_;
  std::function<void(const std::string&)> log_;
  mutable std::mutex mutex_;
  std::condition_variable cv_;
  bool woken_ = false;
  struct Client {
    ParticipantKey owner{};
    int hands = 0;
  };
  std::map<std::string, Client> clients_;
  std::map<HandAddress, std::uint64_t> last_sequence_;  // known hands
  std::map<HandAddress, InputSample> pending_;
  std::set<std::pair<std::string, RejectReason>> logged_;
  std::uint64_t accepted_ = 0;
  std::array<std::uint64_t, static_cast<int>(RejectReason::kCount)> rejected_{};
};

}  // namespace telegrasp::server
