// Packet loss (issue 13 section 2): the server, a bot and a second subscriber (telegrasp-echo) on
// the UDP-only profile, with every packet arriving on `lo` dropped with probability P (iptables in
// this test's own network namespace). Grasps still complete, and every GraspEvent (reliable)
// reaches both subscribers exactly once: event_id 1, 2, 3 ... with no gap and no repeat.
#include "fault_env.h"
#include "process.h"
#include "telegrasp/idl/cli.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <chrono>
#include <cstdint>
#include <fstream>
#include <iostream>
#include <string>
#include <thread>
#include <vector>

namespace telegrasp::testing {
namespace {

using namespace std::chrono_literals;
using Clock = std::chrono::steady_clock;

constexpr auto kGuard = 300s;  // against a hang only: a run takes 15-40 s
constexpr int kObjects = 4, kTrials = 2;
// Grasps still complete: at least 7 of the 8 trials held after the lift at any loss (room for one
// miss of the operator's, as without loss; every trial held in the six runs measured).
constexpr int kMinHeld = 7;
// Four objects in two rows, 33 cm and more apart. In one row 20 cm apart, the second trials of two
// neighbours (soup can, mustard bottle) were not grasped in 6 attempts in about half the lossy runs (the
// server never grasped: no event was lost), likely the two hands in each other's way; spread out,
// every trial held in 6 of 6.
const char* kScene = R"(
objects { model: "005_tomato_soup_can" x: 0.45 y: -0.3 }
objects { model: "006_mustard_bottle" x: 0.78 y: -0.3 }
objects { model: "003_cracker_box" x: 0.45 y: 0.3 }
objects { model: "013_apple" x: 0.78 y: 0.3 }
)";

std::string percent(double p) { return std::to_string(static_cast<int>(p * 100 + 0.5)); }

// Waits until `ready` or `timeout`; whether it became ready.
template <class F>
bool wait_for(F ready, std::chrono::milliseconds timeout) {
  const auto deadline = Clock::now() + timeout;
  while (!ready()) {
    if (Clock::now() > deadline) return false;
    std::this_thread::sleep_for(50ms);
  }
  return true;
}

std::vector<std::uint64_t> echo_event_ids(const std::string& path, int* grasps = nullptr, int* releases = nullptr) {
  std::vector<std::uint64_t> ids;
  for (const nlohmann::json& j : read_json_lines(path)) {
    if (j.value("topic", "") != "GraspEvent") continue;
    ids.push_back(j.at("event_id").get<std::uint64_t>());
    if (grasps && j.value("kind", "") == "grasp") ++*grasps;
    if (releases && j.value("kind", "") == "release") ++*releases;
  }
  return ids;
}

bool echo_has_status(const std::string& path) {
  for (const nlohmann::json& j : read_json_lines(path))
    if (j.value("topic", "") == "ServerStatus") return true;
  return false;
}

class PacketLossTest : public ::testing::TestWithParam<double> {};

TEST_P(PacketLossTest, GraspsCompleteAndEveryGraspEventArrivesOnce) {
  if (!in_private_network()) GTEST_SKIP() << private_network_failure();
  const double loss = GetParam();
  const std::string tag = "loss" + percent(loss);
  const std::string error = drop_loopback_packets(loss);
  ASSERT_EQ(error, "") << "packet loss needs iptables with the statistic match (deploy/install-deps.sh)";
  // The namespace is this process's own: any domain will do.
  const std::string domain = "0";
  const std::string config = work_path(tag + "_scene.textproto");
  std::ofstream(config) << kScene;

  // 1. The server, then the second subscriber; the bot starts once the subscriber hears the server
  //    (GraspEvent is volatile: a reader matched after an event never gets it) and discovery has
  //    had time to match its GraspEvent reader too.
  ChildProcess server({bin("telegrasp-server"), "--domain", domain, "--profile", "udp", "--config", config},
                      work_path(tag + "_server.log"));
  const std::string echo_log = work_path(tag + "_echo.jsonl");
  ChildProcess echo(
      {bin("telegrasp-echo"), "--domain", domain, "--profile", "udp", "--topics", "GraspEvent,ServerStatus"}, echo_log);
  ASSERT_TRUE(wait_for([&] { return echo_has_status(echo_log); }, 60s))
      << "telegrasp-echo heard no ServerStatus in 60 s\n"
      << server.log_tail();
  std::this_thread::sleep_for(3s);

  // 2. The bot: both hands, every object twice.
  const std::string json = work_path(tag + "_bot.json");
  const auto start = Clock::now();
  ChildProcess bot(
      {bin("telegrasp-bot"), "--client-id", "lossy", "--hands", "both", "--trials", std::to_string(kTrials), "--seed",
       "1", "--domain", domain, "--profile", "udp", "--json", json, "--timeout-s", "60"},
      work_path(tag + "_bot.log"));
  const int status = bot.wait(kGuard);
  const double seconds = std::chrono::duration<double>(Clock::now() - start).count();
  ASSERT_NE(status, -1) << "the bot did not finish in " << kGuard.count() << " s; see " << bot.log_path();
  ASSERT_TRUE(status == 0 || status == cli::kExitNotHeld) << bot.exit_description() << "\n" << bot.log_tail();

  std::ifstream in(json);
  const nlohmann::json result = nlohmann::json::parse(in, nullptr, false);
  ASSERT_TRUE(result.is_object() && result.contains("grasps") && result.contains("grasp_events")) << json;

  // 3. The echo has every event the bot has, and (the bot's hands removed 0.5 s after it ended)
  //    a release for every grasp.
  const std::uint64_t bot_last =
      result["grasp_events"]["last"].is_null() ? 0 : result["grasp_events"]["last"].get<std::uint64_t>();
  int grasps = 0, releases = 0;
  wait_for(
      [&] {
        grasps = releases = 0;
        const std::vector<std::uint64_t> ids = echo_event_ids(echo_log, &grasps, &releases);
        return !ids.empty() && check_event_ids(ids).ids.back() >= bot_last && grasps == releases;
      },
      20s);
  std::this_thread::sleep_for(1s);
  echo.stop();
  server.stop();

  // 4. Grasps complete: every trial recorded, most held, each grasp's event in its record.
  int held = 0, grasped = 0;
  double time_sum = 0;
  std::string reasons;
  for (const nlohmann::json& g : result["grasps"]) {
    held += g.value("held_after_lift", false);
    if (g["time_to_grasp_s"].is_number()) grasped += 1, time_sum += g["time_to_grasp_s"].get<double>();
    if (g["reason"].is_string()) reasons += "\n  " + g.value("object", "?") + ": " + g["reason"].get<std::string>();
  }
  const int trials = static_cast<int>(result["grasps"].size());
  std::cout << "[ measured ] loss " << percent(loss) << " %: held " << held << "/" << trials << ", mean time to grasp "
            << (grasped ? time_sum / grasped : 0) << " s over " << grasped << " grasps, run " << seconds
            << " s; events at the bot: " << result["grasp_events"]["received"] << ", at the echo: " << grasps + releases
            << reasons << "\n";
  EXPECT_EQ(trials, kObjects * kTrials);
  EXPECT_GE(held, kMinHeld) << reasons;
  EXPECT_EQ(reasons.find("no grasp event received"), std::string::npos)
      << "a grasp the bot saw never had its event:" << reasons;

  // 5. Not one event lost or repeated, at either subscriber.
  const nlohmann::json& be = result["grasp_events"];
  EXPECT_EQ(be["first"], 1) << "the bot missed the first event(s): " << be.dump();
  EXPECT_TRUE(be["missing"].empty()) << "events lost at the bot: " << be.dump();
  EXPECT_TRUE(be["duplicates"].empty()) << "events repeated at the bot: " << be.dump();
  grasps = releases = 0;
  const EventIds echo_ids = check_event_ids(echo_event_ids(echo_log, &grasps, &releases));
  ASSERT_FALSE(echo_ids.ids.empty()) << "the echo got no GraspEvent; see " << echo_log;
  EXPECT_EQ(echo_ids.ids.front(), 1u) << echo_ids.describe();
  EXPECT_TRUE(echo_ids.missing.empty()) << "events lost at the echo: " << echo_ids.describe();
  EXPECT_TRUE(echo_ids.duplicates.empty()) << "events repeated at the echo: " << echo_ids.describe();
  EXPECT_GE(echo_ids.ids.back(), bot_last) << echo_ids.describe();
  EXPECT_EQ(grasps, releases) << "every grasp is released (the bot's hands are removed when it ends)";
  EXPECT_GE(grasps, held);
}

INSTANTIATE_TEST_SUITE_P(Loss, PacketLossTest, ::testing::Values(0.0, 0.05, 0.20),
                         [](const ::testing::TestParamInfo<double>& info) { return "Percent" + percent(info.param); });

}  // namespace
}  // namespace telegrasp::testing
