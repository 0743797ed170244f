// telegrasp-eval's in-process run: scripted grasps on objects with no network; reports success,
// time and ND.
#include "telegrasp/idl/cli.h"
#include "progress_line.h"
#include "commands.h"
#include "eval_inputs.h"
#include "grasp_report.h"
#include "grasp_svg.h"
#include "nd_bound_table.h"
#include "telegrasp/sim/hand_rig.h"
#include "telegrasp/sim/object_model.h"
#include "telegrasp/sim/scripted_operator.h"
#include "telegrasp/sim/world.h"
#include "skill_flag.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <mutex>
#include <optional>
#include <numbers>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

namespace {

using namespace telegrasp::sim;
using nlohmann::json;
using telegrasp::eval::EvalInputs;
using telegrasp::eval::parse_offline_flag;
using telegrasp::report::capsule_records;
using telegrasp::report::fmt;
using telegrasp::report::grasp_figures;
using telegrasp::report::Record;
using telegrasp::report::summarize;

constexpr const char* kUsage = R"(Usage: telegrasp-eval run [options]

Grasps every object with a scripted operator, in-process (no network), and reports
per-object success, time to grasp and the paper's ND error metric.

Options:
  --objects DIR       every mesh file in DIR (PLY, OBJ, STL, glTF, ...); default: the 30
                      built-in stand-ins of the paper's protocol
  --mode M            precise | discrete | both (default precise)
  --speed-scale LIST  closing speed multipliers, comma separated (default 1): the operator
                      squeezes the trigger that much faster and the joints' speed limits scale
  --trials N          random orientations per object (default 5)
  --seed S            random seed (default 1)
  --skill NAME        perfect | experienced | inexperienced (default experienced)
  --selection M       surface | origin: how the palm sphere ranks objects (default surface)
  --rig FILE          hand rig text file (default: built-in human_right_opposable)
  --stretch X,Y,Z     stretch every object along its x, y and z by these factors (0.25-4) about
                      its centre of mass, mass by their product: shapes nobody tuned for
  --json FILE         write every grasp record and the summaries as JSON
  --svg DIR           draw each object's first held grasp (three views) as DIR/<object>_<mode>.svg
  --bound FILE        an nd-bound --json file of the same objects and rig: adds a table of each
                      object's grasp tick |ND| beside the oracle's, and the mean over the objects
                      the oracle takes to the paper's 1.12 mm or below (on the others no clean
                      grasp with nd-bound's --min-hits capsules hitting gets there)
  --jobs N            worker threads (default 2; --threads, its old name, still works)
  -h, --help          this text

Progress goes to stderr (in place on a terminal, a line every few seconds in a log), the
per-object tables and summaries to stdout.
Exit status: 0 done, 1 a runtime failure (the --objects folder, the rig or a mesh missing or
unreadable, an output not writable), 2 a usage error (a bad or missing option or value).
Other subcommands: telegrasp-eval --help.
)";

struct Options {
  std::string objects_dir, rig_path, json_path, svg_dir, bound_path, skill = "experienced";
  std::vector<ClosingMode> modes{ClosingMode::kPrecise};
  SelectionMetric selection = SelectionMetric::kSurface;
  std::vector<double> speeds{1.0};
  Eigen::Vector3d stretch = Eigen::Vector3d::Ones();
  int trials = 5, threads = 2;
  std::uint64_t seed = 1;
};

constexpr const char* kTool = "telegrasp-eval run";

[[noreturn]] void usage_error(const std::string& what) { telegrasp::cli::usage_exit(kTool, what); }

Options parse(int argc, char** argv) {
  Options o;
  telegrasp::cli::for_each_option(argc, argv, kUsage, usage_error, [&](const std::string& a, const auto& value) {
    if (parse_offline_flag(kTool, a, value, o, usage_error))
      ;
    else if (telegrasp::cli::text_flag(a, value, {{"--bound", &o.bound_path}}))
      ;
    else if (a == "--skill")
      o.skill = telegrasp::tools::parse_skill(a, value(), usage_error);
    else if (a == "--selection") {
      const std::string m = value();
      if (m == "surface")
        o.selection = SelectionMetric::kSurface;
      else if (m == "origin")
        o.selection = SelectionMetric::kOrigin;
      else
        usage_error("--selection expects surface or origin, got '" + m + "'");
    } else if (a == "--trials")
      o.trials = static_cast<int>(telegrasp::cli::parse_whole(a, value(), 1, 100000, usage_error));
    else if (a == "--mode") {
      const std::string m = value();
      if (m == "both")
        o.modes = {ClosingMode::kPrecise, ClosingMode::kDiscrete};
      else if (const std::optional<ClosingMode> mode = parse_closing_mode(m))
        o.modes = {*mode};
      else
        usage_error("--mode expects precise, discrete or both, got '" + m + "'");
    } else if (a == "--speed-scale") {
      o.speeds.clear();
      std::stringstream ss(value());
      for (std::string item; std::getline(ss, item, ',');) {
        char* end = nullptr;
        const double s = std::strtod(item.c_str(), &end);
        if (item.empty() || *end != '\0' || !(s > 0) || !std::isfinite(s))
          usage_error("--speed-scale expects positive numbers, got '" + item + "'");
        o.speeds.push_back(s);
      }
    } else if (a == "--stretch") {
      std::stringstream ss(value());
      int n = 0;
      for (std::string item; std::getline(ss, item, ',');) {
        if (n == 3) usage_error("--stretch expects three factors X,Y,Z, got more");
        o.stretch[n++] = telegrasp::cli::parse_number(a, item, 0.25, 4.0, usage_error);
      }
      if (n != 3) usage_error("--stretch expects three factors X,Y,Z, got " + std::to_string(n));
    } else {
      return false;
    }
    return true;
  });
  return o;
}

// The eval's view of a trial: the shared grasp record and its picture.
struct Trial {
  Record record;
  std::string svg;  // picture of the settled hold, if asked for
};

struct Config {
  ClosingMode mode;
  double speed;
};

// One grasp trial: the object rests at a random pose in front of the operator, who reaches,
// grasps, lifts 10 cm, holds 1 s and releases.
Trial run_trial(const ObjectModelPtr& model, const std::shared_ptr<const HandRig>& rig, const Options& opt,
                const Config& cfg, int trial, std::uint64_t seed, bool draw) {
  WorldSettings ws;
  ws.grasp.mode = cfg.mode;
  ws.grasp.speed_scale = cfg.speed;
  ws.grasp.selection = opt.selection;
  ws.grasp.quality_volume = QualityVolume::kCompute;  // offline: the records keep the volume
  World world(ws);
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> ux(0.40, 0.50), uy(-0.08, 0.08), uyaw(0.0, 2.0 * std::numbers::pi);
  const double x = ux(rng), y = uy(rng), yaw = uyaw(rng);
  const ObjectId object = world.add_object(model, World::resting_pose(*model, x, y, yaw));
  const HandId hand = world.add_hand(rig);
  ControllerInput start;
  start.X_WorldPalm.translation() = Eigen::Vector3d(0.15, -0.20, 0.30);
  start.X_WorldPalm.linear() = Eigen::Matrix3d::Identity();
  world.set_input(hand, start);
  for (int i = 0; i < static_cast<int>(0.5 / ws.dt); ++i) world.step();  // let the object settle

  // A faster close: the operator squeezes the trigger faster and the joints may move faster.
  OperatorSkill skill = skill_profile(opt.skill);
  skill.squeeze_time /= cfg.speed;
  ScriptedOperator op(rig, skill, rng(), ws.grasp, ws.dt);
  const double t0 = world.time();
  const double z0 = world.object_pose(object).translation().z();
  op.begin(*model, world.object_pose(object), start.X_WorldPalm, t0);
  Trial out;
  Record& rec = out.record;
  rec.object = model->name;
  rec.mode = closing_mode_name(cfg.mode);
  rec.speed_scale = cfg.speed;
  rec.trial = trial;
  double z_held = -1e9;
  std::optional<GraspMetrics> held;  // the hand as it was on the last tick of the hold
  GraspSnapshot picture;
  while (!op.done() && world.time() - t0 < 30.0) {
    const bool grasped = world.holder(object) == hand;
    op.see_hand_raised(world.hand(hand).state().resolve_offset().z());
    const ControllerInput in = op.next(world.time(), grasped);
    world.set_input(hand, in);
    world.step();
    if (op.phase() == OperatorPhase::kHold) {
      z_held = std::max(z_held, world.object_pose(object).translation().z());
      if (auto now = world.hand(hand).hold_metrics()) {
        held = std::move(now);
        if (draw) picture = snapshot(world.hand(hand), {object, world.object_pose(object), model.get()}, "");
      }
    }
    for (const GraspEvent& e : world.events()) {
      if (e.kind != GraspEvent::Kind::kGrasp || rec.grasped || !e.metrics) continue;
      rec.grasped = true;
      rec.time_to_grasp_s = e.time - t0;
      telegrasp::report::record_grasp_tick(e, *rig, rec);
      const Eigen::Isometry3d X_ObjectPalm = world.hand(hand).state().X_PalmObject.inverse();
      const Eigen::Vector3d up_Object = world.object_pose(object).linear().transpose() * Eigen::Vector3d::UnitZ();
      rec.across_smallest = closes_across_shortest_side(model->shape, X_ObjectPalm, {}, up_Object);
      rec.across_smallest_ignoring_table = closes_across_shortest_side(model->shape, X_ObjectPalm);
    }
  }
  if (held) {
    rec.hand_error_mm = held->hand_error_mm;
    rec.capsules = capsule_records(*held, *rig);
    rec.figures = grasp_figures(*held);
    if (draw) {
      char title[160];
      std::snprintf(title, sizeof title, "%s, %s mode x%g, trial %d: HandError %.1f mm", model->name.c_str(),
                    rec.mode.c_str(), cfg.speed, trial, held->hand_error_mm);
      picture.title = title;
      out.svg = render_svg(picture);
    }
  }
  rec.attempts = op.attempts();
  rec.held_after_lift = op.held_after_lift() && z_held - z0 > 0.8 * ScriptedOperator::kLiftHeight;
  return out;
}

// Loads the rig and the objects and opens the outputs, so a bad file fails before any trial runs;
// says what was loaded on stderr. On failure says why on stderr and returns nothing. `bounds`:
// --bound's file, when given.
std::optional<EvalInputs> load_inputs(const Options& opt, std::ofstream& json_out,
                                      std::optional<telegrasp::report::NdBounds>& bounds) {
  EvalInputs in;
  try {
    in = telegrasp::eval::load_eval_inputs(opt.rig_path, opt.objects_dir);
    if (opt.stretch != Eigen::Vector3d::Ones()) in.models = telegrasp::eval::stretched(in.models, opt.stretch);
  } catch (const std::exception& e) {
    std::cerr << kTool << ": " << e.what() << "\n";
    return std::nullopt;
  }
  try {
    if (!opt.bound_path.empty()) bounds = telegrasp::report::read_nd_bounds(opt.bound_path);
  } catch (const std::exception& e) {
    std::cerr << kTool << ": --bound " << e.what() << "\n";
    return std::nullopt;
  }
  if (const std::string error = telegrasp::eval::prepare_outputs(opt.json_path, json_out, opt.svg_dir);
      !error.empty()) {
    std::cerr << kTool << ": " << error << "\n";
    return std::nullopt;
  }
  std::size_t max_bytes = 0;
  for (const auto& m : in.models) max_bytes = std::max(max_bytes, m->memory_bytes());
  std::cerr << in.models.size() << " objects (" << (opt.objects_dir.empty() ? "built-in stand-ins" : opt.objects_dir)
            << (opt.stretch != Eigen::Vector3d::Ones() ? ", stretched x" + fmt(opt.stretch.x(), 3) + " y" +
                                                             fmt(opt.stretch.y(), 3) + " z" + fmt(opt.stretch.z(), 3)
                                                       : "")
            << "), largest model " << fmt(static_cast<double>(max_bytes) / 1e6, 2) << " MB; rig " << in.rig->name()
            << "; skill " << opt.skill << "\n";
  if (bounds && !bounds->rig.empty() && bounds->rig != in.rig->name())
    std::cerr << kTool << ": warning: --bound " << opt.bound_path << " is rig " << bounds->rig << "'s, this run is rig "
              << in.rig->name() << "'s\n";
  return in;
}

// One trial to run: a config (mode and speed), an object and the trial's number.
struct Job {
  std::size_t config, object;
  int trial;
};

std::vector<Config> make_configs(const Options& opt) {
  std::vector<Config> configs;
  for (ClosingMode m : opt.modes)
    for (double s : opt.speeds) configs.push_back({m, s});
  return configs;
}

// Every config, object and trial, in that nesting: the order of the records everywhere after.
std::vector<Job> make_jobs(std::size_t configs, std::size_t objects, int trials) {
  std::vector<Job> jobs;
  for (std::size_t c = 0; c < configs; ++c)
    for (std::size_t o = 0; o < objects; ++o)
      for (int t = 0; t < trials; ++t) jobs.push_back({c, o, t});
  return jobs;
}

// One job's trial. A trial that throws counts as not grasped, and is said once on stderr.
Trial run_job(const Job& job, const std::vector<Config>& configs, const EvalInputs& in, const Options& opt,
              std::mutex& log_mutex, telegrasp::tools::ProgressLine& progress) {
  // The trial's seed depends on the object and trial only, so modes and speeds see the same poses.
  const std::uint64_t seed = opt.seed * 1000003ULL + job.object * 1009ULL + static_cast<std::uint64_t>(job.trial);
  const bool draw = !opt.svg_dir.empty() && job.trial == 0;
  try {
    return run_trial(in.models[job.object], in.rig, opt, configs[job.config], job.trial, seed, draw);
  } catch (const std::exception& e) {
    Trial failed;
    Record& rec = failed.record;
    rec.object = in.models[job.object]->name;
    rec.mode = closing_mode_name(configs[job.config].mode);
    rec.speed_scale = configs[job.config].speed;
    rec.trial = job.trial;
    std::lock_guard lock(log_mutex);
    progress.break_line();
    std::cerr << kTool << ": " << rec.object << " trial " << job.trial << " failed: " << e.what() << "\n";
    return failed;
  }
}

// Runs every job on opt.threads threads, with a progress line on stderr (ProgressLine: in place
// on a terminal, every few seconds in a log). Returns the trials in the jobs' order.
std::vector<Trial> run_jobs(const std::vector<Job>& jobs, const std::vector<Config>& configs, const EvalInputs& in,
                            const Options& opt) {
  std::vector<Trial> trials(jobs.size());
  std::atomic<std::size_t> next{0}, finished{0};
  std::mutex log_mutex;
  telegrasp::tools::ProgressLine progress;
  auto worker = [&] {
    for (std::size_t j = next++; j < jobs.size(); j = next++) {
      const Job& job = jobs[j];
      trials[j] = run_job(job, configs, in, opt, log_mutex, progress);
      const Record& rec = trials[j].record;
      const std::size_t done = ++finished;
      std::lock_guard lock(log_mutex);
      if (done < jobs.size() && !progress.due()) continue;
      std::ostringstream line;
      line << "[" << done << "/" << jobs.size() << "] " << rec.mode << " x" << configs[job.config].speed << " "
           << rec.object << " trial " << job.trial << (rec.held_after_lift ? " held" : " NOT held");
      if (done == jobs.size())
        progress.finish(line.str());
      else
        progress.show(line.str());
    }
  };
  std::vector<std::thread> pool;
  for (int i = 0; i < opt.threads; ++i) pool.emplace_back(worker);
  for (auto& t : pool) t.join();
  return trials;
}

// Per config, the per-object table and the summary line on stdout; returns the summaries.
json print_summaries(const std::vector<Config>& configs, const std::vector<Job>& jobs, const std::vector<Trial>& trials,
                     const std::vector<ObjectModelPtr>& models, const Options& opt,
                     const std::optional<telegrasp::report::NdBounds>& bounds) {
  json summaries = json::array();
  for (std::size_t c = 0; c < configs.size(); ++c) {
    std::cout << "\n== mode " << closing_mode_name(configs[c].mode) << ", closing speed x" << configs[c].speed
              << ", skill " << opt.skill << " ==\n";
    std::vector<telegrasp::report::ObjectRows> rows(models.size());
    std::vector<const Record*> all;
    for (std::size_t o = 0; o < models.size(); ++o) rows[o].object = models[o]->name;
    for (std::size_t j = 0; j < jobs.size(); ++j) {
      if (jobs[j].config != c) continue;
      rows[jobs[j].object].records.push_back(&trials[j].record);
      all.push_back(&trials[j].record);
    }
    telegrasp::report::print_object_table(rows);
    telegrasp::report::print_type_table(all);
    json s = summarize(all);
    s["mode"] = closing_mode_name(configs[c].mode);
    s["speed_scale"] = configs[c].speed;
    s["skill"] = opt.skill;
    if (opt.stretch != Eigen::Vector3d::Ones()) s["stretch"] = {opt.stretch.x(), opt.stretch.y(), opt.stretch.z()};
    if (bounds) s["nd_bound"] = telegrasp::report::print_nd_bound_table(rows, *bounds);
    std::cout << "summary: " << s.dump() << "\n";
    summaries.push_back(s);
  }
  return summaries;
}

// The configs' summaries side by side, one row each.
void print_side_by_side(const json& summaries) {
  std::cout << "\n== side by side ==\n";
  std::printf("%-9s %6s %7s %10s %10s %10s %10s %8s %12s %10s %12s\n", "mode", "speed", "held%", "|ND|med", "|ND|p95",
              "|NDc|med", "|NDc|p95", "noNDc", "minSD_mm", "SD<-0.1", "palmSDmin");
  for (const json& s : summaries) {
    auto get = [&](const char* k) { return s[k].is_null() ? NAN : s[k].get<double>(); };
    std::printf("%-9s %6s %7s %10s %10s %10s %10s %8d %12s %10d %12s\n", s["mode"].get<std::string>().c_str(),
                fmt(get("speed_scale"), 1).c_str(), fmt(100 * get("held_rate"), 1).c_str(),
                fmt(get("nd_abs_median_mm"), 3).c_str(), fmt(get("nd_abs_p95_mm"), 3).c_str(),
                fmt(get("nd_contact_abs_median_mm"), 3).c_str(), fmt(get("nd_contact_abs_p95_mm"), 3).c_str(),
                s["blocked_without_nd_contact"].get<int>(), fmt(get("min_blocked_signed_distance_mm"), 3).c_str(),
                s["blocked_below_minus_0_1mm"].get<int>(), fmt(get("palm_signed_distance_min_mm"), 3).c_str());
  }
}

// Each drawn trial's picture as svg_dir/<object>_<mode>_x<speed>.svg.
void write_pictures(const std::vector<Trial>& trials, const std::string& svg_dir) {
  int written = 0;
  for (const Trial& t : trials) {
    if (t.svg.empty()) continue;
    const Record& r = t.record;
    char name[256];
    std::snprintf(name, sizeof name, "%s_%s_x%g.svg", r.object.c_str(), r.mode.c_str(), r.speed_scale);
    std::ofstream(std::filesystem::path(svg_dir) / name) << t.svg;
    ++written;
  }
  std::cerr << "wrote " << written << " pictures to " << svg_dir << "\n";
}

// Every grasp record and the summaries into the opened `json_out`; false (said on stderr) when
// writing fails. `summaries` by value: [0] adds a null entry when there are none, as always.
bool write_json(std::ofstream& json_out, const std::string& json_path, const std::vector<Trial>& trials,
                json summaries) {
  json grasps = json::array();
  for (const Trial& t : trials) grasps.push_back(telegrasp::report::record_json(t.record));
  json_out << json{{"grasps", grasps}, {"summary", summaries[0]}, {"summaries", summaries}}.dump(1) << "\n";
  if (!json_out.flush()) {
    std::cerr << kTool << ": --json " << json_path << ": cannot write\n";
    return false;
  }
  std::cerr << "wrote " << json_path << "\n";
  return true;
}

}  // namespace

int telegrasp::eval::run_in_process(int argc, char** argv) {
  const Options opt = parse(argc, argv);
  std::ofstream json_out;
  std::optional<telegrasp::report::NdBounds> bounds;
  const std::optional<EvalInputs> in = load_inputs(opt, json_out, bounds);
  if (!in) return telegrasp::cli::kExitFailure;
  const std::vector<Config> configs = make_configs(opt);
  const std::vector<Job> jobs = make_jobs(configs.size(), in->models.size(), opt.trials);
  const std::vector<Trial> trials = run_jobs(jobs, configs, *in, opt);
  const json summaries = print_summaries(configs, jobs, trials, in->models, opt, bounds);
  if (configs.size() > 1) print_side_by_side(summaries);
  if (!opt.svg_dir.empty()) write_pictures(trials, opt.svg_dir);
  if (!opt.json_path.empty() && !write_json(json_out, opt.json_path, trials, summaries))
    return telegrasp::cli::kExitFailure;
  return 0;
}
