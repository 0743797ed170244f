#include "input_mailbox.h"

#include <iostream>

namespace telegrasp::server {

InputMailbox::InputMailbox(std::array<std::size_t, 2> fingers, int max_hands,
                           std::function<void(const std::string&)> log)
    : fingers_(fingers), max_hands_(max_hands), log_(std::move(log)) {
  if (!log_) log_ = [](const std::string& line) { std::cerr << line << std::endl; };
}

bool InputMailbox::reject(RejectReason reason, const std::string& client_id) {
  ++rejected_[static_cast<int>(reason)];
  if (logged_.emplace(client_id, reason).second)
    log_("telegrasp-server: dropping controller states of client '" + client_id + "': " + std::string(name(reason)) +
         " (counted in ServerStatus.rejected; said once per client and reason)");
  return false;
}

bool InputMailbox::refuse(RejectReason reason, const std::string& client_id) {
  std::lock_guard lock(mutex_);
  return reject(reason, client_id);
}

bool InputMailbox::offer(const msg::ControllerState& state, const ParticipantKey& writer, std::int64_t received_ns) {
  std::lock_guard lock(mutex_);
  const std::string client_id = state.client_id().to_string();
  RejectReason reason{};
  if (!validate_controller_state(state, fingers_, reason)) return reject(reason, client_id);
  const HandAddress hand{client_id, state.hand_side()};
  auto client = clients_.find(client_id);
  if (client != clients_.end() && client->second.owner != writer)
    return reject(RejectReason::kClientIdOwnedByAnotherParticipant, client_id);
  auto last = last_sequence_.find(hand);
  if (last != last_sequence_.end()) {
    if (state.sequence_number() <= last->second) return reject(RejectReason::kStaleSequence, client_id);
    last->second = state.sequence_number();
  } else {
    if (static_cast<int>(last_sequence_.size()) >= max_hands_) return reject(RejectReason::kTooManyHands, client_id);
    last_sequence_.emplace(hand, state.sequence_number());
    if (client == clients_.end()) client = clients_.emplace(client_id, Client{writer, 0}).first;
    ++client->second.hands;
  }
  ++accepted_;
  pending_[hand] = InputSample{hand, state, received_ns};
  cv_.notify_one();
  return true;
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
  if (last_sequence_.erase(hand) == 0) return;
  pending_.erase(hand);
  auto client = clients_.find(hand.client_id);
  if (client != clients_.end() && --client->second.hands <= 0) clients_.erase(client);
}

std::uint64_t InputMailbox::accepted() const {
  std::lock_guard lock(mutex_);
  return accepted_;
}

std::array<std::uint64_t, static_cast<int>(RejectReason::kCount)> InputMailbox::rejected() const {
  std::lock_guard lock(mutex_);
  return rejected_;
}

}  // namespace telegrasp::server
