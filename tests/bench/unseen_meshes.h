// Stand-ins for 10k-triangle meshes nobody tuned for, generated in code: the YCB meshes under
// random rotations (the BVH is axis-aligned) and procedural shapes like the slow unseen ones
// (a long thin marker, a spoon, a toy airplane), each also triangulated irregularly (slivers).
#pragma once

#include "telegrasp/sim/triangle_mesh.h"

#include <string>
#include <vector>

namespace telegrasp::sim::bench {

/// One generated mesh and the name the bench shows it under.
struct NamedMesh {
  std::string name;
  TriangleMesh mesh;
};

/// `mesh` turned by a random rotation drawn from `seed` (about its vertex centroid).
TriangleMesh randomly_rotated(const TriangleMesh& mesh, unsigned seed);

/// The procedural set: marker (capped cylinder 0.12 x 0.018 m with a conical tip), spoon (thin
/// shallow bowl on a thin bent handle), toy airplane (fuselage, thin wings, tailplane and fin as
/// separate closed shells 1 mm apart), each about 10,000 triangles, in a regular and in a
/// "slivers" triangulation (uneven, jittered parameter grid, random quad diagonals), and each of
/// those under a random rotation. Closed and outward-facing; deterministic.
std::vector<NamedMesh> procedural_unseen_meshes();

}  // namespace telegrasp::sim::bench
