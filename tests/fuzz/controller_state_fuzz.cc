// Fuzzes what the server does with ControllerState bytes from the network: the DDS type's CDR
// deserialization (the reader's path), the recording's from_cdr, the mailbox's validation and
// per-hand history, then the accepted samples into a SceneServer (to_sim_input, the hands) and
// one simulation tick.
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

/// One server for the whole run: an empty table with two stand-ins, at most 4 hands (the state a
/// long run builds up, hands joining, freezing and leaving, is part of what is fuzzed).
struct Server {
  server::ServerSettings settings = [] {
    server::ServerSettings s;
    s.max_hands = 4;
    s.objects = {{"056_tennis_ball", 0.3, 0.0, 0.0, {}}, {"013_apple", 0.5, 0.1, 1.0, {}}};
    return s;
  }();
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
  static idl::SafeType<msg::ControllerStatePubSubType> type;  // as DdsParticipant registers it

  // The recording's decoder (replay reads recorded samples with it).
  msg::ControllerState from_recording;
  (void)server::from_cdr(std::string(reinterpret_cast<const char*>(data), size), from_recording);

  eprosima::fastrtps::rtps::SerializedPayload_t payload(static_cast<std::uint32_t>(size));
  if (size > 0) std::memcpy(payload.data, data, size);
  payload.length = static_cast<std::uint32_t>(size);
  msg::ControllerState state;
  if (!type.deserialize(&payload, &state)) return 0;

  // Two participants, chosen by the sequence number's low bit: client ids owned by another
  // participant are part of the validation.
  server::ParticipantKey writer{};
  writer[0] = static_cast<std::uint8_t>(1 + (state.sequence_number() & 1));
  the_server->now_ns += 11'111'111;
  the_server->mailbox.offer(state, writer, the_server->now_ns);
  the_server->scene->on_inputs(the_server->mailbox.drain(), the_server->now_ns);
  the_server->scene->tick(the_server->now_ns);
  return 0;
}
