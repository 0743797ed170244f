// What the fault tests share: a private network namespace for the whole test process, packet loss
// on its loopback interface, and reading telegrasp-echo's and telegrasp-bot's outputs.
#pragma once

#include <nlohmann/json.hpp>

#include <cstdint>
#include <string>
#include <vector>

namespace telegrasp::testing {

/// Moves this process into a new network namespace with only `lo`, up (unshare(CLONE_NEWNET),
/// then `ip link set lo up`). Called once by main() before any thread starts; every program a
/// test starts inherits the namespace, so no test traffic leaves it and iptables rules added
/// here vanish with the process. False (with the reason in `why`) if that cannot be done (not
/// root, no unshare, no `ip`): the tests then skip.
bool enter_private_network(std::string& why);

/// Whether enter_private_network succeeded, and why not.
bool in_private_network();
const std::string& private_network_failure();

/// Drops each packet arriving on `lo` with probability `p` (iptables -m statistic), replacing any
/// rule an earlier test of this process added (p = 0: no loss); "" on success, else the command
/// and its output.
std::string drop_loopback_packets(double p);

/// The JSON objects of a file of lines (telegrasp-echo's output; lines that are not JSON objects,
/// e.g. its stderr, are skipped).
std::vector<nlohmann::json> read_json_lines(const std::string& path);

/// A sorted list of event ids checked for gaps and repeats.
struct EventIds {
  std::vector<std::uint64_t> ids;  ///< sorted
  std::vector<std::uint64_t> missing, duplicates;
  std::string describe() const;
};
EventIds check_event_ids(std::vector<std::uint64_t> ids);

}  // namespace telegrasp::testing
