#include "nd_bound_table.h"

#include <cmath>
#include <cstdio>
#include <fstream>
#include <stdexcept>

namespace telegrasp::report {

using nlohmann::json;

NdBounds read_nd_bounds(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error(path + ": cannot open");
  const json j = json::parse(in, nullptr, /*allow_exceptions=*/false);
  if (j.is_discarded()) throw std::runtime_error(path + ": not JSON");
  if (!j.contains("objects") || !j["objects"].is_array())
    throw std::runtime_error(path + ": no \"objects\" array (write it with telegrasp-eval nd-bound --json)");
  NdBounds out;
  if (j.contains("summary") && j["summary"].contains("rig") && j["summary"]["rig"].is_string())
    out.rig = j["summary"]["rig"].get<std::string>();
  for (std::size_t i = 0; i < j["objects"].size(); ++i) {
    const json& o = j["objects"][i];
    const std::string where = path + ": objects[" + std::to_string(i) + "]";
    if (!o.contains("object") || !o["object"].is_string()) throw std::runtime_error(where + ": no \"object\" name");
    if (!o.contains("kept")) throw std::runtime_error(where + ": no \"kept\" grasp (null when none was clean)");
    const json& kept = o["kept"];
    if (kept.is_null()) {
      out.nd_mean_mm[o["object"]] = std::nullopt;
    } else if (kept.contains("nd_mean_mm") && kept["nd_mean_mm"].is_number()) {
      out.nd_mean_mm[o["object"]] = kept["nd_mean_mm"].get<double>();
    } else {
      throw std::runtime_error(where + ".kept: no number \"nd_mean_mm\"");
    }
  }
  return out;
}

json print_nd_bound_table(const std::vector<ObjectRows>& objects, const NdBounds& bounds) {
  std::printf(
      "\nthe grasp tick's mean |ND| beside the nd-bound oracle's (its lowest with --min-hits capsules hitting):\n");
  std::printf("%-26s %9s %5s %9s %9s\n", "object", "|ND|mean", "hits", "no_hit", "oracle");
  struct Pool {
    double sum = 0;
    int hits = 0;
  } all, reachable;
  json beyond = json::array(), unknown = json::array(), reached = json::array();
  for (const ObjectRows& o : objects) {
    Pool p;
    int no_hit = 0;
    for (const Record* r : o.records) {
      if (!r->grasped) continue;
      int hits = 0;
      for (const CapsuleMetricRecord& c : r->grasp_tick_capsules)
        if (c.hit) {
          p.sum += std::abs(c.nd_midlength_mm);
          ++hits;
        }
      p.hits += hits;
      no_hit += hits == 0;
    }
    all.sum += p.sum;
    all.hits += p.hits;
    const auto found = bounds.nd_mean_mm.find(o.object);
    const bool known = found != bounds.nd_mean_mm.end();
    const bool clean = known && found->second.has_value();  // the oracle kept a clean grasp
    const double bound = clean ? *found->second : NAN;
    const double mean = p.hits > 0 ? p.sum / p.hits : NAN;
    std::printf("%-26s %9s %5d %9d %9s\n", o.object.c_str(), fmt(mean, 3).c_str(), p.hits, no_hit,
                !known  ? "?"
                : clean ? fmt(bound, 3).c_str()
                        : "none");
    if (!known) {
      unknown.push_back(o.object);
    } else if (!clean || bound > kPaperNdExperiencedMm) {
      beyond.push_back(o.object);
    } else {
      reached.push_back(o.object);
      reachable.sum += p.sum;
      reachable.hits += p.hits;
    }
  }
  auto mean_of = [](const Pool& p) { return p.hits > 0 ? json(p.sum / p.hits) : json(nullptr); };
  std::printf(
      "grasp tick mean |ND|: %s mm over all %zu objects (%d capsules hit); %s mm over the %zu the oracle "
      "takes to %.2f mm or below (%d hit)\n",
      fmt(all.hits > 0 ? all.sum / all.hits : NAN, 3).c_str(), objects.size(), all.hits,
      fmt(reachable.hits > 0 ? reachable.sum / reachable.hits : NAN, 3).c_str(), reached.size(), kPaperNdExperiencedMm,
      reachable.hits);
  auto names = [](const json& list) {
    std::string s;
    for (const json& n : list) s += (s.empty() ? "" : " ") + n.get<std::string>();
    return s;
  };
  if (!beyond.empty()) std::printf("the oracle above it or without a clean grasp: %s\n", names(beyond).c_str());
  if (!unknown.empty()) std::printf("not in the oracle's file: %s\n", names(unknown).c_str());
  return {{"paper_nd_mm", kPaperNdExperiencedMm},
          {"oracle_rig", bounds.rig},
          {"grasp_tick_nd_abs_mean_mm", mean_of(all)},
          {"reachable",
           {{"grasp_tick_nd_abs_mean_mm", mean_of(reachable)}, {"capsules_hit", reachable.hits}, {"objects", reached}}},
          {"beyond", beyond},
          {"unknown", unknown}};
}

}  // namespace telegrasp::report
