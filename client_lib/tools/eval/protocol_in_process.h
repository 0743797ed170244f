// One participant of a protocol run without DDS: the participant's loop (participant.cc) against
// a sim::World set up as a lockstep telegrasp-server sets up its own, in this process. The time to
// grasp is simulated time, so the records' times equal those of the DDS run for the same seed
// (README, "Calibration"); used to fit the skill profiles quickly (telegrasp-eval protocol
// --in-process).
#pragma once

#include "grasp_report.h"
#include "telegrasp/sim/hand_rig.h"
#include "telegrasp/sim/object_model.h"
#include "telegrasp/sim/scripted_operator.h"

#include <cstdint>
#include <map>
#include <memory>
#include <string>
#include <vector>

namespace telegrasp::eval {

/// Who runs, on what: the job of one (mode, participant) of a protocol run.
struct InProcessParticipant {
  std::string mode = "precise", group = "experienced";
  int participant = 1, count = 30;
  std::uint64_t seed = 1;
  sim::OperatorSkill skill;  ///< The participant's skill (participant_skill).
};

/// The grasp records of one participant, as `telegrasp-eval participant` would write them (without
/// contacts and the grasp tick's hand). `models` must hold every protocol object.
std::vector<report::Record> run_participant_in_process(const InProcessParticipant& p,
                                                       const std::map<std::string, sim::ObjectModelPtr>& models,
                                                       const std::shared_ptr<const sim::HandRig>& rig);

}  // namespace telegrasp::eval
