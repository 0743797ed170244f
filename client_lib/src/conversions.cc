#include "conversions.h"

#include "telegrasp/idl/eigen_conversions.h"
#include "telegrasp/idl/geometry_hash.h"

#include <cmath>
#include <map>
#include <string>
#include <type_traits>
#include <vector>

namespace telegrasp::client_lib {

namespace {

client::HandKey hand_key(const std::string& client_id, std::uint8_t side) {
  return client::HandKey{client_id, from_msg_side(side)};
}

template <class T>
struct is_vector : std::false_type {};
template <class T, class A>
struct is_vector<std::vector<T, A>> : std::true_type {};

// The wire value of the client value `c`: `c` itself where the types convert (numbers, strings
// into bounded strings), to_msg where they do not (poses, vectors, enums), element by element for
// sequences.
template <class W, class C>
W wire(const C& c) {
  if constexpr (std::is_convertible_v<const C&, W>) {
    return static_cast<W>(c);
  } else if constexpr (is_vector<W>::value) {
    W out;
    out.reserve(c.size());
    for (const auto& x : c) out.push_back(wire<typename W::value_type>(x));
    return out;
  } else {
    return to_msg(c);
  }
}

// The client value of the wire value `w`: the reverse of wire().
template <class C, class W>
C native(const W& w) {
  if constexpr (requires { w.to_string(); }) {
    return w.to_string();
  } else if constexpr (std::is_convertible_v<const W&, C>) {
    return static_cast<C>(w);
  } else if constexpr (is_vector<C>::value) {
    C out;
    out.reserve(w.size());
    for (const auto& x : w) out.push_back(native<typename C::value_type>(x));
    return out;
  } else {
    return from_msg(w);
  }
}

// Each message type below lists its fields once (`..._fields(copy, m, s)`); to_msg runs the list
// with ToWire (wire field <- client field), from_msg with FromWire (client field <- wire field).
struct ToWire {
  template <class W, class C>
  void operator()(W& w, const C& c) const {
    w = wire<W>(c);
  }
};
struct FromWire {
  template <class W, class C>
  void operator()(const W& w, C& c) const {
    c = native<C>(w);
  }
};

// A hand is two wire fields, client_id and hand_side.
void copy_hand(ToWire, auto& m, const client::HandKey& h) {
  m.client_id(h.client_id);
  m.hand_side(to_msg_side(h.side));
}
void copy_hand(FromWire, const auto& m, client::HandKey& h) { h = hand_key(m.client_id().to_string(), m.hand_side()); }

constexpr auto controller_fields = [](auto copy, auto& m, auto& s) {
  copy(m.sequence_number(), s.sequence_number);
  copy(m.client_time_ns(), s.client_time_ns);
  copy(m.palm(), s.X_WorldPalm);
  copy(m.trigger(), s.trigger);
  copy(m.curls(), s.curls);
  copy(m.buttons(), s.buttons);
  copy(m.tracking_valid(), s.tracking_valid);
  copy(m.lockstep_tick(), s.lockstep_tick);
};

constexpr auto skeleton_fields = [](auto copy, auto& m, auto& s) {
  copy_hand(copy, m, s.hand);
  copy(m.rig(), s.rig);
  copy(m.tick(), s.tick);
  copy(m.time(), s.time);
  copy(m.input_sequence(), s.input_sequence);
  copy(m.input_client_time_ns(), s.input_client_time_ns);
  copy(m.late_latched(), s.late_latched);
  copy(m.frozen(), s.frozen);
  copy(m.palm(), s.X_WorldPalm);
  copy(m.phalanges(), s.X_WorldPhalanx);
  copy(m.joint_angles(), s.joint_angles);
  copy(m.tracked_palm(), s.X_WorldTracked);
  copy(m.resolve_offset(), s.resolve_offset);
  copy(m.resolve_angle(), s.resolve_angle);
};

constexpr auto grasp_state_fields = [](auto copy, auto& m, auto& s) {
  copy_hand(copy, m, s.hand);
  copy(m.tick(), s.tick);
  copy(m.time(), s.time);
  copy(m.selected_object(), s.selected_object);
  copy(m.grasped_object(), s.grasped_object);
  copy(m.trigger(), s.trigger);
  copy(m.blocked(), s.blocked);
  copy(m.palm_contact(), s.palm_contact);
  copy(m.epsilon(), s.epsilon);
  copy(m.volume(), s.volume);
  copy(m.force_closure(), s.force_closure);
  copy(m.grasp_type(), s.grasp_type);
};

constexpr auto contact_fields = [](auto copy, auto& m, auto& c) {
  copy(m.phalanx(), c.phalanx);
  copy(m.p_world(), c.p_WorldContact);
  copy(m.n_world(), c.n_World);
  copy(m.p_object(), c.p_ObjectContact);
  copy(m.n_object(), c.n_Object);
  copy(m.nd(), c.nd);
  copy(m.nd_hit(), c.nd_hit);
};

constexpr auto contact_set_fields = [](auto copy, auto& m, auto& s) {
  copy_hand(copy, m, s.hand);
  copy(m.tick(), s.tick);
  copy(m.time(), s.time);
  copy(m.object_id(), s.object_id);
  copy(m.object_pose(), s.X_WorldObject);
  copy(m.contacts(), s.contacts);
};

constexpr auto capsule_fields = [](auto copy, auto& m, auto& r) {
  copy(m.phalanx(), r.phalanx);
  copy(m.phalanx_name(), r.phalanx_name);
  copy(m.hit(), r.hit);
  copy(m.nd(), r.nd);
  copy(m.signed_distance(), r.signed_distance);
  copy(m.blocked(), r.blocked);
  copy(m.contact_hit(), r.contact_hit);
  copy(m.nd_contact(), r.nd_contact);
};

constexpr auto grasp_event_fields = [](auto copy, auto& m, auto& e) {
  copy(m.event_id(), e.event_id);
  copy(m.kind(), e.kind);
  copy_hand(copy, m, e.hand);
  copy(m.object_id(), e.object_id);
  copy(m.object_name(), e.object_name);
  copy(m.tick(), e.tick);
  copy(m.time(), e.time);
  copy(m.object_spawn_time(), e.object_spawn_time);
  copy(m.object_pose(), e.X_WorldObject);
  copy(m.input_sequence(), e.input_sequence);
  copy(m.hand_error_mm(), e.hand_error_mm);
  copy(m.capsules_without_hit(), e.capsules_without_hit);
  copy(m.capsules(), e.capsules);
  copy(m.contacts(), e.contacts);
  copy(m.palm_signed_distance(), e.palm_signed_distance);
  copy(m.epsilon(), e.epsilon);
  copy(m.volume(), e.volume);
  copy(m.force_closure(), e.force_closure);
  copy(m.release_velocity(), e.v_WorldObject);
  copy(m.release_angular_velocity(), e.w_WorldObject);
  copy(m.grasp_type(), e.grasp_type);
};

constexpr auto object_fields = [](auto copy, auto& m, auto& o) {
  copy(m.id(), o.id);
  copy(m.name(), o.name);
  copy(m.pose(), o.X_WorldObject);
  copy(m.linear_velocity(), o.v_WorldObject);
  copy(m.held(), o.held);
  copy(m.spawn_time(), o.spawn_time);
};

constexpr auto scene_fields = [](auto copy, auto& m, auto& s) {
  copy(m.tick(), s.tick);
  copy(m.time(), s.time);
  copy(m.objects(), s.objects);
  copy(m.incarnation(), s.incarnation);
};

constexpr auto command_fields = [](auto copy, auto& m, auto& c) {
  copy(m.kind(), c.kind);
  copy(m.model(), c.model);
  copy(m.object_id(), c.object_id);
  copy(m.on_table(), c.on_table);
  copy(m.x(), c.x);
  copy(m.y(), c.y);
  copy(m.yaw(), c.yaw);
  copy(m.pose(), c.X_WorldObject);
};

constexpr auto status_fields = [](auto copy, auto& m, auto& s) {
  copy(m.tick(), s.tick);
  copy(m.time(), s.time);
  copy(m.tick_rate_hz(), s.tick_rate_hz);
  copy(m.clients(), s.clients);
  copy(m.hands(), s.hands);
  copy(m.objects(), s.objects);
  copy(m.tick_us_p50(), s.tick_us_p50);
  copy(m.tick_us_max(), s.tick_us_max);
  copy(m.tick_us_p99(), s.tick_us_p99);
  copy(m.rss_kib(), s.rss_kib);
  copy(m.heap_kib(), s.heap_kib);
  copy(m.quality_late(), s.quality_late);
  copy(m.missed_ticks(), s.missed_ticks);
  copy(m.inputs_accepted(), s.inputs_accepted);
  copy(m.inputs_rejected(), s.inputs_rejected);
  copy(m.commands_accepted(), s.commands_accepted);
  copy(m.commands_rejected(), s.commands_rejected);
  copy(m.models(), s.models);
  copy(m.notices_sent(), s.notices_sent);
  copy(m.incarnation(), s.incarnation);
};

constexpr auto geometry_fields = [](auto copy, auto& m, auto& g) {
  copy(m.model(), g.model);
  copy(m.content_hash(), g.content_hash);
  copy(m.vertex_count(), g.vertex_count);
  copy(m.triangle_count(), g.triangle_count);
  copy(m.mesh_omitted(), g.mesh_omitted);
  copy(m.p_min(), g.p_ObjectMin);
  copy(m.p_max(), g.p_ObjectMax);
  copy(m.mass(), g.mass_kg);
  copy(m.volume(), g.volume_m3);
  copy(m.inertia_diagonal(), g.inertia_diagonal);
  copy(m.p_source_origin(), g.p_ObjectSourceOrigin);
};

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

// The reverse; a reason sent twice (not by our server) adds up rather than losing a count.
std::map<std::string, std::uint64_t> reject_counts(const std::vector<msg::RejectCount>& counts) {
  std::map<std::string, std::uint64_t> out;
  for (const msg::RejectCount& r : counts) out[r.reason().to_string()] += r.count();
  return out;
}

// A message made from client value `s` with `fields`, and the reverse.
template <class M, class S, class Fields>
M to_wire(const S& s, Fields fields) {
  M m;
  fields(ToWire{}, m, s);
  return m;
}
template <class S, class M, class Fields>
S from_wire(const M& m, Fields fields) {
  S s;
  fields(FromWire{}, m, s);
  return s;
}

}  // namespace

msg::Vec3 to_msg(const Eigen::Vector3d& v) { return idl::to_msg(v); }
Eigen::Vector3d from_msg(const msg::Vec3& v) { return idl::to_eigen(v); }
msg::Pose3 to_msg(const Eigen::Isometry3d& X_AB) { return idl::to_msg(X_AB); }
Eigen::Isometry3d from_msg(const msg::Pose3& pose) { return idl::to_eigen(pose); }

std::uint8_t to_msg_side(client::HandSide side) { return static_cast<std::uint8_t>(side); }

client::HandSide from_msg_side(std::uint8_t side) { return static_cast<client::HandSide>(side); }

msg::ControllerState to_msg(const client::ControllerSample& sample, const std::string& client_id) {
  msg::ControllerState m = to_wire<msg::ControllerState>(sample, controller_fields);
  m.client_id(client_id);
  m.hand_side(to_msg_side(sample.side));
  return m;
}

client::ControllerSample from_msg(const msg::ControllerState& m) {
  client::ControllerSample s = from_wire<client::ControllerSample>(m, controller_fields);
  s.side = from_msg_side(m.hand_side());
  return s;
}

msg::HandSkeleton to_msg(const client::HandSkeleton& s) { return to_wire<msg::HandSkeleton>(s, skeleton_fields); }
client::HandSkeleton from_msg(const msg::HandSkeleton& m) {
  return from_wire<client::HandSkeleton>(m, skeleton_fields);
}

msg::GraspState to_msg(const client::GraspState& s) { return to_wire<msg::GraspState>(s, grasp_state_fields); }
client::GraspState from_msg(const msg::GraspState& m) { return from_wire<client::GraspState>(m, grasp_state_fields); }

msg::ContactPoint to_msg(const client::ContactPoint& c) { return to_wire<msg::ContactPoint>(c, contact_fields); }
client::ContactPoint from_msg(const msg::ContactPoint& m) { return from_wire<client::ContactPoint>(m, contact_fields); }

msg::ContactSet to_msg(const client::ContactSet& s) { return to_wire<msg::ContactSet>(s, contact_set_fields); }
client::ContactSet from_msg(const msg::ContactSet& m) { return from_wire<client::ContactSet>(m, contact_set_fields); }

msg::CapsuleReport to_msg(const client::CapsuleMetric& r) { return to_wire<msg::CapsuleReport>(r, capsule_fields); }
client::CapsuleMetric from_msg(const msg::CapsuleReport& m) {
  return from_wire<client::CapsuleMetric>(m, capsule_fields);
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

msg::GraspEvent to_msg(const client::GraspEvent& e) { return to_wire<msg::GraspEvent>(e, grasp_event_fields); }
client::GraspEvent from_msg(const msg::GraspEvent& m) { return from_wire<client::GraspEvent>(m, grasp_event_fields); }

msg::ObjectState to_msg(const client::ObjectState& o) {
  msg::ObjectState m = to_wire<msg::ObjectState>(o, object_fields);
  m.holder_client(o.holder.client_id);
  m.holder_hand(to_msg_side(o.holder.side));
  for (const client::HandKey& h : o.holders) {
    msg::ObjectHolder holder;
    copy_hand(ToWire{}, holder, h);
    m.holders().push_back(std::move(holder));
  }
  return m;
}

client::ObjectState from_msg(const msg::ObjectState& m) {
  client::ObjectState o = from_wire<client::ObjectState>(m, object_fields);
  o.holder = hand_key(m.holder_client().to_string(), m.holder_hand());
  for (const msg::ObjectHolder& h : m.holders()) copy_hand(FromWire{}, h, o.holders.emplace_back());
  return o;
}

msg::SceneState to_msg(const client::SceneState& s) { return to_wire<msg::SceneState>(s, scene_fields); }
client::SceneState from_msg(const msg::SceneState& m) { return from_wire<client::SceneState>(m, scene_fields); }

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
  msg::SceneCommand m = to_wire<msg::SceneCommand>(c, command_fields);
  m.client_id(client_id);
  m.command_id(command_id);
  return m;
}

client::SceneCommand from_msg(const msg::SceneCommand& m) { return from_wire<client::SceneCommand>(m, command_fields); }

msg::ServerStatus to_msg(const client::ServerStatus& s) {
  msg::ServerStatus m = to_wire<msg::ServerStatus>(s, status_fields);
  m.rejected(reject_counts(s.rejected));
  m.commands_rejected_by_reason(reject_counts(s.commands_rejected_by_reason));
  return m;
}

client::ServerStatus from_msg(const msg::ServerStatus& m) {
  client::ServerStatus s = from_wire<client::ServerStatus>(m, status_fields);
  s.rejected = reject_counts(m.rejected());
  s.commands_rejected_by_reason = reject_counts(m.commands_rejected_by_reason());
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
  msg::ObjectGeometry m = to_wire<msg::ObjectGeometry>(g, geometry_fields);
  m.vertices().reserve(3 * g.vertices.size());
  for (const Eigen::Vector3f& v : g.vertices) m.vertices().insert(m.vertices().end(), {v.x(), v.y(), v.z()});
  m.triangles().reserve(3 * g.triangles.size());
  for (const auto& t : g.triangles) m.triangles().insert(m.triangles().end(), t.begin(), t.end());
  return m;
}

client::ObjectGeometry from_msg_without_mesh(const msg::ObjectGeometry& m) {
  return from_wire<client::ObjectGeometry>(m, geometry_fields);
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
