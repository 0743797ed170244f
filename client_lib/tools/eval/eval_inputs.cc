#include "eval_inputs.h"

#include "telegrasp/sim/mesh_loading.h"
#include "telegrasp/sim/standin_objects.h"

#include <filesystem>
#include <iostream>
#include <sstream>
#include <stdexcept>

namespace telegrasp::eval {

std::string rig_path_or_default(const std::string& rig_path) {
  return rig_path.empty() ? sim::HandRig::builtin_path(sim::HandRig::default_human(sim::HandSide::kRight)) : rig_path;
}

EvalInputs load_eval_inputs(const std::string& rig_path, const std::string& objects_dir) {
  EvalInputs in;
  in.rig = std::make_shared<const sim::HandRig>(
      sim::HandRig::load(rig_path_or_default(rig_path)));
  if (objects_dir.empty()) {
    for (const auto& o : sim::protocol_objects()) in.models.push_back(sim::make_standin_model(o));
  } else {
    std::cerr << "loading meshes from " << objects_dir << " ...\n";
    try {
      in.models = sim::load_protocol_object_dir(objects_dir);
    } catch (const sim::MeshLoadError& e) {  // names the folder or the file in it
      throw std::runtime_error(std::string("--objects ") + e.what());
    }
  }
  return in;
}

std::vector<sim::ObjectModelPtr> stretched(const std::vector<sim::ObjectModelPtr>& models,
                                           const Eigen::Vector3d& factors) {
  std::vector<sim::ObjectModelPtr> out;
  out.reserve(models.size());
  for (const sim::ObjectModelPtr& m : models) {
    sim::TriangleMesh mesh = m->mesh;
    for (Eigen::Vector3d& v : mesh.vertices) v = v.cwiseProduct(factors);
    std::ostringstream source;
    source << m->source << " stretched x" << factors.x() << " y" << factors.y() << " z" << factors.z();
    out.push_back(sim::make_object_model(m->name, mesh, m->mass_kg * factors.prod(), source.str()));
  }
  return out;
}

std::string prepare_outputs(const std::string& json_path, std::ofstream& json_out, const std::string& svg_dir) {
  if (!svg_dir.empty()) {
    std::error_code ec;
    std::filesystem::create_directories(svg_dir, ec);
    if (!std::filesystem::is_directory(svg_dir)) return "--svg " + svg_dir + ": cannot create the folder";
  }
  if (!json_path.empty()) {
    json_out.open(json_path);
    if (!json_out) return "--json " + json_path + ": cannot write";
  }
  return "";
}

}  // namespace telegrasp::eval
