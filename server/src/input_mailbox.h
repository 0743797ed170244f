// InputMailbox: where DDS listener threads leave controller states for the simulation thread.
#pragma once

#include "conversions.h"
#include "input_validation.h"
#include "server_config.h"

#include <array>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <functional>
#include <map>
#include <mutex>
#include <optional>
#include <set>
#include <string>
#include <vector>

namespace telegrasp::server {

/// The DDS participant that wrote a sample (its GUID prefix).
using ParticipantKey = std::array<std::uint8_t, 12>;

/// What one client or participant may send (ServerSettings has the configured values).
struct InputLimits {
  int max_hands = 256;  ///< Hands in the scene, all clients together.
  int max_hands_per_participant = 16;  ///< Hands one DDS participant may drive.
  double max_input_rate_hz = 250;  ///< Samples per second per hand (bursts of a tenth of it, at least 10).
  double max_command_rate_hz = 20;  ///< Scene commands per second per client (bursts likewise).
  std::vector<Relay> relays;  ///< Prefixes owned by one participant each (server_config.h).
};

/// A token bucket: `rate` per second, at most `burst` at once.
class RateLimiter {
 public:
  RateLimiter() = default;
  explicit RateLimiter(double rate_hz);
  /// Takes one token at steady time `now_ns`; false if there is none.
  bool take(std::int64_t now_ns);

 private:
  double rate_ = 0, burst_ = 0, tokens_ = 0;
  std::int64_t last_ns_ = 0;
  bool started_ = false;
};

/// Why a client is refused, for the client itself (ClientNotice): `kind` is msg::NOTICE_*.
struct Refusal {
  std::string client_id;
  std::uint8_t kind = 0;
  std::string reason, detail;
  std::uint64_t command_id = 0, count = 0;
};

/// The ClientNotice telling `refusal` to its client (time 0: refusals of inputs and of commands
/// before the scene are taken off the simulation thread, which owns the scene time).
msg::ClientNotice make_client_notice(const Refusal& refusal);

/// An accepted controller state, as the simulation thread takes it.
struct InputSample {
  HandAddress hand;
  msg::ControllerState state;
  std::int64_t received_ns = 0;  ///< steady_clock time of arrival.
};

/// Keeps the newest valid sample per hand until the simulation thread drains it. Every offered
/// sample is validated on its own, then against its hand's history: a client id belongs to the
/// first participant that drives it (or sends a command as it) until all its hands are forgotten
/// or the participant leaves, sequence numbers must grow, each hand gets at most
/// max_input_rate_hz samples a second, each participant at most max_hands_per_participant hands.
/// A client id under a relay's prefix belongs to the participant that holds the prefix (the first
/// to drive or command an id under it, until it leaves), whose hands there count against the
/// relay's max_hands instead.
/// A dropped sample is counted per reason, logged once per client and reason, and told to the
/// client (the notifier) at most once a second per reason. Scene commands pass admit_command()
/// first: the same ownership, and max_command_rate_hz per client.
/// Thread-safe: offer(), admit_command() and forget_participant() from any thread; the rest from
/// the simulation thread.
class InputMailbox {
 public:
  /// `fingers[side]`: finger count of the rig driving that side. `log`: where the one-time
  /// messages go (default stderr).
  InputMailbox(std::array<std::size_t, 2> fingers, int max_hands, std::function<void(const std::string&)> log = {});
  InputMailbox(std::array<std::size_t, 2> fingers, const InputLimits& limits,
               std::function<void(const std::string&)> log = {});

  /// Where refusals go to be told to their client (ClientNotice); default: nowhere. Set before
  /// samples arrive.
  void set_notifier(std::function<void(const Refusal&)> notifier);

  /// Validates and stores `state` from participant `writer`; false if it was dropped.
  bool offer(const msg::ControllerState& state, const ParticipantKey& writer, std::int64_t received_ns);
  /// Counts and logs (as offer() does) a sample of `client_id` dropped before it was offered, e.g.
  /// because another authenticated identity owns the client id (identity.h). Returns false.
  bool refuse(RejectReason reason, const std::string& client_id);

  /// Checks a scene command from participant `writer` at steady time `now_ns` before it is queued:
  /// "" if admitted, else the reason (a key of ServerStatus.commands_rejected_by_reason), counted,
  /// logged once per client and reason, and told to the client.
  /// `writer` unset: with DDS Security, another identity owns the command's client id.
  std::string admit_command(const msg::SceneCommand& command, const std::optional<ParticipantKey>& writer,
                            std::int64_t now_ns);
  /// The participant left the domain: the client ids it owned are free and its hands' histories
  /// forgotten (the scene removes the hands themselves when they fall silent).
  void forget_participant(const ParticipantKey& writer);

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
  /// Commands refused by admit_command(), per reason, since construction.
  std::map<std::string, std::uint64_t> commands_rejected() const;
  /// Refusals handed to the notifier.
  std::uint64_t notices() const;

 private:
  bool reject(RejectReason reason, const std::string& client_id, std::int64_t now_ns, std::string detail = "");
  /// The relay whose prefix starts `client_id`; nullptr if none.
  const Relay* relay_of(const std::string& client_id) const;
  /// Logs once per client and reason (at most kMaxLogged pairs), tells the client at most once a
  /// second per reason (always when `every_time`). Called with mutex_ held.
  void refuse(Refusal refusal, std::int64_t now_ns, bool every_time);
  /// The owner check shared by inputs and commands; binds a free client id to `writer`.
  bool owned_by_other(const std::string& client_id, const ParticipantKey& writer);

  const std::array<std::size_t, 2> fingers_;
  const InputLimits limits_;
  std::function<void(const std::string&)> log_;
  std::function<void(const Refusal&)> notify_;
  mutable std::mutex mutex_;
  std::condition_variable cv_;
  bool woken_ = false;
  struct Client {
    ParticipantKey owner{};
    int hands = 0;
    RateLimiter commands;
  };
  struct KnownHand {
    std::uint64_t last_sequence = 0;
    RateLimiter samples;
  };
  static constexpr std::size_t kMaxLogged = 4096;  // (client, reason) pairs remembered for logs and notices
  std::map<std::string, Client> clients_;
  std::map<ParticipantKey, int> participant_hands_;  // hands outside relay prefixes
  struct RelayState {
    ParticipantKey owner{};
    int hands = 0;
  };
  std::map<const Relay*, RelayState> relay_owners_;  // the relays someone holds
  std::map<HandAddress, KnownHand> hands_;
  std::map<HandAddress, InputSample> pending_;
  std::map<std::pair<std::string, std::string>, std::int64_t> refused_;  // last notice time per (client, reason)
  std::map<std::pair<std::string, std::string>, std::uint64_t> refusal_counts_;
  std::uint64_t accepted_ = 0, notices_ = 0;
  std::array<std::uint64_t, static_cast<int>(RejectReason::kCount)> rejected_{};
  std::map<std::string, std::uint64_t> commands_rejected_;
};

}  // namespace telegrasp::server
