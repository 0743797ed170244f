// Tests server/src/scene_server with a recording sink instead of DDS: hands joining, late
// latching, grasp events once each, contacts consistent with the published object pose, silent
// hands frozen then removed with their object dropped, scene commands and the default layout.
#include "controller_state.h"
#include "scene_server.h"

#include "telegrasp/sim/scripted_operator.h"
#include "telegrasp/sim/standin_objects.h"
#include "test_scene.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <set>

namespace telegrasp::server {
namespace {

constexpr std::int64_t kTickNs = 11'111'111;  // 90 Hz
const ParticipantKey kParticipant{1};

struct RecordingSink : OutputSink {
  std::vector<msg::HandSkeleton> skeletons;
  std::vector<msg::GraspState> states;
  std::vector<msg::ContactSet> contacts;
  std::vector<msg::GraspEvent> events;
  std::vector<msg::SceneState> scenes;
  std::vector<HandAddress> removed;
  void publish(const msg::HandSkeleton& m) override { skeletons.push_back(m); }
  void publish(const msg::GraspState& m) override { states.push_back(m); }
  void publish(const msg::ContactSet& m) override { contacts.push_back(m); }
  void publish(const msg::GraspEvent& m) override { events.push_back(m); }
  void publish(const msg::SceneState& m) override { scenes.push_back(m); }
  void publish(const msg::ServerStatus&) override {}
  std::vector<msg::ClientNotice> notices;
  void publish(const msg::ClientNotice& m) override { notices.push_back(m); }
  void hand_removed(const HandAddress& hand) override { removed.push_back(hand); }
};

// A server with an empty scene, driven by hand with explicit clock values.
struct SceneServerTest : ::testing::Test {
  ServerSettings settings = [] {
    ServerSettings s;
    s.empty_scene = true;
    return s;
  }();
  std::vector<sim::ObjectModelPtr> models = standins();
  std::shared_ptr<const sim::HandRig> right = rig("human_right"), left = rig("human_left");
  InputMailbox mailbox{{5, 5}, 16, [](const std::string&) {}};
  RecordingSink sink;
  std::unique_ptr<SceneServer> scene;
  std::int64_t now = 0;
  std::uint64_t seq = 0;

  void SetUp() override { scene = std::make_unique<SceneServer>(settings, models, right, left, mailbox, sink); }

  int spawn(const std::string& model, double x, double y) {
    msg::SceneCommand c;
    c.kind(msg::SCENE_SPAWN);
    c.model(model);
    c.on_table(true);
    c.x(x);
    c.y(y);
    EXPECT_EQ(scene->apply_command(c), "");
    return scene->world().objects().back().value;
  }
  void send(const std::string& client, std::uint8_t side, const sim::ControllerInput& in) {
    ASSERT_TRUE(mailbox.offer(to_state(client, side, ++seq, in), kParticipant, now));
    scene->on_inputs(mailbox.drain(), now);
  }
  void tick() {
    now += kTickNs;
    scene->tick(now);
  }
  // Drives alice's right hand with the scripted operator until it holds `object`, then lifts.
  void grasp_and_lift(int object) {
    const sim::ObjectModel& model = scene->world().object_model(sim::ObjectId(object));
    sim::ScriptedOperator op(right, sim::skill_profile("perfect"), 7);
    Eigen::Isometry3d start = Eigen::Isometry3d::Identity();
    start.translation() =
        scene->world().object_pose(sim::ObjectId(object)).translation() + Eigen::Vector3d(-0.3, -0.2, 0.3);
    op.begin(model, scene->world().object_pose(sim::ObjectId(object)), start, scene->world().time());
    while (op.phase() != sim::OperatorPhase::kHold && scene->world().time() < 20) {
      const bool held = scene->world().holder(sim::ObjectId(object)).valid();
      send("alice", 1, op.next(scene->world().time(), held));
      tick();
    }
  }
};

// Footprints of the default layout never overlap and stay on the table.
TEST(DefaultLayoutTest, KeepsFootprintsApartOnTheTable) {
  const auto models = standins();
  const double gap = 0.15, half = SceneServer::kTableHalfExtent;
  const auto specs = default_layout(models, gap, half);
  ASSERT_EQ(specs.size(), models.size());
  for (std::size_t i = 0; i < specs.size(); ++i) {
    const Eigen::Vector3d lo_i = models[i]->p_ObjectMin + Eigen::Vector3d(specs[i].x, specs[i].y, 0);
    const Eigen::Vector3d hi_i = models[i]->p_ObjectMax + Eigen::Vector3d(specs[i].x, specs[i].y, 0);
    EXPECT_GE(lo_i.x(), -half);
    EXPECT_LE(hi_i.x(), half);
    EXPECT_GE(lo_i.y(), -half);
    EXPECT_LE(hi_i.y(), half);
    for (std::size_t j = 0; j < i; ++j) {
      const Eigen::Vector3d lo_j = models[j]->p_ObjectMin + Eigen::Vector3d(specs[j].x, specs[j].y, 0);
      const Eigen::Vector3d hi_j = models[j]->p_ObjectMax + Eigen::Vector3d(specs[j].x, specs[j].y, 0);
      const bool apart = lo_i.x() >= hi_j.x() + gap - 1e-9 || lo_j.x() >= hi_i.x() + gap - 1e-9 ||
                         lo_i.y() >= hi_j.y() + gap - 1e-9 || lo_j.y() >= hi_i.y() + gap - 1e-9;
      EXPECT_TRUE(apart) << specs[i].model << " and " << specs[j].model;
    }
  }
}

// A hand appears with its first sample; the skeleton reflecting that sample goes out at once
// (late latched), before the tick; grasp states go out on change only.
TEST_F(SceneServerTest, AHandJoinsOnItsFirstSampleAndIsLateLatched) {
  sim::ControllerInput in;
  in.X_WorldPalm.translation() = Eigen::Vector3d(0.1, 0.2, 0.3);
  send("alice", 1, in);
  ASSERT_TRUE(scene->hand_id({"alice", 1}));
  ASSERT_EQ(sink.skeletons.size(), 1u);
  EXPECT_TRUE(sink.skeletons[0].late_latched());
  EXPECT_EQ(sink.skeletons[0].input_sequence(), 1u);
  EXPECT_TRUE(to_eigen(sink.skeletons[0].palm()).isApprox(in.X_WorldPalm, 1e-12));
  tick();
  ASSERT_EQ(sink.skeletons.size(), 2u);
  EXPECT_FALSE(sink.skeletons[1].late_latched());
  EXPECT_TRUE(to_eigen(sink.skeletons[1].palm()).isApprox(in.X_WorldPalm, 1e-12));
  EXPECT_EQ(sink.states.size(), 1u);
  EXPECT_EQ(sink.scenes.size(), 1u);
  tick();  // nothing changed: no new grasp state
  EXPECT_EQ(sink.states.size(), 1u);
  EXPECT_EQ(sink.skeletons.size(), 3u);
}

// One grasp event per grasp, with metrics; every contact set's object-frame points, moved by the
// object pose published in the same tick's SceneState, give its world points.
TEST_F(SceneServerTest, PublishesEachGraspOnceWithConsistentContacts) {
  const int can = spawn("005_tomato_soup_can", 0.45, 0.0);
  for (int i = 0; i < 30; ++i) tick();
  grasp_and_lift(can);
  ASSERT_EQ(sink.events.size(), 1u);
  const msg::GraspEvent& e = sink.events[0];
  EXPECT_EQ(e.kind(), msg::GRASP_EVENT_GRASP);
  EXPECT_EQ(e.object_id(), can);
  EXPECT_EQ(e.object_name().to_string(), "005_tomato_soup_can");
  EXPECT_EQ(e.client_id().to_string(), "alice");
  EXPECT_EQ(e.grasp_type().to_string(), "other");  // human_right lists no grasp types
  EXPECT_FALSE(e.capsules().empty());
  EXPECT_FALSE(e.contacts().empty());
  ASSERT_FALSE(sink.contacts.empty());
  int checked = 0;
  for (const msg::ContactSet& cs : sink.contacts) {
    for (const msg::SceneState& ss : sink.scenes) {
      if (ss.tick() != cs.tick()) continue;
      ASSERT_EQ(ss.objects().size(), 1u);
      EXPECT_TRUE(ss.objects()[0].held());
      EXPECT_EQ(ss.objects()[0].holder_client().to_string(), "alice");
      const Eigen::Isometry3d X_WorldObject = to_eigen(ss.objects()[0].pose());
      for (const msg::ContactPoint& c : cs.contacts()) {
        EXPECT_LT((X_WorldObject * to_eigen(c.p_object()) - to_eigen(c.p_world())).norm(), 1e-6);
        ++checked;
      }
    }
  }
  EXPECT_GT(checked, 0);
}

// A rig with grasp types: the grasp event and the hand's states name the type the ball's shape
// chose (a 6.7 cm ball: a power sphere grasp), and the states name it from the approach on.
struct TypedRigSceneServerTest : SceneServerTest {
  TypedRigSceneServerTest() { right = rig("human_right_opposable"); }
};
TEST_F(TypedRigSceneServerTest, GraspEventsAndStatesCarryTheGraspType) {
  const int ball = spawn("056_tennis_ball", 0.45, 0.0);
  for (int i = 0; i < 30; ++i) tick();
  grasp_and_lift(ball);
  ASSERT_EQ(sink.events.size(), 1u);
  EXPECT_EQ(sink.events[0].grasp_type().to_string(), "power_sphere");
  std::set<std::string> types;
  for (const msg::GraspState& s : sink.states) types.insert(s.grasp_type().to_string());
  EXPECT_TRUE(types.count("power_sphere")) << "states name the type";
  for (const msg::GraspState& s : sink.states) {
    if (s.grasped_object() >= 0) {
      EXPECT_EQ(s.grasp_type().to_string(), "power_sphere");
    }
  }
}

// A hand whose client goes silent is frozen after freeze_after_s, then removed after
// remove_after_s; the object it held is dropped to physics and its release is published.
TEST_F(SceneServerTest, ASilentHandIsFrozenThenRemovedAndDropsItsObject) {
  const int can = spawn("005_tomato_soup_can", 0.45, 0.0);
  for (int i = 0; i < 30; ++i) tick();
  grasp_and_lift(can);
  ASSERT_TRUE(scene->world().holder(sim::ObjectId(can)).valid());
  const std::int64_t last_input = now - kTickNs;  // the last sample arrived before the last tick
  bool saw_frozen = false;
  while (!scene->world().objects().empty() && !sink.removed.size() && now - last_input < 2'000'000'000) {
    tick();
    saw_frozen |= !sink.skeletons.empty() && sink.skeletons.back().frozen();
    if (now - last_input <= static_cast<std::int64_t>(settings.freeze_after_s * 1e9)) {
      EXPECT_FALSE(sink.skeletons.back().frozen());
    }
  }
  EXPECT_TRUE(saw_frozen);
  ASSERT_EQ(sink.removed.size(), 1u);
  EXPECT_EQ(sink.removed[0], (HandAddress{"alice", 1}));
  const double silent_s = static_cast<double>(now - last_input) * 1e-9;
  EXPECT_GT(silent_s, settings.remove_after_s);
  EXPECT_LT(silent_s, 1.0);
  // The release happens with the next step and is published quality_delay_ticks later.
  for (int i = 0; i <= settings.quality_delay_ticks; ++i) tick();
  ASSERT_EQ(sink.events.size(), 2u);
  EXPECT_EQ(sink.events[1].kind(), msg::GRASP_EVENT_RELEASE);
  EXPECT_EQ(sink.events[1].object_id(), can);
  EXPECT_GT(sink.events[1].event_id(), sink.events[0].event_id());
  EXPECT_FALSE(sink.scenes.back().objects()[0].held());
  EXPECT_FALSE(scene->hand_id({"alice", 1}));
  const double z_dropped = scene->world().object_pose(sim::ObjectId(can)).translation().z();
  for (int i = 0; i < 90; ++i) tick();
  EXPECT_LT(scene->world().object_pose(sim::ObjectId(can)).translation().z(), z_dropped - 0.03);  // it fell
}

// Alice's right hand, driven by the scripted operator, closes on `object` until the World's step
// reports the grasp; returns that event (tick, contacts) and leaves the input at `in`.
sim::GraspEvent grasp_until_event(SceneServerTest& t, int object, sim::ControllerInput& in) {
  const sim::ObjectModel& model = t.scene->world().object_model(sim::ObjectId(object));
  sim::ScriptedOperator op(t.right, sim::skill_profile("perfect"), 7);
  Eigen::Isometry3d start = Eigen::Isometry3d::Identity();
  const Eigen::Isometry3d X_WorldObject = t.scene->world().object_pose(sim::ObjectId(object));
  start.translation() = X_WorldObject.translation() + Eigen::Vector3d(-0.3, -0.2, 0.3);
  op.begin(model, X_WorldObject, start, t.scene->world().time());
  while (t.scene->world().time() < 20) {
    in = op.next(t.scene->world().time(), false);
    t.send("alice", 1, in);
    t.tick();
    for (const sim::GraspEvent& e : t.scene->world().events())
      if (e.kind == sim::GraspEvent::Kind::kGrasp) return e;
  }
  ADD_FAILURE() << "no grasp";
  return {};
}

void remove_object(SceneServerTest& t, int object) {
  msg::SceneCommand c;
  c.client_id("alice");
  c.kind(msg::SCENE_REMOVE);
  c.object_id(object);
  EXPECT_EQ(t.scene->apply_command(c), "");
}

// A tennis ball (its grasps are in force closure) spawned and grasped by alice's right hand:
// the ball, the grasp's event as the World reported it, and a fresh quality of its contacts.
struct BallGrasp {
  int ball = -1;
  sim::GraspEvent grasp;
  sim::GraspQuality fresh;
};
BallGrasp grasp_a_ball(SceneServerTest& t, sim::ControllerInput& in) {
  BallGrasp b;
  b.ball = t.spawn("056_tennis_ball", 0.45, 0.0);
  for (int i = 0; i < 30; ++i) t.tick();
  b.grasp = grasp_until_event(t, b.ball, in);
  EXPECT_NE(b.grasp.tick, 0u);
  b.fresh = sim::grasp_quality(sim::HandController::quality_contacts(b.grasp.contacts), t.right->friction(),
                               t.scene->world().object_model(sim::ObjectId(b.ball)).max_radius);
  EXPECT_GT(b.fresh.epsilon, 0.0);
  return b;
}

// The grasp quality leaves the simulation thread: a GraspEvent goes out exactly
// quality_delay_ticks (default 2) after its tick, carrying the quality of the grasp tick's
// contacts (equal to a fresh computation of them, never the pending -1); GraspState shows -1
// (pending) from the grasp until then, then that quality. Releases wait as long.
TEST_F(SceneServerTest, GraspQualityIsPublishedAFixedNumberOfTicksLaterWithItsEvent) {
  ASSERT_EQ(settings.quality_delay_ticks, 2);
  sim::ControllerInput in;
  const BallGrasp b = grasp_a_ball(*this, in);
  const int ball = b.ball;
  const sim::GraspEvent& grasp = b.grasp;
  const sim::GraspQuality& fresh = b.fresh;
  EXPECT_TRUE(sink.events.empty()) << "held for its quality";
  EXPECT_EQ(sink.states.back().grasped_object(), ball);
  EXPECT_EQ(sink.states.back().epsilon(), -1.0);  // pending
  EXPECT_EQ(sink.states.back().volume(), -1.0);
  send("alice", 1, in);
  tick();
  EXPECT_TRUE(sink.events.empty());
  EXPECT_EQ(sink.states.back().epsilon(), -1.0);
  send("alice", 1, in);
  tick();
  ASSERT_EQ(scene->world().tick(), grasp.tick + 2);
  ASSERT_EQ(sink.events.size(), 1u);
  EXPECT_EQ(sink.events[0].kind(), msg::GRASP_EVENT_GRASP);
  EXPECT_EQ(sink.events[0].tick(), grasp.tick);
  EXPECT_EQ(sink.events[0].epsilon(), fresh.epsilon);
  EXPECT_EQ(sink.events[0].force_closure(), fresh.force_closure);
  EXPECT_EQ(sink.events[0].volume(), sim::kVolumeNotComputed);
  EXPECT_EQ(sink.states.back().epsilon(), fresh.epsilon);
  EXPECT_EQ(sink.states.back().tick(), grasp.tick + 2);
  // A release goes out 2 ticks after its own.
  remove_object(*this, ball);
  const std::uint64_t release_tick = scene->world().tick();  // reported with the next step
  for (int i = 0; i < 2; ++i) {
    tick();
    EXPECT_EQ(sink.events.size(), 1u);
  }
  tick();
  ASSERT_EQ(sink.events.size(), 2u);
  EXPECT_EQ(sink.events[1].kind(), msg::GRASP_EVENT_RELEASE);
  EXPECT_EQ(sink.events[1].tick(), release_tick);
  EXPECT_EQ(scene->status({}).quality_late(), scene->world().quality_late());
}

// A grasp whose object goes away before its quality is out: the grasp event still carries the
// quality, and goes out before the release.
TEST_F(SceneServerTest, AGraspReleasedBeforeItsQualityIsPublishedStillGetsIt) {
  sim::ControllerInput in;
  const BallGrasp b = grasp_a_ball(*this, in);
  const sim::GraspEvent& grasp = b.grasp;
  const sim::GraspQuality& fresh = b.fresh;
  remove_object(*this, b.ball);
  for (int i = 0; i < 4; ++i) tick();
  ASSERT_EQ(sink.events.size(), 2u);
  EXPECT_EQ(sink.events[0].kind(), msg::GRASP_EVENT_GRASP);
  EXPECT_EQ(sink.events[0].epsilon(), fresh.epsilon);
  EXPECT_EQ(sink.events[1].kind(), msg::GRASP_EVENT_RELEASE);
  EXPECT_EQ(sink.events[1].tick(), grasp.tick);  // removed before the next step
  EXPECT_GT(sink.events[1].event_id(), sink.events[0].event_id());
}

// A server (with `settings`) whose scene is a 0.6 m long box; alice's right hand squeezes one end
// until it grasps, then her left hand the other end until it grasps too. Returns the box's id.
int right_then_left_on_a_long_box(SceneServerTest& t) {
  sim::TriangleMesh box;
  for (int i = 0; i < 8; ++i) box.vertices.emplace_back(i & 1 ? 0.3 : -0.3, i & 2 ? 0.04 : -0.04, i & 4 ? 0.04 : -0.04);
  box.triangles = {{0, 2, 1}, {1, 2, 3}, {4, 5, 6}, {5, 7, 6}, {0, 1, 4}, {1, 5, 4},
                   {2, 6, 3}, {3, 6, 7}, {0, 4, 2}, {2, 4, 6}, {1, 3, 5}, {3, 7, 5}};
  t.models.push_back(sim::make_object_model("long_box", box, 0, "test"));
  t.scene = std::make_unique<SceneServer>(t.settings, t.models, t.right, t.left, t.mailbox, t.sink);
  const int id = t.spawn("long_box", 0.4, 0.0);
  for (int i = 0; i < 30; ++i) t.tick();
  const sim::ObjectModel& model = t.scene->world().object_model(sim::ObjectId(id));
  const Eigen::Isometry3d X_WorldBox = t.scene->world().object_pose(sim::ObjectId(id));
  const double dt = t.scene->world().dt();
  sim::ControllerInput r, l;
  r.X_WorldPalm = Eigen::Translation3d(0.2, 0, 0) * sim::plan_grasp(t.right, {}, model, X_WorldBox, dt).X_WorldPalm;
  l.X_WorldPalm = Eigen::Translation3d(-0.2, 0, 0) * sim::plan_grasp(t.left, {}, model, X_WorldBox, dt).X_WorldPalm;
  const auto grasps = [&](std::uint8_t side) {
    return std::count_if(t.sink.events.begin(), t.sink.events.end(), [&](const msg::GraspEvent& e) {
      return e.kind() == msg::GRASP_EVENT_GRASP && e.hand_side() == side;
    });
  };
  for (auto [side, input] : {std::pair{std::uint8_t{1}, &r}, {std::uint8_t{0}, &l}}) {
    for (int i = 1; i <= 90 && grasps(side) == 0; ++i) {
      input->trigger = std::min(1.0, i / 30.0);
      t.send("alice", 1, r);  // both hands send every tick
      t.send("alice", 0, l);
      t.tick();
    }
    EXPECT_EQ(grasps(side), 1) << "hand side " << int(side) << " never grasped";
  }
  return id;
}

// Both hold it, nobody lets go, and the scene state lists both holders in grasp order, the first
// also in holder_client/holder_hand.
TEST_F(SceneServerTest, TwoHandsOfOneClientShareAnObjectAndTheSceneListsBoth) {
  const int id = right_then_left_on_a_long_box(*this);
  EXPECT_EQ(scene->world().holders(sim::ObjectId(id)).size(), 2u);
  ASSERT_EQ(sink.events.size(), 2u) << "two grasps, no release";
  const msg::ObjectState& o = sink.scenes.back().objects().at(0);
  expect_held_by(o, {{"alice", 1}, {"alice", 0}});
}

// two_hand_mode takeover: the left hand's grasp takes the box and the right hand lets go.
TEST_F(SceneServerTest, TakeoverModeHandsTheObjectToTheNewestGrasp) {
  settings.two_hand_mode = sim::TwoHandMode::kTakeover;
  right_then_left_on_a_long_box(*this);
  ASSERT_EQ(sink.events.size(), 3u);
  EXPECT_EQ(sink.events[1].kind(), msg::GRASP_EVENT_RELEASE);
  EXPECT_EQ(sink.events[1].hand_side(), 1);
  EXPECT_EQ(sink.events[2].kind(), msg::GRASP_EVENT_GRASP);
  EXPECT_EQ(sink.events[2].hand_side(), 0);
  const msg::ObjectState& o = sink.scenes.back().objects().at(0);
  EXPECT_EQ(o.holder_hand(), 0);
  ASSERT_EQ(o.holders().size(), 1u);
  EXPECT_EQ(o.holders()[0].hand_side(), 0);
}

TEST_F(SceneServerTest, AppliesAndRejectsSceneCommands) {
  msg::SceneCommand c;
  c.kind(msg::SCENE_SPAWN);
  c.model("no_such_thing");
  EXPECT_NE(scene->apply_command(c).find("unknown model"), std::string::npos);
  c.model("005_tomato_soup_can");
  c.on_table(true);
  c.x(50);
  EXPECT_NE(scene->apply_command(c), "");  // off the table
  c.on_table(false);
  c.pose().orientation().w(0);  // not a rotation
  EXPECT_NE(scene->apply_command(c), "");
  c.pose().orientation().w(1);
  c.pose().position().z(0.5);
  EXPECT_EQ(scene->apply_command(c), "");
  ASSERT_EQ(scene->world().objects().size(), 1u);
  EXPECT_NEAR(scene->world().object_pose(scene->world().objects()[0]).translation().z(), 0.5, 1e-12);

  msg::SceneCommand remove;
  remove.kind(msg::SCENE_REMOVE);
  remove.object_id(99);
  EXPECT_NE(scene->apply_command(remove), "");
  remove.object_id(scene->world().objects()[0].value);
  EXPECT_EQ(scene->apply_command(remove), "");
  EXPECT_TRUE(scene->world().objects().empty());

  const msg::ServerStatus s = scene->status({});
  EXPECT_EQ(s.commands_accepted(), 2u);
  EXPECT_EQ(s.commands_rejected(), 4u);
  EXPECT_EQ(s.models().size(), models.size());
}

// An object that falls off the table comes back, at rest, to where it was spawned.
TEST_F(SceneServerTest, AnObjectThatFallsOffTheTableIsPutBack) {
  const int ball = spawn("056_tennis_ball", 0.45, 0.0);
  const Eigen::Isometry3d X_spawn = scene->world().object_pose(sim::ObjectId(ball));
  msg::SceneCommand c;  // a second ball dropped past the table's edge
  c.kind(msg::SCENE_SPAWN);
  c.model("056_tennis_ball");
  c.on_table(false);
  c.pose().orientation().w(1);
  c.pose().position().x(SceneServer::kTableHalfExtent + 0.2);
  c.pose().position().z(0.1);
  ASSERT_EQ(scene->apply_command(c), "");
  const sim::ObjectId dropped = scene->world().objects().back();
  double lowest = 1;
  for (int i = 0; i < 90 * 2; ++i) {
    tick();
    lowest = std::min(lowest, scene->world().object_pose(dropped).translation().z());
  }
  EXPECT_LT(lowest, SceneServer::kFallenHeight + 0.2);  // it did fall
  const Eigen::Vector3d p = scene->world().object_pose(dropped).translation();
  EXPECT_GT(p.z(), SceneServer::kFallenHeight);  // and is back up at its spawn pose or on its way down again
  EXPECT_NEAR(p.x(), SceneServer::kTableHalfExtent + 0.2, 1e-6);
  EXPECT_TRUE(scene->world().object_pose(sim::ObjectId(ball)).isApprox(X_spawn, 1e-3));  // the other one never moved
}

// An object that falls off the table while another one stands where it was spawned goes back at
// the nearest free spot instead: placed into the other one, both would be pushed apart at metres
// per second (a bot once saw a knife "moving at 39 m/s" after such a put-back).
TEST_F(SceneServerTest, AFallenObjectIsPutBackClearOfWhatStandsAtItsSpawn) {
  const int can = spawn("005_tomato_soup_can", 1.8, 0.0);
  const sim::ObjectId can_id(can);
  const Eigen::Vector3d spawned = scene->world().object_pose(can_id).translation();
  // Alice takes the can, carries it past the table's edge and opens her hand there.
  const sim::ObjectModel& model = scene->world().object_model(can_id);
  sim::ScriptedOperator op(right, sim::skill_profile("perfect"), 7);
  Eigen::Isometry3d start = Eigen::Isometry3d::Identity();
  start.translation() = spawned + Eigen::Vector3d(-0.3, -0.2, 0.3);
  op.begin(model, scene->world().object_pose(can_id), start, scene->world().time());
  sim::ControllerInput in;
  while (op.phase() != sim::OperatorPhase::kHold && scene->world().time() < 20) {
    in = op.next(scene->world().time(), scene->world().holder(can_id).valid());
    send("alice", 1, in);
    tick();
  }
  ASSERT_TRUE(scene->world().holder(can_id).valid());
  for (int i = 0; i < 90; ++i) {  // 0.5 m in +x over 1 s
    in.X_WorldPalm.translation().x() += 0.5 / 90;
    send("alice", 1, in);
    tick();
  }
  ASSERT_TRUE(scene->world().holder(can_id).valid());
  ASSERT_GT(scene->world().object_pose(can_id).translation().x(), SceneServer::kTableHalfExtent);
  // Meanwhile a ball was set down where the can was spawned.
  const int ball = spawn("056_tennis_ball", spawned.x(), spawned.y());
  const sim::ObjectId ball_id(ball);
  const Eigen::Vector3d ball_at = scene->world().object_pose(ball_id).translation();
  ASSERT_LT((ball_at.head<2>() - spawned.head<2>()).norm(), 1e-9);
  in.trigger = 0;
  std::fill(in.curls.begin(), in.curls.end(), 0.0);
  bool fell = false;
  for (int i = 0; i < 90 * 3; ++i) {
    send("alice", 1, in);
    tick();
    fell = fell || scene->world().object_pose(can_id).translation().z() < 0;
  }
  ASSERT_TRUE(fell);
  const Eigen::Vector3d can_at = scene->world().object_pose(can_id).translation();
  EXPECT_GT(can_at.z(), -0.01);  // back on the table
  // Clear of the ball: the can's footprint (upright: its horizontal reach) and the ball's radius.
  const Eigen::Vector3d reach = model.p_ObjectMin.cwiseAbs().cwiseMax(model.p_ObjectMax.cwiseAbs());
  EXPECT_GE((can_at.head<2>() - ball_at.head<2>()).norm(),
            std::hypot(reach.x(), reach.y()) + scene->world().object_model(ball_id).max_radius);
  EXPECT_LT((can_at.head<2>() - spawned.head<2>()).norm(), SceneServer::kFreeSpotSearch);
  EXPECT_LT((scene->world().object_pose(ball_id).translation() - ball_at).norm(), 1e-3);  // the ball never moved
  EXPECT_LT(scene->world().object_velocity(can_id).norm(), 0.02);
  EXPECT_LT(scene->world().object_velocity(ball_id).norm(), 0.02);
}

TEST(SceneServerResetTest, ResetRestoresTheConfiguredScene) {
  ServerSettings settings;
  settings.objects = {{"005_tomato_soup_can", 0.4, 0.0, 0.0}, {"056_tennis_ball", 0.6, 0.2, 0.5}};
  InputMailbox mailbox{{5, 5}, 4, [](const std::string&) {}};
  RecordingSink sink;
  SceneServer scene(settings, standins(), rig("human_right"), rig("human_left"), mailbox, sink);
  ASSERT_EQ(scene.world().objects().size(), 2u);
  msg::SceneCommand c;
  c.kind(msg::SCENE_RESET);
  c.client_id("op");
  EXPECT_NE(scene.apply_command(c), "");  // not an operator (yet)
  settings.operators = {"op"};
  SceneServer with_operator(settings, standins(), rig("human_right"), rig("human_left"), mailbox, sink);
  EXPECT_EQ(with_operator.apply_command(c), "");
  const auto objects = with_operator.world().objects();
  ASSERT_EQ(objects.size(), 2u);
  EXPECT_EQ(with_operator.world().object_model(objects[1]).name, "056_tennis_ball");
  EXPECT_NEAR(with_operator.world().object_pose(objects[1]).translation().x(), 0.6, 1e-12);
  settings.objects = {{"no_such_model", 0, 0, 0}};
  EXPECT_THROW(SceneServer(settings, standins(), rig("human_right"), rig("human_left"), mailbox, sink),
               std::runtime_error);
}

// Lockstep: the scene waits for every live hand's answer to the current tick and for the commands
// its client sent before that answer; a frozen hand is not waited for; a client answering an
// older tick (it missed the SceneState) gets the current SceneState again.
struct LockstepTest : SceneServerTest {
  void SetUp() override {
    settings.lockstep = true;
    SceneServerTest::SetUp();
  }
  void answer(const std::string& client, std::uint64_t tick, std::uint32_t commands_sent) {
    msg::ControllerState s = to_state(client, 1, ++seq, sim::ControllerInput{});
    s.lockstep_tick(tick);
    s.commands_sent(commands_sent);
    ASSERT_TRUE(mailbox.offer(s, kParticipant, now));
    scene->on_inputs(mailbox.drain(), now);
  }
};

TEST_F(LockstepTest, WaitsForEveryLiveHandAndItsCommands) {
  EXPECT_FALSE(scene->lockstep_ready()) << "no hands: the scene waits";
  answer("alice", 0, 1);
  EXPECT_FALSE(scene->lockstep_ready()) << "alice's spawn command has not arrived yet";
  msg::SceneCommand c;
  c.client_id("alice");
  c.command_id(1);
  c.kind(msg::SCENE_SPAWN);
  c.model("014_lemon");
  c.on_table(true);
  c.x(0.45);
  EXPECT_EQ(scene->apply_command(c), "");
  EXPECT_TRUE(scene->lockstep_ready());
  EXPECT_TRUE(sink.skeletons.empty()) << "no late latching in lockstep";
  tick();
  EXPECT_FALSE(scene->lockstep_ready()) << "tick 1 is not answered yet";
  {
    ParticipantKey bob{2};
    msg::ControllerState s = to_state("bob", 1, 1, sim::ControllerInput{});
    s.lockstep_tick(1);
    ASSERT_TRUE(mailbox.offer(s, bob, now));
    scene->on_inputs(mailbox.drain(), now);
  }
  EXPECT_FALSE(scene->lockstep_ready()) << "bob answered, alice not";
  answer("alice", 1, 1);
  EXPECT_TRUE(scene->lockstep_ready());
  // Alice goes silent: once frozen, only bob is waited for.
  now += static_cast<std::int64_t>(1e9 * (settings.freeze_after_s + 0.01));
  scene->tick(now);
  ParticipantKey bob{2};
  msg::ControllerState s = to_state("bob", 1, 2, sim::ControllerInput{});
  s.lockstep_tick(2);
  ASSERT_TRUE(mailbox.offer(s, bob, now));
  scene->on_inputs(mailbox.drain(), now);
  EXPECT_TRUE(scene->lockstep_ready());
}

TEST_F(LockstepTest, AnAnswerToAnOlderTickGetsTheSceneStateAgain) {
  answer("alice", 0, 0);
  tick();
  ASSERT_EQ(sink.scenes.size(), 1u);
  answer("alice", 0, 0);  // sent again: it never saw tick 1's SceneState
  ASSERT_EQ(sink.scenes.size(), 2u);
  EXPECT_EQ(sink.scenes[1].tick(), 1u);
  answer("alice", 1, 0);
  EXPECT_EQ(sink.scenes.size(), 2u);
}

// Who may do what: any client spawns and removes what it spawned or holds; only operators remove
// the rest and reset. Each refusal is counted per reason and told to its client.
struct PermissionTest : SceneServerTest {
  void SetUp() override {
    settings.operators = {"op"};
    SceneServerTest::SetUp();
  }
  std::string command(const std::string& client, msg::SceneCommandKind kind, int object = 0, double x = 0.4,
                      double y = 0) {
    msg::SceneCommand c;
    c.client_id(client);
    c.command_id(++command_id);
    c.kind(kind);
    c.model("056_tennis_ball");
    c.on_table(true);
    c.x(x);
    c.y(y);
    c.object_id(object);
    return scene->apply_command(c);
  }
  std::uint64_t command_id = 0;
};

TEST_F(PermissionTest, OnlyOperatorsResetOrRemoveWhatOthersSpawned) {
  ASSERT_EQ(command("alice", msg::SCENE_SPAWN, 0, 0.4, 0.0), "");
  const int alices = scene->world().objects().back().value;
  ASSERT_EQ(command("mallory", msg::SCENE_SPAWN, 0, 0.4, 0.5), "");
  const int mallorys = scene->world().objects().back().value;

  EXPECT_NE(command("mallory", msg::SCENE_REMOVE, alices), "");
  EXPECT_NE(command("mallory", msg::SCENE_RESET), "");
  EXPECT_EQ(scene->world().objects().size(), 2u);
  ASSERT_EQ(sink.notices.size(), 2u);
  EXPECT_EQ(sink.notices[0].client_id().to_string(), "mallory");
  EXPECT_EQ(sink.notices[0].reason().to_string(), "not_permitted");
  EXPECT_EQ(sink.notices[0].command_id(), 3u);
  EXPECT_EQ(sink.notices[0].kind(), msg::NOTICE_COMMAND_REJECTED);
  EXPECT_EQ(sink.notices[1].count(), 2u);  // mallory's second not_permitted

  EXPECT_EQ(command("mallory", msg::SCENE_REMOVE, mallorys), "");  // its own
  EXPECT_EQ(command("op", msg::SCENE_REMOVE, alices), "");  // an operator's right
  EXPECT_TRUE(scene->world().objects().empty());
  EXPECT_EQ(command("op", msg::SCENE_RESET), "");

  const msg::ServerStatus s = scene->status({});
  EXPECT_EQ(s.commands_rejected(), 2u);
  ASSERT_EQ(s.commands_rejected_by_reason().size(), 1u);
  EXPECT_EQ(s.commands_rejected_by_reason()[0].reason().to_string(), "not_permitted");
  EXPECT_EQ(s.commands_rejected_by_reason()[0].count(), 2u);
  EXPECT_EQ(s.notices_sent(), 2u);
}

TEST_F(PermissionTest, AClientMayRemoveTheObjectItHolds) {
  ASSERT_EQ(command("op", msg::SCENE_SPAWN, 0, 0.45, 0.0), "");
  const int ball = scene->world().objects().back().value;
  grasp_and_lift(ball);
  ASSERT_TRUE(scene->world().holder(sim::ObjectId(ball)).valid());
  EXPECT_NE(command("bob", msg::SCENE_REMOVE, ball), "");  // bob neither spawned nor holds it
  EXPECT_EQ(command("alice", msg::SCENE_REMOVE, ball), "");
}

TEST_F(PermissionTest, OpenSceneMakesEveryClientAnOperator) {
  settings.open_scene = true;
  SceneServerTest::SetUp();
  ASSERT_EQ(command("alice", msg::SCENE_SPAWN), "");
  EXPECT_EQ(command("mallory", msg::SCENE_REMOVE, scene->world().objects().back().value), "");
  EXPECT_EQ(command("mallory", msg::SCENE_RESET), "");
}

// 200 spawns of one ball on one spot: each lands at the nearest free spot (no two footprints
// overlap) until the client's spawn limit; the physics is not stalled by interpenetration.
TEST_F(PermissionTest, OverlappingSpawnsGoToTheNearestFreeSpotUpToTheClientsLimit) {
  int refused_limit = 0;
  for (int i = 0; i < 200; ++i)
    if (command("mallory", msg::SCENE_SPAWN, 0, 0.5, 0.0).find("at most") != std::string::npos) ++refused_limit;
  const auto objects = scene->world().objects();
  ASSERT_EQ(static_cast<int>(objects.size()), settings.max_objects_per_client);
  EXPECT_EQ(refused_limit, 200 - settings.max_objects_per_client);
  const double r = scene->world().object_model(objects[0]).max_radius;  // a ball: its footprint radius too
  double farthest = 0;
  for (std::size_t i = 0; i < objects.size(); ++i) {
    const Eigen::Vector3d pi = scene->world().object_pose(objects[i]).translation();
    farthest = std::max(farthest, (pi.head<2>() - Eigen::Vector2d(0.5, 0.0)).norm());
    for (std::size_t j = 0; j < i; ++j)
      EXPECT_GE((pi - scene->world().object_pose(objects[j]).translation()).norm(), 2 * r) << i << " " << j;
  }
  EXPECT_LT(farthest, SceneServer::kFreeSpotSearch);
  for (int i = 0; i < 45; ++i) tick();
  for (sim::ObjectId id : objects)  // resting, not thrown apart
    EXPECT_LT(scene->world().object_velocity(id).norm(), 0.05);
  // An operator has no spawn limit, but the spot search has a radius: a spot with no free place
  // within it is refused.
  EXPECT_EQ(command("op", msg::SCENE_SPAWN, 0, 0.5, 0.0), "");
}

TEST_F(PermissionTest, ASpawnPoseOverlappingAnObjectIsRefused) {
  ASSERT_EQ(command("alice", msg::SCENE_SPAWN, 0, 0.5, 0.0), "");
  msg::SceneCommand c;
  c.client_id("alice");
  c.kind(msg::SCENE_SPAWN);
  c.model("056_tennis_ball");
  c.pose() = to_msg(scene->world().object_pose(scene->world().objects().back()));
  EXPECT_NE(scene->apply_command(c).find("overlaps object"), std::string::npos);
  c.pose().position().z(0.5);  // above it: free
  EXPECT_EQ(scene->apply_command(c), "");
}

}  // namespace
}  // namespace telegrasp::server
