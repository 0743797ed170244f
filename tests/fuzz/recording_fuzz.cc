// Fuzzes the recording reader (server/src/recording.cc): the magic, the header, every frame's
// length, CRC and record; then what replay does with what was read: the header's configuration
// (settings_from_proto) and every recorded CDR payload decoded as its type.
#include "fuzz_common.h"
#include "recording.h"
#include "server_config.h"

#include <stdexcept>

namespace {

using namespace telegrasp;

template <typename Message>
void decode(const std::string& cdr) {
  Message m;
  (void)server::from_cdr(cdr, m);
}

/// An output decoded as the type it names.
void decode_output(const server::proto::Output& output) {
  server::visit_output_type(output.type(),
                            [&]<class Message>(std::type_identity<Message>) { decode<Message>(output.cdr()); });
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const bool silenced = (fuzz::silence_cerr(), true);
  (void)silenced;
  const std::string path = fuzz::write_scratch("fuzz.tgrec", data, size);
  try {
    server::RecordingReader reader(path);
    try {
      (void)server::settings_from_proto(reader.header().config(), "recording header");
    } catch (const std::runtime_error&) {}
    server::proto::Record record;
    while (reader.next(record)) {
      if (record.has_inputs()) {
        for (const auto& sample : record.inputs().samples())
          decode<msg::ControllerState>(sample.controller_state_cdr());
      } else if (record.has_command()) {
        decode<msg::SceneCommand>(record.command().scene_command_cdr());
      } else if (record.has_output()) {
        decode_output(record.output());
      }
    }
  } catch (const server::RecordingError&) {
    // Not a recording, or its header is damaged: refused with a message.
  }
  return 0;
}
