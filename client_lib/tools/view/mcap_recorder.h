// McapRecorder: telegrasp-view's channels written into an MCAP file (client_lib/tools/mcap), the same
// topics, schema names, JSON schemas and JSON messages the viewers get, so the file opens in
// Foxglove or Lichtblick with a time line. telegrasp-view --record writes one live;
// telegrasp-replay --export-mcap writes one from a server recording.
//
// Seeking: a player that jumps to a point of the time line shows, per topic, the newest message
// before it. /scene carries only what changed, so every kKeyframeEveryNs the recorder also writes
// the whole scene on /scene (and the model already sends every frame on /tf that often): after a
// jump the picture is complete within 2 s of log time.
#pragma once

#include "channels.h"
#include "mcap_writer.h"
#include "step_messages.h"
#include "view_model.h"

#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace telegrasp::view {

class McapRecorder {
 public:
  struct Options {
    /// A chunk is compressed and written once its records reach this size.
    std::uint64_t chunk_size_bytes = 1024 * 1024;
    /// Also writes the open chunk once this long has passed since the last write (clock of
    /// flush_if_due), so a killed process loses at most about this much; 0: full chunks only.
    std::uint64_t flush_interval_ns = 0;
  };
  /// The whole scene on /scene at least this often (log time), and at the first message.
  static constexpr std::uint64_t kKeyframeEveryNs = ViewModel::kFullTransformsEveryNs;

  /// Creates (truncates) `path` and writes a Schema and a Channel record per view channel. Throws
  /// std::runtime_error naming the path when it cannot.
  McapRecorder(const std::string& path, const std::vector<Channel>& channels, Options options);

  /// Writes one step's messages (step_messages), logged and published at `time_ns` (ns since
  /// the Unix epoch), then the whole scene if a keyframe is due. `model` is the model after the
  /// step. Throws std::runtime_error naming the path when the file cannot be written.
  void record(const std::vector<StepMessage>& messages, const ViewModel& model, std::uint64_t time_ns);
  /// Writes the whole scene and every frame at `time_ns` (nothing if the model is empty).
  void record_keyframe(const ViewModel& model, std::uint64_t time_ns);
  /// Writes one JSON message on a view channel (channels.h) at `time_ns`.
  void write(std::uint32_t channel, std::string_view json, std::uint64_t time_ns);

  /// With a flush interval: writes the open chunk and flushes the file if the interval has passed
  /// since the last such flush; `now_ns` is any monotonic clock (telegrasp-view: steady_clock).
  void flush_if_due(std::uint64_t now_ns);
  /// Writes the summary and footer and closes the file (the destructor does too). Idempotent.
  void close();

  const mcap::Writer& writer() const { return writer_; }
  std::uint64_t keyframes() const { return keyframes_; }

 private:
  void write_scene_keyframe(const ViewModel& model, std::uint64_t time_ns);

  mcap::Writer writer_;
  Options options_;
  struct Out {
    mcap::ChannelId id;
    std::uint32_t sequence = 0;
  };
  std::map<std::uint32_t, Out> channels_;  ///< By view channel id.
  std::optional<std::uint64_t> last_keyframe_ns_;
  std::optional<std::uint64_t> last_flush_ns_;
  std::uint64_t keyframes_ = 0;
};

}  // namespace telegrasp::view
