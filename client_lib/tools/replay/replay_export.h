// Export of a recording's grasp contacts as CSV, one row per contact.
#pragma once

#include "recording.h"

#include <cstdint>
#include <optional>
#include <string>

namespace telegrasp::server {

/// What export_contacts_csv wrote.
struct ContactExport {
  std::uint64_t events = 0;  ///< Grasp events (release events carry no contacts).
  std::uint64_t rows = 0;  ///< Contacts.
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

}  // namespace telegrasp::server
