// The aggregates of a protocol run (per mode, group and object) and the paper's published
// per-object numbers: the data every report of experiment_report.h is made of.
#include "experiment_aggregate.h"

#include "telegrasp/sim/data_paths.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <set>
#include <sstream>
#include <stdexcept>

namespace telegrasp::report {
namespace {

using nlohmann::json;

json num(double v) { return std::isfinite(v) ? json(v) : json(nullptr); }

json aggregate_fields(const Aggregate& a) {
  return {{"n", a.n},
          {"grasped", a.grasped},
          {"held_after_lift", a.held},
          {"time_to_grasp_mean_s", num(a.time.mean)},
          {"time_to_grasp_sd_s", num(a.time.sd)},
          {"nd_abs_mean_mm", num(a.nd.mean)},
          {"nd_abs_sd_mm", num(a.nd.sd)},
          {"nd_abs_grasps", a.nd.n},
          {"nd_abs_pooled_mean_mm", num(a.nd_pooled)},
          {"capsules_hit", a.capsules_hit},
          {"hand_error_mean_mm", num(a.hand_error.mean)},
          {"hand_error_sd_mm", num(a.hand_error.sd)},
          {"nd_contact_abs_median_mm", num(percentile(a.fidelity.nd_contact_abs, 0.5))},
          {"nd_contact_abs_p95_mm", num(percentile(a.fidelity.nd_contact_abs, 0.95))},
          {"blocked_capsules", a.fidelity.blocked},
          {"blocked_without_nd_contact", a.fidelity.blocked_without_contact},
          {"min_blocked_signed_distance_mm", num(a.fidelity.min_signed_distance)},
          {"blocked_below_minus_0_1mm", a.fidelity.blocked_below},
          {"palm_signed_distance_min_mm", num(a.fidelity.palm_min)},
          {"palm_below_minus_0_1mm", a.fidelity.palm_below},
          {"held_force_closure", a.held_force_closure},
          {"held_force_closure_share", num(a.held ? static_cast<double>(a.held_force_closure) / a.held : NAN)}};
}

}  // namespace

// Adds one grasp's blocked capsules and palm at the grasp tick to `f`.
void add_fidelity(Fidelity& f, const Record& r) {
  for (const CapsuleMetricRecord& c : r.grasp_tick_capsules) {
    if (!c.blocked) continue;
    ++f.blocked;
    if (c.contact_hit) {
      f.nd_contact_abs.push_back(std::abs(c.nd_contact_mm));
    } else {
      ++f.blocked_without_contact;
    }
    f.blocked_below += c.signed_distance_mm < -0.1;
    f.min_signed_distance = std::isfinite(f.min_signed_distance) ? std::min(f.min_signed_distance, c.signed_distance_mm)
                                                                 : c.signed_distance_mm;
  }
  const double palm = r.grasp_tick_figures.palm_signed_distance_mm;
  ++f.palms;
  f.palm_below += palm < -0.1;
  f.palm_min = std::isfinite(f.palm_min) ? std::min(f.palm_min, palm) : palm;
}

// ---------------------------------------------------------------------------------------------
// Statistics

Stat stat(const std::vector<double>& v) {
  Stat s;
  s.n = static_cast<int>(v.size());
  if (v.empty()) return s;
  double sum = 0;
  for (double x : v) sum += x;
  s.mean = sum / static_cast<double>(v.size());
  if (v.size() < 2) return s;
  double sq = 0;
  for (double x : v) sq += (x - s.mean) * (x - s.mean);
  s.sd = std::sqrt(sq / static_cast<double>(v.size() - 1));
  return s;
}

double grasp_nd_abs_mean(const Record& r, int* hits) {
  double sum = 0;
  int n = 0;
  for (const CapsuleMetricRecord& c : r.grasp_tick_capsules)
    if (c.hit) {
      sum += std::abs(c.nd_midlength_mm);
      ++n;
    }
  if (hits) *hits = n;
  return n ? sum / n : NAN;
}

double grasp_min_signed_distance(const Record& r) {
  double m = INFINITY;
  for (const CapsuleMetricRecord& c : r.grasp_tick_capsules)
    if (c.blocked) m = std::min(m, c.signed_distance_mm);
  return std::isfinite(m) ? m : NAN;
}

Aggregate aggregate(const std::vector<const Record*>& records) {
  Aggregate a;
  std::vector<double> times, nds, hand_errors;
  double pooled_sum = 0;
  for (const Record* r : records) {
    ++a.n;
    a.held += r->held_after_lift;
    if (!r->grasped) continue;
    ++a.grasped;
    add_fidelity(a.fidelity, *r);
    a.held_force_closure += r->held_after_lift && r->figures.force_closure;
    times.push_back(r->time_to_grasp_s);
    int hits = 0;
    const double nd = grasp_nd_abs_mean(*r, &hits);
    if (hits) nds.push_back(nd);
    // HandError sums |ND| over fingers: with no capsule hit it has no value (the server sends 0).
    if (hits) hand_errors.push_back(r->grasp_tick_hand_error_mm);
    a.capsules_hit += hits;
    pooled_sum += std::isfinite(nd) ? nd * hits : 0;
  }
  a.time = stat(times);
  a.nd = stat(nds);
  a.hand_error = stat(hand_errors);
  if (a.capsules_hit) a.nd_pooled = pooled_sum / a.capsules_hit;
  return a;
}

AxisTicks axis_ticks(double largest_value) {
  AxisTicks t;
  if (largest_value > 0 && std::isfinite(largest_value)) {
    const double raw = largest_value / 5;
    int exponent = static_cast<int>(std::floor(std::log10(raw)));
    int mantissa = 10;
    for (int m : {1, 2, 5, 10})
      if (m * std::pow(10.0, exponent) >= raw * (1 - 1e-12)) {
        mantissa = m;
        break;
      }
    if (mantissa == 10) mantissa = 1, ++exponent;
    t.step = mantissa * std::pow(10.0, exponent);
    t.top = std::ceil(largest_value / t.step * (1 - 1e-12)) * t.step;
  }
  const int decimals = std::max(0, -static_cast<int>(std::floor(std::log10(t.step) + 1e-9)));
  const int ticks = static_cast<int>(std::lround(t.top / t.step));
  for (int i = 0; i <= ticks; ++i) {
    t.values.push_back(i * t.step);
    t.labels.push_back(fmt(i * t.step, decimals));
  }
  return t;
}

// ---------------------------------------------------------------------------------------------
// What a run contains, in a stable order

std::vector<std::string> modes_of(const ExperimentRun& run) {
  std::vector<std::string> out = run.modes;
  for (const Record& r : run.records)
    if (std::find(out.begin(), out.end(), r.mode) == out.end()) out.push_back(r.mode);
  return out;
}

std::vector<std::string> groups_of(const ExperimentRun& run) {
  std::set<std::string> named;
  for (const auto& [group, count] : run.participants) named.insert(group);
  for (const Record& r : run.records) named.insert(r.group);
  std::vector<std::string> out;
  for (const char* g : {"experienced", "inexperienced"})
    if (named.erase(g)) out.push_back(g);
  out.insert(out.end(), named.begin(), named.end());
  return out;
}

std::vector<std::string> objects_of(const ExperimentRun& run) {
  std::set<std::string> recorded;
  for (const Record& r : run.records) recorded.insert(r.object);
  std::vector<std::string> out;
  for (const std::string& o : run.objects)
    if (recorded.count(o) && std::find(out.begin(), out.end(), o) == out.end()) out.push_back(o);
  for (const Record& r : run.records)
    if (std::find(out.begin(), out.end(), r.object) == out.end()) out.push_back(r.object);
  return out;
}

std::vector<const Record*> select(const ExperimentRun& run, const std::string& mode, const std::string& group,
                                  const std::string& object) {
  std::vector<const Record*> out;
  for (const Record& r : run.records)
    if (r.mode == mode && (group.empty() || r.group == group) && (object.empty() || r.object == object))
      out.push_back(&r);
  return out;
}

// ---------------------------------------------------------------------------------------------
// The paper's numbers and the run's aggregates

std::string default_paper_results_path() { return (sim::data_dir() / "paper_results_per_object.csv").string(); }

std::vector<PaperRow> load_paper_results(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error(path + ": cannot open the paper's results file");
  const std::vector<std::string> columns = {
      "label", "object", "time_s_experienced", "time_s_inexperienced", "err_experienced", "err_inexperienced"};
  std::vector<std::size_t> index;  // file column of each of `columns`
  std::vector<PaperRow> out;
  std::string line;
  int line_no = 0;
  while (std::getline(in, line)) {
    ++line_no;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line.find_first_not_of(" \t") == std::string::npos || line[line.find_first_not_of(" \t")] == '#') continue;
    std::vector<std::string> cells;
    std::stringstream ss(line);
    for (std::string cell; std::getline(ss, cell, ',');) {
      const auto a = cell.find_first_not_of(" \t"), b = cell.find_last_not_of(" \t");
      cells.push_back(a == std::string::npos ? "" : cell.substr(a, b - a + 1));
    }
    if (!line.empty() && line.back() == ',') cells.push_back("");
    const std::string where = path + " line " + std::to_string(line_no);
    if (index.empty()) {  // the header
      for (const std::string& name : columns) {
        const auto it = std::find(cells.begin(), cells.end(), name);
        if (it == cells.end()) throw std::runtime_error(where + ": header has no column '" + name + "'");
        index.push_back(static_cast<std::size_t>(it - cells.begin()));
      }
      continue;
    }
    auto cell = [&](std::size_t k) -> const std::string& {
      if (index[k] >= cells.size())
        throw std::runtime_error(where + " column " + std::to_string(index[k] + 1) + " (" + columns[k] + "): missing");
      return cells[index[k]];
    };
    auto number_at = [&](std::size_t k) {
      const std::string& text = cell(k);
      char* end = nullptr;
      const double v = std::strtod(text.c_str(), &end);
      if (text.empty() || end != text.c_str() + text.size() || !std::isfinite(v) || v < 0)
        throw std::runtime_error(where + " column " + std::to_string(index[k] + 1) + " (" + columns[k] + "): '" + text +
                                 "' is not a non-negative number");
      return v;
    };
    PaperRow row;
    row.label = cell(0);
    row.object = cell(1);
    if (row.label.empty() || row.object.empty())
      throw std::runtime_error(where + ": label and object must not be empty");
    row.time_experienced = number_at(2);
    row.time_inexperienced = number_at(3);
    row.err_experienced = number_at(4);
    row.err_inexperienced = number_at(5);
    out.push_back(std::move(row));
  }
  if (index.empty()) throw std::runtime_error(path + ": no header row");
  return out;
}

json aggregate_json(const ExperimentRun& run) {
  const std::vector<std::string> modes = modes_of(run), groups = groups_of(run), objects = objects_of(run);
  json out;
  out["run"] = {{"protocol", run.protocol},
                {"command_line", run.command_line},
                {"seed", run.seed},
                {"wall_seconds", run.wall_seconds},
                {"created", run.created},
                {"modes", run.modes},
                {"objects", run.objects},
                {"standin_objects", run.standin_objects},
                {"participants", run.participants},
                {"records", run.records.size()}};
  out["metrics"] = {
      {"time_to_grasp_s", "spawn to grasp, mean and sample sd over grasped trials"},
      {"nd_abs_mean_mm",
       "nd_midlength (the paper's ND, at the capsule's mid-length): per grasp, mean |ND| over the capsules that hit "
       "at the grasp tick; then mean and sample sd over grasps (this is what the charts plot)"},
      {"nd_contact_abs_median_mm",
       "nd_contact (ND toward the contact, sim/README.md section 4): median and p95 of |nd_contact| over the blocked "
       "capsules at the grasp tick; blocked_without_nd_contact counts those without one (must be 0)"},
      {"palm_signed_distance_min_mm", "the palm box's exact signed distance to the object at the grasp tick, minimum"},
      {"held_force_closure_share",
       "held grasps whose contacts are in force closure (Ferrari-Canny epsilon > 0, mu of the rig)"},
      {"nd_abs_pooled_mean_mm", "mean |ND| over every hit capsule of the grasped trials, at the grasp tick"},
      {"hand_error_mean_mm",
       "the paper's HandError (sum over fingers of the per-finger mean |ND|) at the grasp tick, "
       "over grasps with a capsule that hit (without one it has no value)"}};
  json by_mgo = json::array(), by_mg = json::array(), by_mo = json::array(), worst = json::array();
  for (const std::string& mode : modes) {
    for (const std::string& group : groups) {
      for (const std::string& object : objects) {
        const auto records = select(run, mode, group, object);
        if (records.empty()) continue;
        json row = {{"mode", mode}, {"group", group}, {"object", object}};
        row.update(aggregate_fields(aggregate(records)));
        by_mgo.push_back(std::move(row));
      }
      const auto records = select(run, mode, group, "");
      if (records.empty()) continue;
      json row = {{"mode", mode}, {"group", group}};
      row.update(aggregate_fields(aggregate(records)));
      by_mg.push_back(std::move(row));
    }
    // Per object over both groups, and the objects that were slowest and least plausible.
    std::vector<std::pair<std::string, Aggregate>> per_object;
    for (const std::string& object : objects) {
      const auto records = select(run, mode, "", object);
      if (records.empty()) continue;
      per_object.emplace_back(object, aggregate(records));
      json row = {{"mode", mode}, {"group", "all"}, {"object", object}};
      row.update(aggregate_fields(per_object.back().second));
      by_mo.push_back(std::move(row));
    }
    auto worst_by = [&](double (*key)(const Aggregate&), const char* field) {
      std::vector<std::pair<std::string, double>> ranked;
      for (const auto& [object, a] : per_object)
        if (std::isfinite(key(a))) ranked.emplace_back(object, key(a));
      std::stable_sort(ranked.begin(), ranked.end(), [](const auto& x, const auto& y) { return x.second > y.second; });
      json list = json::array();
      for (std::size_t i = 0; i < ranked.size() && i < 5; ++i)
        list.push_back({{"object", ranked[i].first}, {field, ranked[i].second}});
      return list;
    };
    worst.push_back({{"mode", mode},
                     {"by_time", worst_by([](const Aggregate& a) { return a.time.mean; }, "time_to_grasp_mean_s")},
                     {"by_nd", worst_by([](const Aggregate& a) { return a.nd.mean; }, "nd_abs_mean_mm")}});
  }
  out["by_mode_group_object"] = std::move(by_mgo);
  out["by_mode_group"] = std::move(by_mg);
  out["by_mode_object"] = std::move(by_mo);
  out["worst_objects"] = std::move(worst);
  return out;
}

}  // namespace telegrasp::report
