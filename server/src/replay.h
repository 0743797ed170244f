// Replay of a recording (recording.h): the scene is rebuilt from the header and driven by the
// server's own loop (ServerLoop), fed from the recording (RecordedFeed): the recorded inputs and
// commands are applied at their recorded times and the ticks taken where the recording took them;
// every output the scene publishes is compared, in order, with the recorded one (replay_diff.h).
#pragma once

#include "recording.h"
#include "replay_diff.h"
#include "scene_setup.h"

#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

namespace telegrasp::server {

/// The models and rigs a recording was made with: rigs from the embedded text, stand-ins, or the
/// recorded mesh files loaded from `objects_dir` ("" = the recorded folder), each checked against
/// its recorded size and hash. Throws RecordingError naming every missing or changed mesh file.
SceneAssets load_recorded_assets(const proto::RecordingHeader& header, const std::string& recording_path,
                                 const std::string& objects_dir = "");

struct ReplayOptions {
  std::string objects_dir;  ///< "": the recorded objects folder.
  /// Called every few thousand records with the reader (records(), offset(), file_size()).
  std::function<void(const RecordingReader&)> progress;
};

struct ReplayResult {
  std::uint64_t records = 0;  ///< Records read.
  std::uint64_t ticks = 0;  ///< Ticks replayed.
  std::uint64_t outputs_compared = 0;  ///< Outputs found identical (ServerStatus is not compared).
  std::uint64_t statuses_skipped = 0;  ///< Recorded ServerStatus messages.
  std::optional<Divergence> divergence;
  std::optional<RecordingDamage> damage;  ///< The recording was damaged; everything before was replayed.
  std::vector<std::string> warnings;  ///< e.g. recorded with another IDL.

  /// "identical: N outputs over T ticks" or the divergence, then the damage, one per line.
  std::string summary() const;
  /// 0 identical, cli::kExitDiverged (6) a divergence, cli::kExitDamaged (3) damaged (and
  /// identical up to the damage).
  int exit_code() const;
};

/// Replays `path` in-process. Stops at the first divergence. Throws RecordingError if the header
/// cannot be read or the scene cannot be rebuilt from it.
ReplayResult replay_recording(const std::string& path, const ReplayOptions& options = {});

}  // namespace telegrasp::server
