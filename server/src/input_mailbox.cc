#include "input_mailbox.h"

#include <algorithm>
#include <chrono>
#include <iostream>

namespace telegrasp::server {

namespace {

std::int64_t steady_now_ns() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

}  // namespace

// Bursts of one second's worth: a client (or a server just started, or starved of CPU) whose
// samples queued up and arrive at once is not punished; a flood still gets `rate` a second.
RateLimiter::RateLimiter(double rate_hz) : rate_(rate_hz), burst_(std::max(10.0, rate_hz)), tokens_(burst_) {}

bool RateLimiter::take(std::int64_t now_ns) {
  if (rate_ <= 0) return true;  // unlimited
  if (started_ && now_ns > last_ns_) tokens_ = std::min(burst_, tokens_ + rate_ * (now_ns - last_ns_) * 1e-9);
  if (!started_ || now_ns > last_ns_) last_ns_ = now_ns;
  started_ = true;
  if (tokens_ < 1) return false;
  tokens_ -= 1;
  return true;
}

msg::ClientNotice make_client_notice(const Refusal& r) {
  msg::ClientNotice n;
  n.client_id(r.client_id.substr(0, 64));
  n.kind(r.kind);
  n.reason(r.reason);
  n.detail(r.detail.substr(0, 256));
  n.command_id(r.command_id);
  n.count(r.count);
  return n;
}

namespace {
InputLimits with_max_hands(int max_hands) {
  InputLimits limits;
  limits.max_hands = max_hands;
  return limits;
}
}  // namespace

InputMailbox::InputMailbox(std::array<std::size_t, 2> fingers, int max_hands,
                           std::function<void(const std::string&)> log)
    : InputMailbox(fingers, with_max_hands(max_hands), std::move(log)) {}

InputMailbox::InputMailbox(std::array<std::size_t, 2> fingers, const InputLimits& limits,
                           std::function<void(const std::string&)> log)
    : fingers_(fingers), limits_(limits), log_(std::move(log)) {
  if (!log_) log_ = [](const std::string& line) { std::cerr << line << std::endl; };
}

void InputMailbox::set_notifier(std::function<void(const Refusal&)> notifier) {
  std::lock_guard lock(mutex_);
  notify_ = std::move(notifier);
}

void InputMailbox::refuse(Refusal r, std::int64_t now_ns, bool every_time) {
  const auto key = std::make_pair(r.client_id, r.reason);
  auto count = refusal_counts_.find(key);
  if (count == refusal_counts_.end()) {
    if (refusal_counts_.size() >= kMaxLogged) {  // a flood of fresh ids: counted, not logged nor told
      if (refusal_counts_.size() == kMaxLogged) {
        log_("telegrasp-server: more than " + std::to_string(kMaxLogged) +
             " clients refused: further ones are only counted in ServerStatus");
        refusal_counts_[{"", ""}] = 0;  // says it once
      }
      return;
    }
    count = refusal_counts_.emplace(key, 0).first;
    log_("telegrasp-server: refusing " +
         std::string(r.kind == msg::NOTICE_INPUT_REJECTED ? "controller states" : "scene commands") + " of client '" +
         r.client_id + "': " + r.reason + (r.detail.empty() ? "" : " (" + r.detail + ")") +
         " (counted in ServerStatus; said once per client and reason, and told to the client)");
  }
  r.count = ++count->second;
  auto last = refused_.find(key);
  if (!every_time && last != refused_.end() && now_ns - last->second < 1'000'000'000) return;
  refused_[key] = now_ns;
  if (notify_) {
    ++notices_;
    notify_(r);
  }
}

bool InputMailbox::reject(RejectReason reason, const std::string& client_id, std::int64_t now_ns,
                          std::string detail) {
  ++rejected_[static_cast<int>(reason)];
  if (detail.empty()) switch (reason) {
    case RejectReason::kClientIdOwnedByAnotherParticipant:
      detail = "another participant drives this client id: pick another";
      break;
    case RejectReason::kTooManyHands:
      detail = "the scene has its " + std::to_string(limits_.max_hands) + " hands";
      break;
    case RejectReason::kTooManyHandsForParticipant:
      detail = "a participant may drive at most " + std::to_string(limits_.max_hands_per_participant) + " hands";
      break;
    case RejectReason::kRateLimited:
      detail =
          "more than " + std::to_string(static_cast<int>(limits_.max_input_rate_hz)) + " samples per second per hand";
      break;
    default:
      break;
  }
  refuse({client_id, msg::NOTICE_INPUT_REJECTED, std::string(name(reason)), detail, 0, 0}, now_ns, false);
  return false;
}

bool InputMailbox::refuse(RejectReason reason, const std::string& client_id) {
  std::lock_guard lock(mutex_);
  return reject(reason, client_id, steady_now_ns());
}

const Relay* InputMailbox::relay_of(const std::string& client_id) const {
  for (const Relay& r : limits_.relays)
    if (client_id.starts_with(r.prefix)) return &r;  // prefixes never start one another
  return nullptr;
}

bool InputMailbox::owned_by_other(const std::string& client_id, const ParticipantKey& writer) {
  if (const Relay* relay = relay_of(client_id)) {
    const auto [held, free] = relay_owners_.try_emplace(relay, RelayState{writer, 0});
    if (!free && held->second.owner != writer) return true;
  }
  auto client = clients_.find(client_id);
  if (client == clients_.end()) {
    clients_.emplace(client_id, Client{writer, 0, RateLimiter(limits_.max_command_rate_hz)});
    return false;
  }
  return client->second.owner != writer;
}

bool InputMailbox::offer(const msg::ControllerState& state, const ParticipantKey& writer, std::int64_t received_ns) {
  std::lock_guard lock(mutex_);
  const std::string client_id = state.client_id().to_string();
  RejectReason reason{};
  if (!validate_controller_state(state, fingers_, reason)) return reject(reason, client_id, received_ns);
  const HandAddress hand{client_id, state.hand_side()};
  auto known = hands_.find(hand);
  if (known == hands_.end()) {  // a new hand: every check before anything is bound
    auto client = clients_.find(client_id);
    const Relay* relay = relay_of(client_id);
    const auto relay_state = relay ? relay_owners_.find(relay) : relay_owners_.end();
    if ((client != clients_.end() && client->second.owner != writer) ||
        (relay_state != relay_owners_.end() && relay_state->second.owner != writer))
      return reject(RejectReason::kClientIdOwnedByAnotherParticipant, client_id, received_ns,
                    relay ? "client ids starting with '" + relay->prefix + "' belong to another participant (a relay)"
                          : "");
    if (static_cast<int>(hands_.size()) >= limits_.max_hands)
      return reject(RejectReason::kTooManyHands, client_id, received_ns);
    if (relay && relay_state != relay_owners_.end() && relay_state->second.hands >= relay->max_hands)
      return reject(RejectReason::kTooManyHandsForParticipant, client_id, received_ns,
                    "relay '" + relay->prefix + "' may drive at most " + std::to_string(relay->max_hands) + " hands");
    if (!relay && participant_hands_[writer] >= limits_.max_hands_per_participant)
      return reject(RejectReason::kTooManyHandsForParticipant, client_id, received_ns);
    owned_by_other(client_id, writer);  // binds the id (and its relay's prefix) if free
    ++clients_.at(client_id).hands;
    if (relay)
      ++relay_owners_.at(relay).hands;
    else
      ++participant_hands_[writer];
    known = hands_.emplace(hand, KnownHand{0, RateLimiter(limits_.max_input_rate_hz)}).first;
    known->second.last_sequence = state.sequence_number();
  } else {
    if (clients_.at(client_id).owner != writer)
      return reject(RejectReason::kClientIdOwnedByAnotherParticipant, client_id, received_ns);
    if (state.sequence_number() <= known->second.last_sequence)
      return reject(RejectReason::kStaleSequence, client_id, received_ns);
    known->second.last_sequence = state.sequence_number();
  }
  if (!known->second.samples.take(received_ns)) return reject(RejectReason::kRateLimited, client_id, received_ns);
  ++accepted_;
  pending_[hand] = InputSample{hand, state, received_ns};
  cv_.notify_one();
  return true;
}

std::string InputMailbox::admit_command(const msg::SceneCommand& command, const std::optional<ParticipantKey>& writer,
                                        std::int64_t now_ns) {
  std::lock_guard lock(mutex_);
  const std::string client_id = command.client_id().to_string();
  std::string reason, detail;
  if (client_id.empty()) {
    reason = "empty_client_id";
    detail = "a scene command needs the sender's client id";
  } else if (!writer || owned_by_other(client_id, *writer)) {
    reason = "client_id_owned_by_another_participant";
    detail = "another participant uses this client id";
  } else if (!clients_.at(client_id).commands.take(now_ns)) {
    reason = "rate_limited";
    detail = "more than " + std::to_string(limits_.max_command_rate_hz) + " commands per second";
  }
  if (reason.empty()) return "";
  ++commands_rejected_[reason];
  refuse({client_id, msg::NOTICE_COMMAND_REJECTED, reason, detail, command.command_id(), 0}, now_ns,
         reason != "rate_limited");
  return reason;
}

void InputMailbox::forget_participant(const ParticipantKey& writer) {
  std::lock_guard lock(mutex_);
  for (auto client = clients_.begin(); client != clients_.end();) {
    if (client->second.owner != writer) {
      ++client;
      continue;
    }
    for (auto hand = hands_.begin(); hand != hands_.end();)
      hand = hand->first.client_id == client->first ? hands_.erase(hand) : std::next(hand);
    client = clients_.erase(client);
  }
  participant_hands_.erase(writer);
  std::erase_if(relay_owners_, [&](const auto& relay) { return relay.second.owner == writer; });
}

bool InputMailbox::wait(std::chrono::steady_clock::time_point deadline) {
  std::unique_lock lock(mutex_);
  bool woken = true;
  while (!woken_ && pending_.empty())
    if (cv_.wait_until(lock, deadline) == std::cv_status::timeout) {
      woken = false;
      break;
    }
  woken_ = false;
  return woken;
}

void InputMailbox::wake() {
  std::lock_guard lock(mutex_);
  woken_ = true;
  cv_.notify_one();
}

std::vector<InputSample> InputMailbox::drain() {
  std::lock_guard lock(mutex_);
  std::vector<InputSample> out;
  out.reserve(pending_.size());
  for (auto& [hand, sample] : pending_) out.push_back(std::move(sample));
  pending_.clear();
  return out;
}

void InputMailbox::forget_hand(const HandAddress& hand) {
  std::lock_guard lock(mutex_);
  if (hands_.erase(hand) == 0) return;
  pending_.erase(hand);
  auto client = clients_.find(hand.client_id);
  if (client == clients_.end()) return;
  if (const Relay* relay = relay_of(hand.client_id)) {
    if (auto r = relay_owners_.find(relay); r != relay_owners_.end()) --r->second.hands;  // the prefix stays held
  } else if (auto p = participant_hands_.find(client->second.owner); p != participant_hands_.end() && --p->second <= 0) {
    participant_hands_.erase(p);
  }
  if (--client->second.hands <= 0) clients_.erase(client);
}

std::uint64_t InputMailbox::accepted() const {
  std::lock_guard lock(mutex_);
  return accepted_;
}

std::array<std::uint64_t, static_cast<int>(RejectReason::kCount)> InputMailbox::rejected() const {
  std::lock_guard lock(mutex_);
  return rejected_;
}

std::map<std::string, std::uint64_t> InputMailbox::commands_rejected() const {
  std::lock_guard lock(mutex_);
  return commands_rejected_;
}

std::uint64_t InputMailbox::notices() const {
  std::lock_guard lock(mutex_);
  return notices_;
}

}  // namespace telegrasp::server
