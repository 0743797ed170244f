// Command-line parsing shared by the tools, and the conventions every tool follows:
//   exit statuses mean the same in every tool (kExit* below: 0 success, 1 a runtime failure, 2 a
//   usage error, 3 and up one meaning each), and each tool's --help states those it uses;
//   a usage error is two lines on stderr, "<tool>: <what is wrong>" and "(see <tool> --help)";
//   numbers in messages are written as people write them (format_number).
#pragma once

#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <initializer_list>
#include <iostream>
#include <stdexcept>
#include <string>
#include <utility>

namespace telegrasp::cli {

// Exit statuses: one meaning each, in every tool.
/// A runtime failure: a missing or unreadable file or folder, no server found, DDS could not
/// start, an I/O error.
constexpr int kExitFailure = 1;
/// A usage error: a bad or missing option or value.
constexpr int kExitUsage = 2;
/// An input file is truncated or corrupt; what came before the damage was used and reported
/// (telegrasp-replay).
constexpr int kExitDamaged = 3;
/// The server refused this client's hands or one of its commands (telegrasp-bot).
constexpr int kExitRefused = 4;
/// Every trial ran, but some object was not held in every trial (telegrasp-bot).
constexpr int kExitNotHeld = 5;
/// A replay differs from its recording (telegrasp-replay).
constexpr int kExitDiverged = 6;
/// A soak ran to its end but memory grew past a limit (telegrasp-soak).
constexpr int kExitMemoryGrew = 7;
/// A soak's memory stayed flat but fewer grasps happened than asked for (telegrasp-soak).
constexpr int kExitTooFewGrasps = 8;
/// Stopped by SIGINT or SIGTERM (what was done so far is reported).
constexpr int kExitInterrupted = 130;

/// A tool's usage error: prints `what` and does not return.
using Fail = void (*)(const std::string& what);

/// Prints "<tool>: <what>" and "(see <tool> --help)" on stderr and exits with kExitUsage. `tool`
/// is how the user calls it, e.g. "telegrasp-eval run".
[[noreturn]] inline void usage_exit(const std::string& tool, const std::string& what) {
  std::cerr << tool << ": " << what << "\n(see " << tool << " --help)\n";
  std::exit(kExitUsage);
}

/// `x` as people write it: the shortest text that reads back as `x` ("0", "0.25", "90",
/// "1000000000", "1e+20", "nan"), never std::to_string's "0.000000".
[[nodiscard]] inline std::string format_number(double x) {
  char text[32];
  const bool whole = std::isfinite(x) && x == std::trunc(x) && std::abs(x) < 1e15;
  const auto [end, error] = whole ? std::to_chars(text, text + sizeof text, static_cast<long long>(x))
                                  : std::to_chars(text, text + sizeof text, x);
  return error == std::errc() ? std::string(text, end) : std::string("?");
}

/// A 64-bit id (a server run's incarnation, a content hash) as 16 hex digits: JSON numbers lose
/// digits past 2^53, and a fixed width lines the ids up.
[[nodiscard]] inline std::string format_hex64(std::uint64_t v) {
  char text[17];
  std::snprintf(text, sizeof text, "%016llx", static_cast<unsigned long long>(v));
  return text;
}

/// The whole number `v` given to option `flag`, if it lies in [lo, hi]; otherwise calls
/// `fail` (the tool's usage error, which does not return) with a message naming both.
[[nodiscard]] inline long parse_whole(const std::string& flag, const std::string& v, long lo, long hi, Fail fail) {
  long x = 0;
  const auto [end, error] = std::from_chars(v.data(), v.data() + v.size(), x);
  if (!v.empty() && error == std::errc() && end == v.data() + v.size() && x >= lo && x <= hi) return x;
  fail(flag + " expects a whole number in [" + std::to_string(lo) + ", " + std::to_string(hi) + "], got '" + v + "'");
  throw std::logic_error("cli::parse_whole: fail returned");
}

/// The number `v` given to option `flag`, if it is finite and lies in [lo, hi]; otherwise calls
/// `fail` with a message naming both.
[[nodiscard]] inline double parse_number(const std::string& flag, const std::string& v, double lo, double hi,
                                         Fail fail) {
  char* end = nullptr;
  const double x = v.empty() ? NAN : std::strtod(v.c_str(), &end);
  if (!v.empty() && *end == '\0' && std::isfinite(x) && x >= lo && x <= hi) return x;
  fail(flag + " expects a number in [" + format_number(lo) + ", " + format_number(hi) + "], got '" + v + "'");
  throw std::logic_error("cli::parse_number: fail returned");
}

/// Notes on stderr that `tool`'s flag `old_name` is now `new_name`: the old spelling still works
/// for one release.
inline void warn_renamed(const std::string& tool, const std::string& old_name, const std::string& new_name) {
  std::cerr << tool << ": deprecated: " << old_name << " is now " << new_name << " (" << old_name
            << " goes in the next release)\n";
}

/// Whether `arg` is option `name`, or its old spelling `old_name`, which still works for one
/// release and warns (warn_renamed).
[[nodiscard]] inline bool is_flag(const std::string& tool, const std::string& arg, const std::string& name,
                                  const std::string& old_name) {
  if (arg == name) return true;
  if (arg != old_name) return false;
  warn_renamed(tool, old_name, name);
  return true;
}

/// If `flag` is one of `flags` (an option's name and the string its value goes into), stores the
/// value (`value()`, as for_each_option hands it) there and returns true: the options that take
/// a file, folder or name as it is written, in one table instead of an if-chain each.
template <class Value>
bool text_flag(const std::string& flag, const Value& value,
               std::initializer_list<std::pair<const char*, std::string*>> flags) {
  for (const auto& [name, target] : flags)
    if (flag == name) {
      *target = value();
      return true;
    }
  return false;
}

/// Whether `arg` is an option ("-x", "--name") rather than a positional argument ("FILE", "-").
[[nodiscard]] inline bool is_option(const std::string& arg) { return arg.size() > 1 && arg[0] == '-'; }

/// Walks the arguments argv[1..] in order: -h or --help prints `usage` on stdout and exits 0;
/// every other argument goes to handle(arg, value), where value() returns the next argument (or
/// calls `fail` with "<arg> needs a value"). An option may be given more than once: `handle` sees
/// each. Positional arguments reach `handle` too (is_option tells them apart). `handle` returns
/// false for an argument it does not take, and `fail` is called naming it ("unknown option" or
/// "unexpected argument"). `fail` is the tool's usage error and does not return.
template <class Handle>
void for_each_option(int argc, char** argv, const char* usage, Fail fail, Handle&& handle) {
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "-h" || arg == "--help") {
      std::cout << usage;
      std::exit(0);
    }
    auto value = [&]() -> std::string {
      if (i + 1 >= argc) fail(arg + " needs a value");
      return argv[++i];
    };
    if (!handle(arg, value)) fail((is_option(arg) ? "unknown option '" : "unexpected argument '") + arg + "'");
  }
}

}  // namespace telegrasp::cli
