// A recorded server session for the recording, replay and export tests (no DDS): a SceneServer
// driven through the Recorder the way the server's simulation thread drives it.
#pragma once

#include "telegrasp/idl/telegrasp.h"

#include <string>
#include <vector>

namespace telegrasp::server {

struct RecordedSession {
  std::string path;
  std::vector<msg::GraspEvent> events;  ///< As the Recorder forwarded them.
};

/// Records at `path`: a soup can on the table, 10 idle ticks, a tennis ball spawned by command,
/// alice's right hand grasping and lifting the can (the scripted operator, perfect skill), one
/// ServerStatus, then silence until the hand is removed and the can released. Throws
/// std::runtime_error if the session does not go that way.
RecordedSession record_session(const std::string& path);

}  // namespace telegrasp::server
