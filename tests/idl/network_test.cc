// Tests idl/network.h: scene names (DDS partitions) and discovery server lists.
#include "telegrasp/idl/network.h"

#include <fastdds/dds/domain/qos/DomainParticipantQos.hpp>
#include <fastrtps/utils/IPLocator.h>
#include <gtest/gtest.h>

#include <cstdlib>
#include <iterator>

namespace telegrasp::idl {
namespace {

TEST(NetworkTest, SceneNamesAreLettersDigitsAndThreeMarks) {
  EXPECT_EQ(scene_name_error("default"), "");
  EXPECT_EQ(scene_name_error("room-A_2.b"), "");
  EXPECT_EQ(scene_name_error(std::string(64, 'x')), "");
  EXPECT_NE(scene_name_error(""), "");
  EXPECT_NE(scene_name_error(std::string(65, 'x')), "");
  // Partition names are fnmatch patterns: each of these would match other scenes' partitions.
  for (const char* wildcard : {"*", "room?", "r[ab]", "a\\b"})
    EXPECT_NE(scene_name_error(wildcard).find("use letters"), std::string::npos) << wildcard;
  EXPECT_NE(scene_name_error("a b"), "");
  EXPECT_NE(scene_name_error("a/b"), "");
  EXPECT_EQ(scene_partition("lab"), "telegrasp/scene/lab");
}

TEST(NetworkTest, DiscoveryServerListsSplitOnSemicolonsOrCommas) {
  EXPECT_EQ(split_discovery_servers("10.0.0.1:11811;10.0.0.2"),
            (std::vector<std::string>{"10.0.0.1:11811", "10.0.0.2"}));
  EXPECT_EQ(split_discovery_servers(" a:1 , b:2 ;; "), (std::vector<std::string>{"a:1", "b:2"}));
  EXPECT_TRUE(split_discovery_servers("").empty());
}

TEST(NetworkTest, TheEnvironmentFillsWhatIsNotGiven) {
  setenv("TELEGRASP_SCENE", "from-env", 1);
  setenv("TELEGRASP_DISCOVERY_SERVERS", "127.0.0.1:12000;127.0.0.1:12001", 1);
  Network n = resolve_network({});
  EXPECT_EQ(n.scene, "from-env");
  EXPECT_EQ(n.discovery_servers, (std::vector<std::string>{"127.0.0.1:12000", "127.0.0.1:12001"}));
  n = resolve_network({"given", {"127.0.0.1"}});
  EXPECT_EQ(n.scene, "given");
  EXPECT_EQ(n.discovery_servers, (std::vector<std::string>{"127.0.0.1"}));
  setenv("TELEGRASP_SCENE", "bad*", 1);
  try {
    resolve_network({});
    ADD_FAILURE() << "no error for TELEGRASP_SCENE=bad*";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("TELEGRASP_SCENE"), std::string::npos) << e.what();
  }
  unsetenv("TELEGRASP_SCENE");
  unsetenv("TELEGRASP_DISCOVERY_SERVERS");
  n = resolve_network({});
  EXPECT_EQ(n.scene, "default");
  EXPECT_TRUE(n.discovery_servers.empty());
}

TEST(NetworkTest, BadServerAddressesAreNamed) {
  for (const char* bad : {"127.0.0.1:0", "127.0.0.1:70000", "127.0.0.1:x", ":11811", "no-such-host.invalid:11811"}) {
    try {
      resolve_network({"s", {bad}});
      ADD_FAILURE() << "no error for " << bad;
    } catch (const std::runtime_error& e) {
      EXPECT_NE(std::string(e.what()).find(bad), std::string::npos) << e.what();
    }
  }
}

TEST(NetworkTest, ServersBecomeClientDiscoveryWithTheCliServersPrefixes) {
  eprosima::fastdds::dds::DomainParticipantQos qos;
  apply_discovery_servers(qos, {});
  EXPECT_EQ(qos.wire_protocol().builtin.discovery_config.discoveryProtocol,
            eprosima::fastrtps::rtps::DiscoveryProtocol_t::SIMPLE)
      << "no servers: the profile's discovery stays";
  apply_discovery_servers(qos, {"10.1.2.3", "localhost:12345"});
  const auto& d = qos.wire_protocol().builtin.discovery_config;
  EXPECT_EQ(d.discoveryProtocol, eprosima::fastrtps::rtps::DiscoveryProtocol_t::CLIENT);
  ASSERT_EQ(d.m_DiscoveryServers.size(), 2u);
  const auto& first = d.m_DiscoveryServers.front();
  const auto& second = *std::next(d.m_DiscoveryServers.begin());
  // `fastdds discovery -i N` names its server 44.53.<N>.5f.45.50.52.4f.53.49.4d.41.
  eprosima::fastrtps::rtps::GuidPrefix_t zero, one;
  std::istringstream("44.53.00.5f.45.50.52.4f.53.49.4d.41") >> zero;
  std::istringstream("44.53.01.5f.45.50.52.4f.53.49.4d.41") >> one;
  EXPECT_EQ(first.guidPrefix, zero);
  EXPECT_EQ(second.guidPrefix, one);
  ASSERT_EQ(first.metatrafficUnicastLocatorList.size(), 1u);
  const auto& l0 = *first.metatrafficUnicastLocatorList.begin();
  const auto& l1 = *second.metatrafficUnicastLocatorList.begin();
  EXPECT_EQ(eprosima::fastrtps::rtps::IPLocator::ip_to_string(l0), "10.1.2.3");
  EXPECT_EQ(l0.port, 11811u);
  EXPECT_EQ(eprosima::fastrtps::rtps::IPLocator::ip_to_string(l1), "127.0.0.1");
  EXPECT_EQ(l1.port, 12345u);
}

}  // namespace
}  // namespace telegrasp::idl
