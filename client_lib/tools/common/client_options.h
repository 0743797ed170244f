// The ClientOptions of a tool's own DDS client, from the network flags it parsed
// (telegrasp/idl/network_flags.h): its options type has the members of idl::NetworkFlags.
#pragma once

#include "telegrasp/client/client.h"

#include <string>

namespace telegrasp::tools {

template <class NetworkOptions>
[[nodiscard]] client::ClientOptions client_options(const NetworkOptions& flags, std::string client_id,
                                                   unsigned topics) {
  client::ClientOptions o;
  o.client_id = std::move(client_id);
  o.domain = flags.domain;
  o.profile = flags.profile;
  o.profiles_file = flags.profiles_file;
  o.scene = flags.scene;
  o.discovery_servers = flags.discovery_servers;
  o.topics = topics;
  return o;
}

}  // namespace telegrasp::tools
