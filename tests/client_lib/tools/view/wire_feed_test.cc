// Tests telegrasp-view's WireFeed (client_lib/tools/view/wire_feed.h), the model's input built
// from wire samples for telegrasp-replay --export-mcap: the newest sample per hand, a disposed
// hand forgotten with its states, grasp events handed over once, values converted as the client
// library does (a quaternion normalized).
#include "wire_feed.h"

#include <gtest/gtest.h>

namespace telegrasp::view {
namespace {

constexpr std::uint8_t kLeft = msg::HAND_LEFT;
constexpr std::uint8_t kRight = msg::HAND_RIGHT;

// A message of type M from hand (`client`, `side`).
template <class M>
M of_hand(const std::string& client, std::uint8_t side) {
  M m;
  m.client_id(client);
  m.hand_side(side);
  return m;
}

msg::HandSkeleton skeleton(const std::string& client, std::uint8_t side, std::uint64_t tick, double x) {
  auto m = of_hand<msg::HandSkeleton>(client, side);
  m.rig(side == kLeft ? "human_left" : "human_right");
  m.tick(tick);
  m.palm().position().x(x);
  m.palm().orientation().w(2);  // not a unit quaternion on the wire
  return m;
}

msg::GraspState grasp_state(const std::string& client, std::uint8_t side, std::int32_t grasped) {
  auto m = of_hand<msg::GraspState>(client, side);
  m.selected_object(grasped);
  m.grasped_object(grasped);
  return m;
}

msg::ContactSet contact_set(const std::string& client, std::uint8_t side, std::int32_t object) {
  auto m = of_hand<msg::ContactSet>(client, side);
  m.object_id(object);
  m.object_pose().orientation().w(1);
  return m;
}

TEST(WireFeedTest, KeepsTheNewestSamplePerHand) {
  WireFeed feed;
  feed.add(skeleton("a", kRight, 1, 0.1));
  feed.add(skeleton("a", kLeft, 1, 0.2));
  feed.add(skeleton("a", kRight, 2, 0.3));
  feed.add(grasp_state("a", kRight, 4));
  feed.add(grasp_state("a", kRight, 5));
  const ClientSnapshot s = feed.snapshot();
  // Hand order (client, then side: left before right), the newest of each.
  ASSERT_EQ(s.skeletons.size(), 2u);
  EXPECT_EQ(s.skeletons[0].hand.side, client::HandSide::kLeft);
  EXPECT_EQ(s.skeletons[1].hand.side, client::HandSide::kRight);
  EXPECT_EQ(s.skeletons[1].tick, 2u);
  EXPECT_DOUBLE_EQ(s.skeletons[1].X_WorldPalm.translation().x(), 0.3);
  // The wire's (2, 0, 0, 0) arrives as the identity rotation, as from a live client.
  EXPECT_TRUE(s.skeletons[1].X_WorldPalm.linear().isApprox(Eigen::Matrix3d::Identity(), 1e-15));
  ASSERT_EQ(s.grasp_states.size(), 1u);
  EXPECT_EQ(s.grasp_states.at({"a", client::HandSide::kRight}).grasped_object, 5);
  // Polling again gives the same newest samples.
  EXPECT_EQ(feed.snapshot().skeletons.size(), 2u);
}

TEST(WireFeedTest, ADisposedHandIsForgottenWithItsStates) {
  WireFeed feed;
  feed.add(skeleton("a", kRight, 1, 0));
  feed.add(grasp_state("a", kRight, 3));
  feed.add(contact_set("a", kRight, 3));
  feed.add(skeleton("b", kRight, 1, 0));
  ASSERT_EQ(feed.snapshot().contact_sets.size(), 1u);
  feed.hand_removed("a", kRight);
  const ClientSnapshot s = feed.snapshot();
  ASSERT_EQ(s.skeletons.size(), 1u);
  EXPECT_EQ(s.skeletons[0].hand.client_id, "b");
  EXPECT_TRUE(s.grasp_states.empty());
  EXPECT_TRUE(s.contact_sets.empty());
}

TEST(WireFeedTest, StatesOfAHandWithoutSkeletonAreNotPolled) {
  // telegrasp-view asks for the grasp state and contacts of the hands it has skeletons of.
  WireFeed feed;
  feed.add(grasp_state("a", kRight, 3));
  feed.add(contact_set("a", kRight, 3));
  const ClientSnapshot s = feed.snapshot();
  EXPECT_TRUE(s.grasp_states.empty());
  EXPECT_TRUE(s.contact_sets.empty());
}

TEST(WireFeedTest, HandsOverEachGraspEventOnceAndKeepsTheNewestSceneAndStatus) {
  WireFeed feed;
  for (std::uint64_t id : {1u, 2u}) {
    msg::GraspEvent e;
    e.event_id(id);
    e.client_id("a");
    e.hand_side(kRight);
    feed.add(e);
  }
  msg::SceneState scene;
  scene.tick(7);
  feed.add(scene);
  msg::ServerStatus status;
  status.tick(90);
  feed.add(status);
  const ClientSnapshot first = feed.snapshot();
  ASSERT_EQ(first.events.size(), 2u);
  EXPECT_EQ(first.events[0].event_id, 1u);
  EXPECT_EQ(first.events[1].event_id, 2u);
  ASSERT_TRUE(first.scene && first.status);
  EXPECT_EQ(first.scene->tick, 7u);
  EXPECT_EQ(first.status->tick, 90u);
  const ClientSnapshot second = feed.snapshot();
  EXPECT_TRUE(second.events.empty());
  EXPECT_TRUE(second.scene.has_value());
}

}  // namespace
}  // namespace telegrasp::view
