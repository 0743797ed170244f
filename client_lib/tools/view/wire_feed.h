// WireFeed: the view model's input built from wire (IDL, telegrasp::msg) samples instead of a
// live client, for telegrasp-replay --export-mcap, which reads a server recording. It keeps what
// telegrasp::client keeps for a poll, converted by the client library's own conversions
// (client_lib/src/conversions.h): the newest skeleton, grasp state and contact set per hand, all
// three forgotten when the server disposes the hand; the newest scene state and server status;
// every grasp event since the last snapshot.
#pragma once

#include "telegrasp/idl/telegrasp.h"
#include "view_model.h"

#include <map>
#include <optional>
#include <string>
#include <vector>

namespace telegrasp::view {

class WireFeed {
 public:
  void add(const msg::HandSkeleton& m);
  void add(const msg::GraspState& m);
  void add(const msg::ContactSet& m);
  void add(const msg::GraspEvent& m);
  void add(const msg::SceneState& m);
  void add(const msg::ServerStatus& m);
  /// The server disposed the hand (`side` as on the wire: HAND_LEFT, HAND_RIGHT).
  void hand_removed(const std::string& client_id, std::uint8_t side);

  /// What telegrasp-view's poll of the client would return now: skeletons in hand order, the
  /// grasp state and contact set of each hand with a skeleton; the grasp events are handed over once.
  ClientSnapshot snapshot();

 private:
  std::map<client::HandKey, client::HandSkeleton> skeletons_;
  std::map<client::HandKey, client::GraspState> grasp_states_;
  std::map<client::HandKey, client::ContactSet> contact_sets_;
  std::optional<client::SceneState> scene_;
  std::optional<client::ServerStatus> status_;
  std::vector<client::GraspEvent> events_;
};

}  // namespace telegrasp::view
