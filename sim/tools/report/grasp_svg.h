// A picture of one grasp: three orthographic views of the object, the hand's capsules and contacts.
#pragma once

#include "telegrasp/sim/hand_controller.h"
#include "telegrasp/sim/object_model.h"

#include <Eigen/Geometry>

#include <string>
#include <vector>

namespace telegrasp::sim {

/// What a grasp picture shows, all in the world frame.
struct GraspSnapshot {
  std::string title;
  const ObjectModel* model = nullptr;
  Eigen::Isometry3d X_WorldObject = Eigen::Isometry3d::Identity();
  struct Capsule {
    Eigen::Vector3d a, b;
    double radius = 0;
    bool blocked = false;
  };
  std::vector<Capsule> capsules;
  std::vector<Eigen::Vector3d> contacts;
};

/// The capsules and contacts of `hand` as they are now, and the object it holds (or `object`).
GraspSnapshot snapshot(const HandController& hand, const ObjectView& object, const std::string& title);

/// Renders top (x-y), front (x-z) and side (y-z) views as a self-contained SVG document.
std::string render_svg(const GraspSnapshot& snap);

}  // namespace telegrasp::sim
