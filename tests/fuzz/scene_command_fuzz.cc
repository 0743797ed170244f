// Fuzzes what the server does with SceneCommand bytes from the network: the DDS type's CDR
// deserialization, the recording's from_cdr, then SceneServer::apply_command (its checks of
// the model, object id, table bounds and pose) and one tick, on a scene kept for the whole run.
#include "fuzz_common.h"
#include "input_mailbox.h"
#include "recording.h"
#include "scene_server.h"
#include "telegrasp/idl/safe_type.h"
#include "telegrasp/idl/telegraspPubSubTypes.h"
#include "telegrasp/sim/standin_objects.h"

#include <fastdds/rtps/common/SerializedPayload.h>

#include <cstring>
#include <memory>

namespace {

using namespace telegrasp;

struct NullSink : server::OutputSink {
  void publish(const msg::HandSkeleton&) override {}
  void publish(const msg::GraspState&) override {}
  void publish(const msg::ContactSet&) override {}
  void publish(const msg::GraspEvent&) override {}
  void publish(const msg::SceneState&) override {}
  void publish(const msg::ServerStatus&) override {}
  void hand_removed(const server::HandAddress&) override {}
};

/// The default scene: every stand-in in its grid (object ids 1..30 exist, resets respawn them).
struct Server {
  server::ServerSettings settings;
  std::shared_ptr<const sim::HandRig> right =
      std::make_shared<const sim::HandRig>(sim::HandRig::load(sim::HandRig::builtin_path("human_right")));
  std::shared_ptr<const sim::HandRig> left =
      std::make_shared<const sim::HandRig>(sim::HandRig::load(sim::HandRig::builtin_path("human_left")));
  server::InputMailbox mailbox{
      {left->fingers().size(), right->fingers().size()}, settings.max_hands, [](const std::string&) {}};
  NullSink sink;
  std::unique_ptr<server::SceneServer> scene;
  std::int64_t now_ns = 0;

  Server() {
    std::vector<sim::ObjectModelPtr> models;
    for (const auto& o : sim::protocol_objects()) models.push_back(sim::make_standin_model(o));
    scene = std::make_unique<server::SceneServer>(settings, models, right, left, mailbox, sink);
  }
};

Server* the_server = nullptr;

}  // namespace

// The scene is built before the first input (30 stand-ins take seconds under ASan: not a hang).
extern "C" int LLVMFuzzerInitialize(int*, char***) {
  fuzz::silence_cerr();
  the_server = new Server();
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static idl::SafeType<msg::SceneCommandPubSubType> type;  // as DdsParticipant registers it

  msg::SceneCommand from_recording;  // replay decodes recorded commands with from_cdr
  (void)server::from_cdr(std::string(reinterpret_cast<const char*>(data), size), from_recording);

  eprosima::fastrtps::rtps::SerializedPayload_t payload(static_cast<std::uint32_t>(size));
  if (size > 0) std::memcpy(payload.data, data, size);
  payload.length = static_cast<std::uint32_t>(size);
  msg::SceneCommand command;
  if (!type.deserialize(&payload, &command)) return 0;
  (void)the_server->scene->apply_command(command);
  the_server->now_ns += 11'111'111;
  the_server->scene->tick(the_server->now_ns);
  return 0;
}
