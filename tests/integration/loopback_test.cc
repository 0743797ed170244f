// Integration tests on loopback with real processes: telegrasp-server, telegrasp-bot, and a
// telegrasp::client observer in the test. Each test runs on a DDS domain leased for it
// (tests/common/test_domain.h) with the loopback profile (shared memory and 127.0.0.1 only), so
// concurrent runs never cross.
#include "process.h"
#include "telegrasp/client/client.h"
#include "test_domain.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <csignal>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <mutex>
#include <set>
#include <thread>

namespace telegrasp::testing {
namespace {

using namespace std::chrono_literals;
using client::Client;
using client::ClientOptions;
using telegrasp::testing::DomainLease;

std::string write_config(const std::string& name, const std::string& text) {
  const std::string path = work_path(name + ".textproto");
  std::ofstream(path) << text;
  return path;
}

// Everything an observer saw, guarded by one mutex.
struct Observed {
  std::mutex mutex;
  std::vector<client::GraspEvent> events;
  std::vector<client::ContactSet> contacts;
  std::map<std::uint64_t, client::SceneState> scenes;  // by tick
  std::vector<client::HandSkeleton> skeletons;
  std::optional<client::ServerStatus> status;
};

std::unique_ptr<Client> observe(int domain, Observed& seen, const std::string& id = "observer") {
  ClientOptions o;
  o.client_id = id;
  o.domain = domain;
  auto c = std::make_unique<Client>(o);
  c->on_grasp_event([&](const client::GraspEvent& e) { std::lock_guard l(seen.mutex); seen.events.push_back(e); });
  c->on_contact_set([&](const client::ContactSet& s) { std::lock_guard l(seen.mutex); seen.contacts.push_back(s); });
  c->on_scene_state([&](const client::SceneState& s) { std::lock_guard l(seen.mutex); seen.scenes[s.tick] = s; });
  c->on_hand_skeleton([&](const client::HandSkeleton& s) { std::lock_guard l(seen.mutex); seen.skeletons.push_back(s); });
  c->on_server_status([&](const client::ServerStatus& s) { std::lock_guard l(seen.mutex); seen.status = s; });
  return c;
}

std::unique_ptr<ChildProcess> start_server(int domain, const std::string& config, const std::string& name) {
  std::vector<std::string> args{bin("telegrasp-server"), "--domain", std::to_string(domain), "--profile", "loopback"};
  if (!config.empty()) args.insert(args.end(), {"--config", config});
  return std::make_unique<ChildProcess>(args, work_path(name + "_server.log"));
}

std::unique_ptr<ChildProcess> start_bot(int domain, const std::string& id, const std::string& hands, int trials,
                                        const std::string& json) {
  return std::make_unique<ChildProcess>(
      std::vector<std::string>{bin("telegrasp-bot"), "--client-id", id, "--hands", hands, "--trials", std::to_string(trials),
                               "--seed", "3", "--domain", std::to_string(domain), "--profile", "loopback", "--json", json,
                               "--timeout", "30"},
      work_path(id + ".log"));
}

// Polls `done` every 10 ms until it holds or `timeout` passes.
template <typename F>
bool eventually(F done, std::chrono::milliseconds timeout) {
  const auto end = std::chrono::steady_clock::now() + timeout;
  while (std::chrono::steady_clock::now() < end) {
    if (done()) return true;
    std::this_thread::sleep_for(10ms);
  }
  return done();
}

std::uint64_t rejected(const client::ServerStatus& s, const std::string& reason) {
  auto it = s.rejected.find(reason);
  return it == s.rejected.end() ? 0 : it->second;
}

const char* kFourObjects = R"(
objects { model: "005_tomato_soup_can" x: 0.45 y: -0.35 }
objects { model: "056_tennis_ball" x: 0.45 y: 0.35 }
objects { model: "013_apple" x: 0.8 y: -0.35 }
objects { model: "009_gelatin_box" x: 0.8 y: 0.35 yaw: 0.3 }
)";

// Two bots, four hands, one scene: every grasp event arrives exactly once, and contacts in object
// coordinates moved by the object pose published for the same tick give the world contacts.
TEST(LoopbackTest, TwoBotsFourHandsEveryEventOnceContactsConsistent) {
  const DomainLease lease;
  const int domain = lease.domain();
  Observed seen;
  auto observer = observe(domain, seen);
  auto server = start_server(domain, write_config("four", kFourObjects), "four");
  ASSERT_TRUE(observer->wait_for_server(20s)) << "no server on domain " << domain;
  const std::string json_a = work_path("bot_a.json"), json_b = work_path("bot_b.json");
  auto a = start_bot(domain, "bot-a", "both", 1, json_a);
  auto b = start_bot(domain, "bot-b", "both", 1, json_b);
  EXPECT_EQ(a->wait(240s), 0) << "see " << work_path("bot-a.log");
  EXPECT_EQ(b->wait(240s), 0) << "see " << work_path("bot-b.log");
  std::this_thread::sleep_for(500ms);  // the last releases

  int grasped_records = 0;
  for (const auto& path : {json_a, json_b}) {
    std::ifstream in(path);
    ASSERT_TRUE(in) << path;
    const nlohmann::json j = nlohmann::json::parse(in);
    for (const auto& g : j["grasps"]) grasped_records += g["grasped"].get<bool>();
  }

  std::lock_guard lock(seen.mutex);
  // Exactly once: the server numbers events 1, 2, 3 ...; we saw each id once and none is missing.
  std::set<std::uint64_t> ids;
  int grasps = 0;
  for (const auto& e : seen.events) {
    EXPECT_TRUE(ids.insert(e.event_id).second) << "event " << e.event_id << " arrived twice";
    if (e.kind == client::GraspEvent::Kind::kGrasp) {
      ++grasps;
      EXPECT_FALSE(e.capsules.empty());
      EXPECT_TRUE(e.hand.client_id == "bot-a" || e.hand.client_id == "bot-b");
    }
  }
  ASSERT_FALSE(ids.empty());
  EXPECT_EQ(*ids.begin(), 1u);
  EXPECT_EQ(*ids.rbegin(), ids.size()) << "an event id is missing";
  EXPECT_GE(grasps, 8 * 3 / 4) << "two bots x four objects: most trials grasp";
  EXPECT_EQ(grasps, grasped_records) << "each bot's grasped record comes from one event";

  int checked = 0;
  for (const auto& cs : seen.contacts) {
    auto scene = seen.scenes.find(cs.tick);
    if (scene == seen.scenes.end()) continue;  // best effort: that tick's scene state was superseded
    for (const auto& o : scene->second.objects) {
      if (o.id != cs.object_id) continue;
      for (const auto& c : cs.contacts) {
        EXPECT_LT((o.X_WorldObject * c.p_ObjectContact - c.p_WorldContact).norm(), 1e-6);
        EXPECT_LT((o.X_WorldObject.linear() * c.n_Object - c.n_World).norm(), 1e-6);
        ++checked;
      }
    }
  }
  EXPECT_GT(checked, 100);
}

// A bot killed with SIGKILL while holding: its object is back to physics within 1 s, and the
// other bot carries on to the end of its trials.
TEST(LoopbackTest, KilledBotsObjectIsReleasedWithinOneSecond) {
  const DomainLease lease;
  const int domain = lease.domain();
  Observed seen;
  auto observer = observe(domain, seen);
  auto server = start_server(domain, write_config("kill", kFourObjects), "kill");
  ASSERT_TRUE(observer->wait_for_server(20s));
  auto victim = start_bot(domain, "victim", "right", 3, work_path("victim.json"));
  auto survivor = start_bot(domain, "survivor", "left", 1, work_path("survivor.json"));

  // Wait until the victim lifts something.
  int held_object = -1;
  double rest_z = 0;
  std::map<int, double> first_z;
  ASSERT_TRUE(eventually([&] {
    std::lock_guard l(seen.mutex);
    if (seen.scenes.empty()) return false;
    for (const auto& [tick, s] : seen.scenes)
      for (const auto& o : s.objects) first_z.emplace(o.id, o.X_WorldObject.translation().z());
    for (const auto& o : seen.scenes.rbegin()->second.objects)
      if (o.held && o.holder.client_id == "victim" && o.X_WorldObject.translation().z() > first_z[o.id] + 0.05) {
        held_object = o.id;
        rest_z = first_z[o.id];
        return true;
      }
    return false;
  }, 60s)) << "the victim never lifted an object";
  victim->signal(SIGKILL);
  const auto killed_at = std::chrono::steady_clock::now();
  ASSERT_TRUE(eventually([&] {
    std::lock_guard l(seen.mutex);
    for (const auto& o : seen.scenes.rbegin()->second.objects)
      if (o.id == held_object) return !o.held;
    return false;
  }, 5s));
  const double released_after_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - killed_at).count();
  EXPECT_LT(released_after_s, 1.0);
  std::cout << "[ measured ] object " << held_object << " released " << released_after_s << " s after SIGKILL\n";
  {
    std::lock_guard l(seen.mutex);
    bool release_event = false;
    for (const auto& e : seen.events)
      release_event |= e.kind == client::GraspEvent::Kind::kRelease && e.hand.client_id == "victim" && e.object_id == held_object;
    EXPECT_TRUE(release_event);
  }
  // Physics has it: it falls back toward the table.
  EXPECT_TRUE(eventually([&] {
    std::lock_guard l(seen.mutex);
    for (const auto& o : seen.scenes.rbegin()->second.objects)
      if (o.id == held_object) return o.X_WorldObject.translation().z() < rest_z + 0.02;
    return false;
  }, 3s));
  EXPECT_EQ(survivor->wait(240s), 0) << "see " << work_path("survivor.log");
}

// Every kind of bad input is dropped and counted once per sample under its reason, and the server
// keeps serving: a valid sample afterwards is reflected in a skeleton.
TEST(LoopbackTest, BadInputsAreRejectedAndCounted) {
  const DomainLease lease;
  const int domain = lease.domain();
  Observed seen;
  auto observer = observe(domain, seen);
  auto server = start_server(domain, "", "bad");
  ASSERT_TRUE(observer->wait_for_server(20s));
  ClientOptions o;
  o.client_id = "eve";
  o.domain = domain;
  o.topics = 0;
  Client eve(o);
  ASSERT_TRUE(eve.wait_for_server(20s));

  client::ControllerSample good;
  good.X_WorldPalm.translation() = Eigen::Vector3d(0, -0.5, 0.5);  // above the table, far from objects
  eve.publish(good);  // sequence 1, accepted: the hand exists now
  const double nan = std::nan("");
  std::vector<std::pair<std::string, client::ControllerSample>> bad;
  auto make = [&](const std::string& reason, auto change) {
    client::ControllerSample s = good;
    change(s);
    bad.emplace_back(reason, s);
  };
  make("non_finite", [&](auto& s) { s.X_WorldPalm.translation().x() = nan; });
  make("quaternion_not_unit", [&](auto& s) { s.X_WorldPalm.linear() *= 0.5; });
  make("trigger_out_of_range", [&](auto& s) { s.trigger = 5; });
  make("curls_wrong_count", [&](auto& s) { s.curls = {0.5, 0.5}; });
  make("curls_out_of_range", [&](auto& s) { s.curls = {0.5, 0.5, 0.5, 0.5, 2.0}; });
  make("unknown_hand_side", [&](auto& s) { s.side = static_cast<client::HandSide>(7); });
  make("stale_sequence", [&](auto& s) { s.sequence_number = 1; });
  for (const auto& [reason, s] : bad) {
    eve.publish(s);
    std::this_thread::sleep_for(50ms);  // one sample per instance at a time (keep-last 1)
  }
  ASSERT_TRUE(eventually([&] {
    std::lock_guard l(seen.mutex);
    if (!seen.status) return false;
    for (const auto& [reason, s] : bad)
      if (rejected(*seen.status, reason) == 0) return false;
    return true;
  }, 10s)) << "not every reason was counted";
  {
    std::lock_guard l(seen.mutex);
    for (const auto& [reason, s] : bad) EXPECT_EQ(rejected(*seen.status, reason), 1u) << reason;
    EXPECT_EQ(seen.status->inputs_rejected, bad.size());
  }
  // Still serving: the next valid sample shows up in eve's skeleton.
  good.X_WorldPalm.translation().z() = 0.6;
  const std::uint64_t seq = eve.publish(good);
  EXPECT_TRUE(eventually([&] {
    std::lock_guard l(seen.mutex);
    for (const auto& s : seen.skeletons)
      if (s.hand.client_id == "eve" && s.input_sequence == seq && std::abs(s.X_WorldPalm.translation().z() - 0.6) < 1e-9) return true;
    return false;
  }, 5s));
  EXPECT_TRUE(server->running());
}

// A second participant claiming another client's id cannot move that client's hand.
TEST(LoopbackTest, ASpoofedClientIdCannotMoveAnotherClientsHand) {
  const DomainLease lease;
  const int domain = lease.domain();
  Observed seen;
  auto observer = observe(domain, seen);
  auto server = start_server(domain, "", "spoof");
  ASSERT_TRUE(observer->wait_for_server(20s));
  ClientOptions o;
  o.client_id = "alice";
  o.domain = domain;
  o.topics = 0;
  Client alice(o);
  Client mallory(o);  // same client id, another participant
  ASSERT_TRUE(alice.wait_for_server(20s));
  ASSERT_TRUE(mallory.wait_for_server(20s));
  client::ControllerSample mine, theirs;
  mine.X_WorldPalm.translation() = Eigen::Vector3d(0, -0.6, 0.4);
  theirs.X_WorldPalm.translation() = Eigen::Vector3d(0, -0.6, 0.9);
  theirs.sequence_number = 1'000'000;  // "newer" than anything alice sends
  for (int i = 0; i < 40; ++i) {
    alice.publish(mine);
    std::this_thread::sleep_for(5ms);
    theirs.sequence_number += 1;
    mallory.publish(theirs);
    std::this_thread::sleep_for(10ms);
  }
  ASSERT_TRUE(eventually([&] {
    std::lock_guard l(seen.mutex);
    return seen.status && rejected(*seen.status, "client_id_owned_by_another_participant") > 0;
  }, 5s));
  std::lock_guard l(seen.mutex);
  int alice_skeletons = 0;
  for (const auto& s : seen.skeletons) {
    if (s.hand.client_id != "alice") continue;
    ++alice_skeletons;
    EXPECT_NEAR(s.X_WorldPalm.translation().z(), 0.4, 1e-9) << "the spoofer moved alice's hand";
  }
  EXPECT_GT(alice_skeletons, 10);
}

}  // namespace
}  // namespace telegrasp::testing
