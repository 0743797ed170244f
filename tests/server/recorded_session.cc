#include "recorded_session.h"

#include "controller_state.h"
#include "recording.h"
#include "scene_server.h"
#include "scene_setup.h"

#include "telegrasp/sim/scripted_operator.h"

#include <stdexcept>

namespace telegrasp::server {
namespace {

constexpr std::int64_t kTickNs = 11'111'111;  // 90 Hz
const ParticipantKey kParticipant{1};

void demand(bool ok, const std::string& what) {
  if (!ok) throw std::runtime_error("record_session: " + what);
}

// What the Recorder forwarded, to check the recording against.
struct CollectingSink : OutputSink {
  std::vector<msg::GraspEvent> events;
  std::vector<HandAddress> removed;
  void publish(const msg::HandSkeleton&) override {}
  void publish(const msg::GraspState&) override {}
  void publish(const msg::ContactSet&) override {}
  void publish(const msg::GraspEvent& m) override { events.push_back(m); }
  void publish(const msg::SceneState&) override {}
  void publish(const msg::ServerStatus&) override {}
  void hand_removed(const HandAddress& hand) override { removed.push_back(hand); }
};

}  // namespace

RecordedSession record_session(const std::string& path) {
  ServerSettings settings;
  settings.objects = {{"005_tomato_soup_can", 0.45, 0.0, 0.0}};
  const SceneAssets assets = load_scene_assets(settings);
  CollectingSink sink;
  InputMailbox mailbox({assets.left_rig->fingers().size(), assets.right_rig->fingers().size()}, settings.max_hands,
                       [](const std::string&) {});
  {
    Recorder recorder(path, settings, assets, sink);
    SceneServer scene(settings, assets.models, assets.right_rig, assets.left_rig, mailbox, recorder);
    std::int64_t now = 0;
    std::uint64_t seq = 0;
    auto tick = [&] {
      now += kTickNs;
      recorder.tick(now);
      scene.tick(now);
    };
    auto send = [&](const sim::ControllerInput& in) {
      demand(mailbox.offer(to_state("alice", 1, ++seq, in), kParticipant, now), "the mailbox refused a sample");
      std::vector<InputSample> samples = mailbox.drain();
      recorder.inputs(samples, now);
      scene.on_inputs(std::move(samples), now);
    };
    for (int i = 0; i < 10; ++i) tick();
    msg::SceneCommand spawn;
    spawn.client_id("alice");
    spawn.command_id(1);
    spawn.kind(msg::SCENE_SPAWN);
    spawn.model("056_tennis_ball");
    spawn.on_table(true);
    spawn.x(0.45);
    spawn.y(0.4);
    recorder.command(spawn, now);
    const std::string refused = scene.apply_command(spawn);
    demand(refused.empty(), "the spawn was refused: " + refused);

    const sim::ObjectId can = scene.world().objects().front();
    sim::ScriptedOperator op(assets.right_rig, sim::skill_profile("perfect"), 7);
    Eigen::Isometry3d start = Eigen::Isometry3d::Identity();
    start.translation() = scene.world().object_pose(can).translation() + Eigen::Vector3d(-0.3, -0.2, 0.3);
    op.begin(scene.world().object_model(can), scene.world().object_pose(can), start, scene.world().time());
    while (op.phase() != sim::OperatorPhase::kHold && scene.world().time() < 20) {
      send(op.next(scene.world().time(), scene.world().holder(can).valid()));
      tick();
    }
    recorder.publish(scene.status({}));
    while (sink.removed.empty() && scene.world().time() < 25) tick();
    tick();  // the release goes out with the next step
    demand(recorder.error().empty(), recorder.error());
  }
  return {path, sink.events};
}

}  // namespace telegrasp::server
