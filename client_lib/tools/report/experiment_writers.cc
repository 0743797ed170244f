// The experiment report's files: the per-grasp and per-object CSV tables, and writing any
// report text to disk.
#include "csv.h"
#include "experiment_aggregate.h"

#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>

namespace telegrasp::report {
namespace {

using nlohmann::json;

// A grasp's fidelity and quality cells (empty when not grasped): the largest |nd_contact| and the
// blocked capsules without one at the grasp tick, the palm's signed distance, epsilon, volume,
// force closure.
std::string figure_cells(const Record& r) {
  if (!r.grasped) return ",,,,,";
  Fidelity f;
  add_fidelity(f, r);
  double worst = NAN;
  for (double v : f.nd_contact_abs) worst = std::isfinite(worst) ? std::max(worst, v) : v;
  const GraspFigures& g = r.grasp_tick_figures;
  return number(worst, 4) + ',' + std::to_string(f.blocked_without_contact) + ',' +
         number(g.palm_signed_distance_mm, 4) + ',' + number(g.epsilon, 6) + ',' + number(g.volume, 6) + ',' +
         (g.force_closure ? "1" : "0");
}

}  // namespace

void write_text_file(const std::string& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary);
  if (!out) throw std::runtime_error(path + ": cannot open for writing");
  out << text;
  out.close();
  if (!out) throw std::runtime_error(path + ": write failed");
}

std::string write_csv(const ExperimentRun& run, const std::string& path) {
  std::ostringstream grasps;
  grasps << "mode,group,participant,object,trial,grasped,held_after_lift,attempts,time_to_grasp_s,hand_error_mm,"
            "nd_abs_mean_mm,capsules_hit,min_signed_distance_mm,contacts,nd_contact_abs_max_mm,"
            "blocked_without_nd_contact,palm_signed_distance_mm,epsilon,volume,force_closure\n";
  for (const Record& r : run.records) {
    int hits = 0;
    const double nd = grasp_nd_abs_mean(r, &hits);
    // Metrics exist only for a grasp (HandError and |ND| only with a capsule that hit); an empty
    // cell is "no value", never zero.
    grasps << csv::field(r.mode) << ',' << csv::field(r.group) << ',' << r.participant << ',' << csv::field(r.object)
           << ',' << r.trial << ',' << (r.grasped ? 1 : 0) << ',' << (r.held_after_lift ? 1 : 0) << ',' << r.attempts
           << ',' << (r.grasped ? number(r.time_to_grasp_s, 4) : "") << ','
           << (r.grasped && hits ? number(r.grasp_tick_hand_error_mm, 4) : "") << ','
           << (r.grasped ? number(nd, 4) : "") << ',' << hits << ','
           << (r.grasped ? number(grasp_min_signed_distance(r), 4) : "") << ',' << r.contacts.size() << ','
           << figure_cells(r) << '\n';
  }
  write_text_file(path, grasps.str());

  const json agg = aggregate_json(run);
  std::ostringstream by_object;
  by_object << "mode,group,object,n,grasped,held_after_lift,time_to_grasp_mean_s,time_to_grasp_sd_s,nd_abs_mean_mm,"
               "nd_abs_sd_mm,nd_abs_grasps,nd_abs_pooled_mean_mm,capsules_hit,hand_error_mean_mm,hand_error_sd_mm,"
               "nd_contact_abs_median_mm,nd_contact_abs_p95_mm,blocked_capsules,blocked_without_nd_contact,"
               "palm_signed_distance_min_mm,held_force_closure,held_force_closure_share\n";
  auto cell = [](const json& v) { return v.is_null() ? std::string() : number(v.get<double>(), 4); };
  auto write_rows = [&](const json& rows) {
    for (const json& r : rows)
      by_object << csv::field(r["mode"].get<std::string>()) << ',' << csv::field(r["group"].get<std::string>()) << ','
                << csv::field(r["object"].get<std::string>()) << ',' << r["n"] << ',' << r["grasped"] << ','
                << r["held_after_lift"] << ',' << cell(r["time_to_grasp_mean_s"]) << ','
                << cell(r["time_to_grasp_sd_s"]) << ',' << cell(r["nd_abs_mean_mm"]) << ',' << cell(r["nd_abs_sd_mm"])
                << ',' << r["nd_abs_grasps"] << ',' << cell(r["nd_abs_pooled_mean_mm"]) << ',' << r["capsules_hit"]
                << ',' << cell(r["hand_error_mean_mm"]) << ',' << cell(r["hand_error_sd_mm"]) << ','
                << cell(r["nd_contact_abs_median_mm"]) << ',' << cell(r["nd_contact_abs_p95_mm"]) << ','
                << r["blocked_capsules"] << ',' << r["blocked_without_nd_contact"] << ','
                << cell(r["palm_signed_distance_min_mm"]) << ',' << r["held_force_closure"] << ','
                << cell(r["held_force_closure_share"]) << '\n';
  };
  write_rows(agg["by_mode_group_object"]);
  write_rows(agg["by_mode_object"]);
  const std::filesystem::path p(path);
  const std::string second = (p.parent_path() / (p.stem().string() + "_by_object.csv")).string();
  write_text_file(second, by_object.str());
  return second;
}

}  // namespace telegrasp::report
