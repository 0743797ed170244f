#include "scene_directory.h"

#include "telegrasp/idl/cli.h"

#include <cstdio>
#include <sstream>

namespace telegrasp::server {

msg::SceneAnnouncement make_claim(const AnnouncerFacts& facts) {
  msg::SceneAnnouncement a;
  a.incarnation(facts.incarnation);
  a.scene(facts.scene);
  a.host(facts.host.substr(0, 128));
  a.version(facts.version.substr(0, 64));
  a.started(facts.started);
  a.serving(false);
  return a;
}

msg::SceneAnnouncement make_announcement(const AnnouncerFacts& facts, const msg::ServerStatus& status,
                                         double cpu_percent, int host_cores, double host_load) {
  msg::SceneAnnouncement a = make_claim(facts);
  a.serving(true);
  a.clients(status.clients());
  a.hands(status.hands());
  a.objects(status.objects());
  a.tick_rate_hz(status.tick_rate_hz());
  a.tick_us_p99(status.tick_us_p99());
  a.missed_ticks(status.missed_ticks());
  a.cpu_percent(cpu_percent);
  a.host_cores(host_cores);
  a.host_load(host_load);
  return a;
}

bool claimed_before(const msg::SceneAnnouncement& a, const msg::SceneAnnouncement& b) {
  if (a.started() != b.started()) return a.started() < b.started();
  return a.incarnation() < b.incarnation();
}

std::optional<msg::SceneAnnouncement> older_claim(const msg::SceneAnnouncement& mine,
                                                  const std::vector<msg::SceneAnnouncement>& live) {
  std::optional<msg::SceneAnnouncement> oldest;
  for (const msg::SceneAnnouncement& a : live) {
    if (a.incarnation() == mine.incarnation() || a.scene() != mine.scene()) continue;
    if (!claimed_before(a, mine)) continue;
    if (!oldest || claimed_before(a, *oldest)) oldest = a;
  }
  return oldest;
}

std::string describe_run(const msg::SceneAnnouncement& run) {
  std::ostringstream out;
  out << run.host().to_string() << " (run " << cli::format_hex64(run.incarnation()) << ", telegrasp "
      << run.version().to_string() << ", " << run.hands() << " hands)";
  return out.str();
}

std::string already_served_message(const msg::SceneAnnouncement& keeper) {
  return "scene '" + keeper.scene().to_string() + "' is already served by " + describe_run(keeper) +
         ": stop that server first, or serve another scene with --scene NAME";
}

}  // namespace telegrasp::server
