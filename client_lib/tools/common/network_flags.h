// The flags every networked tool shares for where it meets its server: --scene and
// --discovery-server (ClientOptions::scene, ClientOptions::discovery_servers), checked as they
// are parsed.
#pragma once

#include "telegrasp/client/client.h"

#include <string>

namespace telegrasp::tools {

/// Applies `flag` onto `options` (client::ClientOptions, or a tool's options with the same `scene`
/// and `discovery_servers` members) if it is --scene or --discovery-server (`value()` gives its
/// value) and returns true; false for any other flag. A bad value goes to `fail` (a usage error).
template <class Options, class Value, class Fail>
bool parse_network_flag(const std::string& flag, const Value& value, Options& options, Fail fail) {
  if (flag == "--scene") {
    options.scene = value();
    if (const std::string e = client::scene_name_error(options.scene); !e.empty()) fail("--scene: " + e);
    return true;
  }
  if (flag == "--discovery-server") {
    options.discovery_servers.push_back(value());
    if (const std::string e = client::discovery_server_error(options.discovery_servers.back()); !e.empty())
      fail("--discovery-server: " + e);
    return true;
  }
  return false;
}

}  // namespace telegrasp::tools
