// Integration test of two hands on one object over DDS on loopback: a real telegrasp-server (its
// scene one long box, from a mesh file) and two clients in this process, alice and bob, each
// driving one right hand at fixed poses planned over either end of the box. Both grasp it, lift it,
// bob lets go, alice lets go. Every subscriber (an observer, alice and bob) must see one holder
// set per tick (the same at every subscriber, the first holder in the old fields, no hand twice),
// the holder sets in the order {} {alice} {alice, bob} {alice} {}, and never a lost or doubled
// object: one object in every SceneState. Times are guards against hangs, not asserted.
#include "process.h"
#include "telegrasp/client/client.h"
#include "telegrasp/sim/object_model.h"
#include "telegrasp/sim/scripted_operator.h"
#include "telegrasp/sim/world.h"
#include "test_domain.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <mutex>
#include <thread>

namespace telegrasp::testing {
namespace {

using namespace std::chrono_literals;
using client::Client;
using client::ClientOptions;
using client::HandKey;

constexpr auto kEventGuard = 30s;
const Eigen::Vector3d kHalfExtents(0.3, 0.04, 0.04);  // a 0.6 x 0.08 x 0.08 m box

// The box as an OBJ file in a folder of its own (the server's objects_dir); returns the folder.
std::string write_long_box() {
  const std::string dir = work_path("two_hands_objects");
  std::filesystem::create_directories(dir);
  std::ofstream obj(dir + "/long_box.obj");
  for (int i = 0; i < 8; ++i)
    obj << "v " << (i & 1 ? 1 : -1) * kHalfExtents.x() << " " << (i & 2 ? 1 : -1) * kHalfExtents.y() << " "
        << (i & 4 ? 1 : -1) * kHalfExtents.z() << "\n";
  // Two triangles per face, counter-clockwise seen from outside (1-based indices).
  for (const char* f :
       {"1 3 2", "2 3 4", "5 6 7", "6 8 7", "1 2 5", "2 6 5", "3 7 4", "4 7 8", "1 5 3", "3 5 7", "2 4 6", "4 8 6"})
    obj << "f " << f << "\n";
  return dir;
}

sim::TriangleMesh box_mesh() {
  sim::TriangleMesh m;
  for (int i = 0; i < 8; ++i)
    m.vertices.emplace_back((i & 1 ? 1 : -1) * kHalfExtents.x(), (i & 2 ? 1 : -1) * kHalfExtents.y(),
                            (i & 4 ? 1 : -1) * kHalfExtents.z());
  m.triangles = {{0, 2, 1}, {1, 2, 3}, {4, 5, 6}, {5, 7, 6}, {0, 1, 4}, {1, 5, 4},
                 {2, 6, 3}, {3, 6, 7}, {0, 4, 2}, {2, 4, 6}, {1, 3, 5}, {3, 7, 5}};
  return m;
}

// What one subscriber saw of the scene: the holder set per tick, and any malformed scene state.
struct SceneLog {
  std::mutex mutex;
  std::map<std::uint64_t, std::vector<HandKey>> holders;  // by tick
  std::vector<std::string> problems;
  double z = 0;  // the box's height in the newest state

  void add(const client::SceneState& s) {
    std::lock_guard l(mutex);
    if (s.objects.size() != 1)
      problems.push_back("tick " + std::to_string(s.tick) + ": " + std::to_string(s.objects.size()) +
                         " objects (expected 1)");
    if (s.objects.empty()) return;
    const client::ObjectState& o = s.objects.front();
    if (o.held != !o.holders.empty())
      problems.push_back("tick " + std::to_string(s.tick) + ": held != !holders.empty()");
    if (o.held && !(o.holder == o.holders.front()))
      problems.push_back("tick " + std::to_string(s.tick) + ": holder is not holders[0]");
    if (o.holders.size() == 2 && o.holders[0] == o.holders[1])
      problems.push_back("tick " + std::to_string(s.tick) + ": one hand holds it twice");
    holders[s.tick] = o.holders;
    z = o.X_WorldObject.translation().z();
  }
  double height() {
    std::lock_guard l(mutex);
    return z;
  }
  std::vector<HandKey> newest() {
    std::lock_guard l(mutex);
    return holders.empty() ? std::vector<HandKey>{} : holders.rbegin()->second;
  }
  // The distinct holder sets in the order they appeared.
  std::vector<std::vector<HandKey>> sequence() {
    std::lock_guard l(mutex);
    std::vector<std::vector<HandKey>> out;
    for (const auto& [tick, h] : holders)
      if (out.empty() || out.back() != h) out.push_back(h);
    return out;
  }
};

// A client driving one right hand: publishes its current pose and trigger every 10 ms, and logs
// the scene it receives.
class Driver {
 public:
  Driver(const std::string& id, int domain) {
    client_ = std::make_unique<Client>(client_options(id, domain));
    client_->on_scene_state([this](const client::SceneState& s) { log.add(s); });
  }
  ~Driver() { stop(); }
  void start(const Eigen::Isometry3d& X_WorldPalm) {
    set(X_WorldPalm, 0);
    thread_ = std::thread([this] {
      while (!stopping_) {
        client::ControllerSample s;
        {
          std::lock_guard l(mutex_);
          s = sample_;
        }
        client_->publish(s);
        std::this_thread::sleep_for(10ms);
      }
    });
  }
  void stop() {
    stopping_ = true;
    if (thread_.joinable()) thread_.join();
  }
  void set(const Eigen::Isometry3d& X_WorldPalm, double trigger) {
    std::lock_guard l(mutex_);
    sample_.side = client::HandSide::kRight;
    sample_.X_WorldPalm = X_WorldPalm;
    sample_.trigger = trigger;
  }
  // Moves from `from` to `to` while setting the trigger to `trigger`, over `seconds`.
  void move(const Eigen::Isometry3d& from, const Eigen::Isometry3d& to, double trigger, double seconds) {
    const int steps = static_cast<int>(seconds * 100);
    for (int i = 1; i <= steps; ++i) {
      Eigen::Isometry3d X = from;
      X.translation() += (to.translation() - from.translation()) * i / steps;
      set(X, trigger);
      std::this_thread::sleep_for(10ms);
    }
  }
  Client& client() { return *client_; }
  SceneLog log;

 private:
  std::unique_ptr<Client> client_;
  std::mutex mutex_;
  client::ControllerSample sample_;
  std::atomic<bool> stopping_{false};
  std::thread thread_;
};

Eigen::Isometry3d shifted(const Eigen::Vector3d& by, const Eigen::Isometry3d& X) {
  return Eigen::Translation3d(by) * X;
}

TEST(TwoHandsTest, TwoClientsHoldOneBoxAndEverySubscriberSeesOneHolderSet) {
  const DomainLease lease;
  const int domain = lease.domain();
  const std::string config = work_path("two_hands.textproto");
  std::ofstream(config) << "objects_dir: \"" << write_long_box() << "\"\n"
                        << "objects { model: \"long_box\" x: 0.4 y: 0 }\n";
  ChildProcess server(
      {bin("telegrasp-server"), "--domain", std::to_string(domain), "--profile", "loopback", "--config", config},
      work_path("two_hands_server.log"));
  SceneLog observed;
  ClientOptions o;
  o.client_id = "observer";
  o.domain = domain;
  Client observer(o);
  observer.on_scene_state([&](const client::SceneState& s) { observed.add(s); });
  std::mutex events_mutex;
  std::vector<client::GraspEvent> events;
  observer.on_grasp_event([&](const client::GraspEvent& e) {
    std::lock_guard l(events_mutex);
    events.push_back(e);
  });
  ASSERT_TRUE(observer.wait_for_server(kStartGuard)) << "no server on domain " << domain;
  Driver alice("alice", domain), bob("bob", domain);
  ASSERT_TRUE(alice.client().wait_for_server(kStartGuard));
  ASSERT_TRUE(bob.client().wait_for_server(kStartGuard));

  // Plan one grasp at the box's middle where it rests; each hand takes it 0.2 m towards an end.
  std::optional<client::SceneState> scene;
  ASSERT_TRUE(
      eventually([&] { return (scene = observer.latest_scene_state()) && !scene->objects.empty(); }, kEventGuard));
  const Eigen::Isometry3d X_WorldBox = scene->objects.front().X_WorldObject;
  const double rest_z = X_WorldBox.translation().z();
  auto rig = std::make_shared<const sim::HandRig>(sim::HandRig::load(sim::HandRig::builtin_path("human_right")));
  const auto model = sim::make_object_model("long_box", box_mesh(), 0, "test");
  const sim::GraspPlan plan = sim::plan_grasp(rig, {}, *model, X_WorldBox, 1.0 / 90);
  ASSERT_TRUE(plan.predicted_grasp);
  const Eigen::Isometry3d X_Alice = shifted({-0.2, 0, 0}, plan.X_WorldPalm);
  const Eigen::Isometry3d X_Bob = shifted({0.2, 0, 0}, plan.X_WorldPalm);
  const Eigen::Vector3d up(0, 0, 0.1);
  const HandKey alice_hand{"alice", client::HandSide::kRight}, bob_hand{"bob", client::HandSide::kRight};
  const auto holders_are = [&](const std::vector<HandKey>& expected) {
    return eventually([&] { return observed.newest() == expected; }, kEventGuard);
  };

  // Above the box, then down onto it (open), then squeeze: alice first, then bob.
  alice.start(shifted({0, 0, 0.1}, X_Alice));
  bob.start(shifted({0, 0, 0.1}, X_Bob));
  alice.move(shifted({0, 0, 0.1}, X_Alice), X_Alice, 0, 0.5);
  bob.move(shifted({0, 0, 0.1}, X_Bob), X_Bob, 0, 0.5);
  alice.move(X_Alice, X_Alice, 1, 0.5);
  ASSERT_TRUE(holders_are({alice_hand})) << "alice never held the box";
  bob.move(X_Bob, X_Bob, 1, 0.5);
  ASSERT_TRUE(holders_are({alice_hand, bob_hand})) << "bob never joined alice";
  // Both lift 10 cm together (alice's thread runs the same path as bob's, interleaved).
  std::thread lift([&] { alice.move(X_Alice, shifted(up, X_Alice), 1, 1.0); });
  bob.move(X_Bob, shifted(up, X_Bob), 1, 1.0);
  lift.join();
  ASSERT_TRUE(eventually([&] { return observed.height() > rest_z + 0.08; }, kEventGuard)) << "the box was not lifted";
  EXPECT_EQ(observed.newest(), (std::vector<HandKey>{alice_hand, bob_hand}));
  // Bob lets go: alice keeps the box in the air.
  bob.set(shifted(up, X_Bob), 0);
  ASSERT_TRUE(holders_are({alice_hand})) << "bob's release did not leave the box with alice";
  std::this_thread::sleep_for(300ms);
  EXPECT_GT(observed.height(), rest_z + 0.08) << "alice dropped it";
  // Alice lets go: it falls.
  alice.set(shifted(up, X_Alice), 0);
  ASSERT_TRUE(holders_are({})) << "alice never let go";
  EXPECT_TRUE(eventually([&] { return observed.height() < rest_z + 0.02; }, kEventGuard)) << "the box did not fall";
  alice.stop();
  bob.stop();

  const std::vector<std::vector<HandKey>> expected{{}, {alice_hand}, {alice_hand, bob_hand}, {alice_hand}, {}};
  std::map<std::uint64_t, std::vector<HandKey>> reference;
  {
    std::lock_guard l(observed.mutex);
    reference = observed.holders;
  }
  for (auto [name, log] : {std::pair{"observer", &observed}, {"alice", &alice.log}, {"bob", &bob.log}}) {
    std::lock_guard l(log->mutex);
    EXPECT_TRUE(log->problems.empty()) << name << ": " << log->problems.front();
    int compared = 0;
    for (const auto& [tick, h] : log->holders)
      if (auto it = reference.find(tick); it != reference.end()) {
        EXPECT_EQ(h, it->second) << name << " and the observer disagree at tick " << tick;
        ++compared;
      }
    EXPECT_GT(compared, 0) << name;
  }
  for (auto [name, log] : {std::pair{"observer", &observed}, {"alice", &alice.log}, {"bob", &bob.log}}) {
    EXPECT_EQ(log->sequence(), expected) << name << ": holder sets in another order";
    std::lock_guard l(log->mutex);
    std::cout << "[ measured ] " << name << " saw " << log->holders.size() << " scene states\n";
  }
  // The events: alice grasps, bob grasps (alice keeps it: no release), bob lets go, alice lets go.
  ASSERT_TRUE(eventually(
      [&] {
        std::lock_guard l(events_mutex);
        return events.size() >= 4;
      },
      kEventGuard));
  std::lock_guard l(events_mutex);
  std::sort(events.begin(), events.end(), [](const auto& a, const auto& b) { return a.event_id < b.event_id; });
  using Kind = client::GraspEvent::Kind;
  const std::vector<std::pair<Kind, HandKey>> expected_events{
      {Kind::kGrasp, alice_hand}, {Kind::kGrasp, bob_hand}, {Kind::kRelease, bob_hand}, {Kind::kRelease, alice_hand}};
  ASSERT_EQ(events.size(), expected_events.size());
  for (std::size_t i = 0; i < events.size(); ++i) {
    EXPECT_EQ(events[i].kind, expected_events[i].first) << "event " << i;
    EXPECT_EQ(events[i].hand, expected_events[i].second) << "event " << i;
  }
}

}  // namespace
}  // namespace telegrasp::testing
