// Tests server/src/process_stats: the CPU and memory figures a server reports about itself.
#include "process_stats.h"

#include <gtest/gtest.h>

#include <chrono>
#include <cstring>
#include <memory>
#include <vector>

namespace telegrasp::server {
namespace {

TEST(ProcessStatsTest, ProcessLoadMeasuresThisProcess) {
  ProcessLoad load;
  // Busy for about 50 ms: close to 100 % of one core (a loaded machine may give less).
  const auto end = std::chrono::steady_clock::now() + std::chrono::milliseconds(50);
  volatile double x = 0;
  while (std::chrono::steady_clock::now() < end) x = x + 1;
  const double percent = load.cpu_percent();
  EXPECT_GT(percent, 10);
  EXPECT_LT(percent, 150);
  EXPECT_GE(ProcessLoad::host_cores(), 1);
  EXPECT_GE(ProcessLoad::host_load(), 0);
}

// 32 MiB held in 131,072 blocks of 256 bytes (from malloc's arenas, not mmap): the heap in use
// grows by at least that while they are held and falls back by at least that once they are freed.
// The resident set then holds at least those 32 MiB, as every block is written (it need not grow:
// pages an earlier test freed may be reused).
TEST(ProcessStatsTest, HeapInUseFollowsWhatIsHeldAndFreed) {
  if (!heap_measured()) GTEST_SKIP() << "a sanitizer replaces malloc: the heap in use is not measured";
  constexpr std::size_t kBlocks = 131072, kBlock = 256, kKib = kBlocks * kBlock / 1024;
  const ProcessMemory before = process_memory();
  EXPECT_GT(before.rss_kib, 0u);
  EXPECT_GT(before.heap_kib, 0u);
  std::vector<std::unique_ptr<char[]>> blocks(kBlocks);
  for (auto& b : blocks) {
    b = std::make_unique<char[]>(kBlock);
    std::memset(b.get(), 1, kBlock);
  }
  const ProcessMemory held = process_memory();
  EXPECT_GE(held.heap_kib, before.heap_kib + kKib);
  EXPECT_LT(held.heap_kib, before.heap_kib + 2 * kKib);  // block overheads, not more
  EXPECT_GE(held.rss_kib, kKib);
  blocks.clear();
  blocks.shrink_to_fit();
  const ProcessMemory freed = process_memory();
  EXPECT_LE(freed.heap_kib + kKib, held.heap_kib);
}

}  // namespace
}  // namespace telegrasp::server
