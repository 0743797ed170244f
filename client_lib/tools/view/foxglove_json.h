// Foxglove message JSON for telegrasp-view, built from telegrasp::client types: pure functions,
// no I/O. Field names follow the foxglove.* JSON schemas of the npm package @foxglove/schemas
// (SceneUpdate, FrameTransforms); the telegrasp.* messages are ours (schemas in view_schemas.h).
// Frames: "world"; "<client>/<side>/palm" (parent world); "<client>/<side>/<phalanx>" (parent palm);
// "object/<id>" (parent world). Units SI.
#pragma once

#include "telegrasp/client/types.h"

#include <nlohmann/json.hpp>

#include <cstdint>
#include <string>
#include <vector>

namespace telegrasp::view {

using Json = nlohmann::json;

/// An RGBA colour, components in [0, 1].
struct Rgba {
  double r = 0, g = 0, b = 0, a = 1;
  bool operator==(const Rgba&) const = default;
};

/// The colours of the scene (the page and the tests read them from the entities, not from here).
namespace colours {
inline constexpr Rgba kSkin{0.88, 0.69, 0.56, 1};  ///< A free phalanx, the palm.
inline constexpr Rgba kBlocked{0.84, 0.15, 0.16, 1};  ///< A blocked phalanx, palm contact.
inline constexpr Rgba kFreeObject{0.62, 0.64, 0.68, 1};  ///< An object nobody holds.
inline constexpr Rgba kContact{1.0, 0.85, 0.1, 1};  ///< Contact arrows.
/// A hand's identity colour (its palm sphere, and the object it holds), by palette index.
Rgba hand_colour(std::size_t index);
}  // namespace colours

/// Wall-clock nanoseconds as a foxglove time {"sec","nsec"}.
Json stamp(std::uint64_t ns);

Json pose(const Eigen::Isometry3d& X);
Json pose(const Eigen::Vector3d& p, const Eigen::Quaterniond& q);

/// Frame ids.
std::string palm_frame(const client::HandKey& hand);
std::string phalanx_frame(const client::HandKey& hand, const std::string& phalanx);
std::string object_frame(int object_id);
/// Entity ids: "hand/<client>/<side>" (palm), "hand/<client>/<side>/<phalanx>", "object/<id>",
/// "contacts/<client>/<side>".
std::string hand_entity_id(const client::HandKey& hand);
std::string phalanx_entity_id(const client::HandKey& hand, const std::string& phalanx);
std::string object_entity_id(int object_id);
std::string contacts_entity_id(const client::HandKey& hand);

/// An empty foxglove.SceneEntity (every primitive array present and empty), frame-locked.
Json scene_entity(const std::string& id, const std::string& frame_id, std::uint64_t stamp_ns);
/// Appends {"key","value"} to an entity's metadata.
void add_metadata(Json& entity, const std::string& key, const std::string& value);
void add_sphere(Json& entity, const Eigen::Vector3d& p_FrameCenter, double radius, const Rgba& colour);
void add_box(Json& entity, const Eigen::Isometry3d& X_FrameBox, const Eigen::Vector3d& size, const Rgba& colour);
/// A triangle list (foxglove TriangleListPrimitive): `points` in the entity's frame, three
/// `indices` per triangle.
void add_triangles(Json& entity, const std::vector<Eigen::Vector3d>& points, const std::vector<std::uint32_t>& indices,
                   const Rgba& colour);
/// A capsule from A to B of `radius`: a cylinder along A-B and a sphere at each end.
void add_capsule(Json& entity, const Eigen::Vector3d& p_FrameA, const Eigen::Vector3d& p_FrameB, double radius,
                 const Rgba& colour);
/// An arrow from `p_FrameTail` along the unit direction `d_Frame`, `length` long.
void add_arrow(Json& entity, const Eigen::Vector3d& p_FrameTail, const Eigen::Vector3d& d_Frame, double length,
               const Rgba& colour);
void add_text(Json& entity, const Eigen::Vector3d& p_FrameText, const std::string& text, const Rgba& colour);

/// A foxglove.SceneUpdate of `entities` and of deletions of the entity ids `deleted`.
Json scene_update(std::vector<Json> entities, const std::vector<std::string>& deleted, std::uint64_t stamp_ns);

/// One foxglove.FrameTransform: `child` in `parent` is X_ParentChild, its numbers rounded to
/// 1e-7 (0.1 um; a quaternion to 1e-7 per component) to keep /tf small.
Json frame_transform(const std::string& parent, const std::string& child, const Eigen::Isometry3d& X_ParentChild,
                     std::uint64_t stamp_ns);

/// The telegrasp.* JSON messages of /grasp_state, /grasp_events and /server_status. Poses as
/// {"p":[x,y,z],"q":[w,x,y,z]} like telegrasp-echo; NaN as null. `phalanx_names` names the
/// blocked flags (rig order); empty when the rig is unknown.
Json grasp_state_message(const client::GraspState& state, const std::vector<std::string>& phalanx_names);
Json grasp_event_message(const client::GraspEvent& event);
Json server_status_message(const client::ServerStatus& status);

}  // namespace telegrasp::view
