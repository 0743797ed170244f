// Comparison of what a replay publishes with what the recording holds: each output is compared
// by its bytes, then (if they differ) field by field, naming the first differing field and the
// instance (hand, object, event) it is about.
#pragma once

#include "recording.h"

#include <cstdint>
#include <string>

namespace telegrasp::server {

/// The first output that differs from the recording.
struct Divergence {
  std::uint64_t record = 0;  ///< Index of the recorded output (or, for an extra output, of the next recorded call).
  std::uint64_t tick = 0;  ///< Ticks replayed before it (the world tick it belongs to).
  std::string type;  ///< e.g. "GraspEvent".
  std::string key;  ///< e.g. "client 'alice' right hand", "event 3, object 0 '005_tomato_soup_can'".
  std::string field;  ///< The first differing field, e.g. "contacts[2].p_world.x" ("" if not named).
  std::string message;  ///< All of it in one sentence.
};

/// An output the replayed scene published, as the Recorder would have recorded it.
struct ReplayedOutput {
  proto::OutputType type = proto::OUTPUT_UNSPECIFIED;
  std::string cdr;
  HandAddress removed;  ///< OUTPUT_HAND_REMOVED only.
};

/// Compares a recorded output with the replayed one: true if they are the same (equal bytes, or
/// equal decoded messages); else fills `d` (all but record and tick, which the caller knows).
bool same_output(const proto::Output& recorded, const ReplayedOutput& replayed, Divergence& d);

/// Which instance an output (recorded or replayed) is about, from its type and bytes, e.g.
/// "client 'alice' right hand"; "undecodable" if the bytes do not decode.
std::string key_of_output(proto::OutputType type, const std::string& cdr, const HandAddress& removed);

/// "client 'alice' right hand".
std::string hand_text(const std::string& client_id, unsigned side);

/// The recorded hand address.
HandAddress hand_address(const proto::HandAddress& a);

/// The protobuf output type's name as the IDL calls the message, e.g. "GraspEvent".
std::string output_type_name(proto::OutputType type);

/// The shortest text that reads back to the same double (std::to_chars without a precision).
std::string shortest_number(double v);

}  // namespace telegrasp::server
