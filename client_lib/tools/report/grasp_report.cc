#include "grasp_report.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <numbers>

namespace telegrasp::report {

using nlohmann::json;

json capsule_json(const std::vector<CapsuleMetricRecord>& capsules) {
  json out = json::array();
  for (const auto& c : capsules) {
    const json nd_midlength = c.hit ? json(c.nd_midlength_mm) : json(nullptr);
    out.push_back({{"phalanx", c.phalanx},
                   {"hit", c.hit},
                   {"blocked", c.blocked},
                   {"nd_midlength_mm", nd_midlength},
                   {"nd_mm", nd_midlength},
                   {"contact_hit", c.contact_hit},
                   {"nd_contact_mm", c.contact_hit ? json(c.nd_contact_mm) : json(nullptr)},
                   {"signed_distance_mm", c.signed_distance_mm}});
  }
  return out;
}

double opposition_deg(const std::vector<sim::Contact>& contacts, const sim::HandRig& rig) {
  Eigen::Vector3d thumb = Eigen::Vector3d::Zero(), others = Eigen::Vector3d::Zero();
  for (const sim::Contact& c : contacts) {
    if (!c.phalanx.valid()) continue;  // the palm
    const int finger = rig.phalanges()[c.phalanx.value].finger;
    (rig.fingers()[finger].name == "thumb" ? thumb : others) += c.n_Object;
  }
  if (thumb.norm() < 1e-9 || others.norm() < 1e-9) return NAN;
  const double cos = std::clamp(thumb.normalized().dot(others.normalized()), -1.0, 1.0);
  return std::acos(cos) * 180.0 / std::numbers::pi;
}

GraspFigures grasp_figures(const sim::GraspMetrics& m) {
  return {1000 * m.palm_signed_distance, m.quality.epsilon, m.quality.volume, m.quality.force_closure};
}

void record_grasp_tick(const sim::GraspEvent& e, const sim::HandRig& rig, Record& rec) {
  rec.hand_error_mm = rec.grasp_tick_hand_error_mm = e.metrics->hand_error_mm;
  rec.capsules = rec.grasp_tick_capsules = capsule_records(*e.metrics, rig);
  rec.figures = rec.grasp_tick_figures = grasp_figures(*e.metrics);
  rec.grasp_type = sim::grasp_type_name(e.grasp_type);
  rec.opposition_deg = opposition_deg(e.contacts, rig);
}

void set_hold_quality(Record& rec, const std::optional<sim::GraspQuality>& hold) {
  if (!rec.grasped || !hold) return;
  rec.figures.epsilon = hold->epsilon;
  rec.figures.volume = hold->volume;
  rec.figures.force_closure = hold->force_closure;
}

namespace {

// The figures' keys into `out` (null when not grasped).
void put_figures(json& out, const GraspFigures& f, bool grasped) {
  auto val = [&](const json& v) { return grasped ? v : json(nullptr); };
  out["palm_signed_distance_mm"] = val(f.palm_signed_distance_mm);
  out["epsilon"] = val(f.epsilon);
  out["volume"] = val(f.volume);
  out["force_closure"] = val(f.force_closure);
}

// The figures from `j` (absent in records written before them: zero).
GraspFigures get_figures(const json& j) {
  GraspFigures f;
  auto num = [&](const char* k) { return j.contains(k) && !j.at(k).is_null() ? j.at(k).get<double>() : 0.0; };
  f.palm_signed_distance_mm = num("palm_signed_distance_mm");
  f.epsilon = num("epsilon");
  f.volume = num("volume");
  f.force_closure =
      j.contains("force_closure") && j.at("force_closure").is_boolean() && j.at("force_closure").get<bool>();
  return f;
}

}  // namespace

namespace {

double mean(const std::vector<double>& v) {
  if (v.empty()) return NAN;
  double sum = 0;
  for (double x : v) sum += x;
  return sum / static_cast<double>(v.size());
}

}  // namespace

double percentile(std::vector<double> v, double p) {
  if (v.empty()) return std::nan("");
  std::sort(v.begin(), v.end());
  const double idx = p * static_cast<double>(v.size() - 1);
  const std::size_t i = static_cast<std::size_t>(idx);
  const double f = idx - static_cast<double>(i);
  return i + 1 < v.size() ? v[i] * (1 - f) + v[i + 1] * f : v[i];
}

std::vector<CapsuleMetricRecord> capsule_records(const sim::GraspMetrics& metrics, const sim::HandRig& rig) {
  std::vector<CapsuleMetricRecord> out;
  for (const sim::CapsuleMetric& m : metrics.capsules)
    out.push_back({rig.phalanges()[m.phalanx.value].name, m.hit, m.blocked, 1000 * m.nd, 1000 * m.signed_distance,
                   m.contact_hit, 1000 * m.nd_contact});
  return out;
}

namespace {

// nd_contact over the blocked capsules of some grasps: |ND| values and the blocked ones without it.
struct NdContactStats {
  std::vector<double> abs_mm;
  int blocked_without = 0;
  void add(const std::vector<CapsuleMetricRecord>& capsules) {
    for (const auto& c : capsules) {
      if (!c.blocked) continue;
      if (c.contact_hit) {
        abs_mm.push_back(std::abs(c.nd_contact_mm));
      } else {
        ++blocked_without;
      }
    }
  }
};

// The grasps' hand-level figures: palm distances, force closure and epsilon.
json figures_summary(const std::vector<const Record*>& recs) {
  int grasped = 0, closure = 0, closure_tick = 0, palm_below = 0;
  double palm_min = INFINITY;
  std::vector<double> eps, palm;
  for (const Record* r : recs) {
    if (!r->grasped) continue;
    ++grasped;
    closure += r->figures.force_closure;
    closure_tick += r->grasp_tick_figures.force_closure;
    eps.push_back(r->figures.epsilon);
    palm.push_back(r->figures.palm_signed_distance_mm);
    palm_min = std::min(palm_min, r->figures.palm_signed_distance_mm);
    palm_below += r->figures.palm_signed_distance_mm < -0.1;
  }
  auto num = [](double v) { return std::isfinite(v) ? json(v) : json(nullptr); };
  return {{"palm_signed_distance_min_mm", num(palm_min)},
          {"palm_signed_distance_median_mm", num(percentile(palm, 0.5))},
          {"palm_below_minus_0_1mm", palm_below},
          {"force_closure_grasps", closure},
          {"force_closure_share", num(grasped ? static_cast<double>(closure) / grasped : NAN)},
          {"grasp_tick_force_closure_share", num(grasped ? static_cast<double>(closure_tick) / grasped : NAN)},
          {"epsilon_median", num(percentile(eps, 0.5))}};
}

}  // namespace

json summarize(const std::vector<const Record*>& recs) {
  int grasped = 0, held = 0, capsules = 0, below = 0, blocked_count = 0;
  double time_sum = 0, he_sum = 0, he_tick_sum = 0, min_sd = 1e9;
  std::vector<double> nd_abs, nd_abs_tick, opposition;
  int across_known = 0, across = 0, free_known = 0, across_free = 0;
  NdContactStats contact, contact_tick;
  for (const Record* r : recs) {
    grasped += r->grasped;
    held += r->held_after_lift;
    if (!r->grasped) continue;
    if (std::isfinite(r->opposition_deg)) opposition.push_back(r->opposition_deg);
    if (r->across_smallest) {
      ++across_known;
      across += *r->across_smallest;
    }
    if (r->across_smallest_ignoring_table) {
      ++free_known;
      across_free += *r->across_smallest_ignoring_table;
    }
    time_sum += r->time_to_grasp_s;
    he_sum += r->hand_error_mm;
    he_tick_sum += r->grasp_tick_hand_error_mm;
    for (const auto& c : r->grasp_tick_capsules)
      if (c.hit) nd_abs_tick.push_back(std::abs(c.nd_midlength_mm));
    contact.add(r->capsules);
    contact_tick.add(r->grasp_tick_capsules);
    for (const auto& c : r->capsules) {
      ++capsules;
      if (c.hit) nd_abs.push_back(std::abs(c.nd_midlength_mm));
      if (c.blocked) {
        ++blocked_count;
        min_sd = std::min(min_sd, c.signed_distance_mm);
        below += c.signed_distance_mm < -0.1;
      }
    }
  }
  auto num = [](double v) { return std::isfinite(v) ? json(v) : json(nullptr); };
  json out = {{"trials", recs.size()},
              {"grasped", grasped},
              {"held_after_lift", held},
              {"held_rate", recs.empty() ? 0.0 : static_cast<double>(held) / static_cast<double>(recs.size())},
              {"time_to_grasp_mean_s", num(grasped ? time_sum / grasped : NAN)},
              {"hand_error_mean_mm", num(grasped ? he_sum / grasped : NAN)},
              {"capsules", capsules},
              {"capsules_hit", nd_abs.size()},
              {"nd_abs_median_mm", num(percentile(nd_abs, 0.5))},
              {"nd_abs_mean_mm", num(mean(nd_abs))},
              {"nd_abs_p95_mm", num(percentile(nd_abs, 0.95))},
              {"blocked_capsules", blocked_count},
              {"min_blocked_signed_distance_mm", num(blocked_count ? min_sd : NAN)},
              {"blocked_below_minus_0_1mm", below},
              {"grasp_tick_hand_error_mean_mm", num(grasped ? he_tick_sum / grasped : NAN)},
              {"grasp_tick_nd_abs_median_mm", num(percentile(nd_abs_tick, 0.5))},
              {"grasp_tick_nd_abs_mean_mm", num(mean(nd_abs_tick))},
              {"grasp_tick_capsules_hit", nd_abs_tick.size()},
              {"grasp_tick_nd_abs_p95_mm", num(percentile(nd_abs_tick, 0.95))},
              {"nd_contact_abs_median_mm", num(percentile(contact.abs_mm, 0.5))},
              {"nd_contact_abs_p95_mm", num(percentile(contact.abs_mm, 0.95))},
              {"blocked_without_nd_contact", contact.blocked_without},
              {"grasp_tick_nd_contact_abs_median_mm", num(percentile(contact_tick.abs_mm, 0.5))},
              {"grasp_tick_nd_contact_abs_p95_mm", num(percentile(contact_tick.abs_mm, 0.95))},
              {"grasp_tick_blocked_without_nd_contact", contact_tick.blocked_without}};
  out.update(figures_summary(recs));
  if (!opposition.empty()) out["opposition_median_deg"] = percentile(opposition, 0.5);
  if (across_known > 0) out["across_smallest_share"] = static_cast<double>(across) / across_known;
  if (free_known > 0) out["across_smallest_share_ignoring_table"] = static_cast<double>(across_free) / free_known;
  return out;
}

void print_type_table(const std::vector<const Record*>& records) {
  std::map<std::string, std::vector<const Record*>> by_type;
  for (const Record* r : records)
    if (r->grasped && !r->grasp_type.empty()) by_type[r->grasp_type].push_back(r);
  if (by_type.empty() || (by_type.size() == 1 && by_type.begin()->first == "other")) return;  // a rig without types
  std::printf("%-16s %6s %6s %8s %9s %9s %9s\n", "grasp type", "grasps", "held", "FC", "opp_deg", "|ND|mean", "across");
  for (const auto& [type, recs] : by_type) {
    const json s = summarize(recs);
    auto get = [&](const char* k) { return s.contains(k) && !s[k].is_null() ? s[k].get<double>() : NAN; };
    std::printf("%-16s %6d %6d %8s %9s %9s %9s\n", type.c_str(), s["grasped"].get<int>(),
                s["held_after_lift"].get<int>(), fmt(get("force_closure_share")).c_str(),
                fmt(get("opposition_median_deg"), 0).c_str(), fmt(get("nd_abs_mean_mm"), 3).c_str(),
                fmt(get("across_smallest_share")).c_str());
  }
}

std::string fmt(double v, int prec) {
  if (!std::isfinite(v)) return "-";
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.*f", prec, v);
  return buf;
}

void print_object_table(const std::vector<ObjectRows>& objects) {
  std::printf("%-26s %6s %6s %8s %9s %9s %9s %10s %9s\n", "object", "held", "grasp", "time_s", "|ND|med", "|ND|p95",
              "|NDc|p95", "minSD_mm", "HErr_mm");
  for (const ObjectRows& o : objects) {
    const json s = summarize(o.records);
    auto get = [&](const char* k) { return s[k].is_null() ? NAN : s[k].get<double>(); };
    const int n = static_cast<int>(o.records.size());
    std::printf("%-26s %3d/%-2d %3d/%-2d %8s %9s %9s %9s %10s %9s\n", o.object.c_str(), s["held_after_lift"].get<int>(),
                n, s["grasped"].get<int>(), n, fmt(get("time_to_grasp_mean_s")).c_str(),
                fmt(get("nd_abs_median_mm"), 3).c_str(), fmt(get("nd_abs_p95_mm"), 3).c_str(),
                fmt(get("nd_contact_abs_p95_mm"), 3).c_str(), fmt(get("min_blocked_signed_distance_mm"), 3).c_str(),
                fmt(get("hand_error_mean_mm")).c_str());
  }
}

json record_json(const Record& r) {
  const bool known_mode = !r.mode.empty();
  json out = {{"object", r.object},
              {"trial", r.trial},
              {"mode", known_mode ? json(r.mode) : json(nullptr)},
              {"speed_scale", known_mode ? json(r.speed_scale) : json(nullptr)},
              {"grasped", r.grasped},
              {"held_after_lift", r.held_after_lift},
              {"attempts", r.attempts},
              {"time_to_grasp_s", r.grasped ? json(r.time_to_grasp_s) : json(nullptr)},
              {"hand_error_mm", r.grasped ? json(r.hand_error_mm) : json(nullptr)},
              {"capsules", capsule_json(r.capsules)},
              {"grasp_tick",
               {{"hand_error_mm", r.grasped ? json(r.grasp_tick_hand_error_mm) : json(nullptr)},
                {"capsules", capsule_json(r.grasp_tick_capsules)}}}};
  put_figures(out, r.figures, r.grasped);
  put_figures(out["grasp_tick"], r.grasp_tick_figures, r.grasped);
  if (!r.grasp_type.empty()) out["grasp_tick"]["grasp_type"] = r.grasp_type;
  if (std::isfinite(r.opposition_deg)) out["grasp_tick"]["opposition_deg"] = r.opposition_deg;
  if (r.across_smallest) out["grasp_tick"]["across_smallest_axis"] = *r.across_smallest;
  if (r.across_smallest_ignoring_table)
    out["grasp_tick"]["across_smallest_axis_ignoring_table"] = *r.across_smallest_ignoring_table;
  if (!r.group.empty()) {
    auto vec = [](const Eigen::Vector3d& v) { return json::array({v.x(), v.y(), v.z()}); };
    json contacts = json::array();
    for (const ContactPointRecord& c : r.contacts)
      contacts.push_back({{"phalanx", c.phalanx},
                          {"p_WorldContact_m", vec(c.p_WorldContact)},
                          {"n_World", vec(c.n_World)},
                          {"p_ObjectContact_m", vec(c.p_ObjectContact)},
                          {"n_Object", vec(c.n_Object)}});
    out["group"] = r.group;
    out["participant"] = r.participant;
    out["contacts"] = std::move(contacts);
    if (!r.grasp_tick_hand.empty()) {
      // Rounded to 1 um and 1e-6: a picture needs no more, and 600 records stay small.
      auto round6 = [](double v) { return std::round(v * 1e6) / 1e6 + 0.0; };  // + 0.0: no "-0.0"
      auto pose = [&](const Eigen::Isometry3d& X) {
        const Eigen::Quaterniond q(X.linear());
        return json{
            {"p", json::array({round6(X.translation().x()), round6(X.translation().y()), round6(X.translation().z())})},
            {"q_wxyz", json::array({round6(q.w()), round6(q.x()), round6(q.y()), round6(q.z())})}};
      };
      json frames = json::array();
      for (const HandFrameRecord& f : r.grasp_tick_hand) {
        json frame = pose(f.X_ObjectFrame);
        frame["frame"] = f.frame;
        frames.push_back(std::move(frame));
      }
      out["grasp_tick_hand"] = {{"X_WorldObject", pose(r.grasp_tick_X_WorldObject)}, {"frames", std::move(frames)}};
    }
  }
  return out;
}

Record record_from_json(const json& j) {
  Record r;
  r.object = j.at("object").get<std::string>();
  r.mode = j.at("mode").is_null() ? "" : j.at("mode").get<std::string>();
  if (!r.mode.empty()) r.speed_scale = j.at("speed_scale").get<double>();
  r.trial = j.at("trial").get<int>();
  r.attempts = j.at("attempts").get<int>();
  r.grasped = j.at("grasped").get<bool>();
  r.held_after_lift = j.at("held_after_lift").get<bool>();
  if (r.grasped) {
    r.time_to_grasp_s = j.at("time_to_grasp_s").get<double>();
    r.hand_error_mm = j.at("hand_error_mm").get<double>();
    r.grasp_tick_hand_error_mm = j.at("grasp_tick").at("hand_error_mm").get<double>();
    const json& tick = j.at("grasp_tick");
    if (tick.contains("grasp_type")) r.grasp_type = tick.at("grasp_type").get<std::string>();
    if (tick.contains("opposition_deg")) r.opposition_deg = tick.at("opposition_deg").get<double>();
    if (tick.contains("across_smallest_axis")) r.across_smallest = tick.at("across_smallest_axis").get<bool>();
    if (tick.contains("across_smallest_axis_ignoring_table"))
      r.across_smallest_ignoring_table = tick.at("across_smallest_axis_ignoring_table").get<bool>();
  }
  auto capsules = [](const json& arr) {
    std::vector<CapsuleMetricRecord> out;
    for (const json& c : arr) {
      // Records written before nd_contact name the midlength ND "nd_mm" and have no nd_contact.
      const json& nd = c.contains("nd_midlength_mm") ? c.at("nd_midlength_mm") : c.at("nd_mm");
      const bool contact_hit = c.contains("contact_hit") && c.at("contact_hit").get<bool>();
      out.push_back({c.at("phalanx").get<std::string>(), c.at("hit").get<bool>(), c.at("blocked").get<bool>(),
                     nd.is_null() ? 0.0 : nd.get<double>(), c.at("signed_distance_mm").get<double>(), contact_hit,
                     contact_hit ? c.at("nd_contact_mm").get<double>() : 0.0});
    }
    return out;
  };
  r.capsules = capsules(j.at("capsules"));
  r.grasp_tick_capsules = capsules(j.at("grasp_tick").at("capsules"));
  r.figures = get_figures(j);
  r.grasp_tick_figures = get_figures(j.at("grasp_tick"));
  if (!j.contains("group")) return r;  // not a protocol record
  r.group = j.at("group").get<std::string>();
  r.participant = j.at("participant").get<int>();
  auto vec = [](const json& v) {
    return Eigen::Vector3d(v.at(0).get<double>(), v.at(1).get<double>(), v.at(2).get<double>());
  };
  for (const json& c : j.at("contacts"))
    r.contacts.push_back({c.at("phalanx").get<std::string>(), vec(c.at("p_WorldContact_m")), vec(c.at("n_World")),
                          vec(c.at("p_ObjectContact_m")), vec(c.at("n_Object"))});
  if (!j.contains("grasp_tick_hand")) return r;
  auto pose = [&](const json& p) {
    const json& q = p.at("q_wxyz");
    Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
    X.linear() =
        Eigen::Quaterniond(q.at(0).get<double>(), q.at(1).get<double>(), q.at(2).get<double>(), q.at(3).get<double>())
            .normalized()
            .toRotationMatrix();
    X.translation() = vec(p.at("p"));
    return X;
  };
  const json& hand = j.at("grasp_tick_hand");
  r.grasp_tick_X_WorldObject = pose(hand.at("X_WorldObject"));
  for (const json& f : hand.at("frames")) r.grasp_tick_hand.push_back({f.at("frame").get<std::string>(), pose(f)});
  return r;
}

}  // namespace telegrasp::report
