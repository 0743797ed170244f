#include "foxglove_json.h"

#include "client_json.h"

#include <array>
#include <cmath>

namespace telegrasp::view {
namespace {

Json vec3(const Eigen::Vector3d& v) { return Json{{"x", v.x()}, {"y", v.y()}, {"z", v.z()}}; }

Json colour(const Rgba& c) { return Json{{"r", c.r}, {"g", c.g}, {"b", c.b}, {"a", c.a}}; }

std::string hand_prefix(const client::HandKey& hand) { return hand.client_id + "/" + client::to_string(hand.side); }

}  // namespace

Rgba colours::hand_colour(std::size_t index) {
  // Distinct from skin, blocked red and the grey of free objects.
  static constexpr std::array<Rgba, 6> kPalette = {{
      {0.12, 0.47, 0.71, 1},  // blue
      {0.17, 0.63, 0.17, 1},  // green
      {0.58, 0.40, 0.74, 1},  // purple
      {0.09, 0.75, 0.81, 1},  // cyan
      {0.74, 0.74, 0.13, 1},  // olive
      {0.89, 0.47, 0.76, 1},  // pink
  }};
  return kPalette[index % kPalette.size()];
}

Json stamp(std::uint64_t ns) { return Json{{"sec", ns / 1'000'000'000u}, {"nsec", ns % 1'000'000'000u}}; }

Json pose(const Eigen::Vector3d& p, const Eigen::Quaterniond& q) {
  return Json{{"position", vec3(p)}, {"orientation", Json{{"x", q.x()}, {"y", q.y()}, {"z", q.z()}, {"w", q.w()}}}};
}

Json pose(const Eigen::Isometry3d& X) { return pose(X.translation(), Eigen::Quaterniond(X.linear())); }

std::string palm_frame(const client::HandKey& hand) { return hand_prefix(hand) + "/palm"; }
std::string phalanx_frame(const client::HandKey& hand, const std::string& phalanx) {
  return hand_prefix(hand) + "/" + phalanx;
}
std::string object_frame(int object_id) { return "object/" + std::to_string(object_id); }
std::string hand_entity_id(const client::HandKey& hand) { return "hand/" + hand_prefix(hand); }
std::string phalanx_entity_id(const client::HandKey& hand, const std::string& phalanx) {
  return "hand/" + hand_prefix(hand) + "/" + phalanx;
}
std::string object_entity_id(int object_id) { return "object/" + std::to_string(object_id); }
std::string contacts_entity_id(const client::HandKey& hand) { return "contacts/" + hand_prefix(hand); }

Json scene_entity(const std::string& id, const std::string& frame_id, std::uint64_t stamp_ns) {
  Json e{{"timestamp", stamp(stamp_ns)},
         {"frame_id", frame_id},
         {"id", id},
         {"lifetime", Json{{"sec", 0}, {"nsec", 0}}},  // until replaced or deleted
         {"frame_locked", true},  // moves with its frame's transforms
         {"metadata", Json::array()}};
  for (const char* kind : {"arrows", "cubes", "spheres", "cylinders", "lines", "triangles", "texts", "models"})
    e[kind] = Json::array();
  return e;
}

void add_metadata(Json& entity, const std::string& key, const std::string& value) {
  entity["metadata"].push_back(Json{{"key", key}, {"value", value}});
}

void add_sphere(Json& entity, const Eigen::Vector3d& p_FrameCenter, double radius, const Rgba& c) {
  const double d = 2 * radius;
  entity["spheres"].push_back(Json{{"pose", pose(p_FrameCenter, Eigen::Quaterniond::Identity())},
                                   {"size", vec3(Eigen::Vector3d(d, d, d))},
                                   {"color", colour(c)}});
}

void add_box(Json& entity, const Eigen::Isometry3d& X_FrameBox, const Eigen::Vector3d& size, const Rgba& c) {
  entity["cubes"].push_back(Json{{"pose", pose(X_FrameBox)}, {"size", vec3(size)}, {"color", colour(c)}});
}

void add_triangles(Json& entity, const std::vector<Eigen::Vector3d>& points, const std::vector<std::uint32_t>& indices,
                   const Rgba& c) {
  // Points to 0.01 mm: a mesh's JSON is most of what a viewer receives when it connects.
  auto r = [](double v) { return std::round(v * 1e5) / 1e5; };
  Json ps = Json::array();
  for (const Eigen::Vector3d& p : points) ps.push_back(Json{{"x", r(p.x())}, {"y", r(p.y())}, {"z", r(p.z())}});
  entity["triangles"].push_back(Json{{"pose", pose(Eigen::Isometry3d::Identity())},
                                     {"points", std::move(ps)},
                                     {"color", colour(c)},
                                     {"colors", Json::array()},
                                     {"indices", indices}});
}

void add_capsule(Json& entity, const Eigen::Vector3d& p_FrameA, const Eigen::Vector3d& p_FrameB, double radius,
                 const Rgba& c) {
  const Eigen::Vector3d ab = p_FrameB - p_FrameA;
  const double length = ab.norm();
  if (length > 1e-9) {
    // A foxglove cylinder's axis is its local z.
    const Eigen::Quaterniond q = Eigen::Quaterniond::FromTwoVectors(Eigen::Vector3d::UnitZ(), ab / length);
    entity["cylinders"].push_back(Json{{"pose", pose(0.5 * (p_FrameA + p_FrameB), q)},
                                       {"size", vec3(Eigen::Vector3d(2 * radius, 2 * radius, length))},
                                       {"bottom_scale", 1.0},
                                       {"top_scale", 1.0},
                                       {"color", colour(c)}});
  }
  add_sphere(entity, p_FrameA, radius, c);
  add_sphere(entity, p_FrameB, radius, c);
}

void add_arrow(Json& entity, const Eigen::Vector3d& p_FrameTail, const Eigen::Vector3d& d_Frame, double length,
               const Rgba& c) {
  // A foxglove arrow points along its local +x.
  const Eigen::Vector3d d = d_Frame.norm() > 1e-12 ? Eigen::Vector3d(d_Frame.normalized()) : Eigen::Vector3d::UnitZ();
  const double head = 0.3 * length;
  entity["arrows"].push_back(
      Json{{"pose", pose(p_FrameTail, Eigen::Quaterniond::FromTwoVectors(Eigen::Vector3d::UnitX(), d))},
           {"shaft_length", length - head},
           {"shaft_diameter", 0.08 * length},
           {"head_length", head},
           {"head_diameter", 0.22 * length},
           {"color", colour(c)}});
}

void add_text(Json& entity, const Eigen::Vector3d& p_FrameText, const std::string& text, const Rgba& c) {
  entity["texts"].push_back(Json{{"pose", pose(p_FrameText, Eigen::Quaterniond::Identity())},
                                 {"billboard", true},
                                 {"font_size", 12.0},
                                 {"scale_invariant", true},
                                 {"color", colour(c)},
                                 {"text", text}});
}

Json scene_update(std::vector<Json> entities, const std::vector<std::string>& deleted, std::uint64_t stamp_ns) {
  Json deletions = Json::array();
  for (const std::string& id : deleted)
    deletions.push_back(Json{{"timestamp", stamp(stamp_ns)}, {"type", 0}, {"id", id}});  // MATCHING_ID
  return Json{{"deletions", std::move(deletions)}, {"entities", std::move(entities)}};
}

Json frame_transform(const std::string& parent, const std::string& child, const Eigen::Isometry3d& X_ParentChild,
                     std::uint64_t stamp_ns) {
  const auto r = [](double v) { return std::round(v * 1e7) / 1e7; };  // prints as at most ~9 digits
  const Eigen::Quaterniond q(X_ParentChild.linear());
  const Eigen::Vector3d& p = X_ParentChild.translation();
  return Json{{"timestamp", stamp(stamp_ns)},
              {"parent_frame_id", parent},
              {"child_frame_id", child},
              {"translation", Json{{"x", r(p.x())}, {"y", r(p.y())}, {"z", r(p.z())}}},
              {"rotation", Json{{"x", r(q.x())}, {"y", r(q.y())}, {"z", r(q.z())}, {"w", r(q.w())}}}};
}

Json grasp_state_message(const client::GraspState& s, const std::vector<std::string>& phalanx_names) {
  Json phalanges = Json::array();
  for (std::size_t i = 0; i < s.blocked.size(); ++i)
    phalanges.push_back(Json{{"name", i < phalanx_names.size() ? phalanx_names[i] : "phalanx " + std::to_string(i)},
                             {"blocked", static_cast<bool>(s.blocked[i])}});
  return Json{{"hand", tools::json_form::hand<Json>(s.hand)},
              {"tick", s.tick},
              {"time_s", s.time},
              {"selected_object", s.selected_object},
              {"grasped_object", s.grasped_object},
              {"trigger", s.trigger},
              {"palm_contact", s.palm_contact},
              {"epsilon", s.epsilon},
              {"volume", s.volume},
              {"force_closure", s.force_closure},
              {"grasp_type", s.grasp_type},
              {"phalanges", std::move(phalanges)}};
}

Json grasp_event_message(const client::GraspEvent& e) { return tools::json_form::grasp_event<Json>(e); }

Json server_status_message(const client::ServerStatus& s) { return tools::json_form::server_status<Json>(s); }

}  // namespace telegrasp::view
