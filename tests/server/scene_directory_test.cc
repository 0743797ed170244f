// Tests server/src/scene_directory: which of two runs claiming a scene keeps it, and what a run
// announces.
#include "scene_directory.h"

#include <gtest/gtest.h>

namespace telegrasp::server {
namespace {

msg::SceneAnnouncement run(const std::string& scene, double started, std::uint64_t incarnation) {
  return make_claim({scene, "host-" + std::to_string(incarnation), "0.1.0", incarnation, started});
}

TEST(SceneDirectoryTest, TheEarlierStartKeepsTheScene) {
  EXPECT_TRUE(claimed_before(run("a", 100, 9), run("a", 101, 1)));
  EXPECT_FALSE(claimed_before(run("a", 101, 1), run("a", 100, 9)));
  // Same start: the smaller incarnation, so both runs agree.
  EXPECT_TRUE(claimed_before(run("a", 100, 1), run("a", 100, 2)));
  EXPECT_FALSE(claimed_before(run("a", 100, 2), run("a", 100, 1)));
}

TEST(SceneDirectoryTest, OnlyAnOlderRunOfTheSameSceneStopsAStart) {
  const msg::SceneAnnouncement mine = run("lab", 200, 5);
  EXPECT_FALSE(older_claim(mine, {}));
  EXPECT_FALSE(older_claim(mine, {mine})) << "its own entry";
  EXPECT_FALSE(older_claim(mine, {run("other", 100, 1)})) << "another scene";
  EXPECT_FALSE(older_claim(mine, {run("lab", 300, 7)})) << "a newer run: that one stops";
  const auto keeper = older_claim(mine, {run("lab", 300, 7), run("lab", 150, 3), run("lab", 120, 4), mine});
  ASSERT_TRUE(keeper);
  EXPECT_EQ(keeper->incarnation(), 4u) << "the oldest claim";
}

TEST(SceneDirectoryTest, AnAnnouncementCarriesTheStatusAndLoad) {
  msg::ServerStatus status;
  status.clients(3);
  status.hands(5);
  status.objects(7);
  status.tick_rate_hz(90);
  status.tick_us_p99(812.5);
  status.missed_ticks(11);
  const msg::SceneAnnouncement a = make_announcement({"lab", "h", "0.1.0", 42, 1000.5}, status, 37.5, 8, 0.25);
  EXPECT_EQ(a.scene().to_string(), "lab");
  EXPECT_EQ(a.host().to_string(), "h");
  EXPECT_EQ(a.incarnation(), 42u);
  EXPECT_EQ(a.started(), 1000.5);
  EXPECT_TRUE(a.serving());
  EXPECT_FALSE(make_claim({"lab", "h", "0.1.0", 42, 1000.5}).serving());
  EXPECT_EQ(a.clients(), 3);
  EXPECT_EQ(a.hands(), 5);
  EXPECT_EQ(a.objects(), 7);
  EXPECT_EQ(a.tick_rate_hz(), 90);
  EXPECT_EQ(a.tick_us_p99(), 812.5);
  EXPECT_EQ(a.missed_ticks(), 11u);
  EXPECT_EQ(a.cpu_percent(), 37.5);
  EXPECT_EQ(a.host_cores(), 8);
  EXPECT_EQ(a.host_load(), 0.25);
}

TEST(SceneDirectoryTest, TheRefusalNamesTheSceneHostAndRun) {
  const std::string m = already_served_message(run("lab", 1, 0xabc));
  EXPECT_NE(m.find("scene 'lab' is already served by host-2748"), std::string::npos) << m;
  EXPECT_NE(m.find("0000000000000abc"), std::string::npos) << m;
  EXPECT_NE(m.find("--scene"), std::string::npos) << m;
}

}  // namespace
}  // namespace telegrasp::server
