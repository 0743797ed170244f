// ObjectView: a dynamic object as the grasp system sees it on one tick.
#pragma once

#include "telegrasp/sim/ids.h"
#include "telegrasp/sim/object_model.h"

#include <Eigen/Geometry>

namespace telegrasp::sim {

/// A dynamic object as the grasp system sees it this tick.
struct ObjectView {
  ObjectId id;
  Eigen::Isometry3d X_WorldObject = Eigen::Isometry3d::Identity();
  const ObjectModel* model = nullptr;
};

}  // namespace telegrasp::sim
