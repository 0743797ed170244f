// Replay of a recording (recording.h): the scene is rebuilt from the header and driven by the
// recorded calls; every output it publishes is compared, in order, with the recorded one. Also
// the export of every grasp's contacts as CSV.
#pragma once

#include "recording.h"
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

/// The first output that differs from the recording.
struct Divergence {
  std::uint64_t record = 0;  ///< Index of the recorded output (or, for an extra output, of the next recorded call).
  std::uint64_t tick = 0;    ///< Ticks replayed before it (the world tick it belongs to).
  std::string type;          ///< e.g. "GraspEvent".
  std::string key;           ///< e.g. "client 'alice' right hand", "event 3, object 0 '005_tomato_soup_can'".
  std::string field;         ///< The first differing field, e.g. "contacts[2].p_world.x" ("" if not named).
  std::string message;       ///< All of it in one sentence.
};

struct ReplayOptions {
  std::string objects_dir;  ///< "": the recorded objects folder.
  /// Called every few thousand records with the reader (records(), offset(), file_size()).
  std::function<void(const RecordingReader&)> progress;
};

struct ReplayResult {
  std::uint64_t records = 0;           ///< Records read.
  std::uint64_t ticks = 0;             ///< Ticks replayed.
  std::uint64_t outputs_compared = 0;  ///< Outputs found identical (ServerStatus is not compared).
  std::uint64_t statuses_skipped = 0;  ///< Recorded ServerStatus messages.
  std::optional<Divergence> divergence;
  std::optional<RecordingDamage> damage;  ///< The recording was damaged; everything before was replayed.
  std::vector<std::string> warnings;      ///< e.g. recorded with another IDL.

  /// "identical: N outputs over T ticks" or the divergence, then the damage, one per line.
  std::string summary() const;
  /// 0 identical, 1 divergence, 3 damaged (and identical up to the damage).
  int exit_code() const;
};

/// Replays `path` in-process. Stops at the first divergence. Throws RecordingError if the header
/// cannot be read or the scene cannot be rebuilt from it.
ReplayResult replay_recording(const std::string& path, const ReplayOptions& options = {});

/// What export_contacts_csv wrote.
struct ContactExport {
  std::uint64_t events = 0;  ///< Grasp events (release events carry no contacts).
  std::uint64_t rows = 0;    ///< Contacts.
  std::optional<RecordingDamage> damage;
};

/// The CSV header line export_contacts_csv writes (no newline).
extern const char* const kContactCsvHeader;

/// Writes one CSV row per contact of every recorded GraspEvent of kind grasp, in event order:
/// event_id, client_id, hand (left/right), object_id, object_name, tick, time, phalanx (rig index,
/// -1 = palm), phalanx_name, p_world_{x,y,z}, n_world_{x,y,z}, p_object_{x,y,z}, n_object_{x,y,z},
/// nd_m, nd_hit. Numbers print as the shortest text that reads back to the same double. Throws
/// RecordingError if the recording's header cannot be read or the CSV cannot be written.
ContactExport export_contacts_csv(const std::string& recording_path, const std::string& csv_path);

/// The protobuf output type's name as the IDL calls the message, e.g. "GraspEvent".
std::string output_type_name(proto::OutputType type);

}  // namespace telegrasp::server
