// Processes killed with SIGKILL (issue 13 section 2): a client killed while it holds an object (the
// server releases it and publishes the release within 1 s), and a server killed while it records
// (the recording keeps everything written before the kill, and telegrasp-replay reads it up to the
// cut). Server, bot and this test's subscriber use the UDP-only profile in the test process's own
// network namespace.
#include "fault_env.h"
#include "process.h"
#include "recording.h"
#include "telegrasp/client/client.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <signal.h>

#include <chrono>
#include <cstdint>
#include <fstream>
#include <iostream>
#include <optional>
#include <set>
#include <string>
#include <thread>
#include <vector>

namespace telegrasp::testing {
namespace {

using namespace std::chrono_literals;
using Clock = std::chrono::steady_clock;
namespace client = telegrasp::client;

constexpr auto kGuard = 60s;  // against a hang only
constexpr double kReleaseWithin = 1.0;  // s of server time from the kill to the release event

const char* kScene = R"(
objects { model: "005_tomato_soup_can" x: 0.45 y: -0.3 }
objects { model: "006_mustard_bottle" x: 0.45 y: -0.1 }
objects { model: "003_cracker_box" x: 0.45 y: 0.1 }
objects { model: "013_apple" x: 0.45 y: 0.3 }
)";

std::unique_ptr<client::Client> subscriber(const std::string& domain) {
  client::ClientOptions o;
  o.client_id = "fault-observer";
  o.domain = std::stoi(domain);
  o.profile = "udp";
  o.topics = client::kGraspEvents | client::kSceneStates | client::kServerStatuses;
  return std::make_unique<client::Client>(o);
}

const client::ObjectState* find_object(const client::SceneState& s, int id) {
  for (const client::ObjectState& o : s.objects)
    if (o.id == id) return &o;
  return nullptr;
}

bool held_by(const client::ObjectState& o, const std::string& client_id) {
  for (const client::HandKey& h : o.holders)
    if (h.client_id == client_id) return true;
  return false;
}

// A bot holding an object is killed with SIGKILL: the server, once the hand has been silent for
// its removal time (0.5 s), releases the object and publishes the release event, within 1 s of
// server time of the kill. The events arrive in order: the hand's grasp, then its release of the
// same object, nothing of that hand in between; afterwards nobody holds the object.
TEST(ClientKilledTest, HeldObjectIsReleasedAndTheReleasePublishedWithinOneSecond) {
  if (!in_private_network()) GTEST_SKIP() << private_network_failure();
  const std::string domain = "1", victim = "victim";
  const std::string config = work_path("killed_client_scene.textproto");
  std::ofstream(config) << kScene;
  ChildProcess server({bin("telegrasp-server"), "--domain", domain, "--profile", "udp", "--config", config},
                      work_path("killed_client_server.log"));
  auto observer = subscriber(domain);
  ASSERT_TRUE(observer->wait_for_server(std::chrono::duration_cast<std::chrono::milliseconds>(kGuard)))
      << server.log_tail();
  ChildProcess bot({bin("telegrasp-bot"), "--client-id", victim, "--hands", "right", "--trials", "3", "--domain",
                    domain, "--profile", "udp", "--timeout-s", "60"},
                   work_path("killed_client_bot.log"));

  // 1. Wait for the bot's first grasp, and see the object held in a scene state after it.
  std::vector<client::GraspEvent> events;
  std::optional<client::GraspEvent> grasp;
  const auto deadline = Clock::now() + kGuard;
  while (!grasp && Clock::now() < deadline) {
    for (client::GraspEvent& e : observer->take_grasp_events()) {
      if (!grasp && e.hand.client_id == victim && e.kind == client::GraspEvent::Kind::kGrasp) grasp = e;
      events.push_back(std::move(e));
    }
    std::this_thread::sleep_for(5ms);
  }
  ASSERT_TRUE(grasp) << "the bot grasped nothing in " << kGuard.count() << " s\n" << bot.log_tail();
  std::optional<client::SceneState> scene;
  while (Clock::now() < deadline) {
    scene = observer->latest_scene_state();
    if (scene && scene->tick > grasp->tick) break;
    std::this_thread::sleep_for(5ms);
  }
  ASSERT_TRUE(scene && scene->tick > grasp->tick) << "no scene state after the grasp";
  const client::ObjectState* o = find_object(*scene, grasp->object_id);
  ASSERT_TRUE(o && held_by(*o, victim)) << "the grasped object " << grasp->object_name << " is not held";

  // 2. Kill the bot while it holds (it lifts, then holds 1 s: the grasp is at most a few ticks old).
  const double server_time_at_kill = scene->time;
  const auto killed_at = Clock::now();
  bot.signal(SIGKILL);

  // 3. The release of that object by that hand, and nothing else of the hand before it.
  std::optional<client::GraspEvent> release;
  std::optional<double> wall_s;
  while (!release && Clock::now() < killed_at + kGuard) {
    for (client::GraspEvent& e : observer->take_grasp_events()) {
      if (!release && e.hand.client_id == victim && e.kind == client::GraspEvent::Kind::kRelease) {
        release = e;
        wall_s = std::chrono::duration<double>(Clock::now() - killed_at).count();
      }
      events.push_back(std::move(e));
    }
    std::this_thread::sleep_for(2ms);
  }
  ASSERT_TRUE(release) << "no release event in " << kGuard.count() << " s after the kill\n" << server.log_tail();
  const double server_s = release->time - server_time_at_kill;
  std::cout << "[ measured ] SIGKILLed client's object " << release->object_name << " released after " << server_s
            << " s of server time, the event received " << *wall_s << " s after the kill\n";
  EXPECT_EQ(release->object_id, grasp->object_id) << "the release is of the object it held";
  EXPECT_EQ(release->hand, grasp->hand);
  EXPECT_GT(release->event_id, grasp->event_id);
  EXPECT_GT(release->tick, grasp->tick);
  for (const client::GraspEvent& e : events)
    if (e.hand.client_id == victim && e.event_id > grasp->event_id && e.event_id < release->event_id)
      ADD_FAILURE() << "event " << e.event_id << " of the killed hand between its grasp and its release";
  EXPECT_LE(server_s, kReleaseWithin) << "released " << server_s << " s (server time) after the kill";
  EXPECT_GT(server_s, 0.2) << "released before the hand could have been seen silent: not the kill's release";

  // 4. Afterwards nobody of the killed client holds anything.
  std::optional<client::SceneState> after;
  while (Clock::now() < killed_at + kGuard) {
    after = observer->latest_scene_state();
    if (after && after->tick > release->tick) break;
    std::this_thread::sleep_for(5ms);
  }
  ASSERT_TRUE(after && after->tick > release->tick);
  for (const client::ObjectState& obj : after->objects) EXPECT_FALSE(held_by(obj, victim)) << obj.name;
}

// The server is killed with SIGKILL while it records a bot's grasps, just after it published a
// grasp event: the recording keeps every record written before the kill (every GraspEvent a
// subscriber received, every SceneState up to the last one received), the reader reports the cut
// as a truncation (no End record) and keeps the rest, and telegrasp-replay replays it up to the cut
// with identical outputs (exit 3: damaged, everything before the damage replayed).
TEST(ServerKilledTest, RecordingKeepsEveryRecordWrittenBeforeTheKill) {
  if (!in_private_network()) GTEST_SKIP() << private_network_failure();
  const std::string domain = "2";
  const std::string config = work_path("killed_server_scene.textproto");
  std::ofstream(config) << kScene;
  const std::string recording = work_path("killed_server.tgrec");
  ChildProcess server(
      {bin("telegrasp-server"), "--domain", domain, "--profile", "udp", "--config", config, "--record", recording},
      work_path("killed_server_server.log"));
  auto observer = subscriber(domain);
  ASSERT_TRUE(observer->wait_for_server(std::chrono::duration_cast<std::chrono::milliseconds>(kGuard)))
      << server.log_tail();
  ChildProcess bot({bin("telegrasp-bot"), "--client-id", "recorded", "--hands", "both", "--trials", "3", "--domain",
                    domain, "--profile", "udp", "--timeout-s", "60"},
                   work_path("killed_server_bot.log"));

  // 1. Kill the server as soon as its third grasp event arrives.
  std::set<std::uint64_t> received;
  int grasps = 0;
  std::uint64_t last_scene_tick = 0;
  const auto deadline = Clock::now() + kGuard;
  while (grasps < 3 && Clock::now() < deadline) {
    for (const client::GraspEvent& e : observer->take_grasp_events()) {
      received.insert(e.event_id);
      grasps += e.kind == client::GraspEvent::Kind::kGrasp;
    }
    if (grasps < 3) std::this_thread::sleep_for(1ms);
  }
  ASSERT_EQ(grasps, 3) << "the bot did not grasp three times in " << kGuard.count() << " s\n" << bot.log_tail();
  server.signal(SIGKILL);
  ASSERT_NE(server.wait(10s), -1);
  if (const auto s = observer->latest_scene_state()) last_scene_tick = s->tick;
  bot.stop();

  // 2. Read the file: truncated where the kill cut it, every received event and scene state in it.
  const server::Recording r = server::read_recording(recording);
  ASSERT_TRUE(r.damage.has_value()) << "a killed server's recording has no End record";
  EXPECT_TRUE(r.damage->truncated) << r.damage->message;
  EXPECT_FALSE(r.complete);
  std::set<std::uint64_t> recorded;
  std::uint64_t recorded_scene_tick = 0;
  for (const server::proto::Record& rec : r.records) {
    if (!rec.has_output()) continue;
    if (rec.output().type() == server::proto::OUTPUT_GRASP_EVENT) {
      msg::GraspEvent e;
      ASSERT_TRUE(server::from_cdr(rec.output().cdr(), e));
      recorded.insert(e.event_id());
    } else if (rec.output().type() == server::proto::OUTPUT_SCENE_STATE) {
      msg::SceneState s;
      ASSERT_TRUE(server::from_cdr(rec.output().cdr(), s));
      recorded_scene_tick = std::max<std::uint64_t>(recorded_scene_tick, s.tick());
    }
  }
  std::cout << "[ measured ] killed server's recording: " << r.records.size() << " records kept, " << recorded.size()
            << " grasp events (" << received.size() << " received), last scene tick " << recorded_scene_tick << " ("
            << last_scene_tick << " received); " << r.damage->message << "\n";
  for (std::uint64_t id : received) EXPECT_TRUE(recorded.count(id)) << "event " << id << " received but not recorded";
  EXPECT_GE(recorded_scene_tick, last_scene_tick) << "a scene state was received that the file lacks";

  // 3. telegrasp-replay replays it up to the cut, identical, and says it was cut (exit 3).
  const std::string replay_json = work_path("killed_server_replay.json");
  ChildProcess replay({bin("telegrasp-replay"), recording, "--json", replay_json},
                      work_path("killed_server_replay.log"));
  EXPECT_EQ(replay.wait(120s), 3) << replay.log_tail();
  std::ifstream in(replay_json);
  const nlohmann::json j = nlohmann::json::parse(in, nullptr, false);
  ASSERT_TRUE(j.is_object()) << replay.log_tail();
  EXPECT_EQ(j["identical"], true) << j.dump();
  EXPECT_EQ(j["damage"]["truncated"], true) << j.dump();
  EXPECT_EQ(j["records"], r.records.size());
}

}  // namespace
}  // namespace telegrasp::testing
