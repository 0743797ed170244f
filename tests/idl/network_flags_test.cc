// Tests idl/network_flags.h: the network flags every program parses, each value checked with a
// message naming the flag, the range or rule and the text given; options without a scene take no
// --scene; network_args writes back what parse_network_flag reads.
#include "telegrasp/idl/network_flags.h"

#include <gtest/gtest.h>

#include <string>
#include <vector>

namespace telegrasp::idl {
namespace {

// A usage error that returns to the test instead of exiting.
struct Refused {
  std::string what;
};
void refuse(const std::string& what) { throw Refused{what}; }

// Parses one flag with `value` onto `options`: "" when taken, the refusal, or "not taken".
template <class Options>
std::string parse(const std::string& flag, const std::string& value, Options& options) {
  try {
    return parse_network_flag(flag, [&] { return value; }, options, refuse) ? "" : "not taken";
  } catch (const Refused& r) {
    return r.what;
  }
}

TEST(NetworkFlagsTest, ReadsEachFlagAndNamesTheMistake) {
  NetworkFlags o;
  EXPECT_EQ(parse("--domain", "232", o), "");
  EXPECT_EQ(o.domain, 232);
  EXPECT_EQ(parse("--domain", "999", o), "--domain expects a whole number in [0, 232], got '999'");
  for (const char* bad : {"", "-1", "1.5", "7x", " 7", "99999999999999999999999"})
    EXPECT_NE(parse("--domain", bad, o), "") << "'" << bad << "'";
  EXPECT_EQ(o.domain, 232);
  EXPECT_EQ(parse("--profile", "", o),
            "--profile expects a participant profile name (loopback, shm, udp, lan, wan, secure), got ''");
  EXPECT_EQ(parse("--profile", "udp", o), "");
  EXPECT_EQ(parse("--profiles", "/tmp/p.xml", o), "");
  EXPECT_EQ(parse("--scene", "room-1", o), "");
  EXPECT_EQ(parse("--scene", "*", o).rfind("--scene: ", 0), 0u);
  EXPECT_EQ(parse("--discovery-server", "127.0.0.1:11811", o), "");
  EXPECT_EQ(parse("--discovery-server", "127.0.0.1:0", o).rfind("--discovery-server: ", 0), 0u);
  EXPECT_EQ(parse("--trials", "3", o), "not taken");
}

TEST(NetworkFlagsTest, OptionsWithoutASceneTakeNoSceneFlags) {
  struct {
    int domain = 0;
    std::string profile = "loopback", profiles_file;
  } bench;
  EXPECT_EQ(parse("--domain", "7", bench), "");
  EXPECT_EQ(bench.domain, 7);
  EXPECT_EQ(parse("--scene", "room", bench), "not taken");
  EXPECT_EQ(parse("--discovery-server", "127.0.0.1", bench), "not taken");
  EXPECT_EQ(network_args(bench), (std::vector<std::string>{"--domain", "7", "--profile", "loopback"}));
}

TEST(NetworkFlagsTest, ArgumentsReadBackToTheSameFlags) {
  const NetworkFlags given{12, "udp", "/tmp/p.xml", "room", {"127.0.0.1:11811", "127.0.0.1:11812"}};
  const std::vector<std::string> args = network_args(given);
  NetworkFlags back;
  for (std::size_t i = 0; i + 1 < args.size(); i += 2) EXPECT_EQ(parse(args[i], args[i + 1], back), "") << args[i];
  EXPECT_EQ(back.domain, given.domain);
  EXPECT_EQ(back.profile, given.profile);
  EXPECT_EQ(back.profiles_file, given.profiles_file);
  EXPECT_EQ(back.scene, given.scene);
  EXPECT_EQ(back.discovery_servers, given.discovery_servers);
}

}  // namespace
}  // namespace telegrasp::idl
