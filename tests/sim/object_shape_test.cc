// Tests classify_shape: analytic primitives in any pose get their class, box and fill; the YCB
// meshes get the class a person would name.
#include "telegrasp/sim/object_shape.h"

#include "telegrasp/sim/mesh_loading.h"
#include "telegrasp/sim/object_model.h"
#include "test_meshes.h"

#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <numbers>

namespace telegrasp::sim {
namespace {

using testing::box_mesh;
using testing::cylinder_mesh;
using testing::uv_sphere_mesh;

// `mesh` turned by an arbitrary rotation and moved, so that no answer comes from the mesh axes.
TriangleMesh posed(TriangleMesh mesh) {
  const Eigen::Matrix3d R = (Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized()) *
                             Eigen::AngleAxisd(-1.1, Eigen::Vector3d(0.3, -1, 0.2).normalized()))
                                .toRotationMatrix();
  for (Eigen::Vector3d& v : mesh.vertices) v = R * v + Eigen::Vector3d(0.01, -0.02, 0.03);
  return mesh;
}

ObjectShape shape_of(const TriangleMesh& mesh) { return classify_shape(mesh, compute_mass_properties(mesh)); }

TEST(ObjectShapeTest, ABoxIsItsOwnBoxFilledToOne) {
  const ObjectShape s = shape_of(posed(box_mesh({0.08, 0.02, 0.05})));
  EXPECT_EQ(s.shape, ShapeClass::kBox);
  // The 2-degree search over the principal axes finds the box exactly (its axes are principal).
  EXPECT_NEAR(s.half_extent.x(), 0.02, 1e-9);
  EXPECT_NEAR(s.half_extent.y(), 0.05, 1e-9);
  EXPECT_NEAR(s.half_extent.z(), 0.08, 1e-9);
  EXPECT_NEAR(s.fill, 1.0, 1e-9);
  EXPECT_NEAR(s.X_ObjectBox.linear().determinant(), 1.0, 1e-12);
  EXPECT_EQ(s.axis, -1);
}

TEST(ObjectShapeTest, ASphereFillsPiOverSixOfItsCube) {
  const ObjectShape s = shape_of(posed(uv_sphere_mesh(0.035, 60, 120)));
  EXPECT_EQ(s.shape, ShapeClass::kSphere);
  // The tessellation's solid lies within the sphere: fill a little under pi/6.
  EXPECT_NEAR(s.fill, std::numbers::pi / 6, 0.01);
  EXPECT_NEAR(s.half_extent.z(), 0.035, 1e-3);
}

// A rod along its longest side, a disk across its shortest; fill pi/4 (less the polygon's loss).
TEST(ObjectShapeTest, CylindersAreRodsOrDisksWithTheirAxis) {
  const ObjectShape rod = shape_of(posed(cylinder_mesh(0.02, 0.07, 96)));
  EXPECT_EQ(rod.shape, ShapeClass::kCylinder);
  EXPECT_EQ(rod.axis, 2);
  EXPECT_NEAR(rod.half_extent.z(), 0.07, 1e-9);
  EXPECT_NEAR(rod.fill, std::numbers::pi / 4, 0.01);
  const ObjectShape disk = shape_of(posed(cylinder_mesh(0.05, 0.02, 96)));
  EXPECT_EQ(disk.shape, ShapeClass::kCylinder);
  EXPECT_EQ(disk.axis, 0);
  EXPECT_NEAR(disk.half_extent.x(), 0.02, 1e-9);
  // The cylinder's axis is the box's x axis (in the object frame: the posed z axis).
  const Eigen::Vector3d axis = disk.X_ObjectBox.linear().col(0);
  const TriangleMesh unit = posed(box_mesh({0, 0, 1}));  // two points on the posed z axis
  const Eigen::Vector3d z = (unit.vertices[4] - unit.vertices[0]).normalized();
  EXPECT_NEAR(std::abs(axis.dot(z)), 1.0, 1e-9);
}

// Thickness 2 V / A of a box with sides a, b, c: abc / (ab + bc + ca) (V = abc, A = 2 (ab + bc + ca)).
TEST(ObjectShapeTest, PlatesAreThinAndRodsAreNot) {
  const ObjectShape plate = shape_of(posed(box_mesh({0.1, 0.03, 0.003})));  // 200 x 60 x 6 mm
  const double a = 0.2, b = 0.06, c = 0.006;
  EXPECT_NEAR(plate.thickness, a * b * c / (a * b + b * c + c * a), 1e-12);
  EXPECT_EQ(plate.shape, ShapeClass::kBox);  // a flat box is still a box: it fills its box
  // An L of two such plates fills half its box: thin.
  TriangleMesh l = box_mesh({0.1, 0.03, 0.003});
  TriangleMesh leg = box_mesh({0.003, 0.03, 0.05});
  for (Eigen::Vector3d& v : leg.vertices) v += Eigen::Vector3d(0.097, 0, 0.053);
  const auto base = static_cast<std::uint32_t>(l.vertices.size());
  l.vertices.insert(l.vertices.end(), leg.vertices.begin(), leg.vertices.end());
  for (auto t : leg.triangles) l.triangles.push_back({t[0] + base, t[1] + base, t[2] + base});
  const ObjectShape ell = shape_of(posed(l));
  EXPECT_LT(ell.fill, 0.5);
  EXPECT_EQ(ell.shape, ShapeClass::kThin);
  // As thin, but as narrow as it is thick: a rod, a small cylinder.
  const ObjectShape pencil = shape_of(posed(cylinder_mesh(0.004, 0.08, 48)));
  EXPECT_EQ(pencil.shape, ShapeClass::kCylinder);
  EXPECT_EQ(pencil.axis, 2);
}

// Two boxes crossing (a plus sign in section) fill too little of their box to be a box, and
// are too thick (2 V / A = 24 mm) to be thin.
TEST(ObjectShapeTest, AnythingElseIsOther) {
  TriangleMesh cross = box_mesh({0.06, 0.015, 0.04});
  const TriangleMesh bar = box_mesh({0.015, 0.06, 0.04});
  const auto base = static_cast<std::uint32_t>(cross.vertices.size());
  cross.vertices.insert(cross.vertices.end(), bar.vertices.begin(), bar.vertices.end());
  for (auto t : bar.triangles) cross.triangles.push_back({t[0] + base, t[1] + base, t[2] + base});
  EXPECT_EQ(shape_of(posed(cross)).shape, ShapeClass::kOther);
  EXPECT_EQ(shape_of(TriangleMesh{}).shape, ShapeClass::kOther);
}

TEST(ObjectShapeTest, NamesReadBack) {
  for (ShapeClass s : {ShapeClass::kSphere, ShapeClass::kCylinder, ShapeClass::kBox, ShapeClass::kThin, ShapeClass::kOther})
    EXPECT_EQ(parse_shape_class(shape_class_name(s)), s);
  EXPECT_FALSE(parse_shape_class("ball").has_value());
  EXPECT_FALSE(parse_shape_class("").has_value());
}

// The YCB scans: the cans are cylinders, the balls and fruit spheres, the boxes boxes, the
// flatware thin.
TEST(ObjectShapeTest, YcbMeshesGetTheClassAPersonWouldName) {
  const char* dir = std::getenv("TELEGRASP_YCB_DIR");
  if (!dir || !std::filesystem::exists(std::filesystem::path(dir) / "005_tomato_soup_can.ply"))
    GTEST_SKIP() << "TELEGRASP_YCB_DIR is not set or holds no YCB meshes (ctest sets it); skipping";
  const std::vector<std::pair<const char*, ShapeClass>> expected = {
      {"002_master_chef_can", ShapeClass::kCylinder}, {"005_tomato_soup_can", ShapeClass::kCylinder},
      {"003_cracker_box", ShapeClass::kBox},          {"004_sugar_box", ShapeClass::kBox},
      {"009_gelatin_box", ShapeClass::kBox},          {"055_baseball", ShapeClass::kSphere},
      {"017_orange", ShapeClass::kSphere},            {"014_lemon", ShapeClass::kSphere},
      {"032_knife", ShapeClass::kThin},               {"030_fork", ShapeClass::kThin},
      {"033_spatula", ShapeClass::kThin},
  };
  for (const auto& [name, shape] : expected) {
    const ObjectModelPtr model = load_object_model((std::filesystem::path(dir) / (std::string(name) + ".ply")).string(), 0.0);
    EXPECT_EQ(shape_class_name(model->shape.shape), std::string(shape_class_name(shape)))
        << name << ": box " << 2000 * model->shape.half_extent.transpose() << " mm, fill " << model->shape.fill;
  }
}

}  // namespace
}  // namespace telegrasp::sim
