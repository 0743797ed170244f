// BM_GraspQuality/<n>: grasp_quality() (sim/grasp_quality.h: 8-edge cones, Qhull hull of the 6-D
// wrenches, epsilon and volume) for n contacts spread over a 4 cm sphere with radial normals
// (seeded, 8 different sets cycled). BM_GraspQuality/held/<object>: the contacts of the human
// hand holding a built-in stand-in after a full squeeze (as BM_HandTick's holding tick).
#include "telegrasp/sim/grasp_quality.h"
#include "telegrasp/sim/hand_controller.h"
#include "telegrasp/sim/scripted_operator.h"
#include "telegrasp/sim/standin_objects.h"
#include "telegrasp/sim/world.h"

#include <benchmark/benchmark.h>

#include <algorithm>
#include <random>
#include <string>
#include <vector>

namespace telegrasp::sim {
namespace {

constexpr double kDt = 1.0 / 90.0;

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

void BM_GraspQualityHeld(benchmark::State& state, const std::string& object) {
  static const auto rig = std::make_shared<const HandRig>(HandRig::load(HandRig::builtin_path("human_right")));
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

const bool registered = [] {
  for (const char* object : {"006_mustard_bottle", "011_banana", "013_apple", "035_power_drill"})
    benchmark::RegisterBenchmark((std::string("BM_GraspQuality/held/") + object).c_str(), BM_GraspQualityHeld,
                                 std::string(object))
        ->Unit(benchmark::kMicrosecond);
  return true;
}();

}  // namespace
}  // namespace telegrasp::sim
