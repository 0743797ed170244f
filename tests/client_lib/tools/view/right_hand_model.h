// What telegrasp-view's model tests share: a ViewModel that knows one rig, the shipped right hand,
// and a skeleton of that hand with its palm at (0.4, 0, 0.2) (its phalanges are each test's).
#pragma once

#include "view_model.h"

#include "telegrasp/sim/hand_rig.h"

#include <gtest/gtest.h>

#include <memory>

namespace telegrasp::view {

class RightHandModelTest : public ::testing::Test {
 protected:
  RightHandModelTest()
      : rig_(std::make_unique<sim::HandRig>(sim::HandRig::load(sim::HandRig::builtin_path("human_right")))),
        model_([this](const std::string& name) { return name == "human_right" ? rig_.get() : nullptr; }) {
    skeleton_.hand = {"c1", client::HandSide::kRight};
    skeleton_.rig = "human_right";
    skeleton_.X_WorldPalm.translation() = Eigen::Vector3d(0.4, 0, 0.2);
  }

  std::unique_ptr<sim::HandRig> rig_;
  ViewModel model_;
  client::HandSkeleton skeleton_;
};

}  // namespace telegrasp::view
