// Fuzzes what the server does with ControllerState bytes from the network: the DDS type's CDR
// deserialization (the reader's path), the recording's from_cdr, the mailbox's validation and
// per-hand history, then the accepted samples into a SceneServer (to_sim_input, the hands) and
// one simulation tick.
#include "fuzz_common.h"
#include "fuzz_server.h"
#include "telegrasp/idl/telegraspPubSubTypes.h"

namespace {

using namespace telegrasp;
using fuzz::the_server;

}  // namespace

// One server for the whole run: an empty table with two stand-ins, at most 4 hands (the state a
// long run builds up, hands joining, freezing and leaving, is part of what is fuzzed).
extern "C" int LLVMFuzzerInitialize(int*, char***) {
  server::ServerSettings settings;
  settings.max_hands = 4;
  settings.objects = {{"056_tennis_ball", 0.3, 0.0, 0.0, {}}, {"013_apple", 0.5, 0.1, 1.0, {}}};
  fuzz::start_server(settings);
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  msg::ControllerState state;
  if (!fuzz::decode<msg::ControllerStatePubSubType>(data, size, state)) return 0;

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
