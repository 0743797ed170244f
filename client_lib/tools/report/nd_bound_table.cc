#include "nd_bound_table.h"

#include <algorithm>
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

namespace {

// A summary's pooled grasp-tick mean |ND| (summarize), NaN when no capsule hit.
double mean_mm(const json& summary) {
  const json& v = summary["grasp_tick_nd_abs_mean_mm"];
  return v.is_null() ? NAN : v.get<double>();
}

}  // namespace

json print_nd_bound_table(const std::vector<ObjectRows>& objects, const NdBounds& bounds) {
  std::printf(
      "\nthe grasp tick's mean |ND| beside the nd-bound oracle's (its lowest with --min-hits capsules hitting):\n");
  std::printf("%-26s %9s %5s %9s %9s\n", "object", "|ND|mean", "hits", "no_hit", "oracle");
  std::vector<const Record*> all, reachable;
  json beyond = json::array(), unknown = json::array(), reached = json::array();
  for (const ObjectRows& o : objects) {
    const json s = summarize(o.records);
    int no_hit = 0;
    for (const Record* r : o.records)
      no_hit += r->grasped && std::none_of(r->grasp_tick_capsules.begin(), r->grasp_tick_capsules.end(),
                                           [](const CapsuleMetricRecord& c) { return c.hit; });
    all.insert(all.end(), o.records.begin(), o.records.end());
    const auto found = bounds.nd_mean_mm.find(o.object);
    const bool known = found != bounds.nd_mean_mm.end();
    const bool clean = known && found->second.has_value();  // the oracle kept a clean grasp
    const double bound = clean ? *found->second : NAN;
    std::printf("%-26s %9s %5d %9d %9s\n", o.object.c_str(), fmt(mean_mm(s), 3).c_str(),
                s["grasp_tick_capsules_hit"].get<int>(), no_hit,
                !known  ? "?"
                : clean ? fmt(bound, 3).c_str()
                        : "none");
    if (!known) {
      unknown.push_back(o.object);
    } else if (!clean || bound > kPaperNdExperiencedMm) {
      beyond.push_back(o.object);
    } else {
      reached.push_back(o.object);
      reachable.insert(reachable.end(), o.records.begin(), o.records.end());
    }
  }
  const json s_all = summarize(all), s_reachable = summarize(reachable);
  std::printf(
      "grasp tick mean |ND|: %s mm over all %zu objects (%d capsules hit); %s mm over the %zu the oracle "
      "takes to %.2f mm or below (%d hit)\n",
      fmt(mean_mm(s_all), 3).c_str(), objects.size(), s_all["grasp_tick_capsules_hit"].get<int>(),
      fmt(mean_mm(s_reachable), 3).c_str(), reached.size(), kPaperNdExperiencedMm,
      s_reachable["grasp_tick_capsules_hit"].get<int>());
  auto names = [](const json& list) {
    std::string s;
    for (const json& n : list) s += (s.empty() ? "" : " ") + n.get<std::string>();
    return s;
  };
  if (!beyond.empty()) std::printf("the oracle above it or without a clean grasp: %s\n", names(beyond).c_str());
  if (!unknown.empty()) std::printf("not in the oracle's file: %s\n", names(unknown).c_str());
  return {{"paper_nd_mm", kPaperNdExperiencedMm},
          {"oracle_rig", bounds.rig},
          {"grasp_tick_nd_abs_mean_mm", s_all["grasp_tick_nd_abs_mean_mm"]},
          {"reachable",
           {{"grasp_tick_nd_abs_mean_mm", s_reachable["grasp_tick_nd_abs_mean_mm"]},
            {"capsules_hit", s_reachable["grasp_tick_capsules_hit"]},
            {"objects", reached}}},
          {"beyond", beyond},
          {"unknown", unknown}};
}

}  // namespace telegrasp::report
