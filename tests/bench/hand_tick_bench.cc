// BM_HandTick/<object>/{closing,grasp,holding}: one full simulation tick of one hand (selection,
// interaction manager, finger movement, grasping logic, metrics and contacts) against a YCB mesh
// read from $TELEGRASP_OBJECTS_DIR (default ../shared/data/ycb), or the built-in stand-ins:
// closing = the ticks of the squeeze before the grasp (averaged), grasp = the one tick the grasp
// rule turns true (metrics and contacts taken), holding = a tick while holding.
#include "telegrasp/sim/hand_controller.h"
#include "telegrasp/sim/mesh_loading.h"
#include "telegrasp/sim/scripted_operator.h"
#include "telegrasp/sim/standin_objects.h"
#include "telegrasp/sim/world.h"

#include <benchmark/benchmark.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <mutex>

namespace telegrasp::sim {
namespace {

constexpr double kDt = 1.0 / 90.0;

std::string objects_dir() {
  // The YCB meshes beside the repository when run from its root, as the README does.
  const char* env = std::getenv("TELEGRASP_OBJECTS_DIR");
  return env ? env : "../shared/data/ycb";
}

struct Fixture {
  ObjectModelPtr model;
  Eigen::Isometry3d X_WorldObject;
  GraspPlan plan;
  int grasp_tick = -1;  // index of the tick on which the squeeze grasps
};

std::shared_ptr<const HandRig> rig() {
  static auto r = std::make_shared<const HandRig>(HandRig::load(HandRig::builtin_path("human_right")));
  return r;
}

// The squeeze: the trigger ramps from 0 to 1 in 0.35 s with the hand still at the planned pose.
ControllerInput squeeze(const GraspPlan& plan, int tick) {
  ControllerInput in;
  in.X_WorldPalm = plan.X_WorldPalm;
  in.trigger = std::min(1.0, tick * kDt / 0.35);
  return in;
}

// Loads and plans once per object (outside the timed loops).
const Fixture& fixture(const std::string& source) {
  static std::map<std::string, Fixture> cache;
  static std::mutex mutex;
  std::lock_guard lock(mutex);
  auto it = cache.find(source);
  if (it != cache.end()) return it->second;
  Fixture f;
  const auto known = find_protocol_object(source);
  f.model = std::filesystem::exists(source) ? load_protocol_object_model(source) : make_standin_model(*known);
  f.X_WorldObject = World::resting_pose(*f.model, 0.45, 0.0, 0.4);
  f.plan = plan_grasp(rig(), {}, *f.model, f.X_WorldObject, kDt);
  HandController dry_run(rig(), {});
  const ObjectView view{ObjectId(0), f.X_WorldObject, f.model.get()};
  for (int t = 0; t < 90 && f.grasp_tick < 0; ++t)
    if (dry_run.tick(squeeze(f.plan, t), kDt, {&view, 1}).grasped) f.grasp_tick = t;
  return cache.emplace(source, std::move(f)).first->second;
}

// Every tick of the squeeze before the grasp tick, averaged.
void BM_Closing(benchmark::State& state, const std::string& source) {
  const Fixture& f = fixture(source);
  const ObjectView view{ObjectId(0), f.X_WorldObject, f.model.get()};
  for (auto _ : state) {
    HandController hand(rig(), {});
    for (int t = 0; t < f.grasp_tick; ++t) hand.tick(squeeze(f.plan, t), kDt, {&view, 1});
    benchmark::DoNotOptimize(hand.state().q.data());
  }
  state.counters["tick_us"] =
      benchmark::Counter(f.grasp_tick, benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
  state.counters["ticks"] = f.grasp_tick;
  state.counters["model_MB"] = static_cast<double>(f.model->memory_bytes()) / 1e6;
}

// The grasp tick alone: the rule turns true, metrics (ND sweeps, exact signed distances) and
// contacts are computed. Each iteration copies the hand as it was one tick earlier (included).
void BM_GraspTick(benchmark::State& state, const std::string& source) {
  const Fixture& f = fixture(source);
  const ObjectView view{ObjectId(0), f.X_WorldObject, f.model.get()};
  HandController before(rig(), {});
  for (int t = 0; t < f.grasp_tick; ++t) before.tick(squeeze(f.plan, t), kDt, {&view, 1});
  bool grasped = false;
  for (auto _ : state) {
    HandController hand = before;
    grasped = hand.tick(squeeze(f.plan, f.grasp_tick), kDt, {&view, 1}).grasped;
    benchmark::DoNotOptimize(hand.state().q.data());
  }
  state.counters["tick_us"] =
      benchmark::Counter(1, benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
  state.counters["grasped"] = grasped;
}

// Ticks while holding the grasped object (trigger held at 1, hand still).
void BM_Holding(benchmark::State& state, const std::string& source) {
  const Fixture& f = fixture(source);
  const ObjectView view{ObjectId(0), f.X_WorldObject, f.model.get()};
  HandController hand(rig(), {});
  for (int t = 0; t <= f.grasp_tick; ++t) hand.tick(squeeze(f.plan, t), kDt, {&view, 1});
  ControllerInput in = squeeze(f.plan, 1000);
  for (auto _ : state) {
    hand.tick(in, kDt, {&view, 1});
    benchmark::DoNotOptimize(hand.state().q.data());
  }
  state.counters["tick_us"] =
      benchmark::Counter(1, benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
  state.counters["grasped"] = hand.state().grasped.valid();
}

// Registers one triple per mesh file (or per stand-in when the folder is missing).
const bool registered = [] {
  std::vector<std::pair<std::string, std::string>> objects;  // name, source
  std::error_code ec;
  if (std::filesystem::is_directory(objects_dir(), ec)) {
    for (const auto& e : std::filesystem::directory_iterator(objects_dir(), ec))
      if (is_mesh_file(e.path().string())) objects.emplace_back(e.path().stem().string(), e.path().string());
  }
  if (objects.empty())
    for (const auto& o : protocol_objects()) objects.emplace_back(o.name + "_standin", o.name);
  std::sort(objects.begin(), objects.end());
  for (const auto& [name, source] : objects) {
    benchmark::RegisterBenchmark(("BM_HandTick/" + name + "/closing").c_str(), BM_Closing, source)
        ->Unit(benchmark::kMicrosecond);
    benchmark::RegisterBenchmark(("BM_HandTick/" + name + "/grasp").c_str(), BM_GraspTick, source)
        ->Unit(benchmark::kMicrosecond);
    benchmark::RegisterBenchmark(("BM_HandTick/" + name + "/holding").c_str(), BM_Holding, source)
        ->Unit(benchmark::kMicrosecond);
  }
  return true;
}();

}  // namespace
}  // namespace telegrasp::sim
