#include "process.h"

#include <filesystem>

namespace telegrasp::testing {

std::string bin(const std::string& name) {
  return (std::filesystem::read_symlink("/proc/self/exe").parent_path() / name).string();
}

}  // namespace telegrasp::testing
