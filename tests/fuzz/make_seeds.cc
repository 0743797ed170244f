// telegrasp-fuzz-seeds: writes the generated seed inputs of the fuzz harnesses (tests/fuzz)
// into OUT_DIR/<harness>/: wire samples and commands in CDR as the DDS writers send them, a
// short recording, and small meshes in every format the mesh harness picks. Generated from
// the current IDL and formats at every run, so they never go stale; deploy/run-fuzz.sh adds
// the repository's own files (rigs, the example configuration and questionnaire).
#include "recording.h"
#include "server_config.h"
#include "telegrasp/idl/eigen_conversions.h"

#include <Eigen/Geometry>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <string>
#include <vector>

namespace {

using namespace telegrasp;
namespace fs = std::filesystem;

void write(const fs::path& dir, const std::string& name, const std::string& bytes) {
  fs::create_directories(dir);
  std::ofstream out(dir / name, std::ios::binary);
  out << bytes;
  if (!out) throw std::runtime_error("cannot write " + (dir / name).string());
}

msg::ControllerState controller_state(const std::string& client, std::uint8_t side, std::uint64_t seq, double trigger,
                                      std::vector<double> curls) {
  msg::ControllerState s;
  s.client_id(client);
  s.hand_side(side);
  s.sequence_number(seq);
  s.client_time_ns(static_cast<std::int64_t>(seq) * 1'000'000);
  Eigen::Isometry3d X_WorldPalm = Eigen::Isometry3d::Identity();
  X_WorldPalm.translation() = Eigen::Vector3d(0.3, 0.0, 0.1);
  s.palm(idl::to_msg(X_WorldPalm));
  s.trigger(trigger);
  s.curls(curls);
  s.tracking_valid(true);
  s.lockstep_tick(seq);
  s.commands_sent(1);
  return s;
}

msg::SceneCommand scene_command(msg::SceneCommandKind kind, const std::string& model, std::int32_t object_id,
                                bool on_table) {
  msg::SceneCommand c;
  c.client_id("fuzz-client");
  c.command_id(7);
  c.kind(kind);
  c.model(model);
  c.object_id(object_id);
  c.on_table(on_table);
  c.x(0.4);
  c.y(-0.2);
  c.yaw(0.5);
  Eigen::Isometry3d X_WorldObject = Eigen::Isometry3d::Identity();
  X_WorldObject.translation() = Eigen::Vector3d(0.4, 0.1, 0.3);
  c.pose(idl::to_msg(X_WorldObject));
  return c;
}

/// A closed tetrahedron in each format, behind the harness's format byte (0 PLY, 1 OBJ, 2 STL).
void write_meshes(const fs::path& dir) {
  const float corners[4][3] = {{0, 0, 0}, {0.1f, 0, 0}, {0, 0.1f, 0}, {0, 0, 0.1f}};
  const int faces[4][3] = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};
  std::string ascii_ply(1, '\0');
  ascii_ply +=
      "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n"
      "element face 4\nproperty list uchar int vertex_indices\nend_header\n";
  std::string binary_ply(1, '\0');
  binary_ply +=
      "ply\nformat binary_little_endian 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n"
      "element face 4\nproperty list uchar int vertex_indices\nend_header\n";
  std::string obj(1, '\1'), ascii_stl = std::string(1, '\2') + "solid tetra\n";
  std::string binary_stl(1, '\2');
  binary_stl.append(80, ' ');
  const std::uint32_t facets = 4;
  binary_stl.append(reinterpret_cast<const char*>(&facets), 4);
  for (const auto& c : corners) {
    ascii_ply += std::to_string(c[0]) + " " + std::to_string(c[1]) + " " + std::to_string(c[2]) + "\n";
    binary_ply.append(reinterpret_cast<const char*>(c), sizeof(c));
    obj += "v " + std::to_string(c[0]) + " " + std::to_string(c[1]) + " " + std::to_string(c[2]) + "\n";
  }
  for (const auto& f : faces) {
    ascii_ply += "3 " + std::to_string(f[0]) + " " + std::to_string(f[1]) + " " + std::to_string(f[2]) + "\n";
    binary_ply.push_back(3);
    binary_ply.append(reinterpret_cast<const char*>(f), sizeof(f));
    obj += "f " + std::to_string(f[0] + 1) + " " + std::to_string(f[1] + 1) + " " + std::to_string(f[2] + 1) + "\n";
    ascii_stl += "facet normal 0 0 0\n outer loop\n";
    binary_stl.append(12, '\0');
    for (int v : f) {
      const auto& c = corners[v];
      ascii_stl += "  vertex " + std::to_string(c[0]) + " " + std::to_string(c[1]) + " " + std::to_string(c[2]) + "\n";
      binary_stl.append(reinterpret_cast<const char*>(c), sizeof(c));
    }
    ascii_stl += " endloop\nendfacet\n";
    binary_stl.append(2, '\0');
  }
  ascii_stl += "endsolid tetra\n";
  write(dir, "tetra_ascii.ply", ascii_ply);
  write(dir, "tetra_binary.ply", binary_ply);
  write(dir, "tetra.obj", obj);
  write(dir, "tetra_ascii.stl", ascii_stl);
  write(dir, "tetra_binary.stl", binary_stl);
}

/// A recording of a few records of every kind, complete and cut short.
void write_recordings(const fs::path& dir) {
  server::proto::RecordingHeader header;
  header.set_format_version(server::kRecordingFormatVersion);
  header.set_telegrasp_version(server::telegrasp_version());
  header.set_idl_sha256(server::idl_sha256());
  *header.mutable_config() = server::to_proto(server::ServerSettings{});
  header.mutable_right_rig()->set_text("name: \"r\"");
  std::vector<server::proto::Record> records(4);
  auto* sample = records[0].mutable_inputs()->add_samples();
  sample->set_controller_state_cdr(server::to_cdr(controller_state("a", 1, 1, 0.5, {})));
  sample->set_received_ns(100);
  records[0].mutable_inputs()->set_now_ns(100);
  records[1].mutable_command()->set_scene_command_cdr(
      server::to_cdr(scene_command(msg::SCENE_SPAWN, "056_tennis_ball", 0, true)));
  records[2].mutable_tick()->set_now_ns(200);
  msg::GraspEvent event;
  event.client_id("a");
  records[3].mutable_output()->set_type(server::proto::OUTPUT_GRASP_EVENT);
  records[3].mutable_output()->set_cdr(server::to_cdr(event));
  fs::create_directories(dir);
  server::write_recording((dir / "complete.tgrec").string(), header, records, true);
  server::write_recording((dir / "cut.tgrec").string(), header, records, false);
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2 || std::string(argv[1]) == "--help" || std::string(argv[1]) == "-h") {
    std::cerr << "usage: telegrasp-fuzz-seeds OUT_DIR\n"
                 "Writes the generated seeds of every fuzz harness into OUT_DIR/<harness>/ (controller_state,\n"
                 "scene_command, recording, mesh).\n";
    return argc == 2 ? 0 : 2;
  }
  try {
    const fs::path out = argv[1];
    write(out / "controller_state", "right_trigger", server::to_cdr(controller_state("bot-1", 1, 5, 0.7, {})));
    write(out / "controller_state", "left_curls",
          server::to_cdr(controller_state("bot-2", 0, 9, 0.0, {0.1, 0.2, 0.3, 0.4, 0.5})));
    write(out / "scene_command", "spawn_on_table",
          server::to_cdr(scene_command(msg::SCENE_SPAWN, "056_tennis_ball", 0, true)));
    write(out / "scene_command", "spawn_posed", server::to_cdr(scene_command(msg::SCENE_SPAWN, "013_apple", 0, false)));
    write(out / "scene_command", "remove", server::to_cdr(scene_command(msg::SCENE_REMOVE, "", 3, false)));
    write(out / "scene_command", "reset", server::to_cdr(scene_command(msg::SCENE_RESET, "", 0, false)));
    write_meshes(out / "mesh");
    write_recordings(out / "recording");
  } catch (const std::exception& e) {
    std::cerr << "telegrasp-fuzz-seeds: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
