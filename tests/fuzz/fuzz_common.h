// What the libFuzzer harnesses of tests/fuzz share: a scratch file for the readers that take a
// path, and silence for the logs a rejected input writes (libFuzzer's own reports and the
// sanitizers' still reach stderr: -close_fd_mask is not needed).
#pragma once

#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <string>
#include <string_view>

namespace telegrasp::fuzz {

/// A folder of this process under $TMPDIR (or /tmp), for the harnesses' scratch files; removed at
/// exit.
inline const std::filesystem::path& scratch_dir() {
  static const std::filesystem::path dir = [] {
    const char* tmp = std::getenv("TMPDIR");
    std::filesystem::path d =
        std::filesystem::path(tmp && *tmp ? tmp : "/tmp") / ("telegrasp-fuzz-" + std::to_string(::getpid()));
    std::filesystem::create_directories(d);
    std::atexit([] {
      std::error_code ec;
      std::filesystem::remove_all(scratch_dir(), ec);
    });
    return d;
  }();
  return dir;
}

/// Writes `size` bytes to the scratch file `name` (replacing it) and returns its path.
inline std::string write_scratch(const std::string& name, const std::uint8_t* data, std::size_t size) {
  const std::filesystem::path path = scratch_dir() / name;
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
  return path.string();
}

/// Discards what the code under test writes to std::cerr (one line per rejected input).
inline void silence_cerr() { std::cerr.rdbuf(nullptr); }

}  // namespace telegrasp::fuzz
