#include "telegrasp/sim/data_paths.h"

#include <dlfcn.h>

#include <cstdlib>
#include <stdexcept>
#include <system_error>

// Relative paths from the install's bin/ and lib/ folders to its share/telegrasp folder, set by
// CMake from GNUInstallDirs (the build tree uses the same layout).
#ifndef TELEGRASP_BIN_TO_DATA
#error "TELEGRASP_BIN_TO_DATA must be defined by the build"
#endif
#ifndef TELEGRASP_LIB_TO_DATA
#error "TELEGRASP_LIB_TO_DATA must be defined by the build"
#endif

namespace telegrasp::sim {
namespace {

namespace fs = std::filesystem;

// The file this code was loaded from, and whether it is a shared library (else the program).
struct Module {
  fs::path path;
  bool shared_library = false;
};

Module this_module() {
  // A shared library is named by the absolute path it was loaded from; the main program is
  // named as it was started (perhaps relative, or through $PATH), so ask the kernel for it.
  Dl_info info{};
  if (dladdr(reinterpret_cast<void*>(&this_module), &info) != 0 && info.dli_fname != nullptr) {
    const fs::path p = info.dli_fname;
    if (p.is_absolute() && p.filename().string().find(".so") != std::string::npos) return {p, true};
  }
  std::error_code ec;
  const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  return {ec ? fs::path() : exe, false};
}

}  // namespace

fs::path data_dir() {
  if (const char* env = std::getenv("TELEGRASP_DATA_DIR"); env != nullptr && *env != '\0') return env;
  const Module m = this_module();
  if (m.path.empty()) return {};
  return (m.path.parent_path() / (m.shared_library ? TELEGRASP_LIB_TO_DATA : TELEGRASP_BIN_TO_DATA)).lexically_normal();
}

fs::path data_file(const std::string& relative) {
  const fs::path p = data_dir() / relative;
  std::error_code ec;
  if (!fs::exists(p, ec))
    throw std::runtime_error(
        "telegrasp data file " + p.string() +
        " not found (installed under <prefix>/share/telegrasp; set TELEGRASP_DATA_DIR to its folder)");
  return p;
}

}  // namespace telegrasp::sim
