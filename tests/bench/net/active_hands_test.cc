// Tests telegrasp-bench-scale --active's hands without DDS: the object grid fits the server's
// table and scene, and the hands, driven through a real SceneServer (the server's configuration
// file loader, input mailbox and tick), grasp, lift, hold and release their objects trial after
// trial, as the server's GraspEvents tell.
#include "active_hands.h"

#include "input_mailbox.h"
#include "output_sink.h"
#include "scene_server.h"
#include "server_config.h"

#include "telegrasp/sim/standin_objects.h"

#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <unistd.h>

namespace telegrasp::bench {
namespace {

constexpr const char* kModel = "005_tomato_soup_can";

TEST(ActiveObjectGridTest, FitsTheTableAndTheScene) {
  // The server's table is [-2, 2]^2 m and a scene holds 128 objects.
  for (int h = 0; h < kMaxActiveHands; ++h) {
    const Eigen::Vector2d p = active_object_xy(h);
    EXPECT_LE(p.cwiseAbs().maxCoeff(), 1.8) << "hand " << h;
    for (int k = 0; k < h; ++k) EXPECT_GE((p - active_object_xy(k)).norm(), 0.3 - 1e-9) << h << " and " << k;
  }
}

struct SinkOfEvents : server::OutputSink {
  std::vector<msg::GraspEvent> events;
  std::optional<msg::SceneState> scene;
  void publish(const msg::HandSkeleton&) override {}
  void publish(const msg::GraspState&) override {}
  void publish(const msg::ContactSet&) override {}
  void publish(const msg::GraspEvent& m) override { events.push_back(m); }
  void publish(const msg::SceneState& m) override { scene = m; }
  void publish(const msg::ServerStatus&) override {}
  void hand_removed(const server::HandAddress&) override {}
};

// The server's default hand on `side`, as the bench's server has.
std::shared_ptr<const sim::HandRig> rig(sim::HandSide side) {
  return std::make_shared<const sim::HandRig>(
      sim::HandRig::load(sim::HandRig::builtin_path(sim::HandRig::default_human(side))));
}

TEST(ActiveHandsTest, GraspAndHoldTheirObjectsOnAServer) {
  constexpr int kHands = 4;
  // The scene as the bench configures the server: its configuration lines, through the loader.
  const std::string config =
      (std::filesystem::temp_directory_path() / ("active-hands-test-" + std::to_string(::getpid()) + ".conf")).string();
  std::ofstream(config) << "max_hands: 16\n" << active_objects_config(kHands, kModel);
  server::ServerSettings settings;
  server::load_server_config(config, settings);
  std::filesystem::remove(config);
  ASSERT_EQ(settings.objects.size(), static_cast<std::size_t>(kHands));
  std::vector<sim::ObjectModelPtr> models;
  for (const auto& o : sim::protocol_objects()) models.push_back(sim::make_standin_model(o));
  server::InputMailbox mailbox{{5, 5}, 16, [](const std::string&) {}};
  SinkOfEvents sink;
  server::SceneServer scene(settings, models, rig(sim::HandSide::kRight), rig(sim::HandSide::kLeft), mailbox, sink);
  ASSERT_EQ(scene.world().objects().size(), static_cast<std::size_t>(kHands));

  ActiveHands hands(kModel, kHands, 90.0);
  hands.set_active(true);
  const server::ParticipantKey participant{1};
  std::int64_t now = 0;
  std::uint64_t seq = 0;
  std::size_t events_seen = 0;
  scene.tick(now);  // a first SceneState, as a running server has published before hands come
  for (int k = 0; k < 90 * 9; ++k) {  // 9 s: the 2 s stagger and at least two 2.4 s trials each
    const double t = k / 90.0;
    if (sink.scene) hands.on_scene_state(*sink.scene, t);
    for (; events_seen < sink.events.size(); ++events_seen) hands.on_grasp_event(sink.events[events_seen]);
    for (int h = 0; h < kHands; ++h) {
      const int client = h / 2, side = h % 2;
      ASSERT_TRUE(
          mailbox.offer(hands.sample("scale-" + std::to_string(client), client, side, ++seq, t), participant, now));
    }
    scene.on_inputs(mailbox.drain(), now);
    now += 11'111'111;
    scene.tick(now);
  }
  const ActiveCounts c = hands.counts();
  for (int h = 0; h < kHands; ++h) EXPECT_GE(c.grasps_per_hand[h], 2u) << "hand " << h;
  EXPECT_GE(c.cycles, static_cast<std::uint64_t>(2 * kHands));
  EXPECT_EQ(c.cycles_held, c.cycles) << "every trial held through the lift and hold";
  EXPECT_GE(c.releases + kHands, c.grasps);
  EXPECT_EQ(c.objects_fallen, 0u);
  EXPECT_EQ(c.objects_missing, 0u);
  // Each hand grasped its own object: the one at its grid place.
  for (const msg::GraspEvent& e : sink.events) {
    if (e.kind() != msg::GRASP_EVENT_GRASP) continue;
    const int h = 2 * std::stoi(e.client_id().to_string().substr(6)) + e.hand_side();
    const Eigen::Vector2d place = active_object_xy(h);
    EXPECT_LT(std::hypot(e.object_pose().position().x() - place.x(), e.object_pose().position().y() - place.y()), 0.05)
        << "hand " << h;
  }
}

}  // namespace
}  // namespace telegrasp::bench
