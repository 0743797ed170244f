// Command-line parsing shared by the tools.
#pragma once

#include <cstdlib>
#include <iostream>
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

/// Walks the arguments argv[1..]: -h or --help prints `usage` and exits 0; every other argument
/// goes to handle(flag, value), where value() returns the next argument (or calls `fail` with
/// "<flag> needs a value"). `handle` returns false for an option it does not know, and `fail`
/// is called naming it. `fail` is the tool's usage error and does not return.
template <class Handle>
void for_each_option(int argc, char** argv, const char* usage, void (*fail)(const std::string&), Handle&& handle) {
  for (int i = 1; i < argc; ++i) {
    const std::string flag = argv[i];
    if (flag == "-h" || flag == "--help") {
      std::cout << usage;
      std::exit(0);
    }
    auto value = [&]() -> std::string {
      if (i + 1 >= argc) fail(flag + " needs a value");
      return argv[++i];
    };
    if (!handle(flag, value)) fail("unknown option '" + flag + "'");
  }
}

}  // namespace telegrasp::cli
