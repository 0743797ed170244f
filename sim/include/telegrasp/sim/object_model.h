// ObjectModel: an immutable graspable object (exact mesh, distance structure, mass).
#pragma once

#include "telegrasp/sim/mass_properties.h"
#include "telegrasp/sim/mesh_distance.h"
#include "telegrasp/sim/mesh_loading.h"
#include "telegrasp/sim/object_shape.h"
#include "telegrasp/sim/triangle_mesh.h"

#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace telegrasp::sim {

/// An object's geometry and mass in its own frame, whose origin is the centre of mass.
/// Fingers are tested against `distance` (the exact mesh); physics uses a convex hull of it.
struct ObjectModel {
  std::string name;  ///< e.g. "032_knife".
  std::string source;  ///< File path, or "built-in stand-in".
  TriangleMesh mesh;  ///< Recentred: the centre of mass is the origin.
  MeshDistance distance;  ///< BVH over `mesh` for exact queries.
  MassProperties mass_properties;
  double mass_kg = 0;
  Eigen::Vector3d p_ObjectMin{0, 0, 0}, p_ObjectMax{0, 0, 0};  ///< Bounds of `mesh`.
  Eigen::Vector3d p_OriginalCenterOfMass{0, 0, 0};  ///< Where the origin was in the source file's frame.
  double max_radius = 0;  ///< Largest distance from the centre of mass to a vertex, m (grasp quality's torque scale).
  ObjectShape shape;  ///< Its class and oriented box (classify_shape); a scene may set the class.
  std::optional<double> friction;  ///< Coulomb friction coefficient mu against the hand; unset: the rig's.

  /// Heap bytes held by this model (mesh and distance structure).
  [[nodiscard]] std::size_t memory_bytes() const;
};

using ObjectModelPtr = std::shared_ptr<const ObjectModel>;

/// Builds a model from a clean closed mesh: recentres it on its centre of mass and builds the
/// distance structure. Mass is `mass_kg` if > 0, else volume x 500 kg/m^3.
/// Throws MeshLoadError (naming `source`) if the mesh encloses no volume.
ObjectModelPtr make_object_model(const std::string& name, const TriangleMesh& mesh, double mass_kg,
                                 const std::string& source);

/// Builds a model from a mesh that is already in its model frame (origin at its centre of mass),
/// such as the geometry a telegrasp server publishes: it is not recentred, so poses and contact
/// points given in that frame apply unchanged. Computes the mass properties, bounds and distance
/// structure; `mass_kg` is kept as given (if > 0, else volume x 500 kg/m^3) and
/// `p_OriginalCenterOfMass` is stored as is. Throws MeshLoadError naming `source` if the mesh has
/// no triangle, an index past its vertices, a non-finite coordinate, or encloses no volume.
ObjectModelPtr make_object_model_in_model_frame(
    const std::string& name, TriangleMesh mesh, double mass_kg, const std::string& source,
    const Eigen::Vector3d& p_OriginalCenterOfMass = Eigen::Vector3d::Zero());

/// Loads a mesh file as an object named after the file stem, of mass `mass_kg` (<= 0: volume x
/// 500 kg/m^3, as make_object_model), read within `limits`. Throws MeshLoadError naming the file.
ObjectModelPtr load_object_model(const std::string& path, double mass_kg, const MeshLoadLimits& limits = {});

/// The mass in kg of the object a file stem names (<= 0: unknown, taken from its volume).
using MassLookup = std::function<double(const std::string& stem)>;

/// Every mesh file in `dir` (sorted by name), each of the mass `mass_kg_of` gives its stem (null:
/// all from their volumes); throws MeshLoadError if `dir` is not a folder, holds no mesh file, or
/// a file fails to load (each read within `limits`).
std::vector<ObjectModelPtr> load_object_dir(const std::string& dir, const MassLookup& mass_kg_of,
                                            const MeshLoadLimits& limits = {});

}  // namespace telegrasp::sim
