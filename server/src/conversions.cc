#include "conversions.h"

#include "telegrasp/idl/geometry_hash.h"

#include <algorithm>
#include <cmath>

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
  for (const Eigen::Isometry3d& X_PalmPhalanx : s.X_PalmPhalanx)
    m.phalanges().push_back(to_msg(X_WorldPalm * X_PalmPhalanx));
  m.joint_angles(s.q);
  // Late latched, the new sample's pose is both: the resolved pose is searched on the tick.
  const Eigen::Isometry3d& X_WorldTracked = X_WorldPalm_override ? *X_WorldPalm_override : s.X_WorldTracked;
  m.tracked_palm(to_msg(X_WorldTracked));
  m.resolve_offset(to_msg(Eigen::Vector3d(X_WorldPalm.translation() - X_WorldTracked.translation())));
  m.resolve_angle(Eigen::AngleAxisd(X_WorldPalm.linear() * X_WorldTracked.linear().transpose()).angle());
  return m;
}

void set_holders(msg::ObjectState& object, const std::vector<HandAddress>& holders) {
  object.held(!holders.empty());
  object.holders().clear();
  for (const HandAddress& h : holders) {
    msg::ObjectHolder m;
    m.client_id(h.client_id);
    m.hand_side(h.side);
    object.holders().push_back(std::move(m));
  }
  if (holders.empty()) return;
  object.holder_client(holders.front().client_id);
  object.holder_hand(holders.front().side);
}

msg::GraspState make_grasp_state(const HandAddress& address, const sim::HandController& hand, std::uint64_t tick,
                                 double time) {
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
  m.grasp_type(sim::grasp_type_name(s.grasp_type));
  if (const auto metrics = hand.hold_metrics()) {
    m.epsilon(metrics->quality.epsilon);
    m.volume(metrics->quality.volume);
    m.force_closure(metrics->quality.force_closure);
  }
  return m;
}

bool quality_changed(const msg::GraspState& before, const msg::GraspState& now) {
  auto moved = [](double a, double b) {
    return std::abs(a - b) > std::max(kQualityAbsoluteChange, kQualityRelativeChange * std::abs(a));
  };
  return before.force_closure() != now.force_closure() || moved(before.epsilon(), now.epsilon()) ||
         moved(before.volume(), now.volume());
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

void set_metrics(msg::GraspEvent& m, const sim::GraspMetrics& metrics, const sim::HandRig& rig) {
  m.hand_error_mm(metrics.hand_error_mm);
  m.capsules_without_hit(metrics.capsules_without_hit);
  m.capsules().clear();
  for (const sim::CapsuleMetric& c : metrics.capsules) {
    msg::CapsuleReport r;
    r.phalanx(static_cast<std::int16_t>(c.phalanx.value));
    r.phalanx_name(rig.phalanges()[c.phalanx.value].name);
    r.hit(c.hit);
    r.nd(c.nd);
    r.signed_distance(c.signed_distance);
    r.blocked(c.blocked);
    r.contact_hit(c.contact_hit);
    r.nd_contact(c.nd_contact);
    m.capsules().push_back(std::move(r));
  }
  m.palm_signed_distance(metrics.palm_signed_distance);
  m.epsilon(metrics.quality.epsilon);
  m.volume(metrics.quality.volume);
  m.force_closure(metrics.quality.force_closure);
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
  if (e.metrics) set_metrics(m, *e.metrics, rig);
  for (const sim::Contact& c : e.contacts) m.contacts().push_back(to_msg(c));
  m.release_velocity(to_msg(e.v_WorldObject));
  m.release_angular_velocity(to_msg(e.w_WorldObject));
  m.grasp_type(sim::grasp_type_name(e.grasp_type));
  return m;
}

msg::ObjectGeometry make_object_geometry(const sim::ObjectModel& model, std::uint32_t max_triangles) {
  const sim::TriangleMesh& mesh = model.mesh;
  std::vector<float> xyz;
  xyz.reserve(3 * mesh.vertices.size());
  for (const Eigen::Vector3d& v : mesh.vertices)
    for (int k = 0; k < 3; ++k) xyz.push_back(static_cast<float>(v[k]));
  std::vector<std::uint32_t> indices;
  indices.reserve(3 * mesh.triangles.size());
  for (const auto& t : mesh.triangles) indices.insert(indices.end(), t.begin(), t.end());

  msg::ObjectGeometry m;
  m.model(model.name);
  m.content_hash(idl::geometry_content_hash(xyz.data(), mesh.vertices.size(), indices.data(), mesh.triangles.size()));
  m.vertex_count(static_cast<std::uint32_t>(mesh.vertices.size()));
  m.triangle_count(static_cast<std::uint32_t>(mesh.triangles.size()));
  m.mesh_omitted(mesh.triangles.size() > max_triangles);
  if (!m.mesh_omitted()) {
    m.vertices(std::move(xyz));
    m.triangles(std::move(indices));
  }
  m.p_min(to_msg(model.p_ObjectMin));
  m.p_max(to_msg(model.p_ObjectMax));
  m.mass(model.mass_kg);
  const sim::MassProperties& mp = model.mass_properties;
  m.volume(mp.volume);
  const double density = mp.volume > 0 ? model.mass_kg / mp.volume : 0.0;
  m.inertia_diagonal(to_msg(Eigen::Vector3d(mp.inertia_per_density.diagonal() * density)));
  m.p_source_origin(to_msg(Eigen::Vector3d(-model.p_OriginalCenterOfMass)));
  return m;
}

sim::TriangleMesh to_sim_mesh(const msg::ObjectGeometry& m) {
  sim::TriangleMesh mesh;
  const std::vector<float>& xyz = m.vertices();
  mesh.vertices.reserve(xyz.size() / 3);
  for (std::size_t i = 0; i + 2 < xyz.size(); i += 3) mesh.vertices.emplace_back(xyz[i], xyz[i + 1], xyz[i + 2]);
  const std::vector<std::uint32_t>& idx = m.triangles();
  mesh.triangles.reserve(idx.size() / 3);
  for (std::size_t i = 0; i + 2 < idx.size(); i += 3) mesh.triangles.push_back({idx[i], idx[i + 1], idx[i + 2]});
  return mesh;
}

}  // namespace telegrasp::server
