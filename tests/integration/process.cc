#include "process.h"

#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <mutex>
#include <stdexcept>

namespace telegrasp::testing {
namespace {

std::mutex work_dir_mutex;
std::filesystem::path work_dir;  // empty until first used

// Removes the scratch folder after the last test if all passed.
class WorkDirCleanup : public ::testing::Environment {
 public:
  void TearDown() override {
    std::lock_guard lock(work_dir_mutex);
    if (work_dir.empty()) return;
    if (::testing::UnitTest::GetInstance()->Passed()) {
      std::error_code ignored;
      std::filesystem::remove_all(work_dir, ignored);
    } else {
      std::cerr << "the programs' logs and results are kept in " << work_dir.string() << "\n";
    }
  }
};

[[maybe_unused]] const ::testing::Environment* const cleanup = ::testing::AddGlobalTestEnvironment(new WorkDirCleanup);

}  // namespace

std::string bin(const std::string& name) {
  return (std::filesystem::read_symlink("/proc/self/exe").parent_path() / name).string();
}

std::string work_path(const std::string& name) {
  std::lock_guard lock(work_dir_mutex);
  if (work_dir.empty()) {
    std::string pattern = (std::filesystem::temp_directory_path() / "telegrasp_integration.XXXXXX").string();
    if (::mkdtemp(pattern.data()) == nullptr) throw std::runtime_error("cannot make a folder like " + pattern);
    work_dir = pattern;
  }
  return (work_dir / name).string();
}

}  // namespace telegrasp::testing
