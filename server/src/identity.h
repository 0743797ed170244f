// ClientIdentities: with DDS Security, the certificate subject each remote participant
// authenticated as, and the subject each client id belongs to.
#pragma once

#include "input_mailbox.h"

#include <cstddef>
#include <map>
#include <mutex>
#include <optional>
#include <string>

namespace eprosima::fastrtps::rtps {
class ParticipantProxyData;
}  // namespace eprosima::fastrtps::rtps

namespace telegrasp::server {

/// The certificate subject (RFC 2253, e.g. "CN=alice,O=telegrasp") a discovered participant
/// authenticated with: the "dds.cert.sn" property of its PKI-DH IdentityToken; "" if it has none
/// (no DDS Security).
std::string certificate_subject(const eprosima::fastrtps::rtps::ParticipantProxyData& participant);

/// Binds every client id to the certificate subject that first drove it, for the server's life:
/// another identity never drives that client's hands, even once the owner has left, while the
/// owner may come back from a new participant (a restarted client). Thread-safe: DDS listener
/// threads call all of it.
class ClientIdentities {
 public:
  /// At most this many client ids are bound; an identity asking for more is refused.
  static constexpr std::size_t kMaxClientIds = 65536;

  /// `participant` (its GUID prefix) authenticated as `subject` (may be called again).
  void participant_discovered(const ParticipantKey& participant, const std::string& subject);
  /// `participant` left or was dropped; the client ids of its subject stay bound to it.
  void participant_left(const ParticipantKey& participant);

  /// The owner key under which InputMailbox keeps `participant`'s hands (one per subject, so
  /// every participant of an identity drives its client ids), binding `client_id` to the
  /// participant's subject if it is free. nullopt, and nothing bound, if the participant never
  /// authenticated or `client_id` belongs to another subject.
  std::optional<ParticipantKey> admit(const ParticipantKey& participant, const std::string& client_id);

  /// The subject `participant` authenticated as; "" if unknown.
  std::string subject_of(const ParticipantKey& participant) const;

 private:
  mutable std::mutex mutex_;
  std::map<ParticipantKey, std::string> subjects_;  // live participants
  std::map<std::string, ParticipantKey> subject_keys_;  // subject -> its owner key, made on first sight
  std::map<std::string, std::string> client_subject_;  // client id -> subject
};

}  // namespace telegrasp::server
