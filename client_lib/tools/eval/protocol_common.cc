#include "protocol_common.h"

#include "telegrasp/sim/standin_objects.h"

#include <cmath>
#include <fstream>
#include <iostream>
#include <numbers>
#include <optional>
#include <random>
#include <set>
#include <sstream>
#include <stdexcept>

namespace telegrasp::eval {
namespace {

// One generator per purpose and person, so that adding a draw to one does not shift the others.
std::mt19937_64 generator(std::uint64_t seed, std::uint64_t purpose, int participant, int index = 0) {
  std::seed_seq seq{static_cast<std::uint32_t>(seed), static_cast<std::uint32_t>(seed >> 32),
                    static_cast<std::uint32_t>(purpose), static_cast<std::uint32_t>(participant),
                    static_cast<std::uint32_t>(index)};
  return std::mt19937_64(seq);
}

}  // namespace

const std::vector<std::string>& paper_object_order() {
  static const std::vector<std::string> order = [] {
    std::vector<std::string> names;
    for (const sim::ProtocolObject& o : sim::protocol_objects_in_paper_order()) names.push_back(o.name);
    return names;
  }();
  return order;
}

std::map<std::string, sim::ObjectModelPtr> protocol_models(const std::string& objects_dir,
                                                           std::vector<std::string>* standins) {
  std::map<std::string, sim::ObjectModelPtr> models;
  if (!objects_dir.empty())
    for (auto& m : sim::load_protocol_object_dir(objects_dir)) models.emplace(m->name, std::move(m));
  for (const auto& o : sim::protocol_objects()) {
    if (models.count(o.name)) continue;
    models.emplace(o.name, sim::make_standin_model(o));
    if (standins) standins->push_back(o.name);
  }
  return models;
}

sim::OperatorSkill participant_skill(const std::string& group, std::uint64_t seed, int participant,
                                     const std::vector<sim::OperatorSkill>* profiles) {
  std::optional<sim::OperatorSkill> base;
  if (profiles)
    for (const sim::OperatorSkill& p : *profiles)
      if (p.name == group) base = p;
  if (!base) base = sim::skill_profile(group);
  auto rng = generator(seed, 1, participant);
  const double speed = std::exp(std::normal_distribution<double>(0.0, 0.15)(rng));
  const double precision = std::exp(std::normal_distribution<double>(0.0, 0.2)(rng));
  return base->scaled(speed, precision);
}

std::vector<sim::OperatorSkill> load_skill_file(const std::string& path) {
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  if (!in) throw std::runtime_error(path + ": cannot read");
  try {
    return sim::parse_skill_profiles(text.str());
  } catch (const std::invalid_argument& e) {
    throw std::runtime_error(path + ": " + e.what());
  }
}

bool load_skills_flag(const std::string& path, std::vector<sim::OperatorSkill>& skills, const std::string& tool) {
  try {
    if (!path.empty()) skills = load_skill_file(path);
    return true;
  } catch (const std::exception& e) {
    std::cerr << tool << ": --skills " << e.what() << "\n";
    return false;
  }
}

Placement object_placement(std::uint64_t seed, int participant, int index) {
  auto rng = generator(seed, 2, participant, index);
  Placement p;
  p.x = std::uniform_real_distribution<double>(0.40, 0.55)(rng);
  p.y = std::uniform_real_distribution<double>(-0.10, 0.10)(rng);
  p.yaw = std::uniform_real_distribution<double>(-std::numbers::pi, std::numbers::pi)(rng);
  return p;
}

Eigen::Isometry3d home_palm_pose() {
  Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
  X.translation() = Eigen::Vector3d(0.20, -0.20, 0.30);
  return X;
}

std::uint64_t grasp_seed(std::uint64_t seed, int participant, int index) {
  return generator(seed, 3, participant, index)();
}

}  // namespace telegrasp::eval
