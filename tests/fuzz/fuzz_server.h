// What the harnesses of the server's network inputs (controller-state, scene-command) share: a
// SceneServer kept for the whole run, with nowhere to publish, and the two decoders bytes from the
// network meet.
#pragma once

#include "fuzz_common.h"
#include "input_mailbox.h"
#include "recording.h"
#include "scene_server.h"
#include "telegrasp/idl/safe_type.h"
#include "telegrasp/sim/standin_objects.h"

#include <fastdds/rtps/common/SerializedPayload.h>

#include <cstring>
#include <memory>
#include <string>

namespace telegrasp::fuzz {

struct NullSink : server::OutputSink {
  void publish(const msg::HandSkeleton&) override {}
  void publish(const msg::GraspState&) override {}
  void publish(const msg::ContactSet&) override {}
  void publish(const msg::GraspEvent&) override {}
  void publish(const msg::SceneState&) override {}
  void publish(const msg::ServerStatus&) override {}
  void hand_removed(const server::HandAddress&) override {}
};

/// A SceneServer over the 30 stand-in models with the built-in human rigs, scene and limits from
/// `settings`; `now_ns` is the harness's clock.
struct FuzzServer {
  explicit FuzzServer(server::ServerSettings s) : settings(std::move(s)) {
    std::vector<sim::ObjectModelPtr> models;
    for (const auto& o : sim::protocol_objects()) models.push_back(sim::make_standin_model(o));
    scene = std::make_unique<server::SceneServer>(settings, models, right, left, mailbox, sink);
  }

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
};

/// The one server of a harness, kept for the whole run (the state a long run builds up is part of
/// what is fuzzed); made by start_server.
inline FuzzServer* the_server = nullptr;

/// Silences std::cerr and makes the_server from `settings`. Called from LLVMFuzzerInitialize, so
/// the scene is built before the first input (30 stand-ins take seconds under ASan: not a hang).
inline void start_server(server::ServerSettings settings) {
  silence_cerr();
  the_server = new FuzzServer(std::move(settings));
}

/// Decodes `data` on both paths bytes of type PubSubType::type take into the server: the
/// recording's from_cdr (replay; its result is not used further) and the DDS type's
/// deserialization as DdsParticipant registers it. True when the latter gives `sample`.
template <class PubSubType>
bool decode(const std::uint8_t* data, std::size_t size, typename PubSubType::type& sample) {
  static idl::SafeType<PubSubType> type;
  typename PubSubType::type from_recording;
  (void)server::from_cdr(std::string(reinterpret_cast<const char*>(data), size), from_recording);
  eprosima::fastrtps::rtps::SerializedPayload_t payload(static_cast<std::uint32_t>(size));
  if (size > 0) std::memcpy(payload.data, data, size);
  payload.length = static_cast<std::uint32_t>(size);
  return type.deserialize(&payload, &sample);
}

}  // namespace telegrasp::fuzz
