#include "channels.h"

#include <nlohmann/json.hpp>

#include <fstream>
#include <sstream>
#include <stdexcept>

namespace telegrasp::view {
namespace {

using Json = nlohmann::json;

std::string read_schema(const std::filesystem::path& dir, const std::string& name) {
  const std::filesystem::path path = dir / (name + ".json");
  std::ifstream in(path);
  std::stringstream text;
  if (in) text << in.rdbuf();
  const Json schema = Json::parse(text.str(), nullptr, false);
  if (!in || schema.is_discarded() || !schema.is_object())
    throw std::runtime_error(path.string() + ": missing or not a JSON schema (the build generates it from the npm " +
                             "package @foxglove/schemas: run deploy/install-deps.sh, then build again)");
  return schema.dump();
}

Json number() { return Json{{"type", "number"}}; }
Json integer() { return Json{{"type", "integer"}}; }
Json string() { return Json{{"type", "string"}}; }
Json boolean() { return Json{{"type", "boolean"}}; }
Json array_of(Json items) { return Json{{"type", "array"}, {"items", std::move(items)}}; }
Json object(const std::string& title, Json properties) {
  return Json{{"title", title}, {"type", "object"}, {"properties", std::move(properties)}};
}
Json hand() { return object("telegrasp.HandKey", {{"client_id", string()}, {"side", string()}}); }
Json vec3() { return array_of(number()); }
Json echo_pose() { return object("telegrasp.Pose", {{"p_m", vec3()}, {"q_wxyz", array_of(number())}}); }

// Field names and meanings as in client_lib/include/telegrasp/client/types.h, with the unit of
// every quantity appended as telegrasp-echo writes them.
Json grasp_state_schema() {
  Json s =
      object("telegrasp.GraspState",
             {{"hand", hand()},
              {"tick", integer()},
              {"time_s", number()},
              {"selected_object", integer()},
              {"grasped_object", integer()},
              {"trigger", number()},
              {"palm_contact", boolean()},
              {"epsilon", number()},
              {"volume", number()},
              {"force_closure", boolean()},
              {"grasp_type", string()},
              {"phalanges", array_of(object("telegrasp.PhalanxState", {{"name", string()}, {"blocked", boolean()}}))}});
  s["description"] = "A hand's grasp state, sent when it changes (GraspState topic); -1: no object";
  return s;
}

// nd_midlength_mm: the paper's ND (nd_mm: its alias for one release); nd_contact_mm: ND toward the
// contact (blocked capsules).
Json capsule_schema() {
  const Json nullable = Json{{"type", {"number", "null"}}};
  return object("telegrasp.CapsuleMetric", {{"phalanx", integer()},
                                            {"phalanx_name", string()},
                                            {"hit", boolean()},
                                            {"nd_midlength_mm", nullable},
                                            {"nd_mm", nullable},
                                            {"contact_hit", boolean()},
                                            {"nd_contact_mm", nullable},
                                            {"signed_distance_mm", number()},
                                            {"blocked", boolean()}});
}

Json grasp_event_schema() {
  Json s =
      object("telegrasp.GraspEvent",
             {{"event_id", integer()},
              {"kind", Json{{"type", "string"}, {"enum", {"grasp", "release"}}}},
              {"hand", hand()},
              {"object_id", integer()},
              {"object_name", string()},
              {"tick", integer()},
              {"time_s", number()},
              {"object_spawn_time_s", number()},
              {"X_WorldObject", echo_pose()},
              {"input_sequence", integer()},
              {"hand_error_mm", number()},
              {"capsules_without_hit", integer()},
              {"palm_signed_distance_mm", number()},
              {"epsilon", number()},
              {"volume", number()},
              {"force_closure", boolean()},
              {"grasp_type", string()},
              {"capsules", array_of(capsule_schema())},
              {"contacts", array_of(object("telegrasp.ContactPoint", {{"phalanx", integer()},
                                                                      {"p_WorldContact_m", vec3()},
                                                                      {"n_World", vec3()},
                                                                      {"p_ObjectContact_m", vec3()},
                                                                      {"n_Object", vec3()},
                                                                      {"nd_mm", Json{{"type", {"number", "null"}}}},
                                                                      {"nd_hit", boolean()}}))},
              {"v_WorldObject_m_per_s", vec3()},
              {"w_WorldObject_rad_per_s", vec3()}});
  s["description"] =
      "A grasp or release (GraspEvent topic); grasps carry the paper's metrics (nd_midlength_mm null: "
      "no hit), nd_contact_mm, the palm's signed distance and the grasp quality";
  return s;
}

Json server_status_schema() {
  Json s =
      object("telegrasp.ServerStatus", {{"tick", integer()},
                                        {"time_s", number()},
                                        {"tick_rate_hz", number()},
                                        {"clients", integer()},
                                        {"hands", integer()},
                                        {"objects", integer()},
                                        {"tick_us_p50", number()},
                                        {"tick_us_p99", number()},
                                        {"tick_us_max", number()},
                                        {"missed_ticks", integer()},
                                        {"inputs_accepted", integer()},
                                        {"inputs_rejected", integer()},
                                        {"rejected", Json{{"type", "object"}, {"additionalProperties", integer()}}},
                                        {"commands_accepted", integer()},
                                        {"commands_rejected", integer()},
                                        {"models", array_of(string())}});
  s["description"] = "The server's status, once a second (ServerStatus topic)";
  return s;
}

Json pose_schema() {
  return object("telegrasp.PoseJson",
                {{"position", object("telegrasp.Vector3", {{"x", number()}, {"y", number()}, {"z", number()}})},
                 {"orientation",
                  object("telegrasp.Quaternion", {{"x", number()}, {"y", number()}, {"z", number()}, {"w", number()}})}});
}

// Field meanings as HandSkeleton in client_lib/include/telegrasp/client/types.h; input_seq and
// input_stamp are the page's own for the newest sample the skeleton reflects (null: a sample the
// bridge sent itself, or one no longer remembered).
Json driven_hand_schema() {
  Json s = object("telegrasp.DrivenHand", {{"client_id", string()},
                                           {"side", string()},
                                           {"rig", string()},
                                           {"tick", integer()},
                                           {"input_seq", Json{{"type", {"integer", "null"}}}},
                                           {"input_stamp", Json{{"type", {"object", "null"}}}},
                                           {"late_latched", boolean()},
                                           {"frozen", boolean()},
                                           {"palm", pose_schema()},
                                           {"tracked_palm", pose_schema()},
                                           {"resolve_offset_m", vec3()},
                                           {"resolve_angle_rad", number()},
                                           {"phalanges", array_of(pose_schema())},
                                           {"phalanx_names", array_of(string())},
                                           {"joint_angles_rad", array_of(number())}});
  s["description"] =
      "A hand this connection drives, as the server resolved it (HandSkeleton topic), sent as it arrives";
  return s;
}

}  // namespace

Channel driven_hands_channel() {
  return {kDrivenHandsChannel, "/xr/hands", "telegrasp.DrivenHand", driven_hand_schema().dump(), true};
}

std::vector<Channel> view_channels(const std::filesystem::path& schema_dir) {
  return {
      {kSceneChannel, "/scene", "foxglove.SceneUpdate", read_schema(schema_dir, "foxglove.SceneUpdate"), false},
      {kTransformsChannel, "/tf", "foxglove.FrameTransforms", read_schema(schema_dir, "foxglove.FrameTransforms"),
       true},
      {kGraspStateChannel, "/grasp_state", "telegrasp.GraspState", grasp_state_schema().dump(), false},
      {kGraspEventsChannel, "/grasp_events", "telegrasp.GraspEvent", grasp_event_schema().dump(), false},
      {kServerStatusChannel, "/server_status", "telegrasp.ServerStatus", server_status_schema().dump(), true},
  };
}

}  // namespace telegrasp::view
