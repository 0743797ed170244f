// Fuzzes mesh loading: the first byte picks the format (PLY, OBJ or STL, by the file's
// extension, as assimp picks its importer), the rest is the file. load_object_model reads it
// as the server reads objects_dir: the header checks, assimp, clean_mesh, then mass properties
// and the distance structure of a mesh that loads.
#include "fuzz_common.h"
#include "telegrasp/sim/mesh_loading.h"
#include "telegrasp/sim/object_model.h"

#include <assimp/DefaultLogger.hpp>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const bool silenced = (telegrasp::fuzz::silence_cerr(), true);
  (void)silenced;
  if (size == 0) return 0;
  static const char* const kExtensions[] = {"ply", "obj", "stl"};
  const std::string path =
      telegrasp::fuzz::write_scratch(std::string("mesh.") + kExtensions[data[0] % 3], data + 1, size - 1);
  try {
    (void)telegrasp::sim::load_object_model(path, 0.0);
  } catch (const telegrasp::sim::MeshLoadError&) {
    // A refused mesh: the expected outcome for most inputs.
  }
  return 0;
}
