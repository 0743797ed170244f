// A scripted operator's skill profile given on the command line (--skill, --group).
#pragma once

#include "telegrasp/idl/cli.h"
#include "telegrasp/sim/scripted_operator.h"

#include <stdexcept>
#include <string>

namespace telegrasp::tools {

/// `name`, if it names a skill profile (perfect, experienced, inexperienced); otherwise calls
/// `fail`, the tool's usage error, with a message naming `flag`.
inline std::string parse_skill(const std::string& flag, const std::string& name, cli::Fail fail) {
  try {
    (void)sim::skill_profile(name);
  } catch (const std::invalid_argument&) {
    fail(flag + " expects perfect, experienced or inexperienced, got '" + name + "'");
  }
  return name;
}

}  // namespace telegrasp::tools
