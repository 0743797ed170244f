#include "conversions.h"

namespace telegrasp::server {

sim::ControllerInput to_sim_input(const msg::ControllerState& state) {
  sim::ControllerInput in;
  in.X_WorldPalm = to_eigen(state.palm());
  in.trigger = state.trigger();
  in.curls = state.curls();
  in.tracking_valid = state.tracking_valid();
  return in;
}

msg::HandSkeleton make_hand_skeleton(const HandAddress& address, const sim::HandController& hand, std::uint64_t tick,
                                     double time, const InputStamp& input, bool frozen,
                                     const Eigen::Isometry3d* X_WorldPalm_override) {
  const sim::HandState& s = hand.state();
  const Eigen::Isometry3d& X_WorldPalm = X_WorldPalm_override ? *X_WorldPalm_override : s.X_WorldPalm;
  msg::HandSkeleton m;
  m.client_id(address.client_id);
  m.hand_side(address.side);
  m.rig(hand.rig().name());
  m.tick(tick);
  m.time(time);
  m.input_sequence(input.sequence);
  m.input_client_time_ns(input.client_time_ns);
  m.late_latched(X_WorldPalm_override != nullptr);
  m.frozen(frozen);
  m.palm(to_msg(X_WorldPalm));
  m.phalanges().reserve(s.X_PalmPhalanx.size());
  for (const Eigen::Isometry3d& X_PalmPhalanx : s.X_PalmPhalanx) m.phalanges().push_back(to_msg(X_WorldPalm * X_PalmPhalanx));
  m.joint_angles(s.q);
  return m;
}

msg::GraspState make_grasp_state(const HandAddress& address, const sim::HandController& hand, std::uint64_t tick, double time) {
  const sim::HandState& s = hand.state();
  msg::GraspState m;
  m.client_id(address.client_id);
  m.hand_side(address.side);
  m.tick(tick);
  m.time(time);
  m.selected_object(s.selected.value);
  m.grasped_object(s.grasped.value);
  m.trigger(s.trigger);
  m.blocked().assign(s.blocked.begin(), s.blocked.end());
  m.palm_contact(s.palm_contact);
  return m;
}

msg::ContactPoint to_msg(const sim::Contact& c) {
  msg::ContactPoint m;
  m.phalanx(static_cast<std::int16_t>(c.phalanx.value));
  m.p_world(to_msg(c.p_WorldContact));
  m.n_world(to_msg(c.n_World));
  m.p_object(to_msg(c.p_ObjectContact));
  m.n_object(to_msg(c.n_Object));
  m.nd(c.nd);
  m.nd_hit(c.nd_hit);
  return m;
}

sim::Contact to_sim(const msg::ContactPoint& m) {
  sim::Contact c;
  c.phalanx = sim::PhalanxId(m.phalanx());
  c.p_WorldContact = to_eigen(m.p_world());
  c.n_World = to_eigen(m.n_world());
  c.p_ObjectContact = to_eigen(m.p_object());
  c.n_Object = to_eigen(m.n_object());
  c.nd = m.nd();
  c.nd_hit = m.nd_hit();
  return c;
}

msg::ContactSet make_contact_set(const HandAddress& address, const sim::HandController& hand, std::uint64_t tick,
                                 double time, const Eigen::Isometry3d& X_WorldObject) {
  msg::ContactSet m;
  m.client_id(address.client_id);
  m.hand_side(address.side);
  m.tick(tick);
  m.time(time);
  m.object_id(hand.state().grasped.value);
  m.object_pose(to_msg(X_WorldObject));
  for (const sim::Contact& c : hand.contacts()) m.contacts().push_back(to_msg(c));
  return m;
}

msg::GraspEvent make_grasp_event(const sim::GraspEvent& e, const sim::HandRig& rig, const EventContext& ctx) {
  msg::GraspEvent m;
  m.event_id(ctx.event_id);
  m.kind(e.kind == sim::GraspEvent::Kind::kGrasp ? msg::GRASP_EVENT_GRASP : msg::GRASP_EVENT_RELEASE);
  m.client_id(ctx.hand.client_id);
  m.hand_side(ctx.hand.side);
  m.object_id(e.object.value);
  m.object_name(ctx.object_name);
  m.tick(e.tick);
  m.time(e.time);
  m.object_spawn_time(ctx.object_spawn_time);
  m.object_pose(to_msg(ctx.X_WorldObject));
  m.input_sequence(ctx.input_sequence);
  if (e.metrics) {
    m.hand_error_mm(e.metrics->hand_error_mm);
    m.capsules_without_hit(e.metrics->capsules_without_hit);
    for (const sim::CapsuleMetric& c : e.metrics->capsules) {
      msg::CapsuleReport r;
      r.phalanx(static_cast<std::int16_t>(c.phalanx.value));
      r.phalanx_name(rig.phalanges()[c.phalanx.value].name);
      r.hit(c.hit);
      r.nd(c.nd);
      r.signed_distance(c.signed_distance);
      r.blocked(c.blocked);
      m.capsules().push_back(std::move(r));
    }
  }
  for (const sim::Contact& c : e.contacts) m.contacts().push_back(to_msg(c));
  m.release_velocity(to_msg(e.v_WorldObject));
  m.release_angular_velocity(to_msg(e.w_WorldObject));
  return m;
}

}  // namespace telegrasp::server
