// BM_HandTick/<object>/pushing: one tick of one open hand whose controller pushes into the object
// and back (up to 40 mm past the planned pose along the approach, with a sideways wobble), so the
// resolved-pose search runs every tick against the exact mesh: the worst case of operator pose
// error. BM_HandTick/<object>/pushing_unresolved: the same with GraspSettings::resolve_pose off
// (the hand follows the controller in, as before the resolved pose). Objects as in hand_tick_bench.cc:
// $TELEGRASP_OBJECTS_DIR (default ../shared/data/ycb), or the built-in stand-ins.
#include "sim_bench.h"
#include "telegrasp/sim/hand_controller.h"
#include "telegrasp/sim/mesh_loading.h"
#include "telegrasp/sim/scripted_operator.h"
#include "telegrasp/sim/standin_objects.h"
#include "telegrasp/sim/world.h"

#include <benchmark/benchmark.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>

namespace telegrasp::sim {
namespace {

using bench::kDt;
constexpr int kTicks = 90;  // one second of pushing, repeated

// The controller at tick t: the planned pose moved along the approach by up to 40 mm past it and
// 10 mm short, wobbling 5 mm sideways.
ControllerInput pushing(const GraspPlan& plan, int t) {
  ControllerInput in;
  in.X_WorldPalm = plan.X_WorldPalm;
  const double phase = 2.0 * 3.141592653589793 * t / kTicks;
  const Eigen::Vector3d side = plan.approach_World.unitOrthogonal();
  in.X_WorldPalm.translation() +=
      (0.015 - 0.025 * std::cos(phase)) * plan.approach_World + 0.005 * std::sin(3 * phase) * side;
  return in;
}

void BM_Pushing(benchmark::State& state, const std::string& source, bool resolve) {
  const auto known = find_protocol_object(source);
  const ObjectModelPtr model =
      std::filesystem::exists(source) ? load_protocol_object_model(source) : make_standin_model(*known);
  const Eigen::Isometry3d X_WorldObject = World::resting_pose(*model, 0.45, 0.0, 0.4);
  const GraspPlan plan = plan_grasp(bench::right_rig(), {}, *model, X_WorldObject, kDt);
  const ObjectView view{ObjectId(0), X_WorldObject, model.get()};
  GraspSettings settings;
  settings.resolve_pose = resolve;
  HandController hand(bench::right_rig(), settings);
  int t = 0;
  for (auto _ : state) {
    hand.tick(pushing(plan, t), kDt, {&view, 1});
    t = (t + 1) % kTicks;
    benchmark::DoNotOptimize(hand.state().X_WorldPalm.data());
  }
  state.counters["tick_us"] =
      benchmark::Counter(1, benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
  const Eigen::Vector3d offset = hand.state().X_WorldPalm.translation() - hand.state().X_WorldTracked.translation();
  state.counters["offset_mm"] = 1000.0 * offset.norm();
}

const bool registered = [] {
  std::vector<std::pair<std::string, std::string>> objects = bench::object_mesh_files();  // name, source
  if (objects.empty())
    for (const auto& o : protocol_objects()) objects.emplace_back(o.name + "_standin", o.name);
  std::sort(objects.begin(), objects.end());
  for (const auto& [name, source] : objects)
    for (bool resolve : {true, false})
      benchmark::RegisterBenchmark(("BM_HandTick/" + name + (resolve ? "/pushing" : "/pushing_unresolved")).c_str(),
                                   BM_Pushing, source, resolve)
          ->Unit(benchmark::kMicrosecond);
  return true;
}();

}  // namespace
}  // namespace telegrasp::sim
