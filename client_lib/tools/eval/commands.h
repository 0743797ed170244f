// The subcommands of telegrasp-eval; main.cc picks one from the first argument. run, nd-bound
// and questionnaire need only sim (the library telegrasp_eval_offline); protocol and participant
// run over DDS.
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
/// telegrasp-eval protocol [options]: the paper's experiment over DDS (protocol.cc).
int run_protocol(int argc, char** argv);
/// telegrasp-eval participant [options]: one bot participant of a protocol run, started by
/// run_protocol in its own process (participant.cc).
int run_participant(int argc, char** argv);

}  // namespace telegrasp::eval
