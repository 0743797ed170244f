#include "step_messages.h"

#include "channels.h"

namespace telegrasp::view {

std::shared_ptr<const std::string> payload(const Json& message) {
  return std::make_shared<const std::string>(message.dump());
}

std::vector<StepMessage> step_messages(const ViewUpdate& update) {
  std::vector<StepMessage> out;
  if (update.scene) out.push_back({kSceneChannel, payload(*update.scene)});
  if (update.transforms) out.push_back({kTransformsChannel, payload(*update.transforms)});
  for (const Json& s : update.grasp_states) out.push_back({kGraspStateChannel, payload(s)});
  for (const Json& e : update.grasp_events) out.push_back({kGraspEventsChannel, payload(e)});
  if (update.server_status) out.push_back({kServerStatusChannel, payload(*update.server_status)});
  return out;
}

}  // namespace telegrasp::view
