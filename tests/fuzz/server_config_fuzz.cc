// Fuzzes the server configuration file (server/proto/server_config.proto in protobuf text):
// load_server_config (read, parse, apply) and validate_settings, as telegrasp-server does at
// start-up; valid settings are also turned back into a message and re-read (a recording's
// header carries them).
#include "fuzz_common.h"
#include "server_config.h"
#include "server_config.pb.h"

#include <stdexcept>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const bool silenced = (telegrasp::fuzz::silence_cerr(), true);  // protobuf's parse errors
  (void)silenced;
  const std::string path = telegrasp::fuzz::write_scratch("server.textproto", data, size);
  telegrasp::server::ServerSettings settings;
  try {
    telegrasp::server::load_server_config(path, settings);
    telegrasp::server::validate_settings(settings, path);
    (void)telegrasp::server::settings_from_proto(telegrasp::server::to_proto(settings), "round trip");
  } catch (const std::runtime_error&) {
    // A refused configuration: the expected outcome for most inputs.
  }
  return 0;
}
