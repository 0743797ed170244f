#include "wire_feed.h"

#include "conversions.h"

#include <utility>

namespace telegrasp::view {

using client_lib::from_msg;

void WireFeed::add(const msg::HandSkeleton& m) {
  client::HandSkeleton s = from_msg(m);
  skeletons_.insert_or_assign(s.hand, std::move(s));
}

void WireFeed::add(const msg::GraspState& m) {
  client::GraspState s = from_msg(m);
  grasp_states_.insert_or_assign(s.hand, std::move(s));
}

void WireFeed::add(const msg::ContactSet& m) {
  client::ContactSet s = from_msg(m);
  contact_sets_.insert_or_assign(s.hand, std::move(s));
}

void WireFeed::add(const msg::GraspEvent& m) { events_.push_back(from_msg(m)); }
void WireFeed::add(const msg::SceneState& m) { scene_ = from_msg(m); }
void WireFeed::add(const msg::ServerStatus& m) { status_ = from_msg(m); }

void WireFeed::hand_removed(const std::string& client_id, std::uint8_t side) {
  const client::HandKey hand{client_id, client_lib::from_msg_side(side)};
  skeletons_.erase(hand);
  grasp_states_.erase(hand);
  contact_sets_.erase(hand);
}

ClientSnapshot WireFeed::snapshot() {
  ClientSnapshot s;
  // As telegrasp-view polls: per-hand states of the hands that have a skeleton.
  for (const auto& [hand, skeleton] : skeletons_) {
    s.skeletons.push_back(skeleton);
    if (const auto g = grasp_states_.find(hand); g != grasp_states_.end()) s.grasp_states.emplace(hand, g->second);
    if (const auto c = contact_sets_.find(hand); c != contact_sets_.end()) s.contact_sets.emplace(hand, c->second);
  }
  s.scene = scene_;
  s.status = status_;
  s.events = std::exchange(events_, {});
  return s;
}

}  // namespace telegrasp::view
