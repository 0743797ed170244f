// Where a participant meets others: its scene (the DDS partition of every scene topic) and, for
// networks without multicast, the Fast DDS discovery servers it registers with.
#pragma once

#include "telegrasp/idl/fastdds_fwd.h"

#include <string>
#include <vector>

namespace telegrasp::idl {

/// The scene and discovery servers of a participant. Empty fields are filled by
/// resolve_network() from the environment, then the defaults.
struct Network {
  /// The scene (room) name: the topics of scene S are in DDS partition "telegrasp/scene/S", so a
  /// participant never receives another scene's samples. "" = $TELEGRASP_SCENE, else "default".
  std::string scene;
  /// Discovery servers, "HOST[:PORT]" (port 11811 when left out), in server-id order: the i-th is
  /// the one started as `fastdds discovery -i i`. Given, the participant discovers only through
  /// them (Fast DDS CLIENT discovery), whatever its profile's discovery. Empty =
  /// $TELEGRASP_DISCOVERY_SERVERS ("HOST:PORT;HOST:PORT", as ROS_DISCOVERY_SERVER), else the
  /// profile's own discovery.
  std::vector<std::string> discovery_servers;
};

/// Longest scene name.
inline constexpr std::size_t kMaxSceneNameLength = 64;

/// "" when `name` can be a scene name, else why not: 1 to 64 characters of letters, digits, '-',
/// '_' and '.'. DDS partition wildcards ('*', '?', '[') are refused: a scene named "*" would
/// match, and receive, every scene's samples.
std::string scene_name_error(const std::string& name);

/// Splits a discovery server list: entries separated by ';' or ',' (spaces ignored).
std::vector<std::string> split_discovery_servers(const std::string& list);

/// `given` with its empty fields taken from the environment or the defaults, checked. Throws
/// std::runtime_error naming the variable or value that is wrong (a bad scene name, a server
/// address that is not HOST[:PORT] or whose host does not resolve to an IPv4 address).
Network resolve_network(Network given);

/// The DDS partition of `scene`'s topics.
std::string scene_partition(const std::string& scene);

/// Replaces the discovery of `qos` with CLIENT discovery through `servers` ("HOST[:PORT]", in
/// server-id order); does nothing when `servers` is empty. Throws std::runtime_error naming an
/// address that is wrong.
void apply_discovery_servers(eprosima::fastdds::dds::DomainParticipantQos& qos, const std::vector<std::string>& servers);

}  // namespace telegrasp::idl
