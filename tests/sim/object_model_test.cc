// Tests sim/src/object_model.cc: a model built from a mesh already in its model frame (as a client
// receives it) keeps that frame, its mass and its mesh, and matches the model it was taken from.
#include "telegrasp/sim/mesh_loading.h"
#include "telegrasp/sim/object_model.h"

#include "test_meshes.h"

#include <gtest/gtest.h>

#include <cmath>

namespace telegrasp::sim {
namespace {

// A 4 x 6 x 10 cm box whose centre is off the origin by `offset`.
TriangleMesh offset_box(const Eigen::Vector3d& offset) {
  return translated(testing::box_mesh({0.02, 0.03, 0.05}), offset);
}

// Not recentred: the box keeps its place, so poses given in the sender's frame still apply.
TEST(ObjectModelTest, InModelFrameKeepsTheFrameAndTheMass) {
  const Eigen::Vector3d offset(0.01, -0.02, 0.03);
  const ObjectModelPtr m = make_object_model_in_model_frame("box", offset_box(offset), 0.7, "test", {1, 2, 3});
  EXPECT_EQ(m->name, "box");
  EXPECT_EQ(m->source, "test");
  EXPECT_EQ(m->mass_kg, 0.7);
  EXPECT_EQ(m->p_OriginalCenterOfMass, Eigen::Vector3d(1, 2, 3));
  constexpr double kTolerance = 1e-12;
  EXPECT_TRUE(m->p_ObjectMin.isApprox(offset - Eigen::Vector3d(0.02, 0.03, 0.05), kTolerance));
  EXPECT_TRUE(m->p_ObjectMax.isApprox(offset + Eigen::Vector3d(0.02, 0.03, 0.05), kTolerance));
  EXPECT_NEAR(m->mass_properties.volume, 0.04 * 0.06 * 0.1, kTolerance);
  EXPECT_TRUE(m->mass_properties.centroid.isApprox(offset, kTolerance));
  // The distance structure is over the mesh where it is: the box's centre is 2 cm inside.
  EXPECT_NEAR(m->distance.signed_distance(offset), -0.02, kTolerance);
}

// make_object_model's output, rebuilt in its own frame, is the same model.
TEST(ObjectModelTest, InModelFrameRebuildsARecentredModel) {
  const ObjectModelPtr original = make_object_model("box", offset_box({0.1, 0.2, 0.3}), 0.5, "test");
  const ObjectModelPtr rebuilt = make_object_model_in_model_frame("box", original->mesh, original->mass_kg, "rebuilt",
                                                                  original->p_OriginalCenterOfMass);
  EXPECT_EQ(rebuilt->mesh.triangles, original->mesh.triangles);
  EXPECT_EQ(rebuilt->p_ObjectMin, original->p_ObjectMin);
  EXPECT_EQ(rebuilt->p_ObjectMax, original->p_ObjectMax);
  EXPECT_EQ(rebuilt->p_OriginalCenterOfMass, original->p_OriginalCenterOfMass);
  EXPECT_NEAR(rebuilt->mass_properties.volume, original->mass_properties.volume, 1e-15);
  EXPECT_TRUE(
      rebuilt->mass_properties.inertia_per_density.isApprox(original->mass_properties.inertia_per_density, 1e-12));
}

// Caller mistakes name the source and what is wrong.
TEST(ObjectModelTest, InModelFrameRefusesBrokenMeshes) {
  auto message = [](TriangleMesh mesh) {
    try {
      make_object_model_in_model_frame("x", std::move(mesh), 1.0, "wire");
    } catch (const MeshLoadError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_EQ(message({}), "wire: the mesh has no triangle");
  TriangleMesh bad_index = testing::box_mesh({0.01, 0.01, 0.01});
  bad_index.triangles[3][1] = 8;
  EXPECT_EQ(message(bad_index), "wire: triangle index 8 is past the 8 vertices");
  TriangleMesh nan = testing::box_mesh({0.01, 0.01, 0.01});
  nan.vertices[2].y() = std::nan("");
  EXPECT_EQ(message(nan), "wire: the mesh has a non-finite vertex coordinate");
  TriangleMesh flat = testing::box_mesh({0.01, 0.01, 0.01});
  for (Eigen::Vector3d& v : flat.vertices) v.z() = 0;
  EXPECT_NE(message(flat).find("wire: the mesh encloses no volume"), std::string::npos);
}

}  // namespace
}  // namespace telegrasp::sim
