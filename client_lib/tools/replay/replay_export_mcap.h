// Export of a recording into an MCAP file with telegrasp-view's channels (/scene, /tf,
// /grasp_state, /grasp_events, /server_status: the same topics, schemas and JSON messages), so a
// recorded run opens in Foxglove or Lichtblick with its time line. The recorded outputs are fed,
// in order, to the view's own model (client_lib/tools/view: WireFeed, ViewModel, McapRecorder)
// as telegrasp-view would have polled them from a live server.
#pragma once

#include "recording.h"

#include <cstdint>
#include <optional>
#include <string>

namespace telegrasp::server {

struct McapExportOptions {
  /// View updates per second of server time, as telegrasp-view's --rate (default 30).
  double rate_hz = 30;
  /// The foxglove.* JSON schemas telegrasp-view serves; "" is share/telegrasp/view/schemas of
  /// this installation or build (sim::data_dir()).
  std::string schema_dir;
};

/// What export_mcap wrote.
struct McapExport {
  std::uint64_t outputs = 0;  ///< Recorded outputs read (every type, hand removals included).
  std::uint64_t steps = 0;  ///< View model updates.
  std::uint64_t messages = 0;  ///< MCAP messages written.
  std::uint64_t bytes = 0;  ///< The MCAP file's size.
  /// Log times of the first and last message, ns since the Unix epoch (0 when none).
  std::uint64_t start_time_ns = 0, end_time_ns = 0;
  std::optional<RecordingDamage> damage;
};

/// Writes `mcap_path` from the recording at `recording_path`. The view model is updated (a step,
/// telegrasp-view's poll) after the first tick and then after each tick at least 1/rate_hz of
/// server time after the previous step's, with every output of the ticks in between; the step's
/// messages are logged (and published and stamped) at the recording's start (header
/// created_unix_ns) plus the server time of that tick. The file ends with the whole scene and
/// every frame at the last output's time. A damaged recording
/// is exported up to the damage (`damage` says where). Throws RecordingError if the header
/// cannot be read, an output does not decode with this build's IDL, or the MCAP file or the
/// schemas cannot be read or written; std::invalid_argument for a rate outside (0, 1000].
McapExport export_mcap(const std::string& recording_path, const std::string& mcap_path,
                       const McapExportOptions& options = {});

}  // namespace telegrasp::server
