// SceneAssets: what a SceneServer is built from besides its settings (models and the two rigs),
// with where each came from, so a recording can name them and a replay can check them.
#pragma once

#include "server_config.h"
#include "telegrasp/sim/hand_rig.h"
#include "telegrasp/sim/object_model.h"

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace telegrasp::server {

/// One mesh file a model was loaded from.
struct MeshFileInfo {
  std::string name;  ///< File name inside the objects folder.
  std::uint64_t size = 0;  ///< Bytes.
  std::uint64_t fnv1a64 = 0;  ///< content_hash() of the file.
};

/// Where the models came from: the built-in stand-ins (objects_dir empty) or a folder's meshes,
/// then, with fill_standins, the stand-ins of the protocol objects the folder has no mesh of.
struct ModelSource {
  std::string objects_dir;
  std::vector<MeshFileInfo> files;  ///< In loading order; empty for the stand-ins.
  std::vector<std::string> standins;  ///< fill_standins: stand-ins added after the meshes, in order.
};

/// The models and rigs of a scene, with their sources.
struct SceneAssets {
  std::vector<sim::ObjectModelPtr> models;
  std::shared_ptr<const sim::HandRig> right_rig, left_rig;
  std::string right_rig_path, left_rig_path;  ///< Files read (the built-in rigs' paths when settings name none).
  std::string right_rig_text, left_rig_text;  ///< Their full text.
  ModelSource model_source;
};

/// Loads what `settings` names: every mesh of objects_dir (else the 30 stand-ins), with
/// fill_standins followed by the stand-in of each protocol object no mesh is named after (in
/// protocol order), and the right and left rigs (else the built-in human rigs). Throws
/// std::runtime_error (MeshLoadError, RigError) naming the file that failed.
SceneAssets load_scene_assets(const ServerSettings& settings);

/// FNV-1a 64-bit hash and size of a file's bytes. Throws std::runtime_error naming the file if it
/// cannot be read.
MeshFileInfo describe_file(const std::string& path);

/// A text file's full content. Throws std::runtime_error naming the file if it cannot be read.
std::string read_text_file(const std::string& path);

}  // namespace telegrasp::server
