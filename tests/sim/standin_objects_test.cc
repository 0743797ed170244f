// Tests the protocol object table, find_protocol_object, the procedural stand-in meshes (closed,
// consistently outward, sized to the table extent, resting on z = 0, centred in x/y) and the
// loading of mesh files with the protocol objects' real masses.
#include "telegrasp/sim/standin_objects.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cctype>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <random>
#include <utility>

#include "telegrasp/sim/mass_properties.h"
#include "telegrasp/sim/mesh_loading.h"

namespace telegrasp::sim {
namespace {

/// Every directed edge appears once and its reverse once (closed, consistently oriented).
bool is_watertight_and_consistent(const TriangleMesh& mesh, std::string* problem) {
  std::map<std::pair<std::uint32_t, std::uint32_t>, int> directed;
  for (const auto& t : mesh.triangles) {
    for (int k = 0; k < 3; ++k) ++directed[{t[k], t[(k + 1) % 3]}];
  }
  for (const auto& [edge, count] : directed) {
    const auto reverse = directed.find({edge.second, edge.first});
    if (count != 1 || reverse == directed.end() || reverse->second != 1) {
      *problem = "edge " + std::to_string(edge.first) + "-" + std::to_string(edge.second) + " used " +
                 std::to_string(count) + " times, reverse " +
                 std::to_string(reverse == directed.end() ? 0 : reverse->second);
      return false;
    }
  }
  return true;
}

TEST(ProtocolObjects, ThirtyInProtocolOrder) {
  const auto& objects = protocol_objects();
  ASSERT_EQ(objects.size(), 30u);
  EXPECT_EQ(objects.front().id, "002");
  EXPECT_EQ(objects.front().name, "002_master_chef_can");
  EXPECT_EQ(objects.back().id, "072-a");
  EXPECT_EQ(objects.back().name, "072-a_toy_airplane");
  EXPECT_EQ(objects[19].name, "032_knife");
  EXPECT_TRUE(objects[5].extent.isApprox(Eigen::Vector3d(0.086, 0.086, 0.034)));  // 007 tuna
  std::set<std::string> ids;
  for (std::size_t i = 0; i < objects.size(); ++i) {
    const ProtocolObject& o = objects[i];
    EXPECT_TRUE(ids.insert(o.id).second) << o.id;
    EXPECT_EQ(o.name.rfind(o.id + "_", 0), 0u) << o.name;
    if (i > 0) {
      EXPECT_LT(objects[i - 1].id, o.id);  // Ids ascend in protocol order.
    }
    EXPECT_GT(o.mass_kg, 0.005) << o.name;
    EXPECT_LT(o.mass_kg, 2.0) << o.name;
    EXPECT_TRUE((o.extent.array() > 0.01).all() && (o.extent.array() < 0.4).all()) << o.name;
  }
}

// Expects find_protocol_object(query) to find an object whose `field` is `expected`.
void expect_found(const std::string& query, std::string ProtocolObject::*field, const std::string& expected) {
  const auto found = find_protocol_object(query);
  ASSERT_TRUE(found.has_value());
  EXPECT_EQ((*found).*field, expected);
}

TEST(ProtocolObjects, FindByIdFullNameShortName) {
  ASSERT_NO_FATAL_FAILURE(expect_found("032", &ProtocolObject::name, "032_knife"));
  ASSERT_NO_FATAL_FAILURE(expect_found("005_Tomato_Soup_Can", &ProtocolObject::id, "005"));
  ASSERT_NO_FATAL_FAILURE(expect_found("power_drill", &ProtocolObject::id, "035"));
  ASSERT_NO_FATAL_FAILURE(expect_found("072-A", &ProtocolObject::name, "072-a_toy_airplane"));
  EXPECT_EQ(find_protocol_object("knife")->id, "032");
  EXPECT_FALSE(find_protocol_object("099_rubber_duck").has_value());
  EXPECT_FALSE(find_protocol_object("").has_value());
  EXPECT_FALSE(find_protocol_object("03").has_value());
}

class StandinMeshTest : public ::testing::TestWithParam<std::size_t> {};

TEST_P(StandinMeshTest, ClosedOutwardAndSizedToExtent) {
  const ProtocolObject& object = protocol_objects()[GetParam()];
  const TriangleMesh mesh = make_standin_mesh(object);
  SCOPED_TRACE(object.name);

  EXPECT_GE(mesh.triangles.size(), 500u);
  EXPECT_LE(mesh.triangles.size(), 10000u);
  for (const auto& t : mesh.triangles) {
    for (std::uint32_t v : t) ASSERT_LT(v, mesh.vertices.size());
  }
  std::string problem;
  EXPECT_TRUE(is_watertight_and_consistent(mesh, &problem)) << problem;

  // Nothing for clean_mesh to remove: no slivers below its area limit, no duplicates.
  MeshCleanReport report;
  const TriangleMesh cleaned = clean_mesh(mesh, 1e-9, &report);
  EXPECT_EQ(report.vertices_welded, 0u);
  EXPECT_EQ(report.degenerate_dropped, 0u);
  EXPECT_EQ(report.duplicate_dropped, 0u);

  const MassProperties props = compute_mass_properties(mesh);
  EXPECT_GT(props.volume, 0.0);
  EXPECT_LT(props.volume, object.extent.prod() * (1 + 1e-9));

  const Eigen::Vector3d lo = mesh.min_corner(), hi = mesh.max_corner();
  EXPECT_LT(((hi - lo) - object.extent).cwiseAbs().maxCoeff(), 1e-3);
  EXPECT_NEAR(lo.z(), 0.0, 1e-12);
  EXPECT_NEAR(0.5 * (lo.x() + hi.x()), 0.0, 1e-3);
  EXPECT_NEAR(0.5 * (lo.y() + hi.y()), 0.0, 1e-3);
  EXPECT_TRUE((props.centroid.array() > lo.array()).all() && (props.centroid.array() < hi.array()).all());
}

INSTANTIATE_TEST_SUITE_P(AllProtocolObjects, StandinMeshTest, ::testing::Range<std::size_t>(0, 30),
                         [](const ::testing::TestParamInfo<std::size_t>& info) {
                           std::string name = protocol_objects()[info.param].name;
                           for (char& c : name) {
                             if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
                           }
                           return name;
                         });

TEST(StandinMesh, BoxFacesHaveShortEdges) {
  const TriangleMesh mesh = make_standin_mesh(*find_protocol_object("cracker_box"));
  double longest = 0;
  for (const auto& t : mesh.triangles) {
    for (int k = 0; k < 3; ++k)
      longest = std::max(longest, (mesh.vertices[t[k]] - mesh.vertices[t[(k + 1) % 3]]).norm());
  }
  EXPECT_LE(longest, 0.0101);
}

TEST(StandinMesh, UnknownObjectGetsABoxOfItsExtent) {
  const ProtocolObject custom{"900", "900_custom", {0.05, 0.04, 0.03}, 0.1};
  const TriangleMesh mesh = make_standin_mesh(custom);
  EXPECT_NEAR(compute_mass_properties(mesh).volume, 0.05 * 0.04 * 0.03, 1e-12);
}

// A folder with two 10 cm cubes, one named after a protocol object: the protocol loaders give
// that one its real mass and the other the mass of its volume at 500 kg/m^3; the generic
// loaders, knowing no catalogue, give both the volume's.
TEST(ProtocolObjectFiles, ProtocolNamesGetTheirRealMass) {
  namespace fs = std::filesystem;
  const fs::path dir =
      fs::temp_directory_path() / ("telegrasp_standin_objects_test_" + std::to_string(std::random_device{}()));
  fs::create_directories(dir);
  const std::string cube =
      "v 0 0 0\nv 0.1 0 0\nv 0.1 0.1 0\nv 0 0.1 0\nv 0 0 0.1\nv 0.1 0 0.1\nv 0.1 0.1 0.1\nv 0 0.1 0.1\n"
      "f 1 4 3 2\nf 5 6 7 8\nf 1 2 6 5\nf 2 3 7 6\nf 3 4 8 7\nf 4 1 5 8\n";
  const std::string baseball = (dir / "055_baseball.obj").string();
  std::ofstream(baseball) << cube;
  std::ofstream(dir / "zz_cube.obj") << cube;
  constexpr double kVolumeMass = 1e-3 * 500.0;
  constexpr double kTol = 1e-6;  // kg: the file is read in float (0.1 m is off by ~1e-9 m)
  const double real_mass = find_protocol_object("055_baseball")->mass_kg;

  const std::vector<ObjectModelPtr> protocol = load_protocol_object_dir(dir.string());
  ASSERT_EQ(protocol.size(), 2u);
  EXPECT_EQ(protocol[0]->name, "055_baseball");
  EXPECT_EQ(protocol[0]->mass_kg, real_mass);
  EXPECT_EQ(protocol[1]->name, "zz_cube");
  EXPECT_NEAR(protocol[1]->mass_kg, kVolumeMass, kTol);
  EXPECT_EQ(load_protocol_object_model(baseball)->mass_kg, real_mass);

  const std::vector<ObjectModelPtr> generic = load_object_dir(dir.string(), nullptr);
  ASSERT_EQ(generic.size(), 2u);
  EXPECT_NEAR(generic[0]->mass_kg, kVolumeMass, kTol);
  EXPECT_NEAR(load_object_model(baseball, 0.0)->mass_kg, kVolumeMass, kTol);
  EXPECT_EQ(load_object_model(baseball, 2.0)->mass_kg, 2.0);
  fs::remove_all(dir);
}

// The paper presented the objects in its own order (labels a..ad of its per-object figures):
// every object has one place in it, lemon first and the toy airplane last.
TEST(ProtocolObjects, PaperOrderIsAPermutationFromLemonToAirplane) {
  const std::vector<ProtocolObject> ordered = protocol_objects_in_paper_order();
  ASSERT_EQ(ordered.size(), protocol_objects().size());
  for (std::size_t i = 0; i < ordered.size(); ++i) EXPECT_EQ(ordered[i].paper_order, static_cast<int>(i));
  EXPECT_EQ(ordered.front().name, "014_lemon");
  EXPECT_EQ(ordered[11].name, "002_master_chef_can");
  EXPECT_EQ(ordered.back().name, "072-a_toy_airplane");
}

}  // namespace
}  // namespace telegrasp::sim
