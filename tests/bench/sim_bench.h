// What the simulation benchmarks share: the 90 Hz tick, where the YCB meshes are and the shipped
// right hand.
#pragma once

#include "telegrasp/sim/hand_rig.h"
#include "telegrasp/sim/mesh_loading.h"

#include <cstdlib>
#include <filesystem>
#include <memory>
#include <string>
#include <utility>
#include <vector>

namespace telegrasp::sim::bench {

inline constexpr double kDt = 1.0 / 90.0;

/// The YCB meshes: $TELEGRASP_OBJECTS_DIR, else beside the repository when run from its root, as
/// the README does.
inline std::string objects_dir() {
  const char* env = std::getenv("TELEGRASP_OBJECTS_DIR");
  return env ? env : "../shared/data/ycb";
}

/// The mesh files in objects_dir() as (stem, path), in directory order; none when it is missing.
inline std::vector<std::pair<std::string, std::string>> object_mesh_files() {
  std::vector<std::pair<std::string, std::string>> files;
  std::error_code ec;
  if (std::filesystem::is_directory(objects_dir(), ec)) {
    for (const auto& e : std::filesystem::directory_iterator(objects_dir(), ec))
      if (is_mesh_file(e.path().string())) files.emplace_back(e.path().stem().string(), e.path().string());
  }
  return files;
}

/// The right hand the benches measure, loaded once: the built-in rig named by
/// $TELEGRASP_BENCH_RIG (e.g. human_right, the flat thumb) or the default, human_right_opposable.
inline std::shared_ptr<const HandRig> right_rig() {
  static auto r = [] {
    const char* name = std::getenv("TELEGRASP_BENCH_RIG");
    const std::string rig = name && *name ? name : HandRig::default_human(HandSide::kRight);
    return std::make_shared<const HandRig>(HandRig::load(HandRig::builtin_path(rig)));
  }();
  return r;
}

}  // namespace telegrasp::sim::bench
