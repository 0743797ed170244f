// Command-line parsing shared by the tools.
#pragma once

#include <stdexcept>
#include <string>

namespace telegrasp::cli {

/// The whole number `v` given to option `flag`, if it lies in [lo, hi]; otherwise calls
/// `fail` (the tool's usage error, which does not return) with a message naming both.
[[nodiscard]] inline long parse_whole(const std::string& flag, const std::string& v, long lo, long hi,
                                      void (*fail)(const std::string&)) {
  try {
    std::size_t used = 0;
    const long x = std::stol(v, &used);
    if (used == v.size() && x >= lo && x <= hi) return x;
  } catch (const std::exception&) {
  }
  fail(flag + " expects a whole number in [" + std::to_string(lo) + ", " + std::to_string(hi) + "], got '" + v + "'");
  throw std::logic_error("cli::parse_whole: fail returned");
}

}  // namespace telegrasp::cli
