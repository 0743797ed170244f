#include "conversions.h"

#include "telegrasp/idl/eigen_conversions.h"
#include "telegrasp/idl/geometry_hash.h"

#include <cmath>

namespace telegrasp::client_lib {

namespace {

client::HandKey hand_key(const std::string& client_id, std::uint8_t side) {
  return client::HandKey{client_id, from_msg_side(side)};
}

template <class Out, class In>
std::vector<Out> to_msgs(const std::vector<In>& in) {
  std::vector<Out> out;
  out.reserve(in.size());
  for (const In& x : in) out.push_back(to_msg(x));
  return out;
}

template <class Out, class In>
std::vector<Out> from_msgs(const std::vector<In>& in) {
  std::vector<Out> out;
  out.reserve(in.size());
  for (const In& x : in) out.push_back(from_msg(x));
  return out;
}

}  // namespace

msg::Vec3 to_msg(const Eigen::Vector3d& v) { return idl::to_msg(v); }
Eigen::Vector3d from_msg(const msg::Vec3& v) { return idl::to_eigen(v); }
msg::Pose3 to_msg(const Eigen::Isometry3d& X_AB) { return idl::to_msg(X_AB); }
Eigen::Isometry3d from_msg(const msg::Pose3& pose) { return idl::to_eigen(pose); }

std::uint8_t to_msg_side(client::HandSide side) { return static_cast<std::uint8_t>(side); }

client::HandSide from_msg_side(std::uint8_t side) { return static_cast<client::HandSide>(side); }

msg::ControllerState to_msg(const client::ControllerSample& sample, const std::string& client_id) {
  msg::ControllerState m;
  m.client_id(client_id);
  m.hand_side(to_msg_side(sample.side));
  m.sequence_number(sample.sequence_number);
  m.client_time_ns(sample.client_time_ns);
  m.palm(to_msg(sample.X_WorldPalm));
  m.trigger(sample.trigger);
  m.curls(sample.curls);
  m.buttons(sample.buttons);
  m.tracking_valid(sample.tracking_valid);
  m.lockstep_tick(sample.lockstep_tick);
  return m;
}

client::ControllerSample from_msg(const msg::ControllerState& m) {
  client::ControllerSample s;
  s.side = from_msg_side(m.hand_side());
  s.X_WorldPalm = from_msg(m.palm());
  s.trigger = m.trigger();
  s.curls = m.curls();
  s.buttons = m.buttons();
  s.tracking_valid = m.tracking_valid();
  s.sequence_number = m.sequence_number();
  s.client_time_ns = m.client_time_ns();
  s.lockstep_tick = m.lockstep_tick();
  return s;
}

msg::HandSkeleton to_msg(const client::HandSkeleton& s) {
  msg::HandSkeleton m;
  m.client_id(s.hand.client_id);
  m.hand_side(to_msg_side(s.hand.side));
  m.rig(s.rig);
  m.tick(s.tick);
  m.time(s.time);
  m.input_sequence(s.input_sequence);
  m.input_client_time_ns(s.input_client_time_ns);
  m.late_latched(s.late_latched);
  m.frozen(s.frozen);
  m.palm(to_msg(s.X_WorldPalm));
  m.phalanges(to_msgs<msg::Pose3>(s.X_WorldPhalanx));
  m.joint_angles(s.joint_angles);
  m.tracked_palm(to_msg(s.X_WorldTracked));
  m.resolve_offset(to_msg(s.resolve_offset));
  m.resolve_angle(s.resolve_angle);
  return m;
}

client::HandSkeleton from_msg(const msg::HandSkeleton& m) {
  client::HandSkeleton s;
  s.hand = hand_key(m.client_id().to_string(), m.hand_side());
  s.rig = m.rig().to_string();
  s.tick = m.tick();
  s.time = m.time();
  s.input_sequence = m.input_sequence();
  s.input_client_time_ns = m.input_client_time_ns();
  s.late_latched = m.late_latched();
  s.frozen = m.frozen();
  s.X_WorldPalm = from_msg(m.palm());
  s.X_WorldPhalanx = from_msgs<Eigen::Isometry3d>(m.phalanges());
  s.joint_angles = m.joint_angles();
  s.X_WorldTracked = from_msg(m.tracked_palm());
  s.resolve_offset = from_msg(m.resolve_offset());
  s.resolve_angle = m.resolve_angle();
  return s;
}

msg::GraspState to_msg(const client::GraspState& s) {
  msg::GraspState m;
  m.client_id(s.hand.client_id);
  m.hand_side(to_msg_side(s.hand.side));
  m.tick(s.tick);
  m.time(s.time);
  m.selected_object(s.selected_object);
  m.grasped_object(s.grasped_object);
  m.trigger(s.trigger);
  m.blocked(s.blocked);
  m.palm_contact(s.palm_contact);
  m.epsilon(s.epsilon);
  m.volume(s.volume);
  m.force_closure(s.force_closure);
  m.grasp_type(s.grasp_type);
  return m;
}

client::GraspState from_msg(const msg::GraspState& m) {
  client::GraspState s;
  s.hand = hand_key(m.client_id().to_string(), m.hand_side());
  s.tick = m.tick();
  s.time = m.time();
  s.selected_object = m.selected_object();
  s.grasped_object = m.grasped_object();
  s.trigger = m.trigger();
  s.blocked = m.blocked();
  s.palm_contact = m.palm_contact();
  s.epsilon = m.epsilon();
  s.volume = m.volume();
  s.force_closure = m.force_closure();
  s.grasp_type = m.grasp_type().to_string();
  return s;
}

msg::ContactPoint to_msg(const client::ContactPoint& c) {
  msg::ContactPoint m;
  m.phalanx(static_cast<std::int16_t>(c.phalanx));
  m.p_world(to_msg(c.p_WorldContact));
  m.n_world(to_msg(c.n_World));
  m.p_object(to_msg(c.p_ObjectContact));
  m.n_object(to_msg(c.n_Object));
  m.nd(c.nd);
  m.nd_hit(c.nd_hit);
  return m;
}

client::ContactPoint from_msg(const msg::ContactPoint& m) {
  client::ContactPoint c;
  c.phalanx = m.phalanx();
  c.p_WorldContact = from_msg(m.p_world());
  c.n_World = from_msg(m.n_world());
  c.p_ObjectContact = from_msg(m.p_object());
  c.n_Object = from_msg(m.n_object());
  c.nd = m.nd();
  c.nd_hit = m.nd_hit();
  return c;
}

msg::ContactSet to_msg(const client::ContactSet& s) {
  msg::ContactSet m;
  m.client_id(s.hand.client_id);
  m.hand_side(to_msg_side(s.hand.side));
  m.tick(s.tick);
  m.time(s.time);
  m.object_id(s.object_id);
  m.object_pose(to_msg(s.X_WorldObject));
  m.contacts(to_msgs<msg::ContactPoint>(s.contacts));
  return m;
}

client::ContactSet from_msg(const msg::ContactSet& m) {
  client::ContactSet s;
  s.hand = hand_key(m.client_id().to_string(), m.hand_side());
  s.tick = m.tick();
  s.time = m.time();
  s.object_id = m.object_id();
  s.X_WorldObject = from_msg(m.object_pose());
  s.contacts = from_msgs<client::ContactPoint>(m.contacts());
  return s;
}

msg::CapsuleReport to_msg(const client::CapsuleMetric& r) {
  msg::CapsuleReport m;
  m.phalanx(static_cast<std::int16_t>(r.phalanx));
  m.phalanx_name(r.phalanx_name);
  m.hit(r.hit);
  m.nd(r.nd);
  m.signed_distance(r.signed_distance);
  m.blocked(r.blocked);
  m.contact_hit(r.contact_hit);
  m.nd_contact(r.nd_contact);
  return m;
}

client::CapsuleMetric from_msg(const msg::CapsuleReport& m) {
  client::CapsuleMetric r;
  r.phalanx = m.phalanx();
  r.phalanx_name = m.phalanx_name().to_string();
  r.hit = m.hit();
  r.nd = m.nd();
  r.signed_distance = m.signed_distance();
  r.blocked = m.blocked();
  r.contact_hit = m.contact_hit();
  r.nd_contact = m.nd_contact();
  return r;
}

msg::GraspEventKind to_msg(client::GraspEvent::Kind kind) {
  switch (kind) {
    case client::GraspEvent::Kind::kGrasp:
      return msg::GRASP_EVENT_GRASP;
    case client::GraspEvent::Kind::kRelease:
      return msg::GRASP_EVENT_RELEASE;
  }
  return static_cast<msg::GraspEventKind>(kind);  // not a kind: sent unchanged
}

client::GraspEvent::Kind from_msg(msg::GraspEventKind kind) {
  switch (kind) {
    case msg::GRASP_EVENT_GRASP:
      return client::GraspEvent::Kind::kGrasp;
    case msg::GRASP_EVENT_RELEASE:
      return client::GraspEvent::Kind::kRelease;
  }
  return static_cast<client::GraspEvent::Kind>(kind);  // not a kind: kept unchanged
}

msg::GraspEvent to_msg(const client::GraspEvent& e) {
  msg::GraspEvent m;
  m.event_id(e.event_id);
  m.kind(to_msg(e.kind));
  m.client_id(e.hand.client_id);
  m.hand_side(to_msg_side(e.hand.side));
  m.object_id(e.object_id);
  m.object_name(e.object_name);
  m.tick(e.tick);
  m.time(e.time);
  m.object_spawn_time(e.object_spawn_time);
  m.object_pose(to_msg(e.X_WorldObject));
  m.input_sequence(e.input_sequence);
  m.hand_error_mm(e.hand_error_mm);
  m.capsules_without_hit(e.capsules_without_hit);
  m.capsules(to_msgs<msg::CapsuleReport>(e.capsules));
  m.contacts(to_msgs<msg::ContactPoint>(e.contacts));
  m.palm_signed_distance(e.palm_signed_distance);
  m.epsilon(e.epsilon);
  m.volume(e.volume);
  m.force_closure(e.force_closure);
  m.release_velocity(to_msg(e.v_WorldObject));
  m.release_angular_velocity(to_msg(e.w_WorldObject));
  m.grasp_type(e.grasp_type);
  return m;
}

client::GraspEvent from_msg(const msg::GraspEvent& m) {
  client::GraspEvent e;
  e.event_id = m.event_id();
  e.kind = from_msg(m.kind());
  e.hand = hand_key(m.client_id().to_string(), m.hand_side());
  e.object_id = m.object_id();
  e.object_name = m.object_name().to_string();
  e.tick = m.tick();
  e.time = m.time();
  e.object_spawn_time = m.object_spawn_time();
  e.X_WorldObject = from_msg(m.object_pose());
  e.input_sequence = m.input_sequence();
  e.hand_error_mm = m.hand_error_mm();
  e.capsules_without_hit = m.capsules_without_hit();
  e.capsules = from_msgs<client::CapsuleMetric>(m.capsules());
  e.contacts = from_msgs<client::ContactPoint>(m.contacts());
  e.palm_signed_distance = m.palm_signed_distance();
  e.epsilon = m.epsilon();
  e.volume = m.volume();
  e.force_closure = m.force_closure();
  e.v_WorldObject = from_msg(m.release_velocity());
  e.w_WorldObject = from_msg(m.release_angular_velocity());
  e.grasp_type = m.grasp_type().to_string();
  return e;
}

msg::ObjectState to_msg(const client::ObjectState& o) {
  msg::ObjectState m;
  m.id(o.id);
  m.name(o.name);
  m.pose(to_msg(o.X_WorldObject));
  m.linear_velocity(to_msg(o.v_WorldObject));
  m.held(o.held);
  m.holder_client(o.holder.client_id);
  m.holder_hand(to_msg_side(o.holder.side));
  m.spawn_time(o.spawn_time);
  for (const client::HandKey& h : o.holders) {
    msg::ObjectHolder holder;
    holder.client_id(h.client_id);
    holder.hand_side(to_msg_side(h.side));
    m.holders().push_back(std::move(holder));
  }
  return m;
}

client::ObjectState from_msg(const msg::ObjectState& m) {
  client::ObjectState o;
  o.id = m.id();
  o.name = m.name().to_string();
  o.X_WorldObject = from_msg(m.pose());
  o.v_WorldObject = from_msg(m.linear_velocity());
  o.held = m.held();
  o.holder = hand_key(m.holder_client().to_string(), m.holder_hand());
  o.spawn_time = m.spawn_time();
  for (const msg::ObjectHolder& h : m.holders())
    o.holders.push_back(hand_key(h.client_id().to_string(), h.hand_side()));
  return o;
}

msg::SceneState to_msg(const client::SceneState& s) {
  msg::SceneState m;
  m.tick(s.tick);
  m.time(s.time);
  m.objects(to_msgs<msg::ObjectState>(s.objects));
  m.incarnation(s.incarnation);
  return m;
}

client::SceneState from_msg(const msg::SceneState& m) {
  client::SceneState s;
  s.tick = m.tick();
  s.time = m.time();
  s.objects = from_msgs<client::ObjectState>(m.objects());
  s.incarnation = m.incarnation();
  return s;
}

msg::SceneCommandKind to_msg(client::SceneCommand::Kind kind) {
  switch (kind) {
    case client::SceneCommand::Kind::kSpawn:
      return msg::SCENE_SPAWN;
    case client::SceneCommand::Kind::kRemove:
      return msg::SCENE_REMOVE;
    case client::SceneCommand::Kind::kReset:
      return msg::SCENE_RESET;
  }
  return static_cast<msg::SceneCommandKind>(kind);  // not a kind: sent unchanged
}

client::SceneCommand::Kind from_msg(msg::SceneCommandKind kind) {
  switch (kind) {
    case msg::SCENE_SPAWN:
      return client::SceneCommand::Kind::kSpawn;
    case msg::SCENE_REMOVE:
      return client::SceneCommand::Kind::kRemove;
    case msg::SCENE_RESET:
      return client::SceneCommand::Kind::kReset;
  }
  return static_cast<client::SceneCommand::Kind>(kind);  // not a kind: kept unchanged
}

msg::SceneCommand to_msg(const client::SceneCommand& c, const std::string& client_id, std::uint64_t command_id) {
  msg::SceneCommand m;
  m.client_id(client_id);
  m.command_id(command_id);
  m.kind(to_msg(c.kind));
  m.model(c.model);
  m.object_id(c.object_id);
  m.on_table(c.on_table);
  m.x(c.x);
  m.y(c.y);
  m.yaw(c.yaw);
  m.pose(to_msg(c.X_WorldObject));
  return m;
}

client::SceneCommand from_msg(const msg::SceneCommand& m) {
  client::SceneCommand c;
  c.kind = from_msg(m.kind());
  c.model = m.model().to_string();
  c.object_id = m.object_id();
  c.on_table = m.on_table();
  c.x = m.x();
  c.y = m.y();
  c.yaw = m.yaw();
  c.X_WorldObject = from_msg(m.pose());
  return c;
}

namespace {

// Counts per reason as ServerStatus carries them (rejected, commands_rejected_by_reason).
std::vector<msg::RejectCount> reject_counts(const std::map<std::string, std::uint64_t>& by_reason) {
  std::vector<msg::RejectCount> out;
  for (const auto& [reason, count] : by_reason) {
    msg::RejectCount r;
    r.reason(reason);
    r.count(count);
    out.push_back(r);
  }
  return out;
}

}  // namespace

msg::ServerStatus to_msg(const client::ServerStatus& s) {
  msg::ServerStatus m;
  m.tick(s.tick);
  m.time(s.time);
  m.tick_rate_hz(s.tick_rate_hz);
  m.clients(s.clients);
  m.hands(s.hands);
  m.objects(s.objects);
  m.tick_us_p50(s.tick_us_p50);
  m.tick_us_max(s.tick_us_max);
  m.tick_us_p99(s.tick_us_p99);
  m.rss_kib(s.rss_kib);
  m.heap_kib(s.heap_kib);
  m.quality_late(s.quality_late);
  m.missed_ticks(s.missed_ticks);
  m.inputs_accepted(s.inputs_accepted);
  m.inputs_rejected(s.inputs_rejected);
  m.rejected(reject_counts(s.rejected));
  m.commands_accepted(s.commands_accepted);
  m.commands_rejected(s.commands_rejected);
  for (const std::string& model : s.models) m.models().emplace_back(model);
  m.commands_rejected_by_reason(reject_counts(s.commands_rejected_by_reason));
  m.notices_sent(s.notices_sent);
  m.incarnation(s.incarnation);
  return m;
}

client::ServerStatus from_msg(const msg::ServerStatus& m) {
  client::ServerStatus s;
  s.tick = m.tick();
  s.time = m.time();
  s.tick_rate_hz = m.tick_rate_hz();
  s.clients = m.clients();
  s.hands = m.hands();
  s.objects = m.objects();
  s.tick_us_p50 = m.tick_us_p50();
  s.tick_us_max = m.tick_us_max();
  s.tick_us_p99 = m.tick_us_p99();
  s.rss_kib = m.rss_kib();
  s.heap_kib = m.heap_kib();
  s.quality_late = m.quality_late();
  s.missed_ticks = m.missed_ticks();
  s.inputs_accepted = m.inputs_accepted();
  s.inputs_rejected = m.inputs_rejected();
  // A reason sent twice (not by our server) adds up rather than losing a count.
  for (const msg::RejectCount& r : m.rejected()) s.rejected[r.reason().to_string()] += r.count();
  s.commands_accepted = m.commands_accepted();
  s.commands_rejected = m.commands_rejected();
  s.models.reserve(m.models().size());
  for (const auto& model : m.models()) s.models.push_back(model.to_string());
  for (const msg::RejectCount& r : m.commands_rejected_by_reason())
    s.commands_rejected_by_reason[r.reason().to_string()] += r.count();
  s.notices_sent = m.notices_sent();
  s.incarnation = m.incarnation();
  return s;
}

client::Notice from_msg(const msg::ClientNotice& m) {
  client::Notice n;
  n.client_id = m.client_id().to_string();
  n.kind = m.kind() == msg::NOTICE_COMMAND_REJECTED ? client::Notice::Kind::kCommandRejected
                                                    : client::Notice::Kind::kInputRejected;
  n.reason = m.reason().to_string();
  n.detail = m.detail().to_string();
  n.command_id = m.command_id();
  n.count = m.count();
  n.time = m.time();
  return n;
}

client::SceneInfo from_msg(const msg::SceneAnnouncement& m) {
  client::SceneInfo s;
  s.scene = m.scene().to_string();
  s.host = m.host().to_string();
  s.version = m.version().to_string();
  s.incarnation = m.incarnation();
  s.started = m.started();
  s.serving = m.serving();
  s.clients = m.clients();
  s.hands = m.hands();
  s.objects = m.objects();
  s.tick_rate_hz = m.tick_rate_hz();
  s.tick_us_p99 = m.tick_us_p99();
  s.missed_ticks = m.missed_ticks();
  s.cpu_percent = m.cpu_percent();
  s.host_cores = m.host_cores();
  s.host_load = m.host_load();
  return s;
}

msg::ObjectGeometry to_msg(const client::ObjectGeometry& g) {
  msg::ObjectGeometry m;
  m.model(g.model);
  m.content_hash(g.content_hash);
  m.vertex_count(g.vertex_count);
  m.triangle_count(g.triangle_count);
  m.mesh_omitted(g.mesh_omitted);
  m.vertices().reserve(3 * g.vertices.size());
  for (const Eigen::Vector3f& v : g.vertices) m.vertices().insert(m.vertices().end(), {v.x(), v.y(), v.z()});
  m.triangles().reserve(3 * g.triangles.size());
  for (const auto& t : g.triangles) m.triangles().insert(m.triangles().end(), t.begin(), t.end());
  m.p_min(to_msg(g.p_ObjectMin));
  m.p_max(to_msg(g.p_ObjectMax));
  m.mass(g.mass_kg);
  m.volume(g.volume_m3);
  m.inertia_diagonal(to_msg(g.inertia_diagonal));
  m.p_source_origin(to_msg(g.p_ObjectSourceOrigin));
  return m;
}

client::ObjectGeometry from_msg_without_mesh(const msg::ObjectGeometry& m) {
  client::ObjectGeometry g;
  g.model = m.model().to_string();
  g.content_hash = m.content_hash();
  g.vertex_count = m.vertex_count();
  g.triangle_count = m.triangle_count();
  g.mesh_omitted = m.mesh_omitted();
  g.p_ObjectMin = from_msg(m.p_min());
  g.p_ObjectMax = from_msg(m.p_max());
  g.mass_kg = m.mass();
  g.volume_m3 = m.volume();
  g.inertia_diagonal = from_msg(m.inertia_diagonal());
  g.p_ObjectSourceOrigin = from_msg(m.p_source_origin());
  return g;
}

client::ObjectGeometry from_msg(const msg::ObjectGeometry& m) {
  client::ObjectGeometry g = from_msg_without_mesh(m);
  const std::vector<float>& xyz = m.vertices();
  g.vertices.reserve(xyz.size() / 3);
  for (std::size_t i = 0; i + 2 < xyz.size(); i += 3) g.vertices.emplace_back(xyz[i], xyz[i + 1], xyz[i + 2]);
  const std::vector<std::uint32_t>& idx = m.triangles();
  g.triangles.reserve(idx.size() / 3);
  for (std::size_t i = 0; i + 2 < idx.size(); i += 3) g.triangles.push_back({idx[i], idx[i + 1], idx[i + 2]});
  return g;
}

std::string check_object_geometry(const msg::ObjectGeometry& m) {
  const std::vector<float>& xyz = m.vertices();
  const std::vector<std::uint32_t>& idx = m.triangles();
  if (m.mesh_omitted()) return xyz.empty() && idx.empty() ? "" : "mesh_omitted but vertices or triangles sent";
  if (xyz.size() != 3ull * m.vertex_count())
    return std::to_string(xyz.size()) + " vertex coordinates for vertex_count " + std::to_string(m.vertex_count());
  if (idx.size() != 3ull * m.triangle_count())
    return std::to_string(idx.size()) + " triangle indices for triangle_count " + std::to_string(m.triangle_count());
  for (float c : xyz)
    if (!std::isfinite(c)) return "a non-finite vertex coordinate";
  for (std::uint32_t i : idx)
    if (i >= m.vertex_count())
      return "triangle index " + std::to_string(i) + " past the " + std::to_string(m.vertex_count()) + " vertices";
  if (idl::geometry_content_hash(xyz.data(), m.vertex_count(), idx.data(), m.triangle_count()) != m.content_hash())
    return "content_hash does not match the mesh";
  return "";
}

}  // namespace telegrasp::client_lib
