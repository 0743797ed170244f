// Conversions between sim types and the DDS types of idl/: the server's one boundary between
// the two. Pure functions; round-trip tested in tests/server/conversions_test.cc.
#pragma once

#include "telegrasp/idl/eigen_conversions.h"
#include "telegrasp/idl/telegrasp.h"
#include "telegrasp/sim/hand_controller.h"
#include "telegrasp/sim/object_model.h"
#include "telegrasp/sim/world.h"

#include <Eigen/Geometry>

#include <cstdint>
#include <string>
#include <vector>

namespace telegrasp::server {

/// A hand on the wire: (client id, hand side).
struct HandAddress {
  std::string client_id;
  std::uint8_t side = 1;
  auto operator<=>(const HandAddress&) const = default;
};

/// Geometry: idl/include/telegrasp/idl/eigen_conversions.h, shared with the client library.
/// to_eigen(Pose3) expects a validated (finite, unit within 1e-3) quaternion.
using idl::to_eigen;
using idl::to_msg;

/// The sim input a (validated) controller state asks for.
sim::ControllerInput to_sim_input(const msg::ControllerState& state);

/// What a published hand sample says about the input it reflects.
struct InputStamp {
  std::uint64_t sequence = 0;
  std::int64_t client_time_ns = 0;
};

/// The hand's skeleton at its current state. With `X_WorldPalm_override` the palm (and every
/// phalanx with it) is re-posed there, fingers unchanged: the late-latched skeleton.
msg::HandSkeleton make_hand_skeleton(const HandAddress& address, const sim::HandController& hand, std::uint64_t tick,
                                     double time, const InputStamp& input, bool frozen,
                                     const Eigen::Isometry3d* X_WorldPalm_override = nullptr);
/// The hand's grasp state; while holding, with the last grasp quality the World delivered for
/// this grasp (that of its contacts quality_delay_ticks ticks ago; -1, -1, false until the first).
msg::GraspState make_grasp_state(const HandAddress& address, const sim::HandController& hand, std::uint64_t tick,
                                 double time);
/// Who holds an object, on the wire: `held`, the first holder in holder_client/holder_hand (the
/// fields older subscribers read) and every holder, in grasp order, in `holders`.
void set_holders(msg::ObjectState& object, const std::vector<HandAddress>& holders);

/// A held grasp's quality is republished when force closure flips or epsilon or volume move by
/// more than 5 % of the last published value or 1e-3, whichever is larger: smaller moves are
/// rounding from the hand's small motions, not a different grasp.
constexpr double kQualityRelativeChange = 0.05;
constexpr double kQualityAbsoluteChange = 1e-3;
bool quality_changed(const msg::GraspState& before, const msg::GraspState& now);
msg::ContactPoint to_msg(const sim::Contact& contact);
sim::Contact to_sim(const msg::ContactPoint& contact);
/// Contacts of the grasp `hand` holds, with the object's pose at this tick.
msg::ContactSet make_contact_set(const HandAddress& address, const sim::HandController& hand, std::uint64_t tick,
                                 double time, const Eigen::Isometry3d& X_WorldObject);

/// A sim grasp event with everything a subscriber needs to interpret it without the server.
struct EventContext {
  HandAddress hand;
  std::uint64_t event_id = 0;
  std::string object_name;
  double object_spawn_time = 0;
  Eigen::Isometry3d X_WorldObject = Eigen::Isometry3d::Identity();
  std::uint64_t input_sequence = 0;
};
msg::GraspEvent make_grasp_event(const sim::GraspEvent& event, const sim::HandRig& rig, const EventContext& context);
/// A grasp event's metrics: hand error, capsules, palm signed distance, epsilon, volume, force closure.
void set_metrics(msg::GraspEvent& message, const sim::GraspMetrics& metrics, const sim::HandRig& rig);

/// A model's shape and mass as published on the ObjectGeometry topic: its mesh in the model frame
/// (origin at the centre of mass) with vertices rounded to float32, the content hash of that
/// (idl/geometry_hash.h), bounds, mass, volume, inertia diagonal (kg m^2, model axes) and where the
/// source file's origin lies. A mesh of more than `max_triangles` triangles goes out without
/// vertices and triangles, `mesh_omitted` set; everything else, the hash included, is still given.
msg::ObjectGeometry make_object_geometry(const sim::ObjectModel& model,
                                         std::uint32_t max_triangles = msg::OBJECT_GEOMETRY_MAX_TRIANGLES);
/// The mesh a geometry message carries (vertices widened to double; empty if omitted). Expects a
/// message whose sequences hold whole vertices and triangles with indices in range.
sim::TriangleMesh to_sim_mesh(const msg::ObjectGeometry& geometry);

}  // namespace telegrasp::server
