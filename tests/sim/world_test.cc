// Tests World: objects resting under physics, attach on grasp, release with the hand's velocity,
// frame-consistent contacts, input rejection and bit-identical reruns.
#include "telegrasp/sim/world.h"

#include "telegrasp/sim/scripted_operator.h"
#include "telegrasp/sim/standin_objects.h"
#include "test_meshes.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <utility>

namespace telegrasp::sim {
namespace {

std::shared_ptr<const HandRig> human_right() {
  static auto rig = std::make_shared<const HandRig>(HandRig::load(HandRig::builtin_path("human_right")));
  return rig;
}

ObjectModelPtr standin(const std::string& name) { return make_standin_model(*find_protocol_object(name)); }

TEST(WorldTest, ObjectRestsOnTheTable) {
  World world;
  auto box = make_object_model("box", testing::box_mesh({0.03, 0.05, 0.08}), 0.4, "test");
  const ObjectId id = world.add_object(box, World::resting_pose(*box, 0.4, 0.0, 0.3));
  const double z0 = world.object_pose(id).translation().z();
  for (int i = 0; i < 90; ++i) world.step();
  EXPECT_NEAR(world.object_pose(id).translation().z(), 0.08, 1e-3) << "rests on its face on the table top z = 0";
  EXPECT_NEAR(z0, 0.08, 1e-3);
  EXPECT_LT(world.object_velocity(id).norm(), 1e-3);
}

// Drives the hand to the planned grasp pose of `id` and squeezes until the world reports a grasp.
// Returns the grasp event.
std::optional<GraspEvent> grasp(World& world, HandId hand, ObjectId id) {
  const GraspPlan plan = plan_grasp(human_right(), {}, world.object_model(id), world.object_pose(id), world.dt());
  EXPECT_TRUE(plan.predicted_grasp);
  ControllerInput in;
  in.X_WorldPalm = plan.X_WorldPalm;
  for (int t = 0; t < 90; ++t) {
    in.trigger = std::min(1.0, t / 30.0);
    EXPECT_EQ(world.set_input(hand, in), "");
    world.step();
    for (const GraspEvent& e : world.events())
      if (e.kind == GraspEvent::Kind::kGrasp) return e;
  }
  return std::nullopt;
}

// A world with one stand-in resting at (x, y, yaw) and the human right hand, settled for 1/3 s.
struct OneObjectScene {
  World world;
  ObjectModelPtr model;
  ObjectId object;
  HandId hand;
  OneObjectScene(const std::string& name, double x, double y, double yaw) : model(standin(name)) {
    object = world.add_object(model, World::resting_pose(*model, x, y, yaw));
    hand = world.add_hand(human_right());
    for (int i = 0; i < 30; ++i) world.step();
  }
};

TEST(WorldTest, ReleaseCarriesTheHandVelocity) {
  OneObjectScene scene("005_tomato_soup_can", 0.45, 0.0, 0.0);
  auto& [world, model, can, hand] = scene;
  ASSERT_TRUE(grasp(world, hand, can).has_value());
  EXPECT_EQ(world.holder(can), hand);
  // Move the hand at a constant velocity v while turning it at w about its palm, then open it.
  const Eigen::Vector3d v(0.3, -0.1, 0.5), w(0.0, 0.0, 3.0);
  ControllerInput in;
  in.X_WorldPalm = world.hand(hand).state().X_WorldPalm;
  in.trigger = 1.0;
  const double dt = world.dt();  // clang 14 cannot capture a structured binding
  const auto advance = [&] {
    in.X_WorldPalm.translation() += v * dt;
    in.X_WorldPalm.linear() =
        Eigen::AngleAxisd(w.norm() * dt, w.normalized()).toRotationMatrix() * in.X_WorldPalm.linear();
  };
  for (int t = 0; t < 10; ++t) {
    advance();
    world.set_input(hand, in);
    world.step();
    ASSERT_EQ(world.holder(can), hand) << "held while moving";
  }
  const Eigen::Isometry3d held_pose = world.object_pose(can);
  EXPECT_LT((held_pose.translation() - world.hand(hand).grasped_object_pose()->translation()).norm(), 1e-9)
      << "follows the hand exactly";
  // Where the object is as the hand lets go: carried by this tick's hand pose.
  const Eigen::Isometry3d X_PalmObject = world.hand(hand).state().X_PalmObject;
  in.trigger = 0.0;
  advance();
  const Eigen::Vector3d p_released = (in.X_WorldPalm * X_PalmObject).translation();
  world.set_input(hand, in);
  world.step();
  ASSERT_EQ(world.events().size(), 1u);
  const GraspEvent& release = world.events()[0];
  EXPECT_EQ(release.kind, GraspEvent::Kind::kRelease);
  // v_object = v_palm + w x (p_object - p_palm), at the pose where it was let go.
  const Eigen::Vector3d expected_v = v + w.cross(p_released - in.X_WorldPalm.translation());
  EXPECT_LT((release.v_WorldObject - expected_v).norm(), 1e-9);
  EXPECT_LT((release.w_WorldObject - w).norm(), 1e-9);
  EXPECT_FALSE(world.holder(can).valid());
  // After one physics step the object flies with that velocity plus one step of gravity.
  const Eigen::Vector3d expected = expected_v + Eigen::Vector3d(0, 0, -9.81) * world.dt();
  EXPECT_LT((world.object_velocity(can) - expected).norm(), 1e-6);
  EXPECT_LT((world.object_pose(can).translation() - (p_released + expected * world.dt())).norm(), 1e-6);
}

// Object-local contacts, transformed by the object's pose, give the world contacts, and normals
// are unit and point out of the object.
TEST(WorldTest, ObjectLocalContactsMatchWorldContacts) {
  OneObjectScene scene("010_potted_meat_can", 0.42, 0.05, 1.234);
  auto& [world, model, id, hand] = scene;
  const auto event = grasp(world, hand, id);
  ASSERT_TRUE(event.has_value());
  ASSERT_FALSE(event->contacts.empty());
  // The object's pose as the world publishes it (the physics body), not the hand's own record.
  const Eigen::Isometry3d X_WorldObject = world.object_pose(id);
  const HandController& h = world.hand(hand);
  for (const Contact& c : event->contacts) {
    EXPECT_LT((X_WorldObject * c.p_ObjectContact - c.p_WorldContact).norm(), 1e-9);
    EXPECT_LT((X_WorldObject.linear() * c.n_Object - c.n_World).norm(), 1e-9);
    EXPECT_NEAR(c.n_World.norm(), 1.0, 1e-9);
    // The contact lies on the surface, and (for a phalanx) one capsule radius from its axis,
    // within the contact tolerance.
    EXPECT_LT(std::abs(model->distance.signed_distance(c.p_ObjectContact)), 1e-9);
    if (!c.phalanx.valid()) continue;
    const auto& cap = *h.rig().phalanges()[c.phalanx.value].capsule;
    const Eigen::Isometry3d X = h.state().X_WorldPalm * h.state().X_PalmPhalanx[c.phalanx.value];
    const Eigen::Vector3d a = X * cap.p_PhalanxA, b = X * cap.p_PhalanxB;
    const double t = std::clamp((c.p_WorldContact - a).dot(b - a) / (b - a).squaredNorm(), 0.0, 1.0);
    const double from_axis = (c.p_WorldContact - (a + t * (b - a))).norm();
    EXPECT_GE(from_axis, cap.radius - 1e-6);
    EXPECT_LE(from_axis, cap.radius + 2 * 0.05e-3 + 1e-6);
  }
  // Still consistent after the hand has carried the object somewhere else.
  ControllerInput in;
  in.X_WorldPalm = world.hand(hand).state().X_WorldPalm;
  in.X_WorldPalm.translation() += Eigen::Vector3d(0.05, 0.02, 0.1);
  in.X_WorldPalm.linear() =
      Eigen::AngleAxisd(0.4, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix() * in.X_WorldPalm.linear();
  in.trigger = 1.0;
  world.set_input(hand, in);
  world.step();
  const Eigen::Isometry3d moved = world.object_pose(id);
  for (const Contact& c : world.hand(hand).contacts())
    EXPECT_LT((moved * c.p_ObjectContact - c.p_WorldContact).norm(), 1e-9);
}

// Removing a held object lets the hand go and reports the release with the next step's events.
TEST(WorldTest, RemovingAHeldObjectReportsItsRelease) {
  OneObjectScene scene("005_tomato_soup_can", 0.45, 0.0, 0.0);
  auto& [world, model, can, hand] = scene;
  ASSERT_TRUE(grasp(world, hand, can).has_value());
  world.remove_object(can);
  EXPECT_FALSE(world.hand(hand).state().grasped.valid());
  world.step();
  ASSERT_FALSE(world.events().empty());
  EXPECT_EQ(world.events()[0].kind, GraspEvent::Kind::kRelease);
  EXPECT_EQ(world.events()[0].object, can);
  EXPECT_EQ(world.events()[0].hand, hand);
}

// Removing a hand that holds an object drops the object to physics: it falls back to the table,
// nobody holds it, the release is reported once, and the remaining ids are unchanged.
TEST(WorldTest, RemovingAHandDropsItsObjectToPhysics) {
  OneObjectScene scene("005_tomato_soup_can", 0.45, 0.0, 0.0);
  auto& [world, model, can, hand] = scene;
  const HandId other = world.add_hand(human_right());
  ASSERT_TRUE(grasp(world, hand, can).has_value());
  // Lift 5 cm so the drop is visible.
  ControllerInput in;
  in.X_WorldPalm = world.hand(hand).state().X_WorldPalm;
  in.trigger = 1;
  for (int i = 0; i < 45; ++i) {
    in.X_WorldPalm.translation().z() += 0.05 / 45;
    world.set_input(hand, in);
    world.step();
  }
  ASSERT_EQ(world.holder(can), hand);
  const double z_lifted = world.object_pose(can).translation().z();
  world.remove_hand(hand);
  EXPECT_EQ(world.hands(), std::vector<HandId>{other});
  EXPECT_FALSE(world.holder(can).valid());
  int releases = 0;
  for (int i = 0; i < 90; ++i) {
    world.step();
    for (const GraspEvent& e : world.events())
      releases += e.kind == GraspEvent::Kind::kRelease && e.object == can && e.hand == hand;
  }
  EXPECT_EQ(releases, 1);
  EXPECT_LT(world.object_pose(can).translation().z(), z_lifted - 0.04);  // it fell
  world.remove_hand(hand);  // unknown now: ignored
  EXPECT_EQ(world.add_hand(human_right()).value, other.value + 1);  // ids are not reused
}

TEST(WorldTest, RejectsBadInputAndKeepsThePreviousOne) {
  World world;
  const HandId hand = world.add_hand(human_right());
  ControllerInput good;
  good.X_WorldPalm.translation() = Eigen::Vector3d(0.1, 0.2, 0.3);
  good.trigger = 0.5;
  ASSERT_EQ(world.set_input(hand, good), "");
  ControllerInput bad = good;
  bad.X_WorldPalm.translation().x() = std::nan("");
  EXPECT_NE(world.set_input(hand, bad), "");
  bad = good;
  bad.trigger = 2.0;
  EXPECT_NE(world.set_input(hand, bad).find("trigger"), std::string::npos);
  world.step();
  EXPECT_EQ(world.hand(hand).state().X_WorldPalm.translation(), good.X_WorldPalm.translation());
  EXPECT_EQ(world.hand(hand).state().trigger, 0.5);
  EXPECT_THROW(world.set_input(HandId(5), good), std::out_of_range);
}

// One scripted trial, recorded tick by tick.
std::vector<double> run_recorded_trial() {
  World world;
  auto model = standin("006_mustard_bottle");
  const ObjectId id = world.add_object(model, World::resting_pose(*model, 0.45, -0.03, 0.7));
  const HandId hand = world.add_hand(human_right());
  ScriptedOperator op(human_right(), skill_profile("inexperienced"), 42);
  op.begin(*model, world.object_pose(id), Eigen::Isometry3d(Eigen::Translation3d(0.15, -0.2, 0.3)), world.time());
  std::vector<double> trace;
  while (!op.done() && world.time() < 15) {
    world.set_input(hand, op.next(world.time(), world.holder(id) == hand));
    world.step();
    const auto& s = world.hand(hand).state();
    trace.insert(trace.end(), s.q.begin(), s.q.end());
    const Eigen::Isometry3d X = world.object_pose(id);
    trace.insert(trace.end(), X.data(), X.data() + 16);
  }
  return trace;
}

TEST(WorldTest, EqualInputsGiveBitIdenticalRuns) {
  const std::vector<double> a = run_recorded_trial();
  const std::vector<double> b = run_recorded_trial();
  ASSERT_EQ(a.size(), b.size());
  ASSERT_GT(a.size(), 1000u);
  EXPECT_EQ(std::memcmp(a.data(), b.data(), a.size() * sizeof(double)), 0);
}

// Grasp qualities on a worker (quality_delay_ticks 2) are those computed within the step (0),
// bit for bit, delivered exactly 2 steps later; grasp events of the delayed world come without
// metrics, and the result of their quality_job carries the other world's event metrics and
// quality, bit for bit.
TEST(WorldTest, DelayedQualitiesAreTheSameQualitiesDeliveredKStepsLater) {
  WorldSettings inline_settings, delayed_settings;
  delayed_settings.quality_delay_ticks = 2;
  World now(inline_settings), later(delayed_settings);
  const ObjectModelPtr ball = standin("056_tennis_ball");  // its grasps are in force closure
  for (World* w : {&now, &later}) w->add_object(ball, World::resting_pose(*ball, 0.45, 0.02, 0.5));
  const HandId hand = now.add_hand(human_right());
  ASSERT_EQ(later.add_hand(human_right()), hand);
  for (int i = 0; i < 30; ++i) now.step(), later.step();
  ScriptedOperator op(human_right(), skill_profile("experienced"), 3);
  op.begin(*ball, now.object_pose(ObjectId(0)), Eigen::Isometry3d(Eigen::Translation3d(0.15, -0.2, 0.3)), now.time());
  std::vector<QualityResult> from_now, from_later;
  std::vector<GraspMetrics> event_metrics_now;
  std::vector<std::uint64_t> event_jobs_later;
  while (!op.done() && now.time() < 20) {
    const ControllerInput in = op.next(now.time(), now.holder(ObjectId(0)) == hand);
    ASSERT_EQ(now.set_input(hand, in), "");
    ASSERT_EQ(later.set_input(hand, in), "");
    now.step();
    later.step();
    for (const QualityResult& r : now.quality_results()) {
      EXPECT_EQ(r.job.tick, now.tick());
      from_now.push_back(r);
    }
    for (const QualityResult& r : later.quality_results()) {
      EXPECT_EQ(r.job.tick + 2, later.tick());
      from_later.push_back(r);
    }
    for (const GraspEvent& e : now.events())
      if (e.kind == GraspEvent::Kind::kGrasp) event_metrics_now.push_back(e.metrics.value());
    for (const GraspEvent& e : later.events())
      if (e.kind == GraspEvent::Kind::kGrasp) {
        EXPECT_FALSE(e.metrics.has_value());
        event_jobs_later.push_back(e.quality_job);
      }
  }
  for (int i = 0; i < 2; ++i) {  // the last results still due
    now.step(), later.step();
    from_now.insert(from_now.end(), now.quality_results().begin(), now.quality_results().end());
    from_later.insert(from_later.end(), later.quality_results().begin(), later.quality_results().end());
  }
  EXPECT_TRUE(op.held_after_lift());
  ASSERT_GT(from_now.size(), 2u);
  ASSERT_EQ(from_now.size(), from_later.size());
  for (std::size_t i = 0; i < from_now.size(); ++i) {
    EXPECT_EQ(from_now[i].job.id, from_later[i].job.id);
    EXPECT_EQ(from_now[i].job.tick, from_later[i].job.tick);
    EXPECT_EQ(from_now[i].quality.epsilon, from_later[i].quality.epsilon);
    EXPECT_EQ(from_now[i].quality.force_closure, from_later[i].quality.force_closure);
    EXPECT_EQ(from_now[i].computed, from_later[i].computed);
  }
  ASSERT_EQ(event_metrics_now.size(), event_jobs_later.size());
  ASSERT_FALSE(event_jobs_later.empty());
  for (std::size_t i = 0; i < event_jobs_later.size(); ++i) {
    auto r = std::find_if(from_later.begin(), from_later.end(),
                          [&](const QualityResult& q) { return q.job.id == event_jobs_later[i]; });
    ASSERT_NE(r, from_later.end());
    EXPECT_TRUE(r->job.grasp_tick);
    const GraspMetrics& expected = event_metrics_now[i];
    EXPECT_EQ(r->quality.epsilon, expected.quality.epsilon);
    EXPECT_GT(r->quality.epsilon, 0.0);
    ASSERT_NE(r->metrics, nullptr);
    EXPECT_EQ(r->metrics->quality.epsilon, expected.quality.epsilon);
    EXPECT_EQ(r->metrics->hand_error_mm, expected.hand_error_mm);
    EXPECT_EQ(r->metrics->palm_signed_distance, expected.palm_signed_distance);
    ASSERT_EQ(r->metrics->capsules.size(), expected.capsules.size());
    for (std::size_t c = 0; c < expected.capsules.size(); ++c) {
      EXPECT_EQ(r->metrics->capsules[c].nd, expected.capsules[c].nd);
      EXPECT_EQ(r->metrics->capsules[c].signed_distance, expected.capsules[c].signed_distance);
      EXPECT_EQ(r->metrics->capsules[c].nd_contact, expected.capsules[c].nd_contact);
    }
  }
  EXPECT_TRUE(std::any_of(from_later.begin(), from_later.end(), [](const QualityResult& r) {
    return r.quality.epsilon > 0;
  })) << "some held contact set is in force closure";
  EXPECT_EQ(now.quality_late(), 0u);  // within the step: never waits
}

// The worker's results are a function of the jobs alone: on its thread or not, the same, in
// order, the memo's reuse included (a set asked again is not recomputed); a forgotten hand starts
// afresh.
TEST(QualityWorkerTest, ThreadedAndInlineGiveTheSameResults) {
  std::vector<QualityJob> jobs;
  const std::vector<QualityContact> a = {
      {{0.04, 0, 0}, {1, 0, 0}}, {{-0.04, 0, 0}, {-1, 0, 0}}, {{0, 0.04, 0}, {0, 1, 0}}};
  std::vector<QualityContact> b(a);
  b.push_back({{0, -0.04, 0}, {0, -1, 0}});
  for (const std::vector<QualityContact>* set : {&a, &std::as_const(b), &a, &std::as_const(b)}) {
    QualityJob j;
    j.hand = HandId(3);
    j.contacts = *set;
    j.mu = 0.5;
    j.torque_scale = 0.04;
    jobs.push_back(j);
  }
  QualityJob forget;
  forget.hand = HandId(3);
  forget.forget = true;
  jobs.push_back(forget);
  jobs.push_back(jobs.front());
  for (std::size_t i = 0; i < jobs.size(); ++i) jobs[i].id = i + 1;
  QualityWorker threaded(true), inline_worker(false);
  for (const QualityJob& j : jobs) threaded.submit(j), inline_worker.submit(j);
  bool waited = false;
  const std::vector<QualityResult> x = threaded.take(jobs.size(), waited);
  const std::vector<QualityResult> y = inline_worker.take(jobs.size(), waited);
  EXPECT_FALSE(waited);  // inline: done in submit()
  ASSERT_EQ(x.size(), jobs.size());
  ASSERT_EQ(y.size(), jobs.size());
  const std::vector<std::uint64_t> computed = {1, 2, 2, 2, 0, 1};  // reuse, then afresh after forget
  for (std::size_t i = 0; i < jobs.size(); ++i) {
    EXPECT_EQ(x[i].job.id, i + 1);
    EXPECT_EQ(x[i].quality.epsilon, y[i].quality.epsilon);
    EXPECT_EQ(x[i].computed, computed[i]) << i;
    EXPECT_EQ(y[i].computed, computed[i]) << i;
  }
  EXPECT_EQ(x[0].quality.epsilon, x[2].quality.epsilon);
  EXPECT_EQ(x[1].quality.epsilon, grasp_quality(b, 0.5, 0.04).epsilon);
  EXPECT_TRUE(threaded.take(jobs.size(), waited).empty());  // each result is taken once
}

}  // namespace
}  // namespace telegrasp::sim
