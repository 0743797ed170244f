#include "telegrasp/idl/network.h"

#include "telegrasp/idl/topics.h"

#include <fastdds/dds/domain/qos/DomainParticipantQos.hpp>
#include <fastdds/rtps/attributes/ServerAttributes.h>
#include <fastdds/rtps/common/Locator.h>
#include <fastrtps/utils/IPLocator.h>

#include <arpa/inet.h>
#include <netdb.h>
#include <netinet/in.h>

#include <cstdlib>
#include <stdexcept>

namespace telegrasp::idl {

namespace {

std::string env(const char* name) {
  const char* v = std::getenv(name);
  return v == nullptr ? "" : v;
}

struct ServerAddress {
  std::string ip;
  unsigned port = eprosima::fastdds::rtps::DEFAULT_ROS2_SERVER_PORT;
};

// "HOST[:PORT]" with HOST resolved to an IPv4 address.
ServerAddress parse_server(const std::string& text) {
  const std::string what = "discovery server '" + text + "'";
  ServerAddress a;
  std::string host = text;
  if (const auto colon = text.rfind(':'); colon != std::string::npos) {
    host = text.substr(0, colon);
    const std::string port = text.substr(colon + 1);
    char* end = nullptr;
    const long p = port.empty() ? 0 : std::strtol(port.c_str(), &end, 10);
    if (port.empty() || *end != '\0' || p < 1 || p > 65535)
      throw std::runtime_error(what + ": the port must be 1..65535 (HOST:PORT)");
    a.port = static_cast<unsigned>(p);
  }
  if (host.empty()) throw std::runtime_error(what + ": no host (HOST[:PORT])");
  addrinfo hints{};
  hints.ai_family = AF_INET;
  hints.ai_socktype = SOCK_DGRAM;
  addrinfo* found = nullptr;
  if (getaddrinfo(host.c_str(), nullptr, &hints, &found) != 0 || found == nullptr)
    throw std::runtime_error(what + ": host '" + host + "' has no IPv4 address");
  char ip[INET_ADDRSTRLEN] = {};
  inet_ntop(AF_INET, &reinterpret_cast<sockaddr_in*>(found->ai_addr)->sin_addr, ip, sizeof ip);
  freeaddrinfo(found);
  a.ip = ip;
  return a;
}

}  // namespace

std::string scene_name_error(const std::string& name) {
  if (name.empty()) return "a scene name cannot be empty";
  if (name.size() > kMaxSceneNameLength)
    return "scene name '" + name + "' is longer than " + std::to_string(kMaxSceneNameLength) + " characters";
  for (const char c : name) {
    const bool ok =
        (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '-' || c == '_' || c == '.';
    if (!ok)
      return "scene name '" + name + "' has '" + std::string(1, c) +
             "': use letters, digits, '-', '_' and '.' (DDS partition wildcards would match other scenes)";
  }
  return "";
}

std::vector<std::string> split_discovery_servers(const std::string& list) {
  std::vector<std::string> out;
  std::string item;
  for (const char c : list + ";") {
    if (c == ';' || c == ',') {
      if (!item.empty()) out.push_back(item);
      item.clear();
    } else if (c != ' ' && c != '\t') {
      item += c;
    }
  }
  return out;
}

Network resolve_network(Network given) {
  const bool scene_from_env = given.scene.empty();
  if (scene_from_env) given.scene = env("TELEGRASP_SCENE");
  if (given.scene.empty()) given.scene = kDefaultScene;
  if (const std::string e = scene_name_error(given.scene); !e.empty())
    throw std::runtime_error(scene_from_env ? "TELEGRASP_SCENE: " + e : e);
  const bool from_env = given.discovery_servers.empty();
  if (from_env) given.discovery_servers = split_discovery_servers(env("TELEGRASP_DISCOVERY_SERVERS"));
  for (const std::string& s : given.discovery_servers) {
    try {
      parse_server(s);
    } catch (const std::runtime_error& e) {
      throw std::runtime_error(from_env ? "TELEGRASP_DISCOVERY_SERVERS: " + std::string(e.what()) : e.what());
    }
  }
  return given;
}

std::string scene_partition(const std::string& scene) { return kScenePartitionPrefix + scene; }

void apply_discovery_servers(eprosima::fastdds::dds::DomainParticipantQos& qos,
                             const std::vector<std::string>& servers) {
  if (servers.empty()) return;
  namespace rtps = eprosima::fastrtps::rtps;
  eprosima::fastdds::rtps::RemoteServerList_t list;
  for (std::size_t id = 0; id < servers.size(); ++id) {
    const ServerAddress a = parse_server(servers[id]);
    eprosima::fastdds::rtps::RemoteServerAttributes server;
    if (!eprosima::fastdds::rtps::get_server_client_default_guidPrefix(static_cast<int>(id), server.guidPrefix))
      throw std::runtime_error("discovery server '" + servers[id] + "': too many discovery servers");
    rtps::Locator_t locator;
    locator.kind = LOCATOR_KIND_UDPv4;
    rtps::IPLocator::setIPv4(locator, a.ip);
    locator.port = a.port;
    server.metatrafficUnicastLocatorList.push_back(locator);
    list.push_back(server);
  }
  auto& discovery = qos.wire_protocol().builtin.discovery_config;
  discovery.discoveryProtocol = eprosima::fastrtps::rtps::DiscoveryProtocol_t::CLIENT;
  discovery.m_DiscoveryServers = list;
}

}  // namespace telegrasp::idl
