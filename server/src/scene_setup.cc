#include "scene_setup.h"

#include "telegrasp/sim/standin_objects.h"

#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>
#include <stdexcept>

namespace telegrasp::server {

std::string read_text_file(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error(path + ": cannot open");
  std::stringstream buffer;
  buffer << in.rdbuf();
  if (in.bad()) throw std::runtime_error(path + ": read error");
  return buffer.str();
}

MeshFileInfo describe_file(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error(path + ": cannot open");
  MeshFileInfo info;
  info.name = std::filesystem::path(path).filename().string();
  // FNV-1a: a few lines, no dependency, and enough to notice that a mesh changed.
  std::uint64_t h = 0xcbf29ce484222325ull;
  char chunk[1 << 16];
  while (in) {
    in.read(chunk, sizeof chunk);
    const std::streamsize n = in.gcount();
    for (std::streamsize i = 0; i < n; ++i) {
      h ^= static_cast<unsigned char>(chunk[i]);
      h *= 0x100000001b3ull;
    }
    info.size += static_cast<std::uint64_t>(n);
  }
  if (in.bad()) throw std::runtime_error(path + ": read error");
  info.fnv1a64 = h;
  return info;
}

SceneAssets load_scene_assets(const ServerSettings& settings) {
  SceneAssets a;
  if (settings.objects_dir.empty()) {
    for (const auto& o : sim::protocol_objects()) a.models.push_back(sim::make_standin_model(o));
  } else {
    a.model_source.objects_dir = settings.objects_dir;
    a.models = sim::load_protocol_object_dir(settings.objects_dir);
    // Each model's source is the file it was loaded from, in load_protocol_object_dir's order.
    for (const auto& m : a.models) a.model_source.files.push_back(describe_file(m->source));
    if (settings.fill_standins) {
      // After the meshes, so a folder's mesh always wins over the stand-in of the same name.
      std::set<std::string> meshes;
      for (const auto& m : a.models) meshes.insert(m->name);
      for (const auto& o : sim::protocol_objects()) {
        if (meshes.count(o.name)) continue;
        a.models.push_back(sim::make_standin_model(o));
        a.model_source.standins.push_back(o.name);
      }
    }
  }
  // The rig is parsed from the very text that is kept, so a recording holds what was used.
  const auto or_default = [](const std::string& path, sim::HandSide side) {
    return path.empty() ? sim::HandRig::builtin_path(sim::HandRig::default_human(side)) : path;
  };
  a.right_rig_path = or_default(settings.right_rig, sim::HandSide::kRight);
  a.left_rig_path = or_default(settings.left_rig, sim::HandSide::kLeft);
  auto load_rig = [](const std::string& path, std::string& text) {
    try {
      text = read_text_file(path);
    } catch (const std::runtime_error&) {
      throw sim::RigError(path + ": cannot open rig file");  // as HandRig::load says it
    }
    return std::make_shared<const sim::HandRig>(sim::HandRig::parse(text, path));
  };
  a.right_rig = load_rig(a.right_rig_path, a.right_rig_text);
  a.left_rig = load_rig(a.left_rig_path, a.left_rig_text);
  return a;
}

}  // namespace telegrasp::server
