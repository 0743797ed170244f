// The 30 objects of the paper's protocol as procedural meshes, so the project runs with no files,
// and mesh files loaded with the protocol objects' real masses.
#pragma once

#include "telegrasp/sim/object_model.h"
#include "telegrasp/sim/triangle_mesh.h"

#include <Eigen/Core>

#include <optional>
#include <string>
#include <vector>

namespace telegrasp::sim {

/// One object of the evaluation protocol (shared/data/ycb/README.md), in protocol order.
struct ProtocolObject {
  std::string id;  ///< "002", "072-a", ...
  std::string name;  ///< YCB file stem, e.g. "002_master_chef_can".
  Eigen::Vector3d extent;  ///< Bounding-box size in metres (x, y, z), as the YCB table gives it.
  double mass_kg;  ///< Typical real mass, for dynamics.
  int paper_order = 0;  ///< Place in the paper's presentation order (0 = its label a, 29 = ad).
};

/// All 30 protocol objects in the protocol's fixed order (by YCB id).
const std::vector<ProtocolObject>& protocol_objects();

/// The same objects in the order the paper presented them to its participants (paper_order).
std::vector<ProtocolObject> protocol_objects_in_paper_order();

/// The protocol object whose name or id matches (e.g. "032_knife", "032", "knife").
std::optional<ProtocolObject> find_protocol_object(const std::string& name_or_id);

/// A closed, outward-facing procedural stand-in for a protocol object: its shape class
/// (cylinder, box, ellipsoid, handle + head, flat blade, ...) at the object's extent, resting
/// on z = 0 and centred in x/y, with between 500 and 10000 triangles.
TriangleMesh make_standin_mesh(const ProtocolObject& object);

/// The built-in procedural stand-in of a protocol object.
ObjectModelPtr make_standin_model(const ProtocolObject& object);

/// load_object_model, a protocol object (named by the file stem) getting its real mass.
ObjectModelPtr load_protocol_object_model(const std::string& path, const MeshLoadLimits& limits = {});

/// load_object_dir, the protocol objects among the files getting their real masses.
std::vector<ObjectModelPtr> load_protocol_object_dir(const std::string& dir, const MeshLoadLimits& limits = {});

}  // namespace telegrasp::sim
