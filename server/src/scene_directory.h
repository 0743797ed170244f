// The scene directory, server side: what a server announces about itself (SceneAnnouncement, on
// the directory topic in the common partition) and the rule that decides which of two servers
// claiming one scene name keeps it. No DDS here; DdsNode publishes and reads.
#pragma once

#include "telegrasp/idl/telegrasp.h"

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace telegrasp::server {

/// What stays fixed for a server run.
struct AnnouncerFacts {
  std::string scene;
  std::string host;  ///< gethostname()
  std::string version;
  std::uint64_t incarnation = 0;
  double started = 0;  ///< Unix time, s.
};

/// The announcement of a run that is serving, from its latest status and load.
msg::SceneAnnouncement make_announcement(const AnnouncerFacts& facts, const msg::ServerStatus& status,
                                         double cpu_percent, int host_cores, double host_load);
/// The announcement of a run still waiting out its claim (serving false, no load figures).
msg::SceneAnnouncement make_claim(const AnnouncerFacts& facts);

/// Whether `a` claimed its scene before `b`: the earlier start, ties broken by the smaller
/// incarnation (so two runs always agree on which one keeps the scene).
bool claimed_before(const msg::SceneAnnouncement& a, const msg::SceneAnnouncement& b);

/// Among the live announcements `live`, the oldest claim on `mine`'s scene that is older than
/// `mine` (another run keeps the scene: `mine` must not serve it); none when `mine` keeps it.
/// `mine` itself (same incarnation) is ignored.
std::optional<msg::SceneAnnouncement> older_claim(const msg::SceneAnnouncement& mine,
                                                  const std::vector<msg::SceneAnnouncement>& live);

/// A run for people: "HOST (run 00c0ffee..., telegrasp 0.1.0, 3 hands)".
std::string describe_run(const msg::SceneAnnouncement& run);
/// The refusal printed when another run keeps the scene.
std::string already_served_message(const msg::SceneAnnouncement& keeper);

}  // namespace telegrasp::server
