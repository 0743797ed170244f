// Integration tests of the ObjectGeometry topic on loopback with real processes, each on a DDS
// domain leased for it: a client that joins after the server has started receives every model's
// mesh, intact and equal to the server's model; a bot given no mesh files plans on the meshes it
// receives and grasps objects it has no other model of. Times are printed, not asserted.
#include "process.h"
#include "telegrasp/client/client.h"
#include "telegrasp/idl/cli.h"
#include "telegrasp/sim/object_model.h"
#include "telegrasp/sim/standin_objects.h"
#include "test_domain.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <chrono>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <sstream>
#include <thread>

namespace telegrasp::testing {
namespace {

using namespace std::chrono_literals;
namespace fs = std::filesystem;

std::string read_file(const std::string& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

std::unique_ptr<ChildProcess> start_server(int domain, const std::vector<std::string>& extra, const std::string& name) {
  std::vector<std::string> args{bin("telegrasp-server"), "--domain", std::to_string(domain), "--profile", "loopback"};
  args.insert(args.end(), extra.begin(), extra.end());
  return std::make_unique<ChildProcess>(args, work_path(name + "_server.log"));
}

// Waits until the server has printed its start-up line (its geometry is published before it).
bool server_started(ChildProcess& server) {
  return eventually([&] { return read_file(server.log_path()).find("; Ctrl-C to stop") != std::string::npos; },
                    60s);
}

// FNV-1a 64 over the geometry's bytes laid out as telegrasp.idl defines content_hash (counts, then
// coordinates, then indices, each uint32 or float32 little-endian; this host is little-endian).
std::uint64_t recomputed_hash(const client::ObjectGeometry& g) {
  std::uint64_t h = 0xcbf29ce484222325ull;
  auto add = [&h](const void* p) {
    unsigned char b[4];
    std::memcpy(b, p, 4);
    for (unsigned char c : b) h = (h ^ c) * 0x100000001b3ull;
  };
  const std::uint32_t counts[2] = {static_cast<std::uint32_t>(g.vertices.size()),
                                   static_cast<std::uint32_t>(g.triangles.size())};
  add(&counts[0]);
  add(&counts[1]);
  for (const Eigen::Vector3f& v : g.vertices)
    for (int k = 0; k < 3; ++k) add(&v[k]);
  for (const auto& t : g.triangles)
    for (std::uint32_t i : t) add(&i);
  return h;
}

// Joins `domain` after the server started, and returns the seconds until every model the server
// names in its status has arrived (or -1), with the geometries.
double receive_all_geometries(int domain, std::map<std::string, std::shared_ptr<const client::ObjectGeometry>>& got,
                              std::size_t& expected) {
  client::ClientOptions o;
  o.client_id = "geometry-viewer";
  o.domain = domain;
  o.topics = client::kObjectGeometries | client::kServerStatuses;
  const auto start = std::chrono::steady_clock::now();
  client::Client c(o);
  bool all = eventually(
      [&] {
        const auto status = c.latest_server_status();
        if (!status) return false;
        expected = status->models.size();
        return c.object_geometries().size() >= expected;
      },
      60s);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  got = c.object_geometries();
  return all ? seconds : -1;
}

// A late joiner gets the 30 stand-ins: each intact (its hash recomputed from what arrived), with
// the triangles and (within float32 rounding) the vertices, bounds and mass of the server's model.
TEST(ObjectGeometryTest, ALateJoinerReceivesEveryStandInIntact) {
  const DomainLease lease;
  const int domain = lease.domain();
  auto server = start_server(domain, {}, "geometry_standins");
  ASSERT_TRUE(server_started(*server)) << server->log_tail();
  std::this_thread::sleep_for(500ms);  // well after the geometry was written

  std::map<std::string, std::shared_ptr<const client::ObjectGeometry>> got;
  std::size_t expected = 0;
  const double seconds = receive_all_geometries(domain, got, expected);
  ASSERT_GE(seconds, 0) << got.size() << " of " << expected << " geometries arrived";
  std::cout << "[ measured ] a late joiner received " << got.size() << " stand-in geometries in " << seconds << " s\n";

  ASSERT_EQ(got.size(), sim::protocol_objects().size());
  constexpr double kFloat32Rounding = 1e-7;  // m, on coordinates under 1 m
  for (const auto& o : sim::protocol_objects()) {
    SCOPED_TRACE(o.name);
    ASSERT_TRUE(got.count(o.name));
    const client::ObjectGeometry& g = *got.at(o.name);
    const sim::ObjectModelPtr model = sim::make_standin_model(o);  // what the server loaded
    EXPECT_FALSE(g.mesh_omitted);
    EXPECT_EQ(g.content_hash, recomputed_hash(g));
    EXPECT_EQ(g.triangle_count, model->mesh.triangles.size());
    ASSERT_EQ(g.triangles, model->mesh.triangles);
    ASSERT_EQ(g.vertices.size(), model->mesh.vertices.size());
    double worst = 0;
    for (std::size_t i = 0; i < g.vertices.size(); ++i)
      worst = std::max(worst, (g.vertices[i].cast<double>() - model->mesh.vertices[i]).cwiseAbs().maxCoeff());
    EXPECT_LT(worst, kFloat32Rounding);
    EXPECT_EQ(g.p_ObjectMin, model->p_ObjectMin);
    EXPECT_EQ(g.p_ObjectMax, model->p_ObjectMax);
    EXPECT_EQ(g.mass_kg, model->mass_kg);
  }
}

// The same with the YCB meshes (about 180 KB each), when they are beside the repository.
TEST(ObjectGeometryTest, ALateJoinerReceivesEveryYcbMeshIntact) {
  const char* env = std::getenv("TELEGRASP_YCB_DIR");
  const std::string dir = env ? env : "";
  if (dir.empty() || !fs::is_directory(dir)) GTEST_SKIP() << "no YCB meshes (TELEGRASP_YCB_DIR)";
  const DomainLease lease;
  const int domain = lease.domain();
  auto server = start_server(domain, {"--objects", dir}, "geometry_ycb");
  ASSERT_TRUE(server_started(*server)) << server->log_tail();
  std::this_thread::sleep_for(500ms);

  std::map<std::string, std::shared_ptr<const client::ObjectGeometry>> got;
  std::size_t expected = 0;
  const double seconds = receive_all_geometries(domain, got, expected);
  ASSERT_GE(seconds, 0) << got.size() << " of " << expected << " geometries arrived";
  std::size_t bytes = 0;
  for (const auto& [name, g] : got) bytes += 12 * g->vertices.size() + 12 * g->triangles.size();
  std::cout << "[ measured ] a late joiner received " << got.size() << " YCB geometries (" << bytes / 1000
            << " KB of mesh) in " << seconds << " s\n";
  for (const auto& [name, g] : got) {
    SCOPED_TRACE(name);
    EXPECT_FALSE(g->mesh_omitted);
    EXPECT_EQ(g->content_hash, recomputed_hash(*g));
    EXPECT_EQ(g->triangles.size(), g->triangle_count);
    EXPECT_GT(g->triangle_count, 1000u);
  }
}

// Writes `mesh` as a Wavefront OBJ file.
void write_obj(const fs::path& path, const sim::TriangleMesh& mesh) {
  std::ofstream out(path);
  out.precision(9);
  for (const Eigen::Vector3d& v : mesh.vertices) out << "v " << v.x() << ' ' << v.y() << ' ' << v.z() << '\n';
  for (const auto& t : mesh.triangles) out << "f " << t[0] + 1 << ' ' << t[1] + 1 << ' ' << t[2] + 1 << '\n';
}

// A bot with no mesh files plans on the geometry the server publishes: the server serves three
// meshes under names that are no protocol object, so the bot has no stand-in to fall back on, and
// every trial still ends with a record, most of them held.
TEST(ObjectGeometryTest, ABotWithoutMeshFilesPlansOnReceivedGeometry) {
  const DomainLease lease;
  const int domain = lease.domain();
  const fs::path meshes = work_path("geometry_meshes");
  fs::remove_all(meshes);
  fs::create_directories(meshes);
  for (const char* name : {"005_tomato_soup_can", "009_gelatin_box", "055_baseball"})
    write_obj(meshes / ("wire_" + std::string(name).substr(4) + ".obj"),
              sim::make_standin_mesh(*sim::find_protocol_object(name)));
  auto server = start_server(domain, {"--objects", meshes.string()}, "geometry_bot");
  ASSERT_TRUE(server_started(*server)) << server->log_tail();

  const int trials = 2;
  const std::string json = work_path("geometry_bot.json"), log = work_path("geometry_bot.log");
  ChildProcess bot({bin("telegrasp-bot"), "--client-id", "wire-bot", "--trials", std::to_string(trials), "--seed", "3",
                    "--domain", std::to_string(domain), "--profile", "loopback", "--json", json, "--timeout-s", "30"},
                   log);
  const int status = bot.wait(300s);  // 0 every trial held, kExitNotHeld some not (asserted below)
  ASSERT_TRUE(status == 0 || status == cli::kExitNotHeld) << bot.exit_description() << "\n" << bot.log_tail();

  const std::string text = read_file(log);
  EXPECT_NE(text.find("planning on the server's published geometry for 3 model(s): wire_baseball, wire_gelatin_box, "
                      "wire_tomato_soup_can"),
            std::string::npos)
      << text;
  EXPECT_EQ(text.find("no model named"), std::string::npos) << text;

  std::ifstream in(json);
  ASSERT_TRUE(in) << json;
  const nlohmann::json j = nlohmann::json::parse(in);
  std::map<std::string, int> records, held;
  for (const auto& g : j["grasps"]) {
    ++records[g["object"].get<std::string>()];
    held[g["object"].get<std::string>()] += g["held_after_lift"].get<bool>();
  }
  EXPECT_EQ(records, (std::map<std::string, int>{
                         {"wire_baseball", trials}, {"wire_gelatin_box", trials}, {"wire_tomato_soup_can", trials}}));
  // Without a model the bot gives an object up unattempted; planned on the received meshes it
  // holds (today every trial; half leaves room for the operator's noise).
  int total_held = 0;
  for (const auto& [name, n] : held) total_held += n;
  EXPECT_GE(total_held, 3 * trials / 2) << j["grasps"].dump(1);
}

}  // namespace
}  // namespace telegrasp::testing
