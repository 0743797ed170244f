#include "identity.h"

#include <fastdds/rtps/builtin/data/ParticipantProxyData.h>
#include <fastdds/rtps/common/Token.h>

namespace telegrasp::server {

std::string certificate_subject(const eprosima::fastrtps::rtps::ParticipantProxyData& participant) {
#if HAVE_SECURITY
  const std::string* sn =
      eprosima::fastrtps::rtps::DataHolderHelper::find_property_value(participant.identity_token_, "dds.cert.sn");
  if (sn != nullptr) return *sn;
#else
  (void)participant;
#endif
  return "";
}

void ClientIdentities::participant_discovered(const ParticipantKey& participant, const std::string& subject) {
  std::lock_guard lock(mutex_);
  subjects_[participant] = subject;
  if (!subject_keys_.count(subject)) {
    // Owner keys are numbered, not GUID prefixes; with security every sample reaches
    // InputMailbox under one, so they never meet a GUID prefix there.
    ParticipantKey key{0xff, 't', 'g', 'i', 'd'};
    std::size_t n = subject_keys_.size() + 1;
    for (std::size_t i = key.size(); i-- > 5 && n != 0; n >>= 8) key[i] = static_cast<std::uint8_t>(n & 0xff);
    subject_keys_.emplace(subject, key);
  }
}

void ClientIdentities::participant_left(const ParticipantKey& participant) {
  std::lock_guard lock(mutex_);
  subjects_.erase(participant);
}

std::optional<ParticipantKey> ClientIdentities::admit(const ParticipantKey& participant, const std::string& client_id) {
  std::lock_guard lock(mutex_);
  const auto subject = subjects_.find(participant);
  if (subject == subjects_.end() || subject->second.empty()) return std::nullopt;
  const auto owner = client_subject_.find(client_id);
  if (owner == client_subject_.end()) {
    if (client_subject_.size() >= kMaxClientIds) return std::nullopt;
    client_subject_.emplace(client_id, subject->second);
  } else if (owner->second != subject->second) {
    return std::nullopt;
  }
  return subject_keys_.at(subject->second);
}

std::string ClientIdentities::subject_of(const ParticipantKey& participant) const {
  std::lock_guard lock(mutex_);
  const auto it = subjects_.find(participant);
  return it == subjects_.end() ? "" : it->second;
}

}  // namespace telegrasp::server
