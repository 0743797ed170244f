// Tests grasp_svg.h: the picture of a hand-made grasp (a box, two capsules, one contact) has the
// expected elements and names no URL; the readable view looks from the side the finger is on;
// orbit views are orthonormal and right-handed; decimation meets its triangle budget and keeps the
// shape's bounds.
#include "grasp_svg.h"

#include "test_meshes.h"

#include <gtest/gtest.h>

#include <cmath>
#include <regex>
#include <set>
#include <string>

namespace telegrasp::sim {
namespace {

constexpr double kHalf = 0.03;  // m: half edge of the test box
constexpr double kRadius = 0.008;

int count(const std::string& text, const std::string& what) {
  int n = 0;
  for (std::size_t at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++n;
  return n;
}

// A 6 cm box at the world origin; a blocked capsule lying against its +x face, touching it at
// (kHalf, 0, 0) with normal +x; a free capsule above the box.
struct BoxGrasp {
  ObjectModelPtr model = make_object_model("box", testing::box_mesh(Eigen::Vector3d::Constant(kHalf)), 0.1, "test");
  GraspSnapshot snap;
  BoxGrasp() {
    snap.title = "box <grasp>";
    snap.model = model.get();
    snap.capsules.push_back({{kHalf + kRadius, -0.02, 0}, {kHalf + kRadius, 0.02, 0}, kRadius, true});
    snap.capsules.push_back({{-0.02, 0, kHalf + 0.02}, {0.02, 0, kHalf + 0.02}, kRadius, false});
    snap.contacts.push_back({{kHalf, 0, 0}, {1, 0, 0}});
  }
};

TEST(GraspSvgTest, PictureOfAHandMadeGraspHasItsElementsAndNoUrl) {
  const BoxGrasp g;
  const std::string svg = render_view_svg(g.snap, orbit_view(30, 20));

  // One inline <svg> element, titled (escaped), with nothing to fetch.
  EXPECT_EQ(svg.rfind("<svg class=\"grasp\"", 0), 0u);
  EXPECT_EQ(count(svg, "<svg"), 1);
  EXPECT_EQ(count(svg, "</svg>"), 1);
  EXPECT_NE(svg.find("<title>box &lt;grasp> ("), std::string::npos);
  EXPECT_EQ(svg.find("http"), std::string::npos);
  EXPECT_EQ(svg.find("xmlns"), std::string::npos);
  EXPECT_EQ(svg.find("href"), std::string::npos);
  EXPECT_EQ(svg.find("<image"), std::string::npos);

  // Two capsule outlines, one of them blocked; both in front of the box from this side, so no
  // dashed "behind" outline; one contact dot with its normal tick, not hidden.
  EXPECT_EQ(count(svg, "class=\"capsule"), 2);
  EXPECT_EQ(count(svg, "class=\"capsule blocked\""), 1);
  EXPECT_EQ(count(svg, "class=\"capsule-hidden\""), 0);
  EXPECT_EQ(count(svg, "<circle class=\"contact\""), 1);
  EXPECT_EQ(count(svg, "class=\"normal\""), 1);
  // The box is drawn: the three faces toward a viewer above and off its +x+y corner, two
  // triangles each, each face one flat shade.
  const auto g0 = svg.find("<g class=\"object\""), g1 = svg.find("</g>", g0);
  ASSERT_NE(g0, std::string::npos);
  const std::string object = svg.substr(g0, g1 - g0);
  EXPECT_EQ(count(object, "Z"), 6);
  std::set<std::string> fills;
  const std::regex fill(R"re(fill="(#[0-9a-f]{6})")re");
  for (auto it = std::sregex_iterator(object.begin(), object.end(), fill); it != std::sregex_iterator(); ++it)
    fills.insert((*it)[1]);
  EXPECT_EQ(fills.size(), 3u);
}

TEST(GraspSvgTest, CapsuleAndContactBehindTheObjectAreMarkedHidden) {
  const BoxGrasp g;
  // From -x the box stands between the viewer and the blocked capsule and its contact.
  const std::string svg = render_view_svg(g.snap, orbit_view(180, 0));
  EXPECT_EQ(count(svg, "class=\"capsule-hidden\""), 1);
  EXPECT_EQ(count(svg, "<circle class=\"contact hidden\""), 1);
  EXPECT_EQ(count(svg, "stroke-dasharray"), 2);  // the hidden outline and the hidden normal tick
}

TEST(GraspSvgTest, ReadableViewLooksFromTheFingersSide) {
  const BoxGrasp g;
  const View view = readable_view(g.snap);
  // The blocked capsule is on the +x side: a view from there shows it and its contact, a view
  // from -x hides both behind the box. Azimuths 0, 45 and 315 at elevations up to 50 deg have
  // toward.x >= cos 45 cos 50 = 0.45; azimuths 90 to 270 have toward.x <= 0.
  EXPECT_GT(view.toward.x(), 0.4) << view.name;
}

TEST(GraspSvgTest, OrbitViewIsOrthonormalRightHandedAndZUp) {
  // Azimuth 90, elevation 30: the viewer is at +y, above; screen right is -x.
  const View v = orbit_view(90, 30);
  const double s = 0.5, c = std::sqrt(3.0) / 2;
  EXPECT_TRUE(v.toward.isApprox(Eigen::Vector3d(0, c, s), 1e-12)) << v.toward.transpose();
  EXPECT_TRUE(v.right.isApprox(Eigen::Vector3d(-1, 0, 0), 1e-12)) << v.right.transpose();
  EXPECT_TRUE(v.up.isApprox(Eigen::Vector3d(0, -s, c), 1e-12)) << v.up.transpose();
  EXPECT_TRUE(v.right.cross(v.up).isApprox(v.toward, 1e-12));
  EXPECT_EQ(v.name, "azimuth 90\u00b0, elevation 30\u00b0");
}

TEST(GraspSvgTest, DecimationMeetsTheBudgetAndKeepsTheBounds) {
  // A UV sphere of 5 cm radius with 160 x 160 cells: 50880 triangles.
  const TriangleMesh sphere = testing::uv_sphere_mesh(0.05, 160, 160);
  ASSERT_GT(sphere.triangles.size(), 50000u);
  const DrawingMesh decimated = decimate_for_drawing(sphere, 1500);
  const TriangleMesh& drawn = decimated.mesh;
  EXPECT_LE(drawn.triangles.size(), 1500u);
  EXPECT_GT(drawn.triangles.size(), 300u);  // still a sphere, not a handful of faces
  // A cluster's vertex is a mean of vertices within one grid cell of the surface: the bounds
  // shrink by less than a cell (the grid that meets 1500 triangles here is under 40 cells wide,
  // so a cell is over 2.5 mm; 5 mm is the tolerance).
  constexpr double kBoundsTol = 0.005;
  EXPECT_NEAR(drawn.max_corner().x(), 0.05, kBoundsTol);
  EXPECT_NEAR(drawn.min_corner().z(), -0.05, kBoundsTol);
  // Every drawn triangle keeps the outward normal of the sphere where it lies: within 30 deg of
  // the direction from the centre (cells of a few degrees; a folded triangle would point inward).
  ASSERT_EQ(decimated.normals.size(), drawn.triangles.size());
  const double kCos30 = std::cos(30 * 3.14159265358979 / 180);
  for (std::size_t i = 0; i < drawn.triangles.size(); ++i) {
    const auto& t = drawn.triangles[i];
    const Eigen::Vector3d centre = (drawn.vertices[t[0]] + drawn.vertices[t[1]] + drawn.vertices[t[2]]) / 3;
    EXPECT_GT(decimated.normals[i].dot(centre.normalized()), kCos30) << "triangle " << i;
  }
  // A mesh within the budget is returned as it is, with its own normals.
  const TriangleMesh box = testing::box_mesh(Eigen::Vector3d::Constant(kHalf));
  const DrawingMesh same = decimate_for_drawing(box, 1500);
  EXPECT_EQ(same.mesh.triangles, box.triangles);
  EXPECT_TRUE(same.normals.at(0).isApprox(Eigen::Vector3d(0, 0, -1))) << same.normals.at(0).transpose();
}

}  // namespace
}  // namespace telegrasp::sim
