// What the in-process commands (telegrasp-eval, telegrasp-eval nd-bound) load and write.
#pragma once

#include "telegrasp/idl/cli.h"
#include "telegrasp/sim/hand_rig.h"
#include "telegrasp/sim/object_model.h"

#include <Eigen/Core>
#include <cstdint>
#include <fstream>
#include <memory>
#include <string>
#include <vector>

namespace telegrasp::eval {

struct EvalInputs {
  std::shared_ptr<const sim::HandRig> rig;
  std::vector<sim::ObjectModelPtr> models;
};

/// The right hand's rig file: `rig_path`, or the built-in default's (HandRig::default_human) when
/// empty.
std::string rig_path_or_default(const std::string& rig_path);

/// The rig at `rig_path` (empty: the built-in human_right_opposable) and every mesh in `objects_dir`
/// (empty: the 30 built-in stand-ins). Throws with a message naming the bad file (a mesh
/// problem as "--objects <folder or file>: <what is wrong>", the way every tool says it).
EvalInputs load_eval_inputs(const std::string& rig_path, const std::string& objects_dir);

/// Each model's mesh stretched by `factors` along its frame's x, y and z about its centre of mass,
/// its mass by their product (the same density): shapes nobody tuned the planner or the rig for.
/// The name stays; the source says the stretch. Throws MeshLoadError if a stretched mesh encloses no volume.
std::vector<sim::ObjectModelPtr> stretched(const std::vector<sim::ObjectModelPtr>& models,
                                           const Eigen::Vector3d& factors);

/// Opens `json_path` (if given) into `json_out` and creates `svg_dir` (if given), so a long run
/// fails before it starts, not after. Returns "" or what went wrong, naming the option and path.
std::string prepare_outputs(const std::string& json_path, std::ofstream& json_out, const std::string& svg_dir);

/// Applies `flag` onto `o` if it is one of the flags both in-process commands take: --objects,
/// --rig, --json, --svg, --jobs (--threads, its old name, warns) and --seed. `o` is any options
/// type with the members objects_dir, rig_path, json_path, svg_dir, threads and seed; `fail` is
/// the command's usage error.
template <class Options, class Value>
bool parse_offline_flag(const char* tool, const std::string& flag, const Value& value, Options& o, cli::Fail fail) {
  if (cli::text_flag(flag, value,
                     {{"--objects", &o.objects_dir}, {"--rig", &o.rig_path}, {"--json", &o.json_path},
                      {"--svg", &o.svg_dir}}))
    return true;
  if (cli::is_flag(tool, flag, "--jobs", "--threads"))
    o.threads = static_cast<int>(cli::parse_whole(flag, value(), 1, 64, fail));
  else if (flag == "--seed")
    o.seed = static_cast<std::uint64_t>(cli::parse_whole(flag, value(), 0, 1L << 62, fail));
  else
    return false;
  return true;
}

}  // namespace telegrasp::eval
