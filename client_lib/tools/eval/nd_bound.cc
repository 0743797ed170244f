// telegrasp-eval nd-bound: how low can ND go for this rig on these objects, whoever operates it?
// An oracle searches palm poses around each object (random, then refined locally), closes the
// hand at each with precise closing, and keeps the clean grasp with the lowest mean |ND|.
#include "telegrasp/idl/cli.h"
#include "progress_line.h"
#include "commands.h"
#include "eval_inputs.h"
#include "grasp_report.h"
#include "grasp_svg.h"
#include "telegrasp/sim/hand_rig.h"
#include "telegrasp/sim/object_model.h"
#include "telegrasp/sim/scripted_operator.h"
#include "telegrasp/sim/world.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <fstream>
#include <iostream>
#include <mutex>
#include <numbers>
#include <optional>
#include <random>
#include <string>
#include <thread>
#include <vector>

namespace {

using namespace telegrasp::sim;
using nlohmann::json;
using telegrasp::eval::parse_offline_flag;
using telegrasp::report::capsule_json;
using telegrasp::report::capsule_records;
using telegrasp::report::fmt;
using telegrasp::report::percentile;

constexpr const char* kUsage = R"(Usage: telegrasp-eval nd-bound [options]

A lower bound on the ND error metric for a rig, whoever operates it. For each object an
oracle tries palm poses all around it (random orientations and positions, each backed off
along the palm normal until the hand is clear of the object, then the best refined by small
moves), closes the hand fully at each with precise closing, and keeps the clean grasp with
the lowest mean |ND|. Clean: the grasp rule holds, no blocked capsule ends below -0.1 mm,
the palm is outside the object, no finger under the table, at least --min-hits capsules
whose ND sweep hits. It prints per object the kept grasp's |ND| statistics and, over all
kept grasps, the median and 95th percentile of |ND|: the numbers a scripted or human
operator's grasps are measured by. A random search finds an upper estimate of that bound.

Options:
  --objects DIR    every mesh file in DIR; default: the 30 built-in stand-ins
  --rig FILE       hand rig text file (default: built-in human_right_opposable)
  --poses N        random poses per object (default 400)
  --refine N       local refinement steps from the best pose (default 300)
  --min-hits K     capsules whose sweep must hit (default 5)
  --seed S         random seed (default 1)
  --json FILE      write each object's kept grasp (capsules as in telegrasp-eval) and the summary
  --svg DIR        draw each object's kept grasp as DIR/<object>_nd_bound.svg
  --jobs N         worker threads (default 2; --threads, its old name, still works)
  -h, --help       this text

Progress goes to stderr (in place on a terminal, a line every few seconds in a log), the table
to stdout.
Exit status: 0 done, 1 a runtime failure (the --objects folder, the rig or a mesh missing or
unreadable, an output not writable), 2 a usage error (a bad or missing option or value).
)";

struct Options {
  std::string objects_dir, rig_path, json_path, svg_dir;
  int poses = 400, refine = 300, min_hits = 5, threads = 2;
  std::uint64_t seed = 1;
};

constexpr const char* kTool = "telegrasp-eval nd-bound";

[[noreturn]] void usage_error(const std::string& what) { telegrasp::cli::usage_exit(kTool, what); }

Options parse(int argc, char** argv) {
  using telegrasp::cli::parse_whole;
  Options o;
  telegrasp::cli::for_each_option(argc, argv, kUsage, usage_error, [&](const std::string& a, const auto& value) {
    if (parse_offline_flag(kTool, a, value, o, usage_error))
      ;
    else if (a == "--poses")
      o.poses = static_cast<int>(parse_whole(a, value(), 1, 1000000, usage_error));
    else if (a == "--refine")
      o.refine = static_cast<int>(parse_whole(a, value(), 0, 1000000, usage_error));
    else if (a == "--min-hits")
      o.min_hits = static_cast<int>(parse_whole(a, value(), 1, 1000, usage_error));
    else
      return false;
    return true;
  });
  return o;
}

constexpr double kDt = 1.0 / 90.0;

// Searches every object, on --jobs workers, showing a progress line. `poses` gets each object's
// resting pose, the pose its search is made in.
std::vector<NdSearchResult> search_all(const Options& opt, const std::shared_ptr<const HandRig>& rig,
                                       const std::vector<ObjectModelPtr>& models,
                                       std::vector<Eigen::Isometry3d>& poses) {
  NdSearchSettings search;
  search.random_poses = opt.poses;
  search.refinements = opt.refine;
  search.min_hits = opt.min_hits;
  std::vector<NdSearchResult> kept(models.size());
  poses.assign(models.size(), Eigen::Isometry3d::Identity());
  std::atomic<std::size_t> next{0}, finished{0};
  std::mutex log_mutex;
  telegrasp::tools::ProgressLine progress;
  auto worker = [&] {
    for (std::size_t j = next++; j < models.size(); j = next++) {
      poses[j] = World::resting_pose(*models[j], 0.45, 0.0, 0.0);
      NdSearchSettings s = search;
      s.seed = opt.seed * 1000003ULL + j;
      kept[j] = nd_pose_search(rig, *models[j], poses[j], s, kDt);
      std::lock_guard lock(log_mutex);
      const std::size_t done = ++finished;
      const std::string line = "[" + std::to_string(done) + "/" + std::to_string(models.size()) + "] " +
                               models[j]->name + ": " + std::to_string(kept[j].clean_grasps) + " clean grasps of " +
                               std::to_string(kept[j].poses_tried) + " poses";
      if (done == models.size())
        progress.finish(line);
      else
        progress.show(line);
    }
  };
  std::vector<std::thread> pool;
  for (int i = 0; i < opt.threads; ++i) pool.emplace_back(worker);
  for (auto& t : pool) t.join();
  return kept;
}

// One object's row of the table, its JSON and (--svg) its picture; its |ND| values join `pooled`.
json report_object(const Options& opt, const HandRig& rig, const ObjectModelPtr& model, const Eigen::Isometry3d& pose,
                   const NdSearchResult& k, std::vector<double>& pooled) {
  json o = {{"object", model->name}, {"poses_tried", k.poses_tried}, {"clean_grasps", k.clean_grasps}};
  if (!k.best) {
    std::printf("%-28s %7d %7d %9s\n", model->name.c_str(), k.poses_tried, k.clean_grasps, "no clean grasp");
    o["kept"] = nullptr;
    return o;
  }
  std::vector<double> v;
  for (const CapsuleMetric& c : k.best->metrics.capsules)
    if (c.hit) v.push_back(1000.0 * std::abs(c.nd));
  pooled.insert(pooled.end(), v.begin(), v.end());
  std::printf("%-28s %7d %7d %9s %9s %9s %5zu %8d\n", model->name.c_str(), k.poses_tried, k.clean_grasps,
              fmt(k.nd_mean_mm, 3).c_str(), fmt(percentile(v, 0.5), 3).c_str(), fmt(percentile(v, 1.0), 3).c_str(),
              v.size(), k.best->blocked);
  const Eigen::Isometry3d X_ObjectPalm = pose.inverse() * k.best->hand.state().X_WorldPalm;
  const Eigen::Quaterniond q(X_ObjectPalm.linear());
  o["kept"] = {{"nd_mean_mm", k.nd_mean_mm},
               {"hand_error_mm", k.best->metrics.hand_error_mm},
               {"blocked", k.best->blocked},
               {"capsules", capsule_json(capsule_records(k.best->metrics, rig))},
               {"p_object_palm",
                {X_ObjectPalm.translation().x(), X_ObjectPalm.translation().y(), X_ObjectPalm.translation().z()}},
               {"q_object_palm_wxyz", {q.w(), q.x(), q.y(), q.z()}}};
  if (!opt.svg_dir.empty()) {
    const ObjectView view{ObjectId(0), pose, model.get()};
    const std::string title = model->name + ", nd-bound (oracle pose): mean |ND| " + fmt(k.nd_mean_mm, 2) + " mm";
    std::ofstream(opt.svg_dir + "/" + model->name + "_nd_bound.svg") << render_svg(snapshot(k.best->hand, view, title));
  }
  return o;
}

}  // namespace

int telegrasp::eval::run_nd_bound(int argc, char** argv) {
  using namespace telegrasp::eval;
  const Options opt = parse(argc, argv);
  std::shared_ptr<const HandRig> rig;
  std::vector<ObjectModelPtr> models;
  try {
    EvalInputs in = load_eval_inputs(opt.rig_path, opt.objects_dir);
    rig = std::move(in.rig);
    models = std::move(in.models);
  } catch (const std::exception& e) {
    std::cerr << kTool << ": " << e.what() << "\n";
    return telegrasp::cli::kExitFailure;
  }
  std::ofstream json_out;
  if (const std::string error = prepare_outputs(opt.json_path, json_out, opt.svg_dir); !error.empty()) {
    std::cerr << kTool << ": " << error << "\n";
    return telegrasp::cli::kExitFailure;
  }

  std::vector<Eigen::Isometry3d> poses;
  const std::vector<NdSearchResult> kept = search_all(opt, rig, models, poses);

  std::printf("\n== nd-bound: rig %s, %d random poses + %d refinements per object, >= %d hits ==\n",
              rig->name().c_str(), opt.poses, opt.refine, opt.min_hits);
  std::printf("%-28s %7s %7s %9s %9s %9s %5s %8s\n", "object", "tried", "clean", "|ND|mean", "|ND|med", "|ND|max",
              "hits", "blocked");
  json objects = json::array();
  std::vector<double> pooled;
  for (std::size_t j = 0; j < models.size(); ++j)
    objects.push_back(report_object(opt, *rig, models[j], poses[j], kept[j], pooled));
  const json summary = {{"rig", rig->name()},
                        {"min_hits", opt.min_hits},
                        {"objects", models.size()},
                        {"capsules_hit", pooled.size()},
                        {"nd_abs_median_mm", percentile(pooled, 0.5)},
                        {"nd_abs_p95_mm", percentile(pooled, 0.95)}};
  std::printf("over the kept grasps: %zu capsules hit, |ND| median %s mm, 95th percentile %s mm\n", pooled.size(),
              fmt(percentile(pooled, 0.5), 3).c_str(), fmt(percentile(pooled, 0.95), 3).c_str());
  if (!opt.json_path.empty()) {
    json_out << json{{"objects", objects}, {"summary", summary}}.dump(1) << "\n";
    if (!json_out.flush()) {
      std::cerr << kTool << ": --json " << opt.json_path << ": cannot write\n";
      return telegrasp::cli::kExitFailure;
    }
  }
  return 0;
}
