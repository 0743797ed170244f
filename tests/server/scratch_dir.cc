#include "scratch_dir.h"

#include <gtest/gtest.h>

#include <system_error>

#include <unistd.h>

namespace telegrasp::server {
namespace {

struct RemoveScratch : ::testing::Environment {
  explicit RemoveScratch(std::filesystem::path dir) : dir_(std::move(dir)) {}
  void TearDown() override {
    std::error_code ec;
    std::filesystem::remove_all(dir_, ec);
  }
  std::filesystem::path dir_;
};

}  // namespace

const std::filesystem::path& scratch_dir(const std::string& name) {
  static const std::filesystem::path dir = [&] {
    std::filesystem::path d = std::filesystem::temp_directory_path() / (name + "-" + std::to_string(::getpid()));
    std::filesystem::create_directories(d);
    ::testing::AddGlobalTestEnvironment(new RemoveScratch(d));
    return d;
  }();
  return dir;
}

}  // namespace telegrasp::server
