// What the protocol runner and its participants agree on: the paper's object order, the models
// (meshes with built-in stand-ins for what is missing), the operator model of each participant,
// and where each object is spawned.
#pragma once

#include "telegrasp/sim/object_model.h"
#include "telegrasp/sim/scripted_operator.h"

#include <Eigen/Geometry>

#include <cstdint>
#include <map>
#include <string>
#include <vector>

namespace telegrasp::eval {

/// The 30 YCB objects of the paper's experiment, in the order they were presented (the labels
/// a..ad of the paper's per-object figures).
const std::vector<std::string>& paper_object_order();

/// The models of a protocol run: every mesh in `objects_dir` (none if empty), plus the built-in
/// stand-in of each protocol object that has no mesh there (their names go to `standins`).
/// Throws what sim::load_protocol_object_dir throws.
std::map<std::string, sim::ObjectModelPtr> protocol_models(const std::string& objects_dir,
                                                           std::vector<std::string>* standins);

/// The operator model of one participant: the group's skill profile (the one named `group` in
/// `profiles` if given and there, else sim::skill_profile), scaled by the person
/// (OperatorSkill::scaled): a speed factor s ~ lognormal(0, 0.15) multiplies the reach speed and
/// divides the reaction, squeeze and Fitts times; a precision factor p ~ lognormal(0, 0.2)
/// multiplies the pose errors. Drawn from (seed, participant), so a participant is the same
/// person in every mode.
sim::OperatorSkill participant_skill(const std::string& group, std::uint64_t seed, int participant,
                                     const std::vector<sim::OperatorSkill>* profiles = nullptr);

/// The skill profiles of a --skills file (sim::parse_skill_profiles). Throws std::runtime_error
/// naming the file when it cannot be read or parsed.
std::vector<sim::OperatorSkill> load_skill_file(const std::string& path);

/// The --skills flag: the profiles of `path` into `skills` (nothing when `path` is empty); false,
/// with "<tool>: --skills <why>" on stderr, when the file cannot be read or parsed.
bool load_skills_flag(const std::string& path, std::vector<sim::OperatorSkill>& skills, const std::string& tool);

/// Where object number `index` (0-based, protocol order) is spawned for `participant`: resting on
/// the table at a uniform random (x, y) in the reach area (x 0.40..0.55 m, y -0.10..0.10 m in
/// front of the operator) with a uniform random yaw. The same in every mode.
struct Placement {
  double x = 0, y = 0, yaw = 0;
};
Placement object_placement(std::uint64_t seed, int participant, int index);

/// Where the operator's right hand waits between grasps (palm down): 0.35 m from the middle of
/// the reach area.
Eigen::Isometry3d home_palm_pose();

/// Seed of the operator noise for one grasp.
std::uint64_t grasp_seed(std::uint64_t seed, int participant, int index);

}  // namespace telegrasp::eval
