// Tests of apply_security (idl/include/telegrasp/idl/security.h): which files a participant
// profile with DDS Security gets, and the errors that name what is missing.
#include "telegrasp/idl/security.h"

#include <fastdds/dds/domain/qos/DomainParticipantQos.hpp>
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <stdexcept>
#include <string>

namespace telegrasp::idl {
namespace {

namespace fs = std::filesystem;

eprosima::fastdds::dds::DomainParticipantQos secure_qos() {
  eprosima::fastdds::dds::DomainParticipantQos qos;
  qos.properties().properties().emplace_back("dds.sec.auth.plugin", "builtin.PKI-DH");
  return qos;
}

std::map<std::string, std::string> properties(const eprosima::fastdds::dds::DomainParticipantQos& qos) {
  std::map<std::string, std::string> m;
  for (const auto& p : qos.properties().properties()) m[p.name()] = p.value();
  return m;
}

// A security folder as make-certs.sh lays it out (empty files), with identity "alice".
class SecurityFilesTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("telegrasp_security_files_" + std::to_string(::getpid()));
    fs::create_directories(dir_ / "alice");
    for (const char* f : {"ca.pem", "governance.p7s", "alice/cert.pem", "alice/key.pem", "alice/permissions.p7s"})
      std::ofstream(dir_ / f) << "x";
  }
  void TearDown() override { fs::remove_all(dir_); }
  // What apply_security throws for `files`, "" if it does not.
  std::string error(const SecurityFiles& files) {
    auto qos = secure_qos();
    try {
      apply_security(qos, "secure", files);
    } catch (const std::runtime_error& e) {
      return e.what();
    }
    return "";
  }
  fs::path dir_;
};

TEST_F(SecurityFilesTest, AddsTheIdentitysFiles) {
  auto qos = secure_qos();
  ASSERT_TRUE(apply_security(qos, "secure", {dir_.string(), "alice"}));
  const auto p = properties(qos);
  EXPECT_EQ(p.at("dds.sec.auth.builtin.PKI-DH.identity_ca"), "file://" + (dir_ / "ca.pem").string());
  EXPECT_EQ(p.at("dds.sec.auth.builtin.PKI-DH.identity_certificate"), "file://" + (dir_ / "alice/cert.pem").string());
  EXPECT_EQ(p.at("dds.sec.auth.builtin.PKI-DH.private_key"), "file://" + (dir_ / "alice/key.pem").string());
  EXPECT_EQ(p.at("dds.sec.access.builtin.Access-Permissions.permissions_ca"), "file://" + (dir_ / "ca.pem").string());
  EXPECT_EQ(p.at("dds.sec.access.builtin.Access-Permissions.governance"),
            "file://" + (dir_ / "governance.p7s").string());
  EXPECT_EQ(p.at("dds.sec.access.builtin.Access-Permissions.permissions"),
            "file://" + (dir_ / "alice/permissions.p7s").string());
}

TEST_F(SecurityFilesTest, AnIdentitysOwnCaAndGovernanceComeFirst) {
  std::ofstream(dir_ / "alice/ca.pem") << "x";
  std::ofstream(dir_ / "alice/governance.p7s") << "x";
  auto qos = secure_qos();
  ASSERT_TRUE(apply_security(qos, "secure", {dir_.string(), "alice"}));
  EXPECT_EQ(properties(qos).at("dds.sec.auth.builtin.PKI-DH.identity_ca"),
            "file://" + (dir_ / "alice/ca.pem").string());
  EXPECT_EQ(properties(qos).at("dds.sec.access.builtin.Access-Permissions.governance"),
            "file://" + (dir_ / "alice/governance.p7s").string());
}

TEST_F(SecurityFilesTest, ErrorsNameWhatIsMissing) {
  EXPECT_NE(error({"", "alice"}).find("TELEGRASP_SECURITY_DIR"), std::string::npos);
  EXPECT_NE(error({dir_.string(), ""}).find("TELEGRASP_IDENTITY"), std::string::npos);
  EXPECT_NE(error({dir_.string(), "bob"}).find("no identity 'bob'"), std::string::npos);
  fs::remove(dir_ / "alice/key.pem");
  EXPECT_NE(error({dir_.string(), "alice"}).find((dir_ / "alice/key.pem").string()), std::string::npos);
}

TEST_F(SecurityFilesTest, ProfileWithoutSecurity) {
  eprosima::fastdds::dds::DomainParticipantQos qos;
  EXPECT_FALSE(uses_security(qos));
  EXPECT_FALSE(apply_security(qos, "loopback", {}));
  for (const auto& [name, value] : properties(qos)) EXPECT_NE(name.rfind("dds.sec.", 0), 0u) << name;
  // A folder given for a profile without security would run unprotected: refused.
  EXPECT_THROW(apply_security(qos, "loopback", {dir_.string(), "alice"}), std::runtime_error);
}

}  // namespace
}  // namespace telegrasp::idl
