// BM_GraspQuality/<n>: grasp_quality() (sim/grasp_quality.h: 8-edge cones, epsilon by the
// expanding polytope, no volume) for n contacts spread over a 4 cm sphere with radial normals
// (seeded, 8 different sets cycled). BM_GraspQuality/held/<object>: the contacts of the human
// hand holding a built-in stand-in after a full squeeze (as BM_HandTick's holding tick).
// BM_GraspQualityTrial/<object>: one scripted trial of the human hand on a built-in stand-in in a
// World (react, reach, squeeze, lift, hold 1 s, release; "experienced" operator, seed 3), asking
// hold_metrics() on every held tick as the server does. Counters per trial: held_ticks, hulls
// (HandController::quality_hulls(): the qualities computed), hulls_per_held_tick, distinct_sets (the
// distinct contact sets held, the least any cache can do), last_only_hulls (what reusing only
// the last hull's quality, for contacts within 1e-6 m and 1e-6 of it, would build: the rule before
// the hand kept several) and hold_ms (CPU time in hold_metrics(): every hull but the grasp tick's).
#include "sim_bench.h"
#include "telegrasp/sim/grasp_quality.h"
#include "telegrasp/sim/hand_controller.h"
#include "telegrasp/sim/scripted_operator.h"
#include "telegrasp/sim/standin_objects.h"
#include "telegrasp/sim/world.h"

#include <benchmark/benchmark.h>

#include <algorithm>
#include <cmath>
#include <chrono>
#include <ctime>
#include <random>
#include <string>
#include <vector>

namespace telegrasp::sim {
namespace {

using bench::kDt;

void BM_GraspQuality(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  std::mt19937 rng(12);
  std::normal_distribution<double> gauss;
  std::vector<std::vector<QualityContact>> sets(8);
  for (auto& set : sets)
    for (int i = 0; i < n; ++i) {
      const Eigen::Vector3d d = Eigen::Vector3d(gauss(rng), gauss(rng), gauss(rng)).normalized();
      set.push_back({0.04 * d, d});
    }
  std::size_t k = 0;
  int closure = 0;
  for (auto _ : state) {
    const GraspQuality q = grasp_quality(sets[k++ % sets.size()], 0.5, 0.04);
    closure += q.force_closure;
    benchmark::DoNotOptimize(q);
  }
  state.counters["contacts"] = n;
  state.counters["closure_share"] = static_cast<double>(closure) / static_cast<double>(state.iterations());
}
BENCHMARK(BM_GraspQuality)->Arg(5)->Arg(10)->Arg(16)->Unit(benchmark::kMicrosecond);

// BM_Epsilon/<n>: Ferrari-Canny epsilon of n contacts (8-edge cones, mu 0.5, a 4 cm sphere with
// radial normals tilted at random; 16 seeded sets cycled) two ways in one run: wrench_epsilon()
// (the expanding polytope, timed by the benchmark) and Qhull's full hull (qhull_wrench_quality(),
// timed over the same sets before the loop). Counters: incremental_us and qhull_us (mean per
// grasp), ratio (qhull_us / incremental_us), facets (built by the polytope, mean), closure_share
// and max_delta (largest |epsilon difference| between the two on these sets).
void BM_Epsilon(benchmark::State& state) {
  using Clock = std::chrono::steady_clock;
  const int n = static_cast<int>(state.range(0));
  std::mt19937 rng(21);
  std::normal_distribution<double> gauss;
  std::vector<Wrenches> sets(16);
  for (auto& set : sets) {
    std::vector<QualityContact> contacts;
    for (int i = 0; i < n; ++i) {
      const Eigen::Vector3d d = Eigen::Vector3d(gauss(rng), gauss(rng), gauss(rng)).normalized();
      const Eigen::Vector3d tilt = 0.3 * Eigen::Vector3d(gauss(rng), gauss(rng), gauss(rng));
      contacts.push_back({0.04 * d, (d + tilt).normalized()});
    }
    set = contact_wrenches(contacts, 0.5, 0.04);
  }
  std::vector<double> reference(sets.size());
  const auto q0 = Clock::now();
  for (int rep = 0; rep < 2; ++rep)
    for (std::size_t k = 0; k < sets.size(); ++k) reference[k] = qhull_wrench_quality(sets[k]).epsilon;
  const double qhull_us =
      std::chrono::duration<double, std::micro>(Clock::now() - q0).count() / (2.0 * static_cast<double>(sets.size()));
  double max_delta = 0, facets = 0;
  int closure = 0;
  for (std::size_t k = 0; k < sets.size(); ++k) {
    const EpsilonResult e = wrench_epsilon(sets[k]);
    max_delta = std::max(max_delta, std::abs(e.epsilon - reference[k]));
    facets += e.facets;
    closure += e.force_closure;
  }
  std::size_t k = 0;
  const auto e0 = Clock::now();
  for (auto _ : state) benchmark::DoNotOptimize(wrench_epsilon(sets[k++ % sets.size()]));
  const double incremental_us =
      std::chrono::duration<double, std::micro>(Clock::now() - e0).count() / static_cast<double>(state.iterations());
  const double count = static_cast<double>(sets.size());
  state.counters["contacts"] = n;
  state.counters["incremental_us"] = incremental_us;
  state.counters["qhull_us"] = qhull_us;
  state.counters["ratio"] = qhull_us / incremental_us;
  state.counters["facets"] = facets / count;
  state.counters["closure_share"] = closure / count;
  state.counters["max_delta"] = max_delta;
}
BENCHMARK(BM_Epsilon)->Arg(3)->Arg(5)->Arg(10)->Arg(16)->Arg(20)->Unit(benchmark::kMicrosecond);

void BM_GraspQualityHeld(benchmark::State& state, const std::string& object) {
  const auto rig = bench::right_rig();
  const ObjectModelPtr model = make_standin_model(*find_protocol_object(object));
  const Eigen::Isometry3d X_WorldObject = World::resting_pose(*model, 0.45, 0.0, 0.4);
  const GraspPlan plan = plan_grasp(rig, {}, *model, X_WorldObject, kDt);
  const ObjectView view{ObjectId(0), X_WorldObject, model.get()};
  HandController hand(rig, {});
  ControllerInput in;
  in.X_WorldPalm = plan.X_WorldPalm;
  for (int t = 0; t < 120; ++t) {
    in.trigger = std::min(1.0, t * kDt / 0.35);
    hand.tick(in, kDt, {&view, 1});
  }
  std::vector<QualityContact> contacts;
  for (const Contact& c : hand.contacts()) contacts.push_back({c.p_ObjectContact, c.n_Object});
  GraspQuality q;
  for (auto _ : state) {
    q = grasp_quality(contacts, 0.5, model->max_radius);
    benchmark::DoNotOptimize(q);
  }
  state.counters["contacts"] = static_cast<double>(contacts.size());
  state.counters["epsilon"] = q.epsilon;
}

bool same_contacts(const std::vector<QualityContact>& a, const std::vector<QualityContact>& b, double tolerance) {
  return a.size() == b.size() && std::equal(a.begin(), a.end(), b.begin(), [&](const auto& x, const auto& y) {
           return (x.p - y.p).norm() <= tolerance && (x.n - y.n).norm() <= tolerance;
         });
}

double cpu_seconds() {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

void BM_GraspQualityTrial(benchmark::State& state, const std::string& object) {
  const auto rig = bench::right_rig();
  const ObjectModelPtr model = make_standin_model(*find_protocol_object(object));
  int held = 0, distinct = 0, last_only = 0;
  std::uint64_t hulls = 0;
  double hold_s = 0;
  for (auto _ : state) {
    World world;
    const ObjectId id = world.add_object(model, World::resting_pose(*model, 0.45, 0.02, 0.5));
    const HandId hand_id = world.add_hand(rig);
    for (int i = 0; i < 30; ++i) world.step();
    ScriptedOperator op(rig, skill_profile("experienced"), 3);
    op.begin(*model, world.object_pose(id), Eigen::Isometry3d(Eigen::Translation3d(0.15, -0.2, 0.3)), world.time());
    std::vector<std::vector<QualityContact>> seen;
    std::vector<QualityContact> last_hull;
    bool have_last = false;
    held = distinct = last_only = 0;
    hold_s = 0;
    while (!op.done() && world.time() < 20) {
      world.set_input(hand_id, op.next(world.time(), world.holder(id) == hand_id));
      world.step();
      const HandController& hand = world.hand(hand_id);
      if (!hand.state().grasped.valid()) {
        have_last = false;
        continue;
      }
      const double t1 = cpu_seconds();
      benchmark::DoNotOptimize(hand.hold_metrics());
      hold_s += cpu_seconds() - t1;
      ++held;
      state.PauseTiming();
      const std::vector<QualityContact> kept = HandController::quality_contacts(hand.contacts());
      if (std::none_of(seen.begin(), seen.end(), [&](const auto& s) { return same_contacts(s, kept, 0); })) {
        seen.push_back(kept);
      }
      if (!have_last || !same_contacts(kept, last_hull, 1e-6)) {
        ++last_only;
        last_hull = kept;
        have_last = true;
      }
      state.ResumeTiming();
    }
    distinct = static_cast<int>(seen.size());
    hulls = world.quality_computations(hand_id);
  }
  state.counters["held_ticks"] = held;
  state.counters["hulls"] = static_cast<double>(hulls);
  state.counters["hulls_per_held_tick"] = held ? static_cast<double>(hulls) / held : 0.0;
  state.counters["distinct_sets"] = distinct;
  state.counters["last_only_hulls"] = last_only;
  state.counters["hold_ms"] = 1e3 * hold_s;
}

const bool registered = [] {
  for (const char* object : {"006_mustard_bottle", "011_banana", "013_apple", "035_power_drill"})
    benchmark::RegisterBenchmark((std::string("BM_GraspQuality/held/") + object).c_str(), BM_GraspQualityHeld,
                                 std::string(object))
        ->Unit(benchmark::kMicrosecond);
  for (const char* object : {"002_master_chef_can", "005_tomato_soup_can", "006_mustard_bottle", "013_apple"})
    benchmark::RegisterBenchmark((std::string("BM_GraspQualityTrial/") + object).c_str(), BM_GraspQualityTrial,
                                 std::string(object))
        ->Unit(benchmark::kMillisecond)
        ->Iterations(2);
  return true;
}();

}  // namespace
}  // namespace telegrasp::sim
