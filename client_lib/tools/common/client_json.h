// The JSON form of the client library's types, one for every tool that prints or serves them
// (telegrasp-echo's lines, telegrasp-view's telegrasp.* channels): the types' field names with
// the unit of every quantity appended (`time_s`, `p_m`, `nd_mm`; unit normals and quaternions
// have none). Templates over the nlohmann JSON type, so each tool keeps its own (echo an ordered
// one, to print "topic" first).
#pragma once

#include "telegrasp/idl/cli.h"
#include "telegrasp/client/types.h"

#include <Eigen/Geometry>

#include <cstdio>
#include <vector>

namespace telegrasp::tools::json_form {

inline constexpr double kMmPerM = 1000.0;

template <class Json>
Json vec(const Eigen::Vector3d& v) {
  return Json::array({v.x(), v.y(), v.z()});
}

/// {"p_m": [x, y, z], "q_wxyz": [w, x, y, z]}.
template <class Json>
Json pose(const Eigen::Isometry3d& X) {
  const Eigen::Quaterniond q(X.linear());
  return Json{{"p_m", vec<Json>(X.translation())}, {"q_wxyz", Json::array({q.w(), q.x(), q.y(), q.z()})}};
}

template <class Json>
Json hand(const client::HandKey& hand) {
  return Json{{"client_id", hand.client_id}, {"side", client::to_string(hand.side)}};
}

template <class Json>
Json contact(const client::ContactPoint& c) {
  return Json{{"phalanx", c.phalanx},
              {"p_WorldContact_m", vec<Json>(c.p_WorldContact)},
              {"n_World", vec<Json>(c.n_World)},
              {"p_ObjectContact_m", vec<Json>(c.p_ObjectContact)},
              {"n_Object", vec<Json>(c.n_Object)},
              {"nd_mm", c.nd_hit ? Json(kMmPerM * c.nd) : Json()},
              {"nd_hit", c.nd_hit}};
}

/// nd_midlength_mm (the paper's ND) is null without a hit: "no hit" is not 0; nd_mm is its alias,
/// kept for one release. nd_contact_mm (ND toward the contact) is null without contact_hit.
template <class Json>
Json capsule(const client::CapsuleMetric& r) {
  const Json nd_midlength = r.hit ? Json(kMmPerM * r.nd) : Json();
  return Json{{"phalanx", r.phalanx},
              {"phalanx_name", r.phalanx_name},
              {"hit", r.hit},
              {"nd_midlength_mm", nd_midlength},
              {"nd_mm", nd_midlength},
              {"contact_hit", r.contact_hit},
              {"nd_contact_mm", r.contact_hit ? Json(kMmPerM * r.nd_contact) : Json()},
              {"signed_distance_mm", kMmPerM * r.signed_distance},
              {"blocked", r.blocked}};
}

template <class Json, class T, class F>
Json array(const std::vector<T>& items, F form) {
  Json out = Json::array();
  for (const T& item : items) out.push_back(form(item));
  return out;
}

template <class Json>
Json object_state(const client::ObjectState& o) {
  Json j{{"id", o.id},
         {"name", o.name},
         {"X_WorldObject", pose<Json>(o.X_WorldObject)},
         {"v_WorldObject_m_per_s", vec<Json>(o.v_WorldObject)},
         {"held", o.held}};
  if (o.held) j["holder"] = hand<Json>(o.holder);
  if (o.held) j["holders"] = array<Json>(o.holders, hand<Json>);
  j["spawn_time_s"] = o.spawn_time;
  return j;
}

template <class Json>
Json hand_skeleton(const client::HandSkeleton& s) {
  return Json{{"hand", hand<Json>(s.hand)},
              {"rig", s.rig},
              {"tick", s.tick},
              {"time_s", s.time},
              {"input_sequence", s.input_sequence},
              {"input_client_time_ns", s.input_client_time_ns},
              {"late_latched", s.late_latched},
              {"frozen", s.frozen},
              {"X_WorldPalm", pose<Json>(s.X_WorldPalm)},
              {"X_WorldPhalanx", array<Json>(s.X_WorldPhalanx, pose<Json>)},
              {"joint_angles_rad", s.joint_angles},
              {"X_WorldTracked", pose<Json>(s.X_WorldTracked)},
              {"resolve_offset_m", vec<Json>(s.resolve_offset)},
              {"resolve_angle_rad", s.resolve_angle}};
}

template <class Json>
Json grasp_state(const client::GraspState& s) {
  return Json{{"hand", hand<Json>(s.hand)},
              {"tick", s.tick},
              {"time_s", s.time},
              {"selected_object", s.selected_object},
              {"grasped_object", s.grasped_object},
              {"trigger", s.trigger},
              {"blocked", s.blocked},
              {"palm_contact", s.palm_contact},
              {"epsilon", s.epsilon},
              {"volume", s.volume},
              {"force_closure", s.force_closure},
              {"grasp_type", s.grasp_type}};
}

template <class Json>
Json contact_set(const client::ContactSet& s) {
  return Json{{"hand", hand<Json>(s.hand)},
              {"tick", s.tick},
              {"time_s", s.time},
              {"object_id", s.object_id},
              {"X_WorldObject", pose<Json>(s.X_WorldObject)},
              {"contacts", array<Json>(s.contacts, contact<Json>)}};
}

/// Grasps carry the paper's metrics and the contacts; releases the object's velocity.
template <class Json>
Json grasp_event(const client::GraspEvent& e) {
  using Kind = client::GraspEvent::Kind;
  Json j{{"event_id", e.event_id},
         {"kind", e.kind == Kind::kGrasp     ? "grasp"
                  : e.kind == Kind::kRelease ? "release"
                                             : "unknown"},
         {"hand", hand<Json>(e.hand)},
         {"object_id", e.object_id},
         {"object_name", e.object_name},
         {"tick", e.tick},
         {"time_s", e.time},
         {"object_spawn_time_s", e.object_spawn_time},
         {"X_WorldObject", pose<Json>(e.X_WorldObject)},
         {"input_sequence", e.input_sequence}};
  if (e.kind == Kind::kRelease) {
    j["v_WorldObject_m_per_s"] = vec<Json>(e.v_WorldObject);
    j["w_WorldObject_rad_per_s"] = vec<Json>(e.w_WorldObject);
  } else {
    j["hand_error_mm"] = e.hand_error_mm;
    j["capsules_without_hit"] = e.capsules_without_hit;
    j["palm_signed_distance_mm"] = kMmPerM * e.palm_signed_distance;
    j["epsilon"] = e.epsilon;
    j["volume"] = e.volume;
    j["force_closure"] = e.force_closure;
    j["grasp_type"] = e.grasp_type;
    j["capsules"] = array<Json>(e.capsules, capsule<Json>);
    j["contacts"] = array<Json>(e.contacts, contact<Json>);
  }
  return j;
}

template <class Json>
Json scene_state(const client::SceneState& s) {
  return Json{{"tick", s.tick}, {"time_s", s.time}, {"objects", array<Json>(s.objects, object_state<Json>)}};
}

template <class Json>
Json server_status(const client::ServerStatus& s) {
  Json rejected = Json::object();
  for (const auto& [reason, count] : s.rejected) rejected[reason] = count;
  Json commands_rejected_by_reason = Json::object();
  for (const auto& [reason, count] : s.commands_rejected_by_reason) commands_rejected_by_reason[reason] = count;
  return Json{{"tick", s.tick},
              {"time_s", s.time},
              {"tick_rate_hz", s.tick_rate_hz},
              {"clients", s.clients},
              {"hands", s.hands},
              {"objects", s.objects},
              {"tick_us_p50", s.tick_us_p50},
              {"tick_us_p99", s.tick_us_p99},
              {"tick_us_max", s.tick_us_max},
              {"missed_ticks", s.missed_ticks},
              {"rss_kib", s.rss_kib},
              {"heap_kib", s.heap_kib},
              {"quality_late", s.quality_late},
              {"inputs_accepted", s.inputs_accepted},
              {"inputs_rejected", s.inputs_rejected},
              {"rejected", rejected},
              {"commands_accepted", s.commands_accepted},
              {"commands_rejected", s.commands_rejected},
              {"commands_rejected_by_reason", commands_rejected_by_reason},
              {"notices_sent", s.notices_sent},
              {"models", s.models}};
}

/// A summary: the mesh itself is too large for a line.
template <class Json>
Json object_geometry(const client::ObjectGeometry& g) {
  return Json{{"model", g.model},
              {"content_hash", cli::format_hex64(g.content_hash)},
              {"vertex_count", g.vertex_count},
              {"triangle_count", g.triangle_count},
              {"mesh_omitted", g.mesh_omitted},
              {"p_ObjectMin_m", vec<Json>(g.p_ObjectMin)},
              {"p_ObjectMax_m", vec<Json>(g.p_ObjectMax)},
              {"mass_kg", g.mass_kg},
              {"volume_m3", g.volume_m3},
              {"inertia_diagonal_kg_m2", vec<Json>(g.inertia_diagonal)}};
}

}  // namespace telegrasp::tools::json_form
