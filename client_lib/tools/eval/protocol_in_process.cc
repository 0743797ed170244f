#include "protocol_in_process.h"

#include "protocol_common.h"
#include "telegrasp/sim/world.h"

#include <algorithm>

namespace telegrasp::eval {
namespace {

constexpr double kTrialLimit = 30.0;  // s of simulated time before a grasp is cut short (as participant.cc)
constexpr double kTableHalfExtent = 2.0;  // the server's table (SceneServer::kTableHalfExtent)

// One trial, from the tick the object appears to the tick after its release.
class InProcessTrial {
 public:
  InProcessTrial(sim::World& world, sim::HandId hand, const std::shared_ptr<const sim::HandRig>& rig)
      : world_(world), hand_(hand), rig_(rig) {}

  // Spawns object `index` as the server does at a SceneCommand, ticks until it is released, and
  // returns its record. `input` is the hand's input on entry (home) and on return.
  report::Record run(const InProcessParticipant& p, const sim::ObjectModelPtr& model, int index,
                     sim::ControllerInput& input) {
    const Placement place = object_placement(p.seed, p.participant, index);
    const double spawn_time = world_.time();
    object_ = world_.add_object(model, sim::World::resting_pose(*model, place.x, place.y, place.yaw));
    step(input);  // the SceneState that shows the object
    report::Record rec;
    rec.object = model->name;
    sim::ScriptedOperator op(rig_, p.skill, grasp_seed(p.seed, p.participant, index), sim::GraspSettings{},
                             world_.dt());
    const std::uint64_t start_tick = world_.tick();
    const double z0 = world_.object_pose(object_).translation().z();
    op.begin(*model, world_.object_pose(object_), home_palm_pose(), 0.0, index);
    input = op.next(0.0, false);
    double z_max = -1e9;
    bool releasing = false;
    std::optional<sim::GraspQuality> hold_quality;
    while (true) {
      step(input);
      take_grasp_event(spawn_time, rec);
      const bool holding = world_.holder(object_) == hand_;
      if (releasing) {
        if (!holding) break;
        continue;
      }
      const double t = static_cast<double>(world_.tick() - start_tick) * world_.dt();
      op.see_hand_raised(world_.hand(hand_).state().resolve_offset().z());
      input = op.next(t, holding);
      if (op.phase() == sim::OperatorPhase::kHold) {
        z_max = std::max(z_max, world_.object_pose(object_).translation().z());
        // The quality the server publishes in GraspState while held (-1 until the first arrives).
        if (holding)
          if (auto m = world_.hand(hand_).hold_metrics(); m && m->quality.epsilon >= 0) hold_quality = m->quality;
      }
      if (op.done() || t > kTrialLimit) {
        input.trigger = 0;
        input.curls.clear();
        releasing = true;
      }
    }
    rec.mode = p.mode;
    rec.trial = index;
    rec.group = p.group;
    rec.participant = p.participant;
    rec.attempts = op.attempts();
    report::set_hold_quality(rec, hold_quality);
    rec.held_after_lift = op.held_after_lift() && z_max - z0 > 0.8 * sim::ScriptedOperator::kLiftHeight;
    world_.remove_object(object_);
    input = {};
    input.X_WorldPalm = home_palm_pose();
    return rec;
  }

 private:
  void step(const sim::ControllerInput& input) {
    world_.set_input(hand_, input);
    world_.step();
  }

  // The record of the trial's first grasp event, as record_grasp_event fills it from a GraspEvent.
  void take_grasp_event(double spawn_time, report::Record& rec) {
    for (const sim::GraspEvent& e : world_.events()) {
      if (e.kind != sim::GraspEvent::Kind::kGrasp || e.hand != hand_ || e.object != object_ || rec.grasped) continue;
      rec.grasped = true;
      rec.time_to_grasp_s = e.time - spawn_time;
      if (!e.metrics) continue;
      report::record_grasp_tick(e, *rig_, rec);
      for (const sim::Contact& c : e.contacts)
        rec.contacts.push_back({c.phalanx.valid() ? rig_->phalanges()[c.phalanx.value].name : std::string("palm"),
                                c.p_WorldContact, c.n_World, c.p_ObjectContact, c.n_Object});
      record_grasp_tick_hand(e, rec);
    }
  }

  // The hand as the grasp tick left it (the event is of the step just taken), in the object frame,
  // as the participant takes it from that tick's HandSkeleton.
  void record_grasp_tick_hand(const sim::GraspEvent& e, report::Record& rec) {
    const sim::HandState& s = world_.hand(hand_).state();
    const Eigen::Isometry3d X_WorldObject = world_.object_pose(e.object);
    const Eigen::Isometry3d X_ObjectWorld = X_WorldObject.inverse();
    rec.grasp_tick_X_WorldObject = X_WorldObject;
    rec.grasp_tick_hand.push_back({"palm", X_ObjectWorld * s.X_WorldPalm});
    for (std::size_t i = 0; i < s.X_PalmPhalanx.size(); ++i)
      rec.grasp_tick_hand.push_back({rig_->phalanges()[i].name, X_ObjectWorld * s.X_WorldPalm * s.X_PalmPhalanx[i]});
  }

  sim::World& world_;
  sim::HandId hand_;
  std::shared_ptr<const sim::HandRig> rig_;
  sim::ObjectId object_;
};

}  // namespace

std::vector<report::Record> run_participant_in_process(const InProcessParticipant& p,
                                                       const std::map<std::string, sim::ObjectModelPtr>& models,
                                                       const std::shared_ptr<const sim::HandRig>& rig) {
  sim::WorldSettings ws;
  ws.grasp.mode = *sim::parse_closing_mode(p.mode);
  ws.table_half_extent = kTableHalfExtent;
  sim::World world(ws);
  const sim::HandId hand = world.add_hand(rig);
  sim::ControllerInput input;
  input.X_WorldPalm = home_palm_pose();
  InProcessTrial trial(world, hand, rig);
  std::vector<report::Record> records;
  const auto& order = paper_object_order();
  for (int i = 0; i < p.count && i < static_cast<int>(order.size()); ++i)
    records.push_back(trial.run(p, models.at(order[static_cast<std::size_t>(i)]), i, input));
  return records;
}

}  // namespace telegrasp::eval
