// Where telegrasp finds the data it ships: the hand rigs, the Fast DDS profiles and the paper's
// published results. Found relative to the program (or library) itself, so an installed prefix
// stands alone and no source path is compiled in.
#pragma once

#include <filesystem>
#include <string>

namespace telegrasp::sim {

/// The folder of telegrasp's shipped data (`rigs/`, `telegrasp_profiles.xml`,
/// `paper_results_per_object.csv`): $TELEGRASP_DATA_DIR if set, else `share/telegrasp` beside
/// the `bin/` folder of the running program, or beside the `lib/` folder when this code was
/// loaded from the telegrasp client library. That is `<prefix>/share/telegrasp` once installed,
/// and `build/share/telegrasp` in a build tree, where the build stages the same files.
std::filesystem::path data_dir();

/// `data_dir() / relative`. Throws std::runtime_error naming the path looked for and
/// TELEGRASP_DATA_DIR when it does not exist.
std::filesystem::path data_file(const std::string& relative);

}  // namespace telegrasp::sim
