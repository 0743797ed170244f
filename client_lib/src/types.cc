#include "telegrasp/client/types.h"

#include <algorithm>
#include <map>
#include <tuple>

namespace telegrasp::client {

std::string to_string(HandSide side) {
  switch (side) {
    case HandSide::kLeft:
      return "left";
    case HandSide::kRight:
      return "right";
  }
  return "side" + std::to_string(static_cast<unsigned>(side));
}

std::optional<std::string> least_loaded_host(const std::vector<SceneInfo>& scenes) {
  struct Host {
    double load = 0;  // the highest its servers report (each samples the host's load on its own second)
    int hands = 0;
  };
  std::map<std::string, Host> hosts;
  for (const SceneInfo& s : scenes) {
    Host& h = hosts[s.host];
    h.hands += s.hands;
    h.load = std::max(h.load, s.host_load);
  }
  std::optional<std::string> best;
  std::tuple<double, int, std::string> best_key;
  for (const auto& [name, h] : hosts) {
    const auto key = std::make_tuple(h.load, h.hands, name);
    if (!best || key < best_key) best = name, best_key = key;
  }
  return best;
}

}  // namespace telegrasp::client
