// A remote operator with nothing but the wire (issue 12 section 6): telegrasp-bot with no mesh
// files, planning on the ObjectGeometry a free-running server (real time, 90 Hz, not --lockstep)
// publishes, on the hardest objects: the thin ones and the sugar box (a tall box that rocks after
// a release). The full run, every object with 3 trials and several seeds, is
// tests/integration/bot_no_meshes.sh.
#include "bot.h"
#include "process.h"
#include "telegrasp/idl/cli.h"
#include "telegrasp/sim/mesh_loading.h"
#include "telegrasp/sim/standin_objects.h"
#include "test_domain.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <iterator>
#include <map>
#include <string>
#include <vector>

namespace telegrasp::testing {
namespace {

using namespace std::chrono_literals;

// Against a hang only: the run takes about 45 s, and 245 s under ASan+UBSan (the opposable
// hands plan each grasp against the operator's aim errors), which a 240 s guard cut (2026-12-07).
constexpr auto kGuard = 540s;  // under ctest's 600 s for an integration test
constexpr double kTarget = 0.95;  // issue 12 section 6: held in at least 95 % of trials

// The thin stand-ins, the sugar box and the strawberry (small and light: the misses of earlier
// runs), two rows across the table.
const char* kHardObjects = R"(
objects { model: "031_spoon" x: 0.45 y: -0.36 }
objects { model: "037_scissors" x: 0.45 y: -0.12 }
objects { model: "044_flat_screwdriver" x: 0.45 y: 0.12 }
objects { model: "012_strawberry" x: 0.45 y: 0.36 }
objects { model: "030_fork" x: 0.78 y: -0.36 yaw: 0.4 }
objects { model: "032_knife" x: 0.78 y: -0.12 yaw: -0.3 }
objects { model: "033_spatula" x: 0.78 y: 0.12 }
objects { model: "004_sugar_box" x: 0.78 y: 0.36 }
)";
constexpr int kObjects = 8, kTrials = 3;

struct Outcome {
  int held = 0, trials = 0;
  std::map<std::string, std::pair<int, int>> by_object;  // held, trials
  std::vector<std::string> misses;
};

Outcome read_records(const std::string& path) {
  Outcome out;
  std::ifstream in(path);
  const nlohmann::json j = nlohmann::json::parse(in, nullptr, false);
  if (j.is_discarded() || !j.contains("grasps")) return out;
  for (const auto& g : j["grasps"]) {
    const bool held = g.value("held_after_lift", false);
    const std::string object = g.value("object", "?");
    ++out.trials;
    out.held += held;
    auto& [h, n] = out.by_object[object];
    h += held;
    ++n;
    if (!held)
      out.misses.push_back(object + ": " + (g["reason"].is_string() ? g["reason"].get<std::string>() : "no reason"));
  }
  return out;
}

// A bot that cannot load its hand's rig stops at once with the file's name (it used to wait for
// a server, then abort on the uncaught exception).
TEST(BotTest, WithoutItsRigTheBotStopsAtOnceNamingTheFile) {
  const std::string log = work_path("bot_without_rig.log");
  ChildProcess bot({"/usr/bin/env", "TELEGRASP_DATA_DIR=" + work_path("no_such_data"), bin("telegrasp-bot"), "--domain",
                    "0", "--timeout-s", "60"},
                   log);
  EXPECT_EQ(bot.wait(30s), 1) << bot.log_tail();
  std::ifstream in(log);
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_NE(text.find("human_right_opposable.textproto: cannot open rig file"), std::string::npos) << text;
}

// The bot plans on the server's published geometry only (no --objects) and holds the hardest
// objects in at least 95 % of its trials (23 of 24: per object that is 3 of 3 but for one object;
// the full run asks 3 of 3 of every object); every record arrives, and its exit status and last
// line say whether every trial held.
TEST(BotTest, NoMeshFilesHoldsTheHardestObjectsOnAFreeRunningServer) {
  const DomainLease lease;
  const std::string domain = std::to_string(lease.domain());
  const std::string config = work_path("hard.textproto");
  std::ofstream(config) << kHardObjects;
  ChildProcess server({bin("telegrasp-server"), "--domain", domain, "--profile", "loopback", "--config", config},
                      work_path("hard_server.log"));
  const std::string json = work_path("hard_bot.json");
  const auto start = std::chrono::steady_clock::now();
  ChildProcess bot(
      {bin("telegrasp-bot"), "--client-id", "no-meshes", "--hands", "both", "--trials", std::to_string(kTrials),
       "--seed", "2", "--domain", domain, "--profile", "loopback", "--json", json, "--timeout-s", "30"},
      work_path("hard_bot.log"));
  const int status = bot.wait(kGuard);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  ASSERT_NE(status, -1) << "the bot did not finish in " << kGuard.count() << " s; see " << bot.log_path();
  ASSERT_TRUE(status == 0 || status == cli::kExitNotHeld) << bot.exit_description() << "\n" << bot.log_tail();
  const Outcome o = read_records(json);
  std::cout << "[ measured ] held " << o.held << "/" << o.trials << " in " << seconds << " s:";
  for (const auto& [object, hn] : o.by_object) std::cout << " " << object << " " << hn.first << "/" << hn.second;
  std::cout << "\n";
  EXPECT_EQ(o.trials, kObjects * kTrials) << "one record per object and trial";
  EXPECT_EQ(o.by_object.size(), static_cast<std::size_t>(kObjects));
  EXPECT_GE(o.held, kTarget * o.trials) << [&] {
    std::string s = "misses:";
    for (const std::string& m : o.misses) s += "\n  " + m;
    return s + "\nsee " + bot.log_path();
  }();
  // Exit status 0 exactly when every trial held, else 3.
  EXPECT_EQ(status, o.held == o.trials ? 0 : 3);
  // The held line at the end of its output says the same.
  const std::string tail = bot.log_tail(5);
  EXPECT_NE(tail.find("held " + std::to_string(o.held) + "/" + std::to_string(o.trials) + " trials"), std::string::npos)
      << tail;
}

// The geometry a server publishes for a stand-in, as the client library delivers it.
client::ObjectGeometry published(const sim::ObjectModel& m) {
  client::ObjectGeometry g;
  g.model = m.name;
  g.content_hash = 42;
  for (const Eigen::Vector3d& v : m.mesh.vertices) g.vertices.push_back(v.cast<float>());
  g.triangles = m.mesh.triangles;
  g.vertex_count = static_cast<std::uint32_t>(g.vertices.size());
  g.triangle_count = static_cast<std::uint32_t>(g.triangles.size());
  g.p_ObjectMin = m.p_ObjectMin;
  g.p_ObjectMax = m.p_ObjectMax;
  g.mass_kg = m.mass_kg;
  return g;
}

// The bot plans on a received mesh in its model frame, unchanged; a model published without its
// mesh (over the server's size limit) is planned on the box of its bounds instead of given up.
TEST(BotModelTest, ReceivedMeshInTheModelFrameAndTheBoundsWhenTheMeshIsOmitted) {
  const sim::ObjectModelPtr knife = sim::make_standin_model(*sim::find_protocol_object("032_knife"));
  client::ObjectGeometry g = published(*knife);
  const sim::ObjectModelPtr received = bot::model_from_geometry(g);
  EXPECT_EQ(received->name, "032_knife");
  EXPECT_EQ(received->mesh.triangles.size(), knife->mesh.triangles.size());
  EXPECT_LT((received->p_ObjectMin - knife->p_ObjectMin).norm(), 1e-6);
  EXPECT_LT(received->mass_properties.centroid.norm(), 1e-4) << "not in the model frame";

  g.mesh_omitted = true;
  g.vertices.clear();
  g.triangles.clear();
  const sim::ObjectModelPtr box = bot::model_from_geometry(g);
  EXPECT_EQ(box->mesh.triangles.size(), 12u);
  EXPECT_LT((box->p_ObjectMin - knife->p_ObjectMin).norm(), 1e-9);
  EXPECT_LT((box->p_ObjectMax - knife->p_ObjectMax).norm(), 1e-9);
  const Eigen::Vector3d size = knife->p_ObjectMax - knife->p_ObjectMin;
  EXPECT_NEAR(box->mass_properties.volume, size.prod(), 1e-9) << "a closed box, faces outward";
  EXPECT_EQ(box->mass_kg, knife->mass_kg);

  g.p_ObjectMax = g.p_ObjectMin;  // no mesh and no bounds: nothing to plan on
  EXPECT_THROW(bot::model_from_geometry(g), sim::MeshLoadError);
}

}  // namespace
}  // namespace telegrasp::testing
