// The subcommands of telegrasp-eval; main.cc picks one from the first argument. The offline ones
// (run, nd-bound, questionnaire) live in sim/tools/eval.
#pragma once

#include "offline_commands.h"

namespace telegrasp::eval {

/// telegrasp-eval protocol [options]: the paper's experiment over DDS (protocol.cc).
int run_protocol(int argc, char** argv);
/// telegrasp-eval participant [options]: one bot participant of a protocol run, started by
/// run_protocol in its own process (participant.cc).
int run_participant(int argc, char** argv);

}  // namespace telegrasp::eval
