// The subcommands of telegrasp-eval that need only sim (no network); client_lib/tools/eval/main.cc
// dispatches to them.
#pragma once

namespace telegrasp::eval {

/// telegrasp-eval run [options]: scripted grasps in-process, no network (in_process.cc).
int run_in_process(int argc, char** argv);
/// telegrasp-eval questionnaire FILE.csv [options]: scores the paper's questionnaire
/// (questionnaire_main.cc).
int run_questionnaire(int argc, char** argv);
/// telegrasp-eval nd-bound [options]: the lowest ND an oracle pose search finds for a rig
/// (nd_bound.cc).
int run_nd_bound(int argc, char** argv);

}  // namespace telegrasp::eval
