// DDS Security for a participant: the per-identity files (made by deploy/security/make-certs.sh)
// that a `secure` participant profile cannot name itself, added to its QoS as properties.
#pragma once

#include "telegrasp/idl/fastdds_fwd.h"

#include <string>

namespace telegrasp::idl {

/// Where a participant's security files are: `dir` as make-certs.sh made it, `identity` one of
/// its identities (a subfolder holding cert.pem, key.pem, permissions.p7s).
struct SecurityFiles {
  std::string dir;
  std::string identity;
};

/// $TELEGRASP_SECURITY_DIR and $TELEGRASP_IDENTITY ("" when unset).
SecurityFiles security_from_environment();

/// Whether `qos` (a participant profile's) enables DDS Security: it names an authentication plugin.
bool uses_security(const eprosima::fastdds::dds::DomainParticipantQos& qos);

/// If `qos` (of participant profile `profile`) uses security, adds the PKI-DH and
/// Access-Permissions file properties of `files`: the CA and governance of the identity's folder
/// if it has its own (ca.pem, governance.p7s), else of `files.dir`; the identity's certificate,
/// private key and permissions. Returns whether it did. Throws std::runtime_error naming the
/// variable or the file that is missing, or when `files` are given for a profile without security
/// (the participant would run unprotected).
bool apply_security(eprosima::fastdds::dds::DomainParticipantQos& qos, const std::string& profile,
                    const SecurityFiles& files);

}  // namespace telegrasp::idl
