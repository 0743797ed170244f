// Tests the start-up checks of telegrasp::client::Client: bad options throw std::runtime_error
// naming the field (or file, or profile) at fault; good options make a working client.
#include "telegrasp/client/client.h"
#include "test_domain.h"

#include <gtest/gtest.h>

#include <stdexcept>
#include <string>
#include <vector>

namespace telegrasp::client {
namespace {

// Options that make a working client, on a DDS domain no concurrent test uses. The lease lives
// as long as the test process (each test runs in a process of its own under ctest).
ClientOptions good_options() {
  static const telegrasp::testing::DomainLease lease;
  ClientOptions o;
  o.client_id = "options-test";
  o.domain = lease.domain();
  o.topics = 0;
  return o;
}

// The message of the std::runtime_error Client(o) throws, or "" if it does not throw.
std::string construction_error(const ClientOptions& o) {
  try {
    Client client(o);
  } catch (const std::runtime_error& e) {
    return e.what();
  }
  return "";
}

#define EXPECT_ERROR_MENTIONS(options, text)                                                \
  do {                                                                                      \
    const std::string error = construction_error(options);                                  \
    EXPECT_NE(error, "") << "no error";                                                     \
    EXPECT_NE(error.find(text), std::string::npos) << "'" << error << "' lacks " << (text); \
  } while (false)

// One bad field of otherwise good options, and what the error must mention.
struct BadOption {
  const char* name;
  void (*spoil)(ClientOptions&);
  std::vector<std::string> mentions;
};

// In test output, a row by its name.
void PrintTo(const BadOption& bad, std::ostream* os) { *os << bad.name; }

class ClientOptionsRejects : public ::testing::TestWithParam<BadOption> {};

TEST_P(ClientOptionsRejects, NamingTheFieldAtFault) {
  ClientOptions o = good_options();
  GetParam().spoil(o);
  for (const std::string& text : GetParam().mentions) EXPECT_ERROR_MENTIONS(o, text);
}

INSTANTIATE_TEST_SUITE_P(
    ClientOptionsTest, ClientOptionsRejects,
    ::testing::Values(
        BadOption{"AnEmptyClientId", [](ClientOptions& o) { o.client_id = ""; }, {"client_id"}},
        BadOption{"AClientIdWithANulCharacter",
                  [](ClientOptions& o) { o.client_id = std::string("ab\0cd", 5); },
                  {"client_id"}},
        BadOption{"AClientIdLongerThan64Characters",
                  [](ClientOptions& o) { o.client_id = std::string(65, 'x'); },
                  {"client_id", "65"}},
        BadOption{"ADomainBelow0", [](ClientOptions& o) { o.domain = -1; }, {"domain"}},
        BadOption{"ADomainAbove232", [](ClientOptions& o) { o.domain = 233; }, {"domain"}},
        BadOption{"AnEmptyProfile", [](ClientOptions& o) { o.profile = ""; }, {"profile"}},
        BadOption{"AProfileNotInTheFile", [](ClientOptions& o) { o.profile = "no_such_profile"; }, {"no_such_profile"}},
        BadOption{"AMissingProfilesFile",
                  [](ClientOptions& o) { o.profiles_file = "/nonexistent/telegrasp_profiles.xml"; },
                  {"/nonexistent/telegrasp_profiles.xml"}},
        BadOption{
            "UnknownTopicBits", [](ClientOptions& o) { o.topics = (kAllTopics | kSceneDirectory) + 1; }, {"topics"}}),
    [](const ::testing::TestParamInfo<BadOption>& info) { return std::string(info.param.name); });

TEST(ClientOptionsTest, AcceptsTheLimits) {
  ClientOptions o = good_options();
  o.client_id = std::string(64, 'x');
  Client client(o);
  EXPECT_EQ(client.client_id(), o.client_id);
  // Nobody else is on this (leased) domain: no server.
  EXPECT_FALSE(client.wait_for_server(std::chrono::milliseconds(50)));
}

TEST(ClientOptionsTest, RejectsValuesTheWireCannotCarry) {
  Client client(good_options());
  ControllerSample six_curls;
  six_curls.curls.assign(6, 0.5);
  EXPECT_THROW(client.publish(six_curls), std::invalid_argument);
  SceneCommand long_model;
  long_model.model = std::string(129, 'm');
  EXPECT_THROW(client.send_command(long_model), std::invalid_argument);
  // Neither used up a number.
  EXPECT_EQ(client.publish(ControllerSample{}), 1u);
  EXPECT_EQ(client.send_command(SceneCommand{}), 1u);
}

TEST(ClientOptionsTest, RejectsASceneNameThatIsAPartitionPattern) {
  ClientOptions o = good_options();
  o.scene = "room*";
  EXPECT_ERROR_MENTIONS(o, "ClientOptions.scene");
  EXPECT_ERROR_MENTIONS(o, "room*");
  o.scene = "room-1";
  EXPECT_EQ(construction_error(o), "");
  EXPECT_EQ(Client(o).scene(), "room-1");
  EXPECT_EQ(scene_name_error("room-1"), "");
}

TEST(ClientOptionsTest, RejectsADiscoveryServerThatIsNotHostPort) {
  ClientOptions o = good_options();
  o.discovery_servers = {"127.0.0.1:99999"};
  EXPECT_ERROR_MENTIONS(o, "127.0.0.1:99999");
  EXPECT_NE(discovery_server_error("127.0.0.1:99999"), "");
  EXPECT_EQ(discovery_server_error("127.0.0.1:11811"), "");
}

TEST(ClientOptionsTest, TheLeastLoadedHostIsTheOneWithTheLowestLoadPerCore) {
  auto scene = [](const std::string& host, double load, int hands) {
    SceneInfo s;
    s.host = host;
    s.host_load = load;
    s.hands = hands;
    return s;
  };
  EXPECT_FALSE(least_loaded_host({}));
  EXPECT_EQ(least_loaded_host({scene("a", 0.9, 1), scene("b", 0.2, 40), scene("c", 0.5, 0)}), "b");
  // A host's load is the highest any of its servers reports.
  EXPECT_EQ(least_loaded_host({scene("a", 0.3, 0), scene("a", 0.8, 0), scene("b", 0.5, 0)}), "b");
  // Equal loads: fewer hands served there, then the name.
  EXPECT_EQ(least_loaded_host({scene("a", 0.5, 4), scene("b", 0.5, 2), scene("b", 0.5, 1)}), "b");
  EXPECT_EQ(least_loaded_host({scene("b", 0.5, 0), scene("a", 0.5, 0)}), "a");
}

}  // namespace
}  // namespace telegrasp::client
