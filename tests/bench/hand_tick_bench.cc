// BM_HandTick/<object>/{closing,grasp,holding}: one full simulation tick of one hand (selection,
// interaction manager, finger movement, grasping logic, metrics and contacts) against a mesh:
// closing = the ticks of the squeeze before the grasp (averaged), grasp = the one tick the grasp
// rule turns true (contacts taken, and the copy of the hand the World's worker takes the grasp's
// metrics from), holding = a tick while holding. Counters: tick_us and the same figure named
// after the kind (closing_us, grasp_us, holding_us); the grasp tick also has the worker's share,
// which the World computes on its QualityWorker thread, not in this tick: metrics_us (every
// capsule's ND sweep and exact signed distance, the palm's: grasp_tick_metrics()) and quality_us
// (wrench_epsilon() of the grasp's contacts), and contacts.
// Two sets: "ycb", the meshes of $TELEGRASP_OBJECTS_DIR (default ../shared/data/ycb; the
// built-in stand-ins when missing), and "unseen", generated stand-ins for meshes nobody tuned
// for (tests/bench/unseen_meshes.h: those YCB meshes under random rotations, and procedural
// markers, spoons and airplanes). bench_main.cc prints each set's worst object per kind.
#include "hand_tick_bench.h"
#include "sim_bench.h"
#include "telegrasp/sim/hand_controller.h"
#include "telegrasp/sim/mesh_loading.h"
#include "telegrasp/sim/scripted_operator.h"
#include "telegrasp/sim/standin_objects.h"
#include "telegrasp/sim/world.h"
#include "unseen_meshes.h"

#include <benchmark/benchmark.h>

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <functional>
#include <map>
#include <mutex>

namespace telegrasp::sim {
namespace {

using bench::kDt;

struct Fixture {
  ObjectModelPtr model;
  Eigen::Isometry3d X_WorldObject;
  GraspPlan plan;
  int grasp_tick = -1;  // index of the tick on which the squeeze grasps
};

// The squeeze: the trigger ramps from 0 to 1 in 0.35 s with the hand still at the planned pose.
ControllerInput squeeze(const GraspPlan& plan, int tick) {
  ControllerInput in;
  in.X_WorldPalm = plan.X_WorldPalm;
  in.trigger = std::min(1.0, tick * kDt / 0.35);
  return in;
}

/// Makes an object's model (loads or generates its mesh).
using ModelMaker = std::function<ObjectModelPtr()>;

// Makes the model and plans once per object (outside the timed loops).
const Fixture& fixture(const std::string& name, const ModelMaker& make_model) {
  static std::map<std::string, Fixture> cache;
  static std::mutex mutex;
  std::lock_guard lock(mutex);
  auto it = cache.find(name);
  if (it != cache.end()) return it->second;
  Fixture f;
  f.model = make_model();
  f.X_WorldObject = World::resting_pose(*f.model, 0.45, 0.0, 0.4);
  f.plan = plan_grasp(bench::right_rig(), {}, *f.model, f.X_WorldObject, kDt);
  HandController dry_run(bench::right_rig(), {});
  const ObjectView view{ObjectId(0), f.X_WorldObject, f.model.get()};
  for (int t = 0; t < 90 && f.grasp_tick < 0; ++t)
    if (dry_run.tick(squeeze(f.plan, t), kDt, {&view, 1}).grasped) f.grasp_tick = t;
  return cache.emplace(name, std::move(f)).first->second;
}

// Seconds of CPU time per tick (shown in us), as tick_us and as `kind_counter`.
void set_tick_counters(benchmark::State& state, const char* kind_counter, int ticks_per_iteration) {
  const auto per_tick = [&] {
    return benchmark::Counter(ticks_per_iteration,
                              benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
  };
  state.counters["tick_us"] = per_tick();
  state.counters[kind_counter] = per_tick();
}

// Every tick of the squeeze before the grasp tick, averaged.
void BM_Closing(benchmark::State& state, const std::string& name, const ModelMaker& make_model) {
  const Fixture& f = fixture(name, make_model);
  const ObjectView view{ObjectId(0), f.X_WorldObject, f.model.get()};
  for (auto _ : state) {
    HandController hand(bench::right_rig(), {});
    for (int t = 0; t < f.grasp_tick; ++t) hand.tick(squeeze(f.plan, t), kDt, {&view, 1});
    benchmark::DoNotOptimize(hand.state().q.data());
  }
  set_tick_counters(state, "closing_us", f.grasp_tick);
  state.counters["ticks"] = f.grasp_tick;
  state.counters["model_MB"] = static_cast<double>(f.model->memory_bytes()) / 1e6;
}

// The grasp tick alone, as a World's hand makes it: the rule turns true, the contacts are
// taken and the hand is copied for the worker. Each iteration also copies the hand as it was
// one tick earlier (included).
void BM_GraspTick(benchmark::State& state, const std::string& name, const ModelMaker& make_model) {
  const Fixture& f = fixture(name, make_model);
  const ObjectView view{ObjectId(0), f.X_WorldObject, f.model.get()};
  HandController before(bench::right_rig(), {});
  before.defer_grasp_metrics();
  for (int t = 0; t < f.grasp_tick; ++t) before.tick(squeeze(f.plan, t), kDt, {&view, 1});
  bool grasped = false;
  for (auto _ : state) {
    HandController hand = before;
    grasped = hand.tick(squeeze(f.plan, f.grasp_tick), kDt, {&view, 1}).grasped;
    benchmark::DoNotOptimize(hand.contacts().data());
    benchmark::DoNotOptimize(std::make_shared<const HandController>(hand).get());
  }
  set_tick_counters(state, "grasp_us", 1);
  state.counters["grasped"] = grasped;
  // The other path: the grasp's metrics and quality, which the World's QualityWorker computes
  // off the simulation thread (no memo: a new grasp's contact set), timed here outside the loop.
  HandController hand = before;
  hand.tick(squeeze(f.plan, f.grasp_tick), kDt, {&view, 1});
  constexpr int kRepetitions = 20;
  const auto per_repetition_us = [](auto&& run) {
    const auto t0 = std::chrono::steady_clock::now();
    for (int i = 0; i < kRepetitions; ++i) run();
    return std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - t0).count() / kRepetitions;
  };
  state.counters["metrics_us"] = per_repetition_us([&] {
    const HandController copy = hand;  // a fresh copy each time: the worker's has no cached searches
    benchmark::DoNotOptimize(copy.grasp_tick_metrics());
  });
  if (const std::optional<QualityJob> job = hand.quality_inputs()) {
    const Wrenches w = contact_wrenches(job->contacts, job->mu, job->torque_scale);
    state.counters["quality_us"] = per_repetition_us([&] { benchmark::DoNotOptimize(wrench_quality(w)); });
    state.counters["contacts"] = static_cast<double>(job->contacts.size());
  }
}

// Ticks while holding the grasped object (trigger held at 1, hand still).
void BM_Holding(benchmark::State& state, const std::string& name, const ModelMaker& make_model) {
  const Fixture& f = fixture(name, make_model);
  const ObjectView view{ObjectId(0), f.X_WorldObject, f.model.get()};
  HandController hand(bench::right_rig(), {});
  for (int t = 0; t <= f.grasp_tick; ++t) hand.tick(squeeze(f.plan, t), kDt, {&view, 1});
  ControllerInput in = squeeze(f.plan, 1000);
  for (auto _ : state) {
    hand.tick(in, kDt, {&view, 1});
    benchmark::DoNotOptimize(hand.state().q.data());
  }
  set_tick_counters(state, "holding_us", 1);
  state.counters["grasped"] = hand.state().grasped.valid();
}

// Registers the closing, grasp and holding benchmarks of one object.
void register_object(const std::string& name, const ModelMaker& make_model) {
  benchmark::RegisterBenchmark(("BM_HandTick/" + name + "/closing").c_str(), BM_Closing, name, make_model)
      ->Unit(benchmark::kMicrosecond);
  benchmark::RegisterBenchmark(("BM_HandTick/" + name + "/grasp").c_str(), BM_GraspTick, name, make_model)
      ->Unit(benchmark::kMicrosecond);
  benchmark::RegisterBenchmark(("BM_HandTick/" + name + "/holding").c_str(), BM_Holding, name, make_model)
      ->Unit(benchmark::kMicrosecond);
}

// A generated mesh's model; unknown objects weigh their volume x 500 kg/m^3.
ModelMaker generated(std::string name, std::function<TriangleMesh()> make_mesh) {
  return [name = std::move(name), make_mesh = std::move(make_mesh)] {
    return make_object_model(name, make_mesh(), 0.0, "generated by tests/bench/unseen_meshes.cc");
  };
}

// The "ycb" set: one object per mesh file (or per stand-in when the folder is missing); the
// "unseen" set: each of those files under a random rotation, then the procedural meshes.
const bool registered = [] {
  std::vector<std::pair<std::string, std::string>> files = bench::object_mesh_files();  // stem, path
  std::sort(files.begin(), files.end());
  if (files.empty())
    for (const auto& o : protocol_objects())
      register_object(o.name + "_standin", [o] { return make_standin_model(o); });
  for (const auto& [stem, path] : files) register_object(stem, [path] { return load_protocol_object_model(path); });
  unsigned seed = 1;
  for (const auto& [stem, path] : files) {
    const std::string name = stem + "_rotated";
    register_object(name,
                    generated(name, [path, seed] { return bench::randomly_rotated(load_mesh_file(path), seed); }));
    ++seed;
  }
  for (const auto& m : bench::procedural_unseen_meshes())
    register_object(m.name, generated(m.name, [mesh = m.mesh] { return mesh; }));
  return true;
}();

}  // namespace

bool is_unseen_object(const std::string& name) { return name.rfind("gen_", 0) == 0 || name.ends_with("_rotated"); }

}  // namespace telegrasp::sim
