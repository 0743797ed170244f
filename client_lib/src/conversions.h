// The one boundary between the client types (types.h, Eigen/std) and the wire types
// (telegrasp.idl, module telegrasp::msg): pure functions, both directions for every type.
//
// Client -> wire keeps every value as given, valid or not (NaN, non-unit rotations, out-of-range
// triggers, unknown hand sides): the server validates, and its tests send bad input through here.
// Wire -> client normalizes quaternions, so a received pose is always an isometry (or NaN).
#pragma once

#include "telegrasp/client/types.h"
#include "telegrasp/idl/telegrasp.h"

#include <cstdint>
#include <string>

namespace telegrasp::client_lib {

namespace msg = telegrasp::msg;

/// A vector as an IDL Vec3 (x, y, z).
msg::Vec3 to_msg(const Eigen::Vector3d& v);
/// An IDL Vec3 as a vector.
Eigen::Vector3d from_msg(const msg::Vec3& v);

/// X_AB as an IDL Pose3: position p_AB, orientation (w, x, y, z) of R_AB, not normalized.
msg::Pose3 to_msg(const Eigen::Isometry3d& X_AB);
/// An IDL Pose3 as X_AB; the quaternion is normalized first.
Eigen::Isometry3d from_msg(const msg::Pose3& pose);

/// A hand side as the IDL octet (HAND_LEFT, HAND_RIGHT; any other value unchanged).
std::uint8_t to_msg_side(client::HandSide side);
/// An IDL hand-side octet as a HandSide (an unknown value stays that value).
client::HandSide from_msg_side(std::uint8_t side);

/// A controller sample of `client_id`'s hand as the IDL ControllerState, every field as given.
msg::ControllerState to_msg(const client::ControllerSample& sample, const std::string& client_id);
/// An IDL ControllerState as a sample (its client id is the message's client_id()).
client::ControllerSample from_msg(const msg::ControllerState& state);

/// A hand skeleton as the IDL message.
msg::HandSkeleton to_msg(const client::HandSkeleton& skeleton);
/// An IDL hand skeleton as the client type.
client::HandSkeleton from_msg(const msg::HandSkeleton& skeleton);

/// A grasp state as the IDL message.
msg::GraspState to_msg(const client::GraspState& state);
/// An IDL grasp state as the client type.
client::GraspState from_msg(const msg::GraspState& state);

/// A contact point as the IDL message (phalanx as a short).
msg::ContactPoint to_msg(const client::ContactPoint& contact);
/// An IDL contact point as the client type.
client::ContactPoint from_msg(const msg::ContactPoint& contact);

/// A contact set as the IDL message.
msg::ContactSet to_msg(const client::ContactSet& contacts);
/// An IDL contact set as the client type.
client::ContactSet from_msg(const msg::ContactSet& contacts);

/// A capsule report as the IDL message.
msg::CapsuleReport to_msg(const client::CapsuleMetric& report);
/// An IDL capsule report as the client type.
client::CapsuleMetric from_msg(const msg::CapsuleReport& report);

/// A grasp event kind as the IDL enum.
msg::GraspEventKind to_msg(client::GraspEvent::Kind kind);
/// An IDL grasp event kind as the client enum.
client::GraspEvent::Kind from_msg(msg::GraspEventKind kind);

/// A grasp event as the IDL message.
msg::GraspEvent to_msg(const client::GraspEvent& event);
/// An IDL grasp event as the client type.
client::GraspEvent from_msg(const msg::GraspEvent& event);

/// An object state as the IDL message.
msg::ObjectState to_msg(const client::ObjectState& object);
/// An IDL object state as the client type (holder is set whatever `held` says).
client::ObjectState from_msg(const msg::ObjectState& object);

/// A scene state as the IDL message.
msg::SceneState to_msg(const client::SceneState& scene);
/// An IDL scene state as the client type.
client::SceneState from_msg(const msg::SceneState& scene);

/// A scene command kind as the IDL enum.
msg::SceneCommandKind to_msg(client::SceneCommand::Kind kind);
/// An IDL scene command kind as the client enum.
client::SceneCommand::Kind from_msg(msg::SceneCommandKind kind);

/// A scene command from `client_id`, numbered `command_id`, as the IDL message.
msg::SceneCommand to_msg(const client::SceneCommand& command, const std::string& client_id, std::uint64_t command_id);
/// An IDL scene command as the client type (client and command id are the message's).
client::SceneCommand from_msg(const msg::SceneCommand& command);

/// A server status as the IDL message (rejections in reason order).
msg::ServerStatus to_msg(const client::ServerStatus& status);
/// An IDL server status as the client type.
client::ServerStatus from_msg(const msg::ServerStatus& status);
/// A refusal notice as the client type.
client::Notice from_msg(const msg::ClientNotice& notice);
client::SceneInfo from_msg(const msg::SceneAnnouncement& announcement);

/// An object geometry as the IDL message (vertices and triangles flattened, every field as given).
msg::ObjectGeometry to_msg(const client::ObjectGeometry& geometry);
/// An IDL object geometry as the client type (trailing partial vertices or triangles dropped; see
/// check_object_geometry).
client::ObjectGeometry from_msg(const msg::ObjectGeometry& geometry);
/// Everything of an IDL object geometry but its vertices and triangles (left empty).
client::ObjectGeometry from_msg_without_mesh(const msg::ObjectGeometry& geometry);
/// "" if a received geometry is whole and intact, else why not: sequence lengths that disagree with
/// the counts (or a mesh both omitted and sent), a non-finite coordinate, a triangle index past the
/// vertices, or a content hash that does not match the mesh.
std::string check_object_geometry(const msg::ObjectGeometry& geometry);

}  // namespace telegrasp::client_lib
