// Building object models from meshes and mesh files.
#include "telegrasp/sim/object_model.h"

#include "telegrasp/sim/mesh_loading.h"

#include <algorithm>
#include <filesystem>
#include <string>

namespace telegrasp::sim {
namespace {

double max_vertex_radius(const TriangleMesh& mesh) {
  double r = 0;
  for (const Eigen::Vector3d& v : mesh.vertices) r = std::max(r, v.norm());
  return r;
}

}  // namespace

std::size_t ObjectModel::memory_bytes() const {
  return sizeof(*this) + mesh.vertices.capacity() * sizeof(Eigen::Vector3d) +
         mesh.triangles.capacity() * sizeof(mesh.triangles[0]) + distance.memory_bytes();
}

ObjectModelPtr make_object_model(const std::string& name, const TriangleMesh& mesh, double mass_kg,
                                 const std::string& source) {
  auto model = std::make_shared<ObjectModel>();
  model->name = name;
  model->source = source;
  const MassProperties raw = compute_mass_properties(mesh);
  if (!(raw.volume > 1e-12))
    throw MeshLoadError(source + ": the mesh encloses no volume (" + std::to_string(raw.volume) +
                        " m^3): it must be closed and outward-facing");
  model->p_OriginalCenterOfMass = raw.centroid;
  model->mesh = translated(mesh, -raw.centroid);
  model->mass_properties = compute_mass_properties(model->mesh);
  model->mass_kg = mass_kg > 0 ? mass_kg : model->mass_properties.volume * 500.0;
  model->p_ObjectMin = model->mesh.min_corner();
  model->p_ObjectMax = model->mesh.max_corner();
  model->max_radius = max_vertex_radius(model->mesh);
  model->shape = classify_shape(model->mesh, model->mass_properties);
  model->distance = MeshDistance(model->mesh);
  return model;
}

ObjectModelPtr make_object_model_in_model_frame(const std::string& name, TriangleMesh mesh, double mass_kg,
                                                const std::string& source,
                                                const Eigen::Vector3d& p_OriginalCenterOfMass) {
  if (mesh.triangles.empty()) throw MeshLoadError(source + ": the mesh has no triangle");
  for (const Eigen::Vector3d& v : mesh.vertices)
    if (!v.allFinite()) throw MeshLoadError(source + ": the mesh has a non-finite vertex coordinate");
  for (const auto& t : mesh.triangles)
    for (std::uint32_t i : t)
      if (i >= mesh.vertices.size())
        throw MeshLoadError(source + ": triangle index " + std::to_string(i) + " is past the " +
                            std::to_string(mesh.vertices.size()) + " vertices");
  auto model = std::make_shared<ObjectModel>();
  model->name = name;
  model->source = source;
  model->mass_properties = compute_mass_properties(mesh);
  if (!(model->mass_properties.volume > 1e-12))
    throw MeshLoadError(source + ": the mesh encloses no volume (" + std::to_string(model->mass_properties.volume) +
                        " m^3): it must be closed and outward-facing");
  model->mesh = std::move(mesh);
  model->mass_kg = mass_kg > 0 ? mass_kg : model->mass_properties.volume * 500.0;
  model->p_ObjectMin = model->mesh.min_corner();
  model->p_ObjectMax = model->mesh.max_corner();
  model->p_OriginalCenterOfMass = p_OriginalCenterOfMass;
  model->max_radius = max_vertex_radius(model->mesh);
  model->shape = classify_shape(model->mesh, model->mass_properties);
  model->distance = MeshDistance(model->mesh);
  return model;
}

ObjectModelPtr load_object_model(const std::string& path, double mass_kg, const MeshLoadLimits& limits) {
  const std::string stem = std::filesystem::path(path).stem().string();
  return make_object_model(stem, load_mesh_file(path, limits), mass_kg, path);
}

std::vector<ObjectModelPtr> load_object_dir(const std::string& dir, const MassLookup& mass_kg_of,
                                            const MeshLoadLimits& limits) {
  namespace fs = std::filesystem;
  std::error_code ec;
  if (!fs::is_directory(dir, ec)) throw MeshLoadError(dir + ": not a folder");
  std::vector<std::string> files;
  for (const auto& entry : fs::directory_iterator(dir, ec))
    if (entry.is_regular_file() && is_mesh_file(entry.path().string())) files.push_back(entry.path().string());
  if (files.empty()) throw MeshLoadError(dir + ": no mesh file (PLY, OBJ, STL, glTF, ...) in this folder");
  std::sort(files.begin(), files.end());
  std::vector<ObjectModelPtr> models;
  for (const auto& f : files) {
    const double mass_kg = mass_kg_of ? mass_kg_of(std::filesystem::path(f).stem().string()) : 0.0;
    models.push_back(load_object_model(f, mass_kg, limits));
  }
  return models;
}

}  // namespace telegrasp::sim
