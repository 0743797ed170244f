#include "replay_export.h"

#include "csv.h"
#include "replay_diff.h"
#include "telegrasp/idl/topics.h"
#include "telegrasp/sim/hand_rig.h"

#include <cerrno>
#include <cstring>
#include <fstream>
#include <ostream>
#include <string>
#include <vector>

namespace telegrasp::server {
namespace {

// The phalanx names of a recorded rig; none if this build cannot parse it.
std::vector<std::string> phalanx_names(const proto::RigText& r) {
  std::vector<std::string> names;
  try {
    const sim::HandRig rig = sim::HandRig::parse(r.text(), r.path());
    for (const auto& p : rig.phalanges()) names.push_back(p.name);
  } catch (const sim::RigError&) {}
  return names;
}

std::string csv_vec3(const msg::Vec3& p) {
  return shortest_number(p.x()) + "," + shortest_number(p.y()) + "," + shortest_number(p.z());
}

// Writes a row per contact of grasp event `ev`; `names`: the phalanx names by side. Returns the rows.
std::uint64_t write_contact_rows(std::ostream& out, const msg::GraspEvent& ev,
                                 const std::vector<std::string> (&names)[2]) {
  const unsigned side = ev.hand_side();
  const std::string prefix = std::to_string(ev.event_id()) + "," + csv::field(ev.client_id().to_string()) + "," +
                             (side == idl::kHandLeft    ? "left"
                              : side == idl::kHandRight ? "right"
                                                        : std::to_string(side)) +
                             "," + std::to_string(ev.object_id()) + "," + csv::field(ev.object_name().to_string()) +
                             "," + std::to_string(ev.tick()) + "," + shortest_number(ev.time()) + ",";
  for (const msg::ContactPoint& c : ev.contacts()) {
    std::string name;
    if (c.phalanx() < 0)
      name = "palm";
    else if (side < 2 && static_cast<std::size_t>(c.phalanx()) < names[side].size())
      name = names[side][c.phalanx()];
    out << prefix << c.phalanx() << "," << csv::field(name) << "," << csv_vec3(c.p_world()) << ","
        << csv_vec3(c.n_world()) << "," << csv_vec3(c.p_object()) << "," << csv_vec3(c.n_object()) << ","
        << shortest_number(c.nd()) << "," << (c.nd_hit() ? 1 : 0) << "\n";
  }
  return ev.contacts().size();
}

}  // namespace

const char* const kContactCsvHeader =
    "event_id,client_id,hand,object_id,object_name,tick,time,phalanx,phalanx_name,"
    "p_world_x,p_world_y,p_world_z,n_world_x,n_world_y,n_world_z,"
    "p_object_x,p_object_y,p_object_z,n_object_x,n_object_y,n_object_z,nd_m,nd_hit";

ContactExport export_contacts_csv(const std::string& recording_path, const std::string& csv_path) {
  RecordingReader reader(recording_path);
  std::vector<std::string> names[2];
  names[idl::kHandLeft] = phalanx_names(reader.header().left_rig());
  names[idl::kHandRight] = phalanx_names(reader.header().right_rig());

  std::ofstream out(csv_path, std::ios::binary);
  if (!out) throw RecordingError("contacts CSV " + csv_path + ": cannot write (" + std::strerror(errno) + ")");
  out << kContactCsvHeader << "\n";
  ContactExport e;
  proto::Record r;
  while (reader.next(r)) {
    if (!r.has_output() || r.output().type() != proto::OUTPUT_GRASP_EVENT) continue;
    msg::GraspEvent ev;
    if (!from_cdr(r.output().cdr(), ev))
      throw RecordingError("recording " + recording_path + ": record " + std::to_string(reader.records() - 1) +
                           ": the GraspEvent does not decode with this build's IDL");
    if (ev.kind() != msg::GRASP_EVENT_GRASP) continue;
    ++e.events;
    e.rows += write_contact_rows(out, ev, names);
  }
  e.damage = reader.damage();
  out.close();
  if (!out) throw RecordingError("contacts CSV " + csv_path + ": write failed (" + std::strerror(errno) + ")");
  return e;
}

}  // namespace telegrasp::server
