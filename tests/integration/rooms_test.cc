// Rooms: several scenes on one DDS domain, each served by its own telegrasp-server in its own
// DDS partition, found through the scene directory. Over DDS on loopback with real servers:
// - a hand driven in one scene reaches that scene's server and subscribers only;
// - a second server for a scene that is served refuses to start, naming the one that serves it;
// - the directory lists every live server and drops one that stops.
// Times are guards against hangs, not asserted.
#include "process.h"
#include "telegrasp/client/client.h"
#include "test_domain.h"

#include <gtest/gtest.h>

#include <fstream>
#include <sstream>
#include <thread>

namespace telegrasp::testing {
namespace {

using namespace std::chrono_literals;
using client::Client;
using client::ClientOptions;

constexpr auto kGuard = 20s;

ClientOptions in_scene(const std::string& id, int domain, const std::string& scene, unsigned topics = client::kAllTopics) {
  ClientOptions o = client_options(id, domain, topics);
  o.scene = scene;
  return o;
}

std::vector<std::string> server_argv(int domain, const std::string& scene) {
  return {bin("telegrasp-server"), "--domain", std::to_string(domain), "--profile", "loopback", "--scene", scene,
          "--empty-scene"};
}

std::string read_file(const std::string& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

client::ControllerSample hand_in_the_air() {
  client::ControllerSample s;
  s.side = client::HandSide::kRight;
  s.X_WorldPalm.translation() = Eigen::Vector3d(0.3, 0.5, 0.4);
  return s;
}

TEST(RoomsTest, AScenesSamplesReachOnlyThatScene) {
  const DomainLease lease;
  const int domain = lease.domain();
  ChildProcess a(server_argv(domain, "room-a"), work_path("rooms_a_server.log"));
  ChildProcess b(server_argv(domain, "room-b"), work_path("rooms_b_server.log"));
  Client driver(in_scene("driver-a", domain, "room-a"));
  Client watcher_a(in_scene("watcher-a", domain, "room-a"));
  Client watcher_b(in_scene("watcher-b", domain, "room-b"));
  ASSERT_TRUE(driver.wait_for_server(kStartGuard)) << "no server for room-a";
  ASSERT_TRUE(watcher_b.wait_for_server(kStartGuard)) << "no server for room-b";
  EXPECT_EQ(driver.scene(), "room-a");

  // The hand joins room-a: its server, and a subscriber of room-a, see it.
  const client::HandKey hand{"driver-a", client::HandSide::kRight};
  ASSERT_TRUE(eventually(
      [&] {
        driver.publish(hand_in_the_air());
        const auto s = watcher_a.latest_server_status();
        return watcher_a.latest_grasp_state(hand).has_value() && s && s->hands == 1;
      },
      kGuard))
      << "the hand never joined room-a";
  // Keep it there for two of room-b's status periods: room-b's server has no hand and its
  // subscriber never received a sample of it.
  const auto until = std::chrono::steady_clock::now() + 2500ms;
  while (std::chrono::steady_clock::now() < until) {
    driver.publish(hand_in_the_air());
    std::this_thread::sleep_for(11ms);
  }
  const auto b_status = watcher_b.latest_server_status();
  ASSERT_TRUE(b_status);
  EXPECT_EQ(b_status->hands, 0) << "room-b's server took room-a's hand";
  EXPECT_EQ(b_status->inputs_accepted + b_status->inputs_rejected, 0u) << "room-b's server received room-a's samples";
  EXPECT_FALSE(watcher_b.latest_grasp_state(hand).has_value());
  EXPECT_TRUE(watcher_b.latest_hand_skeletons().empty());
  EXPECT_NE(watcher_b.latest_server_status()->incarnation, watcher_a.latest_server_status()->incarnation);
}

TEST(RoomsTest, ASecondServerForAServedSceneRefusesToStart) {
  const DomainLease lease;
  const int domain = lease.domain();
  ChildProcess first(server_argv(domain, "lab"), work_path("rooms_first_server.log"));
  Client watcher(in_scene("watcher", domain, "lab"));
  ASSERT_TRUE(watcher.wait_for_server(kStartGuard));
  const std::uint64_t incarnation = watcher.latest_server_status()->incarnation;

  // A generous claim window: the refusal must not depend on how fast discovery is on a loaded
  // machine (the default, 1.5 s, is what a quiet machine needs).
  std::vector<std::string> second_argv = server_argv(domain, "lab");
  second_argv.insert(second_argv.end(), {"--claim-wait-s", "6"});
  ChildProcess second(second_argv, work_path("rooms_second_server.log"));
  EXPECT_EQ(second.wait(kStartGuard), 1) << read_file(second.log_path());
  char run[17];
  std::snprintf(run, sizeof run, "%016llx", static_cast<unsigned long long>(incarnation));
  const std::string log = read_file(second.log_path());
  EXPECT_NE(log.find("scene 'lab' is already served by"), std::string::npos) << log;
  EXPECT_NE(log.find(run), std::string::npos) << "the refusal names the run that serves the scene: " << log;
  EXPECT_TRUE(first.running()) << "the first server must go on";
  EXPECT_EQ(watcher.latest_server_status()->incarnation, incarnation);
  EXPECT_EQ(watcher.server_restarts(), 0u);
}

TEST(RoomsTest, TheDirectoryListsEveryLiveServer) {
  const DomainLease lease;
  const int domain = lease.domain();
  ChildProcess a(server_argv(domain, "north"), work_path("rooms_north_server.log"));
  ChildProcess b(server_argv(domain, "south"), work_path("rooms_south_server.log"));
  Client directory(in_scene("directory", domain, "elsewhere", client::kSceneDirectory));
  std::vector<client::SceneInfo> scenes;
  ASSERT_TRUE(eventually(
      [&] {
        scenes = directory.scenes();
        return scenes.size() == 2 && scenes[0].serving && scenes[1].serving;
      },
      kStartGuard))
      << scenes.size() << " servers listed";
  EXPECT_EQ(scenes[0].scene, "north");
  EXPECT_EQ(scenes[1].scene, "south");
  for (const auto& s : scenes) {
    EXPECT_NE(s.incarnation, 0u);
    EXPECT_EQ(s.tick_rate_hz, 90.0);
    EXPECT_GE(s.host_cores, 1);
    EXPECT_FALSE(s.host.empty());
  }
  EXPECT_EQ(client::least_loaded_host(scenes), scenes[0].host);  // one host

  // A server that stops leaves the directory (it withdraws its entry).
  ASSERT_EQ(b.stop(), 0);
  ASSERT_TRUE(eventually([&] { return directory.scenes().size() == 1; }, kGuard));
  EXPECT_EQ(directory.scenes()[0].scene, "north");
  // One that dies goes when its liveliness lease (3 s) runs out.
  a.signal(SIGKILL);
  EXPECT_TRUE(eventually([&] { return directory.scenes().empty(); }, kGuard));
}

TEST(RoomsTest, ASceneNameThatWouldMatchOtherScenesIsRefused) {
  const DomainLease lease;
  // DDS partition names match as fnmatch patterns: "*" would receive every scene's samples.
  for (const std::string& bad : {std::string("*"), std::string("room?"), std::string("a[bc]"), std::string(65, 'x')})
    EXPECT_THROW(Client(in_scene("c", lease.domain(), bad)), std::runtime_error) << "'" << bad << "'";
  ChildProcess server({bin("telegrasp-server"), "--scene", "*"}, work_path("rooms_wildcard_server.log"));
  EXPECT_EQ(server.wait(kGuard), 2) << read_file(server.log_path());
}

}  // namespace
}  // namespace telegrasp::testing
