// A scratch folder per test process, for the server tests that write files.
#pragma once

#include <filesystem>
#include <string>

namespace telegrasp::server {

/// <tmp>/<name>-<pid> (ctest runs every test as its own process, in parallel), made on first use
/// and removed when the process's tests end. One per process: later calls return the first.
const std::filesystem::path& scratch_dir(const std::string& name);

}  // namespace telegrasp::server
