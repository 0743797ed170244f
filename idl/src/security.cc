#include "telegrasp/idl/security.h"

#include <fastdds/dds/domain/qos/DomainParticipantQos.hpp>

#include <cstdlib>
#include <filesystem>
#include <stdexcept>

namespace telegrasp::idl {

namespace {

std::string env(const char* name) {
  const char* v = std::getenv(name);
  return v == nullptr ? "" : v;
}

// `name` in the identity's folder if it has its own, else in the security folder.
std::filesystem::path shared_file(const std::filesystem::path& dir, const std::filesystem::path& own,
                                  const char* name) {
  return std::filesystem::is_regular_file(own / name) ? own / name : dir / name;
}

}  // namespace

SecurityFiles security_from_environment() { return {env("TELEGRASP_SECURITY_DIR"), env("TELEGRASP_IDENTITY")}; }

bool uses_security(const eprosima::fastdds::dds::DomainParticipantQos& qos) {
  for (const auto& p : qos.properties().properties())
    if (p.name() == "dds.sec.auth.plugin" && !p.value().empty()) return true;
  return false;
}

bool apply_security(eprosima::fastdds::dds::DomainParticipantQos& qos, const std::string& profile,
                    const SecurityFiles& files) {
  if (!uses_security(qos)) {
    if (!files.dir.empty())
      throw std::runtime_error("a security folder is given (" + files.dir +
                               ", TELEGRASP_SECURITY_DIR or --security) "
                               "but participant profile '" +
                               profile + "' has no DDS Security: use --profile secure, or unset it");
    return false;
  }
  if (files.dir.empty())
    throw std::runtime_error("participant profile '" + profile +
                             "' uses DDS Security: name the folder deploy/security/make-certs.sh made with "
                             "TELEGRASP_SECURITY_DIR (or --security DIR)");
  if (files.identity.empty())
    throw std::runtime_error("participant profile '" + profile +
                             "' uses DDS Security: name this participant's identity (a subfolder of " + files.dir +
                             ") with TELEGRASP_IDENTITY (or --identity NAME)");
  namespace fs = std::filesystem;
  const fs::path dir = fs::absolute(files.dir);
  const fs::path own = dir / files.identity;
  if (!fs::is_directory(own))
    throw std::runtime_error("no identity '" + files.identity + "' in security folder " + dir.string() + " (no " +
                             own.string() + "; make it with deploy/security/make-certs.sh)");
  const fs::path ca = shared_file(dir, own, "ca.pem");
  const fs::path governance = shared_file(dir, own, "governance.p7s");
  const struct {
    const char* property;
    fs::path file;
  } entries[] = {
      {"dds.sec.auth.builtin.PKI-DH.identity_ca", ca},
      {"dds.sec.auth.builtin.PKI-DH.identity_certificate", own / "cert.pem"},
      {"dds.sec.auth.builtin.PKI-DH.private_key", own / "key.pem"},
      {"dds.sec.access.builtin.Access-Permissions.permissions_ca", ca},
      {"dds.sec.access.builtin.Access-Permissions.governance", governance},
      {"dds.sec.access.builtin.Access-Permissions.permissions", own / "permissions.p7s"},
  };
  for (const auto& e : entries) {
    if (!fs::is_regular_file(e.file))
      throw std::runtime_error("DDS Security file " + e.file.string() + " of identity '" + files.identity +
                               "' does not exist");
    qos.properties().properties().emplace_back(e.property, "file://" + e.file.string());
  }
  return true;
}

}  // namespace telegrasp::idl
