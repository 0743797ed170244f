// Tests server/src/snapshot: a scene snapshot written atomically and read back to the same poses,
// each kind of damaged or unusable file refused with a message naming it, the writer's last
// write on a clean stop, the incarnation in SceneState and ServerStatus, and a SceneServer
// started from restored objects (a reset still brings back the configured scene).
#include "scratch_dir.h"
#include "snapshot.h"

#include "recording.h"
#include "replay.h"
#include "scene_server.h"
#include "scene_setup.h"
#include "telegrasp/sim/standin_objects.h"
#include "test_scene.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <functional>
#include <set>

namespace telegrasp::server {
namespace {

namespace fs = std::filesystem;

msg::ObjectState object(int id, const std::string& name, const Eigen::Vector3d& p, const Eigen::Quaterniond& q) {
  msg::ObjectState o;
  o.id(id);
  o.name(name);
  Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
  X.linear() = q.toRotationMatrix();
  X.translation() = p;
  o.pose(to_msg(X));
  return o;
}

// Two objects, one turned about an oblique axis and held.
msg::SceneState two_objects() {
  msg::SceneState s;
  s.tick(1234);
  s.time(13.71);
  s.incarnation(0xFEDCBA9876543210ULL);
  s.objects().push_back(object(3, "005_tomato_soup_can", {0.45, -0.35, 0.0512}, Eigen::Quaterniond::Identity()));
  msg::ObjectState held = object(7, "056_tennis_ball", {0.1234567890123, 0.35, 0.2},
                                 Eigen::Quaterniond(Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized())));
  held.held(true);
  s.objects().push_back(held);
  return s;
}

std::string write_text(const std::string& name, const std::string& text) {
  const std::string path = (scratch_dir("snapshot_test") / name).string();
  std::ofstream(path) << text;
  return path;
}

std::string error_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const SnapshotError& e) {
    return e.what();
  }
  return "";
}

TEST(SnapshotTest, WrittenAtomicallyAndReadBackToTheSamePoses) {
  const fs::path dir = scratch_dir("snapshot_test") / "roundtrip";
  fs::create_directories(dir);
  const std::string path = (dir / "scene.snapshot").string();
  EXPECT_FALSE(read_snapshot(path)) << "no file yet: nothing to restore";

  const msg::SceneState scene = two_objects();
  write_snapshot(path, make_snapshot(scene));
  write_snapshot(path, make_snapshot(scene));  // over an existing file too
  // Only the file itself is left: the temporary one was renamed over it.
  std::set<std::string> files;
  for (const auto& e : fs::directory_iterator(dir)) files.insert(e.path().filename().string());
  EXPECT_EQ(files, std::set<std::string>{"scene.snapshot"});

  const auto back = read_snapshot(path);
  ASSERT_TRUE(back);
  EXPECT_EQ(back->incarnation(), 0xFEDCBA9876543210ULL);
  EXPECT_EQ(back->tick(), 1234u);
  EXPECT_TRUE(back->objects(1).held());
  const std::vector<PlacedObject> placed = placed_objects(*back, standins(), "test");
  ASSERT_EQ(placed.size(), 2u);
  for (std::size_t i = 0; i < placed.size(); ++i) {
    EXPECT_EQ(placed[i].model, scene.objects()[i].name().to_string());
    // Text format keeps every digit of a double: the very same pose.
    EXPECT_TRUE(placed[i].X_WorldObject().isApprox(to_eigen(scene.objects()[i].pose()), 1e-15)) << i;
    EXPECT_EQ(placed[i].p_WorldObject.x(), scene.objects()[i].pose().position().x());
  }
}

TEST(SnapshotTest, DamagedOrUnusableFilesAreRefusedNamingWhatIsWrong) {
  const auto models = standins();
  // Cut inside an object: a parse error with its line.
  const std::string cut = write_text("cut.snapshot", "format_version: 1\nobjects {\n  model: \"005_tomato");
  const std::string parse = error_of([&] { read_snapshot(cut); });
  EXPECT_NE(parse.find("snapshot " + cut), std::string::npos) << parse;
  EXPECT_NE(parse.find("line"), std::string::npos) << parse;

  // Parses, but is not a snapshot (empty), or lost objects (count), or names an unknown model, or
  // has a pose that is not a rotation.
  struct Case {
    const char* text;
    const char* says;
  };
  const Case cases[] = {
      {"", "no format_version"},
      {"format_version: 2 object_count: 0", "format_version is 2"},
      {"format_version: 1 objects { model: \"056_tennis_ball\" pose { qw: 1 } } object_count: 2", "not whole"},
      {"format_version: 1 objects { model: \"056_tennis_ball\" pose { qw: 1 } }", "object_count missing"},
      {"format_version: 1 objects { model: \"no_such_model\" pose { qw: 1 } } object_count: 1",
       "objects[0] (model 'no_such_model'): no such model"},
      {"format_version: 1 objects { model: \"056_tennis_ball\" pose { qw: 0.5 } } object_count: 1", "norm"},
      {"format_version: 1 objects { model: \"056_tennis_ball\" pose { x: nan qw: 1 } } object_count: 1", "not finite"},
  };
  for (const Case& c : cases) {
    const std::string path = write_text("case.snapshot", c.text);
    const std::string why = error_of([&] { placed_objects(*read_snapshot(path), models, "snapshot " + path); });
    EXPECT_NE(why.find("snapshot " + path), std::string::npos) << c.text << " -> " << why;
    EXPECT_NE(why.find(c.says), std::string::npos) << c.text << " -> " << why;
  }

  // A folder that does not exist: found at start-up, not at the first write.
  const std::string nowhere = (scratch_dir("snapshot_test") / "missing" / "scene.snapshot").string();
  const std::string why = error_of([&] { check_snapshot_writable(nowhere); });
  EXPECT_NE(why.find(nowhere), std::string::npos) << why;
  EXPECT_NE(error_of([&] { write_snapshot(nowhere, make_snapshot(two_objects())); }).find(nowhere), std::string::npos);
}

struct CountingSink : OutputSink {
  int scenes = 0, statuses = 0;
  std::vector<msg::SceneState> scene_states;
  void publish(const msg::HandSkeleton&) override {}
  void publish(const msg::GraspState&) override {}
  void publish(const msg::ContactSet&) override {}
  void publish(const msg::GraspEvent&) override {}
  void publish(const msg::SceneState& m) override {
    ++scenes;
    scene_states.push_back(m);
  }
  void publish(const msg::ServerStatus&) override { ++statuses; }
  void hand_removed(const HandAddress&) override {}
};

// Every output goes on to the next sink; the file gets the newest scene state, at the latest when
// the writer goes (a clean stop), even inside its period.
TEST(SnapshotTest, WriterForwardsEverythingAndWritesTheLastStateOnStop) {
  const std::string path = (scratch_dir("snapshot_test") / "writer.snapshot").string();
  CountingSink next;
  msg::SceneState scene = two_objects();
  {
    SnapshotWriter writer(path, next, 3600.0);  // one periodic write, the first state
    writer.publish(scene);
    scene.tick(1235);
    scene.objects()[0].pose().position().x(0.5);
    writer.publish(scene);
    writer.publish(msg::ServerStatus{});
  }
  EXPECT_EQ(next.scenes, 2);
  EXPECT_EQ(next.statuses, 1);
  const auto back = read_snapshot(path);
  ASSERT_TRUE(back);
  EXPECT_EQ(back->tick(), 1235u);
  EXPECT_EQ(back->objects(0).pose().x(), 0.5);
}

// A server started from restored objects has them at their poses (and no configured object); it
// publishes its incarnation; a reset brings back the configured scene.
TEST(SnapshotTest, SceneServerStartsFromRestoredObjectsAndPublishesItsIncarnation) {
  ServerSettings settings;
  settings.objects = {{"005_tomato_soup_can", 0.4, 0.0, 0.0}};
  settings.incarnation = 0x1234;
  settings.operators = {"op"};
  const auto snapshot = make_snapshot(two_objects());
  settings.restored_objects = placed_objects(snapshot, standins(), "test");
  InputMailbox mailbox{{5, 5}, 4, [](const std::string&) {}};
  CountingSink sink;
  SceneServer scene(settings, standins(), rig("human_right"), rig("human_left"), mailbox, sink);
  const auto objects = scene.world().objects();
  ASSERT_EQ(objects.size(), 2u);
  EXPECT_EQ(scene.world().object_model(objects[1]).name, "056_tennis_ball");
  EXPECT_TRUE(scene.world().object_pose(objects[1]).isApprox(settings.restored_objects->at(1).X_WorldObject(), 1e-12));
  scene.tick(11'111'111);
  ASSERT_FALSE(sink.scene_states.empty());
  EXPECT_EQ(sink.scene_states.back().incarnation(), 0x1234u);
  EXPECT_EQ(scene.status(LoopStats{}).incarnation(), 0x1234u);

  msg::SceneCommand reset;
  reset.kind(msg::SCENE_RESET);
  reset.client_id("op");  // settings.operators
  EXPECT_EQ(scene.apply_command(reset), "");
  ASSERT_EQ(scene.world().objects().size(), 1u);
  EXPECT_EQ(scene.world().object_model(scene.world().objects()[0]).name, "005_tomato_soup_can");
}

// A run started from a snapshot replays identically: the recording keeps its incarnation and the
// restored objects exactly as they were read, so every SceneState compares byte for byte.
TEST(SnapshotTest, ARunStartedFromASnapshotReplaysIdentically) {
  ServerSettings settings;
  settings.incarnation = 0xABCDEF0123456789ULL;
  const SceneAssets assets = load_scene_assets(settings);
  settings.restored_objects = placed_objects(make_snapshot(two_objects()), assets.models, "test");
  const std::string path = (scratch_dir("snapshot_test") / "restored.tgrec").string();
  {
    InputMailbox mailbox{{5, 5}, 4, [](const std::string&) {}};
    CountingSink next;
    Recorder recorder(path, settings, assets, next);
    SceneServer scene(settings, assets.models, assets.right_rig, assets.left_rig, mailbox, recorder);
    for (std::int64_t now = 11'111'111; now < 30 * 11'111'111; now += 11'111'111) {
      recorder.tick(now);
      scene.tick(now);  // the held tennis ball comes back in the air and falls
    }
    ASSERT_EQ(next.scene_states.size(), 29u);
    EXPECT_EQ(next.scene_states.back().incarnation(), settings.incarnation);
  }
  EXPECT_EQ(read_recording(path).header.incarnation(), settings.incarnation);
  const ReplayResult result = replay_recording(path);
  EXPECT_FALSE(result.divergence) << result.summary();
  EXPECT_EQ(result.outputs_compared, 29u) << result.summary();
}

}  // namespace
}  // namespace telegrasp::server
