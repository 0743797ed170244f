// What the in-process commands (telegrasp-eval, telegrasp-eval nd-bound) load and write.
#pragma once

#include "telegrasp/sim/hand_rig.h"
#include "telegrasp/sim/object_model.h"

#include <fstream>
#include <memory>
#include <string>
#include <vector>

namespace telegrasp::eval {

struct EvalInputs {
  std::shared_ptr<const sim::HandRig> rig;
  std::vector<sim::ObjectModelPtr> models;
};

/// The rig at `rig_path` (empty: the built-in human_right) and every mesh in `objects_dir`
/// (empty: the 30 built-in stand-ins). Throws with a message naming the bad file (a mesh
/// problem as "--objects <folder or file>: <what is wrong>", the way every tool says it).
EvalInputs load_eval_inputs(const std::string& rig_path, const std::string& objects_dir);

/// Opens `json_path` (if given) into `json_out` and creates `svg_dir` (if given), so a long run
/// fails before it starts, not after. Returns "" or what went wrong, naming the option and path.
std::string prepare_outputs(const std::string& json_path, std::ofstream& json_out, const std::string& svg_dir);

}  // namespace telegrasp::eval
