// telegrasp-bench-sim's main: runs the benchmarks as usual, then prints, per object set ("ycb"
// and "unseen"), the worst object's microseconds per tick kind of BM_HandTick and whether each
// is within the budget (closing 20 us, the other ticks 50 us). With --benchmark_repetitions the
// median of the repetitions is used.
#include "hand_tick_bench.h"

#include <benchmark/benchmark.h>

#include <algorithm>
#include <cstdio>
#include <map>
#include <string>
#include <unistd.h>
#include <vector>

namespace telegrasp::sim {
namespace {

constexpr const char* kKinds[] = {"closing", "grasp", "holding"};

double budget_us(const std::string& kind) { return kind == "closing" ? 20.0 : 50.0; }

/// The console reporter, also keeping each BM_HandTick run's tick_us (us) by set, kind, object.
class SummaryReporter : public benchmark::ConsoleReporter {
 public:
  using Table = std::map<std::string, std::map<std::string, std::map<std::string, double>>>;

  /// Colours only on a terminal.
  SummaryReporter() : ConsoleReporter(isatty(fileno(stdout)) ? OO_ColorTabular : OO_Tabular) {}

  void ReportRuns(const std::vector<Run>& runs) override {
    ConsoleReporter::ReportRuns(runs);
    for (const Run& run : runs) keep(run);
  }

  /// Prints one line per set: the worst object's us per tick kind, and the budget verdict.
  void print_summary() const {
    for (const auto& [set, kinds] : us_) {
      std::printf("SUMMARY %-7s", set.c_str());
      bool all_within = true;
      for (const char* kind : kKinds) {
        const auto it = kinds.find(kind);
        if (it == kinds.end() || it->second.empty()) continue;
        const auto worst = std::max_element(it->second.begin(), it->second.end(),
                                            [](const auto& x, const auto& y) { return x.second < y.second; });
        const bool within = worst->second <= budget_us(kind);
        all_within &= within;
        std::printf("  %s: worst %s %.1f us (budget %.0f: %s)", kind, worst->first.c_str(), worst->second,
                    budget_us(kind), within ? "ok" : "OVER");
      }
      std::printf("  => %s\n", all_within ? "within budget" : "OVER BUDGET");
    }
  }

 private:
  void keep(const Run& run) {
    const std::string name = run.run_name.function_name;  // BM_HandTick/<object>/<kind>
    if (name.rfind("BM_HandTick/", 0) != 0 || run.error_occurred) return;
    // Single runs count when there are no repetitions; otherwise only the median aggregate.
    if (run.run_type == Run::RT_Aggregate ? run.aggregate_name != "median" : run.repetitions > 1) return;
    const auto tick = run.counters.find("tick_us");
    if (tick == run.counters.end()) return;
    const std::size_t slash = name.rfind('/');
    const std::string object = name.substr(12, slash - 12);
    const std::string set = is_unseen_object(object) ? "unseen" : "ycb";
    us_[set][name.substr(slash + 1)][object] = 1e6 * tick->second.value;
  }

  Table us_;
};

}  // namespace
}  // namespace telegrasp::sim

int main(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  telegrasp::sim::SummaryReporter reporter;
  benchmark::RunSpecifiedBenchmarks(&reporter);
  reporter.print_summary();
  benchmark::Shutdown();
  return 0;
}
