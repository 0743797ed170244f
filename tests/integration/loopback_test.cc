// Integration tests on loopback with real processes: telegrasp-server, telegrasp-bot, and a
// telegrasp::client observer in the test. Each test runs on a DDS domain leased for it
// (tests/common/test_domain.h) with the loopback profile (shared memory only), so
// concurrent runs never cross. The tests assert on what happened and in which order; timeouts
// only guard against hangs, and durations are printed, not asserted.
#include "process.h"
#include "telegrasp/client/client.h"
#include "telegrasp/idl/cli.h"
#include "test_domain.h"

#include <fastrtps/xmlparser/XMLProfileManager.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <csignal>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <mutex>
#include <set>
#include <sstream>
#include <thread>
#include <tuple>

namespace telegrasp::testing {
namespace {

using namespace std::chrono_literals;
using client::Client;
using client::ClientOptions;
using client::GraspEvent;
using telegrasp::testing::DomainLease;

// Generous guards against hangs on a loaded machine: a passing test never waits that long.
constexpr auto kEventGuard = 30s;  // something that follows from what the test just did
constexpr auto kBotGuard = 300s;  // a bot's whole run

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
  auto c = std::make_unique<Client>(client_options(id, domain));
  c->on_grasp_event([&](const client::GraspEvent& e) {
    std::lock_guard l(seen.mutex);
    seen.events.push_back(e);
  });
  c->on_contact_set([&](const client::ContactSet& s) {
    std::lock_guard l(seen.mutex);
    seen.contacts.push_back(s);
  });
  c->on_scene_state([&](const client::SceneState& s) {
    std::lock_guard l(seen.mutex);
    seen.scenes[s.tick] = s;
  });
  c->on_hand_skeleton([&](const client::HandSkeleton& s) {
    std::lock_guard l(seen.mutex);
    seen.skeletons.push_back(s);
  });
  c->on_server_status([&](const client::ServerStatus& s) {
    std::lock_guard l(seen.mutex);
    seen.status = s;
  });
  // The tests add clients beside the observer: several participants in this process.
  EXPECT_EQ(eprosima::fastrtps::xmlparser::XMLProfileManager::library_settings().intraprocess_delivery,
            eprosima::fastrtps::INTRAPROCESS_OFF)
      << "Fast DDS intraprocess delivery is on (tests/common/intraprocess_off.cc not linked, or undone by a profile)";
  return c;
}

// Options for a client `id` on `domain` that publishes and subscribes to no topic.
ClientOptions publisher_options(const std::string& id, int domain) { return client_options(id, domain, 0); }

std::unique_ptr<ChildProcess> start_server(int domain, const std::string& config, const std::string& name) {
  std::vector<std::string> args{bin("telegrasp-server"), "--domain", std::to_string(domain), "--profile", "loopback"};
  if (!config.empty()) args.insert(args.end(), {"--config", config});
  return std::make_unique<ChildProcess>(args, work_path(name + "_server.log"));
}

// A leased domain served by a telegrasp-server (with `config` if not empty), watched by an
// observer made before the server.
struct ServedDomain {
  explicit ServedDomain(const std::string& name, const std::string& config = "")
      : server(start_server(domain, config, name)) {}
  const DomainLease lease;
  const int domain = lease.domain();
  Observed seen;
  std::unique_ptr<Client> observer = observe(domain, seen);
  std::unique_ptr<ChildProcess> server;
};

std::unique_ptr<ChildProcess> start_bot(int domain, const std::string& id, const std::string& hands, int trials,
                                        const std::string& json) {
  return std::make_unique<ChildProcess>(
      std::vector<std::string>{bin("telegrasp-bot"), "--client-id", id, "--hands", hands, "--trials",
                               std::to_string(trials), "--seed", "3", "--domain", std::to_string(domain), "--profile",
                               "loopback", "--json", json, "--timeout-s", "30"},
      work_path(id + ".log"));
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

// Per hand, the events alternate grasp, release, grasp, ... and each release lets go of the
// object the grasp before it took. Returns "" or what is wrong; `closed` says whether every
// hand's last event is a release.
std::string check_grasp_release_order(const std::vector<GraspEvent>& events, bool& closed) {
  std::map<std::pair<std::string, int>, const GraspEvent*> open;  // by hand: the grasp not yet released
  std::vector<GraspEvent> by_id = events;
  std::sort(by_id.begin(), by_id.end(), [](const auto& a, const auto& b) { return a.event_id < b.event_id; });
  for (const GraspEvent& e : by_id) {
    const auto hand = std::make_pair(e.hand.client_id, static_cast<int>(e.hand.side));
    const GraspEvent*& held = open[hand];
    const std::string which = "event " + std::to_string(e.event_id) + " (" + e.hand.client_id + ")";
    if (e.kind == GraspEvent::Kind::kGrasp) {
      if (held) return which + ": a grasp while the hand still holds object " + std::to_string(held->object_id);
      held = &e;
    } else {
      if (!held) return which + ": a release without a grasp before it";
      if (held->object_id != e.object_id)
        return which + ": releases object " + std::to_string(e.object_id) + ", the grasp took " +
               std::to_string(held->object_id);
      held = nullptr;
    }
  }
  closed = true;
  for (const auto& [hand, held] : open) closed = closed && held == nullptr;
  return "";
}

// Two bots, four hands, one scene: every trial ends with a record, every grasp event arrives
// exactly once and is followed by its release, each grasp a bot records is an event the observer
// saw, and contacts in object coordinates moved by the object pose published for the same tick
// give the world contacts.
TEST(LoopbackTest, TwoBotsFourHandsEveryEventOnceContactsConsistent) {
  ServedDomain served("four", write_config("four", kFourObjects));
  const int domain = served.domain;
  Observed& seen = served.seen;
  ASSERT_TRUE(served.observer->wait_for_server(kStartGuard)) << "no server on domain " << domain;
  const std::string json_a = work_path("bot_a.json"), json_b = work_path("bot_b.json");
  auto a = start_bot(domain, "bot-a", "both", 1, json_a);
  auto b = start_bot(domain, "bot-b", "both", 1, json_b);
  // 0: every trial held; kExitNotHeld: done, some not held (two bots contend for the objects).
  for (auto* bot : {a.get(), b.get()}) {
    const int status = bot->wait(kBotGuard);
    ASSERT_TRUE(status == 0 || status == cli::kExitNotHeld) << bot->exit_description() << "; see " << bot->log_path();
  }

  // Each bot: one record per object of the scene (grasped or not, or given up).
  std::map<std::tuple<std::string, std::string, int>, int> grasped_records;  // (client, hand, object)
  for (const auto& [path, client_id] : {std::pair{json_a, "bot-a"}, std::pair{json_b, "bot-b"}}) {
    std::ifstream in(path);
    ASSERT_TRUE(in) << path;
    const nlohmann::json j = nlohmann::json::parse(in);
    std::set<int> objects;
    for (const auto& g : j["grasps"]) {
      objects.insert(g["object_id"].get<int>());
      if (g["grasped"].get<bool>())
        ++grasped_records[{client_id, g["hand"].get<std::string>(), g["object_id"].get<int>()}];
    }
    EXPECT_EQ(j["grasps"].size(), 4u) << path << ": one record per object";
    EXPECT_EQ(objects.size(), 4u) << path << ": one record per object";
  }

  // The bots have exited: each grasp is released (the bot opened its hand, or the server let go
  // of the departed hand). Wait for the last releases.
  std::string order_error;
  const bool all_released = eventually(
      [&] {
        std::lock_guard l(seen.mutex);
        bool closed = false;
        order_error = check_grasp_release_order(seen.events, closed);
        return !order_error.empty() || closed;
      },
      kEventGuard);
  EXPECT_EQ(order_error, "");
  EXPECT_TRUE(all_released) << "a grasp was never released";

  std::lock_guard lock(seen.mutex);
  // Exactly once: the server numbers events 1, 2, 3 ...; we saw each id once and none is missing.
  std::set<std::uint64_t> ids;
  std::map<std::tuple<std::string, std::string, int>, int> grasp_events;
  for (const auto& e : seen.events) {
    EXPECT_TRUE(ids.insert(e.event_id).second) << "event " << e.event_id << " arrived twice";
    if (e.kind != GraspEvent::Kind::kGrasp) continue;
    EXPECT_FALSE(e.capsules.empty());
    EXPECT_TRUE(e.hand.client_id == "bot-a" || e.hand.client_id == "bot-b") << e.hand.client_id;
    ++grasp_events[{e.hand.client_id, client::to_string(e.hand.side), e.object_id}];
  }
  ASSERT_FALSE(ids.empty());
  EXPECT_EQ(*ids.begin(), 1u);
  EXPECT_EQ(*ids.rbegin(), ids.size()) << "an event id is missing";
  int grasps = 0, records = 0;
  for (const auto& [key, n] : grasp_events) grasps += n;
  // A bot records the first grasp of a trial; a regrasp in the same trial, or one that reaches
  // the bot after it gave up waiting, is an event without a record, never the other way round.
  for (const auto& [key, n] : grasped_records) {
    records += n;
    const auto& [client_id, hand, object] = key;
    EXPECT_LE(n, grasp_events[key]) << client_id << " " << hand << " hand recorded grasping object " << object
                                    << " without a grasp event the observer saw";
  }
  std::cout << "[ measured ] " << grasps << " grasp events, " << records << " grasped trials of 8\n";
  ASSERT_GT(grasps, 0) << "no grasp at all: nothing below is checked";

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
  std::cout << "[ measured ] " << checked << " contacts checked against their tick's object pose\n";
  EXPECT_GT(checked, 0) << "no contact set met its tick's scene state: nothing was checked";
}

// What the observer last saw of the scene, for a failure's message: was the server still ticking,
// who held what.
std::string scene_summary(Observed& seen) {
  std::lock_guard l(seen.mutex);
  if (seen.scenes.empty()) return "no scene state seen";
  const auto& [tick, scene] = *seen.scenes.rbegin();
  std::ostringstream out;
  out << "the last scene state seen is tick " << tick << " (" << seen.scenes.size() << " kept)";
  for (const auto& o : scene.objects)
    if (o.held) out << ", object " << o.id << " held by " << o.holder.client_id;
  out << ", " << seen.events.size() << " events seen";
  return out.str();
}

// A bot killed with SIGKILL while holding: the server notices the dead hand (liveliness), releases
// its object with a release event after the grasp event, physics takes the object back, and the
// other bot carries on to the end of its trials. The release delay is printed, not asserted.
TEST(LoopbackTest, KilledBotsObjectIsReleasedAndFalls) {
  ServedDomain served("kill", write_config("kill", kFourObjects));
  const int domain = served.domain;
  Observed& seen = served.seen;
  ASSERT_TRUE(served.observer->wait_for_server(kStartGuard));
  // The victim is on the shared-memory transport as any local client: killed, it may leave a lock
  // of its shared memory held (with data-sharing on, the server's next write then threw after a
  // timeout and stopped the server: idl/src/dds_participant.cc).
  auto victim = start_bot(domain, "victim", "right", 3, work_path("victim.json"));
  auto survivor = start_bot(domain, "survivor", "left", 1, work_path("survivor.json"));

  // Wait until the victim lifts something.
  int held_object = -1;
  double rest_z = 0;
  std::map<int, double> first_z;
  ASSERT_TRUE(eventually(
      [&] {
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
      },
      kBotGuard))
      << "the victim never lifted an object; see " << work_path("victim.log");
  victim->signal(SIGKILL);
  const auto killed_at = std::chrono::steady_clock::now();
  auto victims_release = [&]() -> const GraspEvent* {
    for (const auto& e : seen.events)
      if (e.kind == GraspEvent::Kind::kRelease && e.hand.client_id == "victim" && e.object_id == held_object) return &e;
    return nullptr;
  };
  ASSERT_TRUE(eventually(
      [&] {
        std::lock_guard l(seen.mutex);
        return victims_release() != nullptr;
      },
      kEventGuard))
      << "no release event for the dead bot's object " << held_object << "; " << scene_summary(seen) << "; server "
      << (served.server->running() ? "running" : served.server->exit_description()) << ", its log ends:\n"
      << served.server->log_tail(30);
  const double released_after_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - killed_at).count();
  std::cout << "[ measured ] object " << held_object << " released " << released_after_s << " s after SIGKILL\n";
  {
    std::lock_guard l(seen.mutex);
    const GraspEvent* release = victims_release();
    bool grasp_before = false;
    for (const auto& e : seen.events)
      grasp_before |= e.kind == GraspEvent::Kind::kGrasp && e.hand.client_id == "victim" &&
                      e.object_id == held_object && e.event_id < release->event_id;
    EXPECT_TRUE(grasp_before) << "the release (event " << release->event_id << ") has no grasp before it";
  }
  // The scene says so too, and physics has it: it falls back toward the table.
  EXPECT_TRUE(eventually(
      [&] {
        std::lock_guard l(seen.mutex);
        for (const auto& o : seen.scenes.rbegin()->second.objects)
          if (o.id == held_object) return !o.held && o.X_WorldObject.translation().z() < rest_z + 0.02;
        return false;
      },
      kEventGuard))
      << "object " << held_object << " is still held or in the air";
  const int survivor_status = survivor->wait(kBotGuard);  // 0 every trial held, kExitNotHeld some not
  EXPECT_TRUE(survivor_status == 0 || survivor_status == cli::kExitNotHeld)
      << survivor->exit_description() << "; see " << work_path("survivor.log");
}

// Every kind of bad input is dropped and counted once per sample under its reason, and the server
// keeps serving: a valid sample afterwards is reflected in a skeleton.
TEST(LoopbackTest, BadInputsAreRejectedAndCounted) {
  ServedDomain served("bad");
  ASSERT_TRUE(served.observer->wait_for_server(kStartGuard));
  Client eve(publisher_options("eve", served.domain));
  ASSERT_TRUE(eve.wait_for_server(kStartGuard));
  Observed& seen = served.seen;

  client::ControllerSample good;
  good.X_WorldPalm.translation() = Eigen::Vector3d(0, -0.5, 0.5);  // above the table, far from objects
  // Publishes `s` (valid) until eve's skeleton shows one of these samples: best effort loses
  // samples, e.g. until the server's reader has matched eve's writer too.
  auto publish_until_shown = [&](const client::ControllerSample& s) {
    const std::uint64_t first = eve.publish(s);
    return eventually(
        [&] {
          {
            std::lock_guard l(seen.mutex);
            for (const auto& k : seen.skeletons)
              if (k.hand.client_id == "eve" && k.input_sequence >= first &&
                  std::abs(k.X_WorldPalm.translation().z() - s.X_WorldPalm.translation().z()) < 1e-9)
                return true;
          }
          eve.publish(s);
          return false;
        },
        kEventGuard);
  };
  ASSERT_TRUE(publish_until_shown(good)) << "eve's hand never showed in a skeleton";
  // Waits until the status has counted `total` rejected inputs.
  auto rejected_total = [&](std::uint64_t total) {
    return eventually(
        [&] {
          std::lock_guard l(seen.mutex);
          return seen.status && seen.status->inputs_rejected == total;
        },
        kEventGuard);
  };

  // Samples that fail validation, whatever the hand: one at a time (keep-last 1 per hand: a sample
  // could replace the one before unread), each waited for in the server's status (1 Hz). Eve's
  // writer and the server's reader have matched (her skeleton showed), so none is lost.
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
  for (std::size_t i = 0; i < bad.size(); ++i) {
    eve.publish(bad[i].second);
    ASSERT_TRUE(rejected_total(i + 1)) << bad[i].first << " was not counted as rejected input " << i + 1;
  }

  // A stale sequence number is stale only while the hand exists: right after a good sample. A
  // hand silent for remove_after_s is removed, and then the same sample makes a new hand (its
  // skeleton shows the stale sample's height); should a stall of the machine do that, try again.
  make("stale_sequence", [&](auto& s) {
    s.sequence_number = 1;
    s.X_WorldPalm.translation().z() = 0.55;
  });
  bool stale_rejected = false;
  for (int attempt = 1; attempt <= 5 && !stale_rejected; ++attempt) {
    ASSERT_TRUE(publish_until_shown(good));
    const std::size_t skeletons_before = [&] {
      std::lock_guard l(seen.mutex);
      return seen.skeletons.size();
    }();
    eve.publish(bad.back().second);
    bool stale_accepted = false;
    ASSERT_TRUE(eventually(
        [&] {
          std::lock_guard l(seen.mutex);
          stale_rejected = seen.status && seen.status->inputs_rejected == bad.size();
          for (std::size_t i = skeletons_before; i < seen.skeletons.size(); ++i) {
            const auto& k = seen.skeletons[i];
            stale_accepted |= k.hand.client_id == "eve" && k.input_sequence == 1 &&
                              std::abs(k.X_WorldPalm.translation().z() - 0.55) < 1e-9;
          }
          return stale_rejected || stale_accepted;
        },
        kEventGuard))
        << "the stale sample was neither rejected nor accepted";
    if (!stale_rejected)
      std::cout << "[ note ] attempt " << attempt
                << ": the stale sample was accepted (by a new hand, if a stall had the old one removed)\n";
  }
  EXPECT_TRUE(stale_rejected);
  {
    std::lock_guard l(seen.mutex);
    for (const auto& [reason, s] : bad) EXPECT_EQ(rejected(*seen.status, reason), 1u) << reason;
    EXPECT_EQ(seen.status->inputs_rejected, bad.size());
  }
  // Still serving: a valid sample at a new height shows up in eve's skeleton.
  good.X_WorldPalm.translation().z() = 0.6;
  EXPECT_TRUE(publish_until_shown(good)) << "the server stopped taking eve's samples";
  EXPECT_TRUE(served.server->running());
}

// A second participant claiming another client's id cannot move that client's hand.
TEST(LoopbackTest, ASpoofedClientIdCannotMoveAnotherClientsHand) {
  ServedDomain served("spoof");
  ASSERT_TRUE(served.observer->wait_for_server(kStartGuard));
  Observed& seen = served.seen;
  const ClientOptions o = publisher_options("alice", served.domain);
  Client alice(o);
  Client mallory(o);  // same client id, another participant
  ASSERT_TRUE(alice.wait_for_server(kStartGuard));
  ASSERT_TRUE(mallory.wait_for_server(kStartGuard));
  client::ControllerSample mine, theirs;
  mine.X_WorldPalm.translation() = Eigen::Vector3d(0, -0.6, 0.4);
  theirs.X_WorldPalm.translation() = Eigen::Vector3d(0, -0.6, 0.9);
  theirs.sequence_number = 1'000'000;  // "newer" than anything alice sends
  auto alice_skeletons = [&] {
    int n = 0;
    for (const auto& s : seen.skeletons) n += s.hand.client_id == "alice";
    return n;
  };
  // Alice first, until her hand shows: her participant owns the id "alice" from then on.
  ASSERT_TRUE(eventually(
      [&] {
        alice.publish(mine);
        std::lock_guard l(seen.mutex);
        return alice_skeletons() > 0;
      },
      kEventGuard))
      << "alice's hand never showed";
  // Then both, until the server has counted mallory's samples as rejected and shown alice's hand
  // again since.
  int skeletons_at_rejection = -1;
  ASSERT_TRUE(eventually(
      [&] {
        alice.publish(mine);
        theirs.sequence_number += 1;
        mallory.publish(theirs);
        std::lock_guard l(seen.mutex);
        if (skeletons_at_rejection < 0 && seen.status &&
            rejected(*seen.status, "client_id_owned_by_another_participant") > 0)
          skeletons_at_rejection = alice_skeletons();
        return skeletons_at_rejection >= 0 && alice_skeletons() > skeletons_at_rejection;
      },
      kEventGuard))
      << "mallory's samples were never counted as rejected";
  std::lock_guard l(seen.mutex);
  for (const auto& s : seen.skeletons) {
    if (s.hand.client_id != "alice") continue;
    EXPECT_NEAR(s.X_WorldPalm.translation().z(), 0.4, 1e-9) << "the spoofer moved alice's hand";
  }
  std::cout << "[ measured ] " << alice_skeletons() << " skeletons of alice's hand, all where alice put it\n";
}

}  // namespace
}  // namespace telegrasp::testing
