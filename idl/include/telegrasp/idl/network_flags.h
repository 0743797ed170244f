// The flags every program that joins a DDS domain takes, parsed in one place for the server, the
// client tools and the network benches alike: --domain, --profile, --profiles, --scene and
// --discovery-server, each checked as it is parsed, and the same flags written back out for a
// child process.
#pragma once

#include "telegrasp/idl/network.h"
#include "telegrasp/idl/profiles.h"
#include "telegrasp/idl/topics.h"

#include <charconv>
#include <stdexcept>
#include <string>
#include <vector>

namespace telegrasp::idl {

/// The highest DDS domain whose UDP ports fit in 16 bits; --domain takes 0..kMaxDomain.
inline constexpr int kMaxDomain = 232;

/// What the network flags set. A program's own options may hold the same members instead: the
/// functions below take any type with them.
struct NetworkFlags {
  int domain = 0;
  std::string profile = "loopback";  ///< A participant profile of the profiles file.
  std::string profiles_file;  ///< "" = $TELEGRASP_PROFILES, else the shipped file.
  std::string scene;  ///< "" = $TELEGRASP_SCENE, else "default".
  std::vector<std::string> discovery_servers;  ///< "HOST[:PORT]", in server-id order.
};

/// Applies `flag` onto `options` (a NetworkFlags, or any options with its members) if it is one of
/// the network flags and returns true (`value()` gives its value); false for any other flag. A bad
/// value goes to `fail` (the program's usage error, which does not return), naming the flag.
/// Options without `scene` or `discovery_servers` members (a benchmark that joins no scene) do not
/// take --scene or --discovery-server.
template <class Options, class Value, class Fail>
bool parse_network_flag(const std::string& flag, const Value& value, Options& options, Fail fail) {
  if (flag == "--domain") {
    const std::string v = value();
    int domain = -1;
    const auto [end, error] = std::from_chars(v.data(), v.data() + v.size(), domain);
    if (v.empty() || error != std::errc() || end != v.data() + v.size() || domain < 0 || domain > kMaxDomain)
      fail(flag + " expects a whole number in [0, " + std::to_string(kMaxDomain) + "], got '" + v + "'");
    options.domain = domain;
    return true;
  }
  if (flag == "--profile") {
    options.profile = value();
    if (options.profile.empty())
      fail(flag + " expects a participant profile name (" + kShippedProfiles + "), got ''");
    return true;
  }
  if (flag == "--profiles") {
    options.profiles_file = value();
    return true;
  }
  if constexpr (requires { options.scene; }) {
    if (flag == "--scene") {
      options.scene = value();
      if (const std::string e = scene_name_error(options.scene); !e.empty()) fail(flag + ": " + e);
      return true;
    }
  }
  if constexpr (requires { options.discovery_servers; }) {
    if (flag == "--discovery-server") {
      options.discovery_servers.push_back(value());
      try {
        (void)resolve_network({kDefaultScene, {options.discovery_servers.back()}});
      } catch (const std::exception& e) {
        fail(flag + ": " + e.what());
      }
      return true;
    }
  }
  return false;
}

/// The network flags of `options` as arguments, for a child process that takes them too (a flag
/// left at its default is left out, except --domain and --profile).
template <class Options>
std::vector<std::string> network_args(const Options& options) {
  std::vector<std::string> args = {"--domain", std::to_string(options.domain), "--profile", options.profile};
  if (!options.profiles_file.empty()) args.insert(args.end(), {"--profiles", options.profiles_file});
  if constexpr (requires { options.scene; })
    if (!options.scene.empty()) args.insert(args.end(), {"--scene", options.scene});
  if constexpr (requires { options.discovery_servers; })
    for (const std::string& server : options.discovery_servers)
      args.insert(args.end(), {"--discovery-server", server});
  return args;
}

}  // namespace telegrasp::idl
