// What the integration tests share about the programs they start: where they are, and
// ChildProcess (sim/tools/common) to run them.
#pragma once

#include "child_process.h"

#include <string>

namespace telegrasp::testing {

using tools::ChildProcess;

/// The path of the tool `name`, built next to the test program (build/bin).
std::string bin(const std::string& name);

}  // namespace telegrasp::testing
