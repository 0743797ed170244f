// The hand rigs and objects several server tests build scenes from, and a check of the scene they
// publish.
#pragma once

#include "conversions.h"
#include "telegrasp/sim/hand_rig.h"
#include "telegrasp/sim/object_model.h"
#include "telegrasp/sim/standin_objects.h"

#include <gtest/gtest.h>

#include <cstddef>
#include <memory>
#include <string>
#include <utility>
#include <vector>

namespace telegrasp::server {

/// Every protocol object's stand-in model, in protocol order.
inline std::vector<sim::ObjectModelPtr> standins() {
  std::vector<sim::ObjectModelPtr> out;
  for (const auto& o : sim::protocol_objects()) out.push_back(sim::make_standin_model(o));
  return out;
}

/// The built-in rig `name` (e.g. "human_right").
inline std::shared_ptr<const sim::HandRig> rig(const char* name) {
  return std::make_shared<const sim::HandRig>(sim::HandRig::load(sim::HandRig::builtin_path(name)));
}

/// Expects `o` held by the hands `holders` (client id, hand side) in grasp order, the first also in
/// the old holder fields.
inline void expect_held_by(const msg::ObjectState& o, const std::vector<std::pair<std::string, int>>& holders) {
  EXPECT_TRUE(o.held());
  EXPECT_EQ(o.holder_client().to_string(), holders.at(0).first);
  EXPECT_EQ(o.holder_hand(), holders.at(0).second);
  ASSERT_EQ(o.holders().size(), holders.size());
  for (std::size_t i = 0; i < holders.size(); ++i) {
    EXPECT_EQ(o.holders()[i].client_id().to_string(), holders[i].first);
    EXPECT_EQ(o.holders()[i].hand_side(), holders[i].second);
  }
}

}  // namespace telegrasp::server
