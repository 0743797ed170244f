// Fuzzes what the server does with SceneCommand bytes from the network: the DDS type's CDR
// deserialization, the recording's from_cdr, then SceneServer::apply_command (its checks of
// the model, object id, table bounds and pose) and one tick, on a scene kept for the whole run.
#include "fuzz_common.h"
#include "fuzz_server.h"
#include "telegrasp/idl/telegraspPubSubTypes.h"

namespace {

using namespace telegrasp;
using fuzz::the_server;

}  // namespace

// The default scene: every stand-in in its grid (object ids 1..30 exist, resets respawn them).
extern "C" int LLVMFuzzerInitialize(int*, char***) {
  fuzz::start_server(server::ServerSettings{});
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  msg::SceneCommand command;
  if (!fuzz::decode<msg::SceneCommandPubSubType>(data, size, command)) return 0;
  (void)the_server->scene->apply_command(command);
  the_server->now_ns += 11'111'111;
  the_server->scene->tick(the_server->now_ns);
  return 0;
}
