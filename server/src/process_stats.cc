#include "process_stats.h"

#include <malloc.h>
#include <sys/resource.h>
#include <unistd.h>

#include <chrono>
#include <fstream>
#include <string>

namespace telegrasp::server {

namespace {

double process_cpu_s() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  const auto s = [](const timeval& t) { return static_cast<double>(t.tv_sec) + 1e-6 * static_cast<double>(t.tv_usec); };
  return s(u.ru_utime) + s(u.ru_stime);
}

double wall_s() { return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count(); }

}  // namespace

ProcessLoad::ProcessLoad() : last_cpu_s_(process_cpu_s()), last_wall_s_(wall_s()) {}

double ProcessLoad::cpu_percent() {
  const double cpu = process_cpu_s(), wall = wall_s();
  const double percent = wall > last_wall_s_ ? 100.0 * (cpu - last_cpu_s_) / (wall - last_wall_s_) : 0.0;
  last_cpu_s_ = cpu;
  last_wall_s_ = wall;
  return percent;
}

int ProcessLoad::host_cores() {
  const long n = sysconf(_SC_NPROCESSORS_ONLN);
  return n > 0 ? static_cast<int>(n) : 1;
}

double ProcessLoad::host_load() {
  std::ifstream in("/proc/loadavg");
  double load1 = 0;
  if (!(in >> load1)) return 0;
  return load1 / host_cores();
}

ProcessMemory process_memory() {
  ProcessMemory m;
  std::ifstream status("/proc/self/status");
  for (std::string key; status >> key;) {
    if (key == "VmRSS:") {
      status >> m.rss_kib;
      break;
    }
    status.ignore(1 << 12, '\n');
  }
  if (heap_measured()) {
    const struct mallinfo2 heap = mallinfo2();
    m.heap_kib = (heap.uordblks + heap.hblkhd) / 1024;
  }
  return m;
}

}  // namespace telegrasp::server
