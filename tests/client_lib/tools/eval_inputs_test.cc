// telegrasp-eval's inputs (client_lib/tools/eval/eval_inputs.h): --stretch scales each object
// about its centre of mass, its mass with its volume; the stretched box's bounds, mass and class
// are the hand-computed ones.
#include "eval_inputs.h"
#include "test_meshes.h"

#include <gtest/gtest.h>

namespace telegrasp::eval {
namespace {

TEST(EvalInputsTest, StretchScalesTheMeshAboutItsCentreAndTheMassWithTheVolume) {
  const sim::ObjectModelPtr box =
      sim::make_object_model("box", sim::testing::box_mesh(Eigen::Vector3d(0.03, 0.02, 0.01)), 0.2, "test box");
  const std::vector<sim::ObjectModelPtr> out = stretched({box}, Eigen::Vector3d(2, 1.5, 0.5));
  ASSERT_EQ(out.size(), 1u);
  const sim::ObjectModel& s = *out[0];
  EXPECT_EQ(s.name, "box");
  EXPECT_NE(s.source.find("test box stretched x2 y1.5 z0.5"), std::string::npos) << s.source;
  EXPECT_NEAR(s.mass_kg, 0.2 * 1.5, 1e-12);
  EXPECT_TRUE(s.p_ObjectMax.isApprox(Eigen::Vector3d(0.06, 0.03, 0.005), 1e-9)) << s.p_ObjectMax.transpose();
  EXPECT_TRUE(s.p_ObjectMin.isApprox(Eigen::Vector3d(-0.06, -0.03, -0.005), 1e-9)) << s.p_ObjectMin.transpose();
  EXPECT_NEAR(s.mass_properties.volume, 0.12 * 0.06 * 0.01, 1e-12);
  EXPECT_EQ(s.shape.shape, sim::ShapeClass::kBox);
  EXPECT_TRUE(s.shape.half_extent.isApprox(Eigen::Vector3d(0.005, 0.03, 0.06), 1e-6))
      << s.shape.half_extent.transpose();
  // The input is left as it was.
  EXPECT_TRUE(box->p_ObjectMax.isApprox(Eigen::Vector3d(0.03, 0.02, 0.01), 1e-9));
}

}  // namespace
}  // namespace telegrasp::eval
