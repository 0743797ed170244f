// This server process's own figures, for ServerStatus and the scene directory: CPU use, the
// host's load, and memory (resident set and the heap in use).
#pragma once

#include <cstdint>

namespace telegrasp::server {

/// CPU use of this process between two calls (getrusage), and the host's load (/proc/loadavg).
class ProcessLoad {
 public:
  ProcessLoad();
  /// The process's CPU time since the last call (or construction) over the wall time, % of one core.
  double cpu_percent();
  static int host_cores();
  /// The 1-minute load average over host_cores(); 0 when unknown.
  static double host_load();

 private:
  double last_cpu_s_;
  double last_wall_s_;
};

/// Memory of this process, KiB.
struct ProcessMemory {
  /// Resident set (VmRSS of /proc/self/status): what the machine gives the process. It keeps the
  /// high-water mark of the heap wherever the allocator cannot return freed pages.
  std::uint64_t rss_kib = 0;
  /// Bytes the program holds from malloc (glibc mallinfo2: in use in the arenas plus mmapped
  /// blocks): this grows with a leak, and falls again when memory is freed. 0 when malloc is
  /// not glibc's (sanitizer builds replace it): heap_measured() is false then.
  std::uint64_t heap_kib = 0;
};
constexpr bool heap_measured() {
#if defined(__has_feature)
#if __has_feature(address_sanitizer) || __has_feature(thread_sanitizer) || __has_feature(memory_sanitizer)
  return false;
#endif
#endif
#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
  return false;
#endif
  return true;
}
ProcessMemory process_memory();

}  // namespace telegrasp::server
