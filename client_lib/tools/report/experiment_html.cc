// The experiment report as one self-contained HTML page: the run, the per-mode comparison, a
// picture of one grasp per object, the paper's bar charts as inline SVG with their numbers in
// tables, the paper's published numbers beside ours, and the questionnaire's scores.
#include "experiment_aggregate.h"
#include "grasp_svg.h"
#include "paper_correlation.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <map>
#include <optional>
#include <sstream>
#include <tuple>

namespace telegrasp::report {
namespace {

using nlohmann::json;

const PaperRow* find_paper(const std::vector<PaperRow>& paper, const std::string& object) {
  for (const PaperRow& p : paper)
    if (p.object == object) return &p;
  return nullptr;
}

// The paper's letter for an object (the tables' id column, to find it in the paper's figures);
// empty for an object outside the paper's table.
std::string label_of(const std::vector<PaperRow>& paper, const std::vector<std::string>& objects, std::size_t i) {
  if (const PaperRow* p = find_paper(paper, objects[i])) return p->label;
  return "";
}

std::string mode_name(const std::string& mode) { return mode.empty() ? "(mode unknown)" : mode; }

// ---------------------------------------------------------------------------------------------
// Text helpers

std::string esc(const std::string& s) {
  std::string out;
  for (char c : s) {
    switch (c) {
      case '&':
        out += "&amp;";
        break;
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '"':
        out += "&quot;";
        break;
      case '\'':
        out += "&#39;";
        break;
      default:
        out += c;
    }
  }
  return out;
}

const char* const kNoData = "no data";

// "1.23 ± 0.10" with the sd left out when undefined; "no data" when the mean is (never 0).
std::string mean_sd(const Stat& s, int prec = 2) {
  if (!std::isfinite(s.mean)) return kNoData;
  return fmt(s.mean, prec) + (std::isfinite(s.sd) ? " &plusmn; " + fmt(s.sd, prec) : "");
}

// ---------------------------------------------------------------------------------------------
// SVG grouped bar charts

struct Series {
  std::string mode, group, legend, colour;
  std::vector<bool> present;  // per object: false draws a "no data" slot, no bar (no trials, not in the paper)
  std::vector<double> values;  // per object; NaN draws a "no data" bar (trials, but no value)
  std::vector<std::string> cells;  // per object, the table's text
};

struct Chart {
  std::string id, title, y_label;
  std::vector<std::string> objects, labels;
  std::vector<Series> series;
  std::vector<std::pair<std::string, std::vector<std::string>>> table_only;  // extra table columns
};

const char* group_colour(const std::string& group, std::size_t index) {
  if (group == "experienced") return "#1f77b4";
  if (group == "inexperienced") return "#ff7f0e";
  if (group == "all") return "#555555";
  static const char* const others[] = {"#2ca02c", "#9467bd", "#8c564b", "#e377c2", "#17becf"};
  return others[index % 5];
}

const char* mode_colour(const std::string& mode) {
  if (mode == "paper") return "#9e9e9e";
  if (mode == "discrete") return "#d62728";
  return "#2ca02c";  // precise and anything else
}

// An id usable in url(#...): the chart's id with anything but letters and digits as '-'.
std::string css_id(const std::string& s) {
  std::string out;
  for (char c : s) out += std::isalnum(static_cast<unsigned char>(c)) ? c : '-';
  return out;
}

// The hatching of a "no data" slot, in a series' colour.
std::string hatch_pattern(const std::string& id, const std::string& colour) {
  return "<pattern id=\"" + id +
         "\" width=\"4\" height=\"4\" patternUnits=\"userSpaceOnUse\" "
         "patternTransform=\"rotate(45)\"><rect width=\"4\" height=\"4\" fill=\"#ffffff\"/><line x1=\"1\" y1=\"0\" "
         "x2=\"1\" y2=\"4\" stroke=\"" +
         colour + "\" stroke-width=\"1.2\"/></pattern>";
}

// "no data" written up a hatched slot from the axis, on a white strip so it reads over the
// hatching (drawn after the slot).
std::string nodata_text(double x, double w, double axis_y) {
  return "<rect x=\"" + fmt(x, 2) + "\" y=\"" + fmt(axis_y - 32, 1) + "\" width=\"" + fmt(w, 2) +
         "\" height=\"32\" fill=\"#ffffff\"/><text class=\"nodata-label\" transform=\"translate(" +
         fmt(x + w / 2 + 2.4, 1) + "," + fmt(axis_y - 3, 1) + ") rotate(-90)\">" + kNoData + "</text>\n";
}

std::string svg_chart(const Chart& c) {
  // Object names run at -60 degrees below the axis: the longest sets the bottom margin.
  constexpr double kCharPx = 5.2, kSin = 0.866, kCos = 0.5;  // 9 px text; sin and cos of 60 degrees
  std::size_t longest = 1;
  for (const std::string& o : c.objects) longest = std::max(longest, o.size());
  const double name_px = kCharPx * static_cast<double>(longest);
  const std::size_t ns = std::max<std::size_t>(1, c.series.size());
  const double slot = std::max(16.0, 6.0 * static_cast<double>(ns) + 6);
  const double bar_w = (slot - 4) / static_cast<double>(ns);
  const double left = std::max(52.0, kCos * name_px - slot / 2 + 6), right = 12, top = 34, plot_h = 200;
  const double bottom = 10 + kSin * name_px + 18;
  const double plot_w = slot * static_cast<double>(std::max<std::size_t>(1, c.objects.size()));
  const double width = left + plot_w + right, height = top + plot_h + bottom;

  double max = 0;
  bool missing = false;
  for (const Series& s : c.series)
    for (std::size_t i = 0; i < s.values.size(); ++i) {
      if (s.present[i] && std::isfinite(s.values[i]))
        max = std::max(max, s.values[i]);
      else
        missing = true;
    }
  const AxisTicks axis = axis_ticks(max);
  auto y_of = [&](double v) { return top + plot_h * (1 - v / axis.top); };
  const std::string id = css_id(c.id);

  std::ostringstream o;
  // No xmlns: inline SVG in HTML needs none, and the page names no URL at all.
  o << "<svg class=\"chart\" data-chart=\"" << esc(c.id) << "\" viewBox=\"0 0 " << fmt(width, 1) << " "
    << fmt(height, 1) << "\" width=\"" << fmt(width, 0) << "\" height=\"" << fmt(height, 0) << "\" role=\"img\"><title>"
    << esc(c.title) << "</title>\n<defs>";
  for (std::size_t k = 0; k < c.series.size(); ++k)
    o << hatch_pattern("nd-" + id + "-" + std::to_string(k), c.series[k].colour);
  o << hatch_pattern("nd-" + id + "-legend", "#888888") << "</defs>\n";
  // Grid and y axis: a line and an exact label per tick.
  for (std::size_t t = 0; t < axis.values.size(); ++t) {
    const double y = y_of(axis.values[t]);
    o << "<line class=\"grid\" x1=\"" << fmt(left, 1) << "\" x2=\"" << fmt(left + plot_w, 1) << "\" y1=\"" << fmt(y, 1)
      << "\" y2=\"" << fmt(y, 1) << "\"/><text class=\"tick\" x=\"" << fmt(left - 4, 1) << "\" y=\"" << fmt(y + 3, 1)
      << "\" text-anchor=\"end\">" << axis.labels[t] << "</text>\n";
  }
  o << "<text class=\"axis\" transform=\"translate(12," << fmt(top + plot_h / 2, 1) << ") rotate(-90)\" "
    << "text-anchor=\"middle\">" << esc(c.y_label) << "</text>\n";
  // Legend, one entry per series, and the "no data" hatching when a slot has no value.
  double lx = left;
  for (const Series& s : c.series) {
    o << "<rect class=\"legend\" x=\"" << fmt(lx, 1) << "\" y=\"8\" width=\"10\" height=\"10\" fill=\"" << s.colour
      << "\"/><text class=\"legend\" x=\"" << fmt(lx + 14, 1) << "\" y=\"17\">" << esc(s.legend) << "</text>\n";
    lx += 24 + 6.5 * static_cast<double>(s.legend.size());
  }
  if (missing)
    o << "<rect class=\"legend\" x=\"" << fmt(lx, 1) << "\" y=\"8\" width=\"10\" height=\"10\" fill=\"url(#nd-" << id
      << "-legend)\" stroke=\"#888888\" stroke-width=\"0.5\"/><text class=\"legend\" x=\"" << fmt(lx + 14, 1)
      << "\" y=\"17\">" << kNoData << " (no bar, not zero)</text>\n";
  // Bars, hatched "no data" slots and the object names.
  for (std::size_t i = 0; i < c.objects.size(); ++i) {
    const double x0 = left + slot * static_cast<double>(i) + 2;
    for (std::size_t k = 0; k < c.series.size(); ++k) {
      const Series& s = c.series[k];
      const double v = s.values[i];
      const double x = x0 + bar_w * static_cast<double>(k);
      const std::string hatch = "url(#nd-" + id + "-" + std::to_string(k) + ")";
      if (!s.present[i]) {
        o << "<rect class=\"nodata\" x=\"" << fmt(x, 2) << "\" y=\"" << fmt(top, 2) << "\" width=\"" << fmt(bar_w, 2)
          << "\" height=\"" << fmt(plot_h, 2) << "\" fill=\"" << hatch << "\"><title>" << esc(c.objects[i]) << ", "
          << esc(s.legend) << ": no data (" << (s.mode == "paper" ? "not in the paper" : "no trials")
          << ")</title></rect>\n"
          << nodata_text(x, bar_w, top + plot_h);
        continue;
      }
      const bool defined = std::isfinite(v);
      const double h = defined ? std::max(0.0, plot_h * std::min(v, axis.top) / axis.top) : plot_h;
      o << "<rect class=\"bar\" data-chart=\"" << esc(c.id) << "\" data-mode=\"" << esc(s.mode) << "\" data-group=\""
        << esc(s.group) << "\" data-object=\"" << esc(c.objects[i]) << "\" data-value=\"" << number(v, 4) << "\" x=\""
        << fmt(x, 2) << "\" y=\"" << fmt(top + plot_h - h, 2) << "\" width=\"" << fmt(bar_w, 2) << "\" height=\""
        << fmt(h, 2) << "\" fill=\"" << (defined ? s.colour : hatch) << "\"><title>" << esc(c.objects[i]) << ", "
        << esc(s.legend) << ": " << (defined ? fmt(v, 3) : std::string(kNoData)) << "</title></rect>\n";
      if (!defined) o << nodata_text(x, bar_w, top + plot_h);
    }
    const double xc = x0 + (slot - 4) / 2 + 3, yl = top + plot_h + 10;
    o << "<text class=\"xlabel\" transform=\"translate(" << fmt(xc, 1) << "," << fmt(yl, 1)
      << ") rotate(-60)\" text-anchor=\"end\">" << esc(c.objects[i]) << "</text>\n";
  }
  o << "<line class=\"axisline\" x1=\"" << fmt(left, 1) << "\" x2=\"" << fmt(left + plot_w, 1) << "\" y1=\""
    << fmt(top + plot_h, 1) << "\" y2=\"" << fmt(top + plot_h, 1) << "\"/>\n"
    << "<text class=\"axis\" x=\"" << fmt(left + plot_w / 2, 1) << "\" y=\"" << fmt(height - 4, 1)
    << "\" text-anchor=\"middle\">Object</text>\n</svg>\n";
  return o.str();
}

std::string chart_table(const Chart& c) {
  std::ostringstream o;
  o << "<table class=\"numbers\"><tr><th>paper id</th><th>object</th>";
  for (const Series& s : c.series) o << "<th>" << esc(s.legend) << "</th>";
  for (const auto& [name, cells] : c.table_only) o << "<th>" << esc(name) << "</th>";
  o << "</tr>\n";
  for (std::size_t i = 0; i < c.objects.size(); ++i) {
    o << "<tr><td>" << esc(c.labels[i]) << "</td><td>" << esc(c.objects[i]) << "</td>";
    for (const Series& s : c.series) o << "<td>" << (s.present[i] ? s.cells[i] : kNoData) << "</td>";
    for (const auto& [name, cells] : c.table_only) o << "<td>" << cells[i] << "</td>";
    o << "</tr>\n";
  }
  o << "</table>\n";
  return o.str();
}

std::string figure(const Chart& c) {
  return "<figure><figcaption>" + esc(c.title) + "</figcaption>\n" + svg_chart(c) + chart_table(c) + "</figure>\n";
}

// ---------------------------------------------------------------------------------------------
// Page parts

const char* kCss = R"(body{font-family:sans-serif;margin:1.5em;color:#222;max-width:none}
h1{font-size:1.5em}h2{font-size:1.2em;margin-top:2em;border-bottom:1px solid #ccc}h3{font-size:1em}
table{border-collapse:collapse;margin:.5em 0;font-size:.85em}
td,th{border:1px solid #ccc;padding:2px 6px;text-align:right}
th{background:#f2f2f2}td:first-child,th:first-child{text-align:left}
.row{display:flex;flex-wrap:wrap;gap:2em;align-items:flex-start}.col{flex:0 0 auto}
figure{margin:0 0 1.5em 0}figcaption{font-weight:bold;margin-bottom:.3em}
svg.chart{background:#fff;display:block}svg .grid{stroke:#e0e0e0;stroke-width:.5}
svg .axisline{stroke:#333;stroke-width:1}svg text{font-size:9px;fill:#333}svg .axis{font-size:10px}
svg .legend{font-size:10px}svg .nodata-label{font-size:7px;fill:#333}
.caveat{background:#fff8e1;border-left:4px solid #f0ad4e;padding:.5em 1em;max-width:60em}
.rejected{color:#a00}code{background:#f4f4f4;padding:0 3px}
.pictures{display:flex;flex-wrap:wrap;gap:1em}.pictures figure{margin:0;width:260px}
.pictures figcaption{font-weight:normal;font-size:.8em;margin-top:.2em}.pictures b{font-size:1.1em}
svg.grasp{display:block;border:1px solid #ddd}.legend-key{font-size:.85em;max-width:60em}
)";

std::string page(const std::string& title, const std::string& body) {
  return "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n<title>" + esc(title) +
         "</title>\n<style>\n" + kCss + "</style>\n</head>\n<body>\n" + body + "</body>\n</html>\n";
}

std::string unit_caveat(const ExperimentRun& run) {
  std::string out =
      "<div class=\"caveat\" id=\"unit-caveat\"><p><b>How our numbers compare with the paper's.</b></p><ul>\n"
      "<li><b>Time</b> is seconds from the object's spawn to the moment the grasp rule turns true, in both. "
      "The paper's are ten people with a VR headset (4 experienced, 6 inexperienced); ours are a seeded "
      "<b>scripted bot</b>, not humans: its groups differ only in the reach pose error and speed it is given.</li>\n"
      "<li><b>Error.</b> The paper's figures plot \"average error (mm)\" per object and group, averaged over its "
      "participants; its text defines that error as the \"total error for the hand\", HandError (eq. 2): for each "
      "finger the mean |ND| of its two capsule triggers (middle and distal phalanx), <i>summed over the five "
      "fingers</i>, with ND from UE4 sphere traces against the object's collision geometry after the "
      "once-per-frame overlap test stopped the fingers; a per-hand sum in millimetres. The paper does not say on "
      "which frame it was taken. "
      "Ours, in the error charts, is the <b>mean |ND| over the capsules that hit</b> (a per-capsule mean, not a "
      "sum over fingers), in mm, by the exact metric of sim/README.md section 4 (sphere sweep against the exact "
      "mesh), taken at the grasp tick and averaged per grasp, then over the grasps of the object and group. "
      "Our HandError (the paper's per-hand sum, same tick) is in the tables for the paper-vs-ours charts. "
      "The two error columns therefore differ in metric, geometry and closing method: compare their shape across "
      "objects, not their values.</li>\n";
  if (!run.standin_objects.empty())
    out += "<li>" + std::to_string(run.standin_objects.size()) +
           " object(s) were procedural stand-ins, not YCB meshes (listed in the run summary): their geometry "
           "differs from the paper's objects.</li>\n";
  return out + "</ul></div>\n";
}

std::string questionnaire_section(const QuestionnaireSummary& q) {
  std::ostringstream o;
  o << "<h2 id=\"questionnaire\">Questionnaire</h2>\n<p>Source: <code>" << esc(q.source) << "</code>; "
    << q.participants.size() << " participant(s) scored, " << q.rejected.size() << " row(s) rejected. "
    << "Scores (-3..3): Motor Control = ((Q1+Q2)-(Q3+Q4))/4, Finger Movement Realism = (Q5+Q6+Q7)/3, "
    << "Interaction Realism = ((Q8+Q9)-(Q10+Q11)+Q12+Q13+Q14)/7, Embodiment = (MC+FMR+2&middot;IR)/4; "
    << "Q3, Q4, Q10 and Q11 are reversed items. Group values are mean &plusmn; sample sd; the paper's Table 2 "
    << "value is in brackets.</p>\n";
  o << "<table class=\"numbers\"><tr><th>group</th><th>n</th><th>Motor Control</th><th>Finger Movement "
       "Realism</th><th>Interaction Realism</th><th>Embodiment</th></tr>\n";
  for (const QuestionnaireGroup& g : q.groups) {
    const PaperQuestionnaireRow* paper = paper_questionnaire_row(g.group);
    auto col = [&](const ScoreStat& st, double QuestionnaireScores::*field) {
      std::string text = mean_sd({st.n, st.mean, st.sd});
      if (paper) text += " [" + fmt(paper->scores.*field) + "]";
      return "<td>" + text + "</td>";
    };
    o << "<tr><td>" << esc(g.group) << "</td><td>" << g.n << "</td>"
      << col(g.motor_control, &QuestionnaireScores::motor_control)
      << col(g.finger_movement_realism, &QuestionnaireScores::finger_movement_realism)
      << col(g.interaction_realism, &QuestionnaireScores::interaction_realism)
      << col(g.embodiment, &QuestionnaireScores::embodiment) << "</tr>\n";
  }
  o << "</table>\n<p>The paper reports an embodiment score of 1.97 (experienced) and 2.19 (inexperienced).</p>\n";
  o << "<details><summary>Per participant</summary><table class=\"numbers\"><tr><th>id</th><th>group</th>";
  for (int i = 1; i <= kQuestionCount; ++i) o << "<th>Q" << i << "</th>";
  o << "<th>MC</th><th>FMR</th><th>IR</th><th>Embodiment</th></tr>\n";
  for (const QuestionnaireParticipant& p : q.participants) {
    o << "<tr><td>" << esc(p.id) << "</td><td>" << esc(p.group) << "</td>";
    for (int a : p.answers) o << "<td>" << a << "</td>";
    o << "<td>" << fmt(p.scores.motor_control) << "</td><td>" << fmt(p.scores.finger_movement_realism) << "</td><td>"
      << fmt(p.scores.interaction_realism) << "</td><td>" << fmt(p.scores.embodiment) << "</td></tr>\n";
  }
  o << "</table></details>\n";
  if (!q.rejected.empty()) {
    o << "<p class=\"rejected\">Rejected rows (not scored):</p><ul class=\"rejected\">\n";
    for (const RejectedRow& r : q.rejected) o << "<li>" << esc(r.message) << "</li>\n";
    o << "</ul>\n";
  }
  return o.str();
}

// ---------------------------------------------------------------------------------------------
// The experiment page, section by section

// What the sections draw from: the run's modes, groups and objects in a stable order, each
// object's x-axis label, and the aggregate per mode, group ("all" = both) and object, computed once.
struct PageData {
  std::vector<std::string> modes, groups, objects, labels;
  std::map<std::string, std::map<std::string, std::vector<Aggregate>>> agg;
  std::map<std::string, std::map<std::string, std::vector<bool>>> has;  // per object: has records
};

PageData page_data(const ExperimentRun& run, const std::vector<PaperRow>& paper) {
  PageData d{modes_of(run), groups_of(run), objects_of(run), {}, {}, {}};
  for (std::size_t i = 0; i < d.objects.size(); ++i) d.labels.push_back(label_of(paper, d.objects, i));
  for (const std::string& mode : d.modes) {
    std::vector<std::string> with_all = d.groups;
    with_all.push_back("all");
    for (const std::string& group : with_all) {
      std::vector<Aggregate>& aggs = d.agg[mode][group];  // present even with no objects
      std::vector<bool>& has = d.has[mode][group];
      for (const std::string& object : d.objects) {
        const auto records = select(run, mode, group == "all" ? "" : group, object);
        aggs.push_back(aggregate(records));
        has.push_back(!records.empty());
      }
    }
  }
  return d;
}

std::string time_cell(const Aggregate& a) {
  return mean_sd(a.time) + " (" + std::to_string(a.grasped) + "/" + std::to_string(a.n) + ")";
}

std::string nd_cell(const Aggregate& a) { return mean_sd(a.nd, 3) + " (" + std::to_string(a.nd.n) + ")"; }

// The bars of one mode and group: mean time to grasp (or mean |ND|) per object, and table cells.
Series series_of(const PageData& d, const std::string& mode, const std::string& group, const std::string& legend,
                 const std::string& colour, bool time) {
  Series s{mode, group, legend, colour, d.has.at(mode).at(group), {}, {}};
  for (const Aggregate& a : d.agg.at(mode).at(group)) {
    s.values.push_back(time ? a.time.mean : a.nd.mean);
    s.cells.push_back(time ? time_cell(a) : nd_cell(a));
  }
  return s;
}

// Run summary: command, time, seed, modes, participants, objects and stand-in fallbacks.
std::string run_section(const ExperimentRun& run, const PageData& d) {
  std::ostringstream body;
  body << "<h2>Run</h2>\n<table class=\"numbers\">\n<tr><th>command</th><td><code>" << esc(run.command_line)
       << "</code></td></tr>\n<tr><th>created</th><td>" << esc(run.created) << "</td></tr>\n<tr><th>seed</th><td>"
       << run.seed << "</td></tr>\n<tr><th>wall time</th><td>" << fmt(run.wall_seconds, 1)
       << " s</td></tr>\n<tr><th>modes</th><td>";
  for (std::size_t i = 0; i < d.modes.size(); ++i) body << (i ? ", " : "") << esc(mode_name(d.modes[i]));
  body << "</td></tr>\n<tr><th>participants</th><td>";
  {
    bool first = true;
    for (const auto& [group, count] : run.participants) {
      body << (first ? "" : ", ") << esc(group) << ": " << count;
      first = false;
    }
  }
  body << "</td></tr>\n<tr><th>objects</th><td>" << d.objects.size() << " with records of " << run.objects.size()
       << " in the protocol; " << run.records.size() << " grasp trials</td></tr>\n<tr><th>stand-in fallbacks</th><td>";
  if (run.standin_objects.empty()) body << "none";
  for (std::size_t i = 0; i < run.standin_objects.size(); ++i) body << (i ? ", " : "") << esc(run.standin_objects[i]);
  body << "</td></tr>\n</table>\n";
  return body.str();
}

// The slowest and least exact objects of each mode, both groups together (from aggregate_json).
std::string worst_objects_paragraph(const ExperimentRun& run) {
  std::ostringstream body;
  const json aggregates = aggregate_json(run);
  body << "<p>Worst objects (both groups): ";
  for (const json& w : aggregates["worst_objects"]) {
    body << "<br><b>" << esc(mode_name(w["mode"].get<std::string>())) << "</b> by time: ";
    for (const json& o : w["by_time"])
      body << esc(o["object"].get<std::string>()) << " (" << fmt(o["time_to_grasp_mean_s"].get<double>()) << " s) ";
    body << "; by |ND|: ";
    for (const json& o : w["by_nd"])
      body << esc(o["object"].get<std::string>()) << " (" << fmt(o["nd_abs_mean_mm"].get<double>(), 3) << " mm) ";
  }
  body << "</p>\n";
  return body.str();
}

// Precise against discrete time to grasp, grasp by grasp: the same participant, object and trial in
// both modes. Says why they agree and lists where they differ.
std::string mode_times_section(const ExperimentRun& run, const PageData& d) {
  if (std::find(d.modes.begin(), d.modes.end(), "precise") == d.modes.end() ||
      std::find(d.modes.begin(), d.modes.end(), "discrete") == d.modes.end())
    return "";
  constexpr double kSame = 1e-6;  // s: below this the two times are the same number
  using Key = std::tuple<std::string, int, std::string, int>;
  std::map<Key, const Record*> precise;
  for (const Record& r : run.records)
    if (r.mode == "precise" && r.grasped) precise[{r.group, r.participant, r.object, r.trial}] = &r;
  struct Diff {
    const Record *p, *q;
    double delta;
  };
  std::vector<Diff> diffs;
  int pairs = 0;
  for (const Record& r : run.records) {
    if (r.mode != "discrete" || !r.grasped) continue;
    const auto it = precise.find({r.group, r.participant, r.object, r.trial});
    if (it == precise.end()) continue;
    ++pairs;
    const double delta = r.time_to_grasp_s - it->second->time_to_grasp_s;
    if (std::abs(delta) >= kSame) diffs.push_back({it->second, &r, delta});
  }
  std::ostringstream o;
  o << "<h3 id=\"mode-times\">Precise against discrete time to grasp</h3>\n<p>Every participant is the same simulated "
       "person in both modes (the same seed gives the same reaction time, reach speed and pose errors) and is shown "
       "the "
       "same placements, so the hand arrives and closes at the same moments. The closing mode changes only how a "
       "finger stops at the surface (precise: with a gap under 0.05 mm; discrete: up to one step inside), which can "
       "move "
       "the tick the grasp rule turns true by a tick (1/90 s) or so, not the operator's timing. ";
  o << "Of the " << pairs << " grasps made in both modes (same group, participant, object and trial), "
    << pairs - static_cast<int>(diffs.size()) << " have the same time to grasp and " << diffs.size() << " differ";
  if (diffs.empty()) {
    o << ".</p>\n";
    return o.str();
  }
  std::stable_sort(diffs.begin(), diffs.end(),
                   [](const Diff& a, const Diff& b) { return std::abs(a.delta) > std::abs(b.delta); });
  o << ", by at most " << fmt(std::abs(diffs.front().delta), 3) << " s";
  constexpr std::size_t kShown = 12;
  o << (diffs.size() > kShown ? " (the " + std::to_string(kShown) + " largest differences below)" : " (below)")
    << ".</p>\n<table class=\"numbers\"><tr><th>group</th><th>participant</th><th>object</th><th>trial</th><th>precise "
       "(s)"
       "</th><th>discrete (s)</th><th>discrete &minus; precise (s)</th></tr>\n";
  for (std::size_t i = 0; i < diffs.size() && i < kShown; ++i) {
    const Diff& x = diffs[i];
    o << "<tr><td>" << esc(x.p->group) << "</td><td>" << x.p->participant << "</td><td>" << esc(x.p->object)
      << "</td><td>" << x.p->trial << "</td><td>" << fmt(x.p->time_to_grasp_s, 3) << "</td><td>"
      << fmt(x.q->time_to_grasp_s, 3) << "</td><td>" << (x.delta > 0 ? "+" : "") << fmt(x.delta, 3) << "</td></tr>\n";
  }
  o << "</table>\n";
  return o.str();
}

// The hand and object of a record at its grasp tick, in the world frame; nothing when the record
// lacks the palm or a phalanx of `rig`.
std::optional<sim::GraspSnapshot> record_snapshot(const Record& r, const sim::HandRig& rig,
                                                  const sim::ObjectModel& model) {
  std::map<std::string, const Eigen::Isometry3d*> frames;
  for (const HandFrameRecord& f : r.grasp_tick_hand) frames[f.frame] = &f.X_ObjectFrame;
  const Eigen::Isometry3d& X_WorldObject = r.grasp_tick_X_WorldObject;
  if (!frames.count("palm")) return std::nullopt;
  std::vector<Eigen::Isometry3d> X_WorldPhalanx;
  std::vector<bool> blocked;
  for (const sim::PhalanxSpec& p : rig.phalanges()) {
    const auto it = frames.find(p.name);
    if (it == frames.end()) return std::nullopt;
    X_WorldPhalanx.push_back(X_WorldObject * *it->second);
    bool b = false;
    for (const CapsuleMetricRecord& c : r.grasp_tick_capsules) b = b || (c.phalanx == p.name && c.blocked);
    blocked.push_back(b);
  }
  sim::GraspSnapshot snap;
  snap.title = r.object;
  snap.model = &model;
  snap.X_WorldObject = X_WorldObject;
  sim::add_hand(snap, rig, X_WorldObject * *frames.at("palm"), X_WorldPhalanx, blocked);
  for (const ContactPointRecord& c : r.contacts)
    snap.contacts.push_back({X_WorldObject * c.p_ObjectContact, X_WorldObject.linear() * c.n_Object});
  return snap;
}

// One picture per object: the representative grasp in its readable view, with what it shows.
std::string pictures_section(const ExperimentRun& run, const PageData& d, const GraspPictureInputs& in) {
  std::ostringstream o;
  o << "<h2 id=\"pictures\">The grasps, one per object</h2>\n<p class=\"legend-key\">Each picture is one grasp at the "
       "tick its grasp rule turned true: the first experienced participant's in precise mode, held after the lift "
       "(failing that, the first record by: held, precise mode, experienced, participant, trial). The hand is the "
       "server's HandSkeleton of that tick, kept in the object's frame. <b>Grey</b>: the object, its mesh decimated "
       "to at most "
    << sim::PictureOptions{}.max_triangles
    << " triangles for drawing, flat shaded. <b>Light</b> "
       "capsules: free phalanges; <b>dark</b>: blocked; <b>dashed</b> outline: behind the object. Pale see-through "
       "shapes: the palm and the phalanges without a capsule, for context. <b>Red</b> dots: the contacts, with a 10 mm "
       "tick along the surface normal; hollow: behind the object. Viewpoint: world z up; of the 16 views from azimuths "
       "0, 45, ..., 315&deg; at elevations 20&deg; and 50&deg;, the one that shows the most of the hand and of where "
       "it "
       "touches (capsule points the object does not hide, and contacts that neither the object nor a finger "
       "hides).</p>\n"
       "<div class=\"pictures\">\n";
  for (const std::string& object : d.objects) {
    o << "<figure data-object=\"" << esc(object) << "\">";
    const Record* r = representative_grasp(run, object);
    const auto model = in.models.find(object);
    std::optional<sim::GraspSnapshot> snap;
    if (r && model != in.models.end() && model->second && in.rig) snap = record_snapshot(*r, *in.rig, *model->second);
    const bool standin =
        std::find(run.standin_objects.begin(), run.standin_objects.end(), object) != run.standin_objects.end();
    if (!snap) {
      o << "<figcaption><b>" << esc(object) << "</b><br>no picture: "
        << (!r ? "no record has the hand at the grasp tick" : "its model or the hand's rig is not known")
        << "</figcaption>";
    } else {
      const sim::View view = sim::readable_view(*snap);
      int blocked = 0;
      for (const auto& c : snap->capsules) blocked += c.blocked;
      int hits = 0;
      grasp_nd_abs_mean(*r, &hits);
      o << sim::render_view_svg(*snap, view) << "<figcaption><b>" << esc(object) << "</b>"
        << (standin ? " (stand-in)" : "") << "<br>" << esc(mode_name(r->mode)) << ", " << esc(r->group)
        << " participant " << r->participant << ", " << (r->held_after_lift ? "held" : "grasped, not held")
        << (r->grasp_type.empty() || r->grasp_type == "other" ? "" : ", " + esc(r->grasp_type)) << "; "
        << fmt(r->time_to_grasp_s) << " s; HandError "
        << (hits ? fmt(r->grasp_tick_hand_error_mm) + " mm" : std::string(kNoData)) << "<br>" << r->contacts.size()
        << " contact(s), " << blocked << " of " << snap->capsules.size() << " capsules blocked<br>view from "
        << esc(view.name) << "</figcaption>";
    }
    o << "</figure>\n";
  }
  o << "</div>\n";
  return o.str();
}

// Calls fn(mode, group, aggregate) for every mode and group of the page that has records, in
// the page's order: one table row each.
template <typename Fn>
void for_each_mode_and_group(const ExperimentRun& run, const PageData& d, Fn fn) {
  for (const std::string& mode : d.modes)
    for (const std::string& group : d.groups) {
      const auto records = select(run, mode, group, "");
      if (!records.empty()) fn(mode, group, aggregate(records));
    }
}

// Overall per mode and group: the discrete-vs-precise comparison at a glance, then the worst
// objects and how our numbers compare with the paper's.
std::string overall_section(const ExperimentRun& run, const PageData& d) {
  std::ostringstream body;
  body << "<h2>Overall per mode and group</h2>\n<table class=\"numbers\"><tr><th>mode</th><th>group</th><th>trials</th>"
          "<th>grasped</th><th>held after lift</th><th>time to grasp (s)</th><th>mean |ND| at mid-length (mm)</th>"
          "<th>HandError (mm)</th></tr>\n";
  for_each_mode_and_group(run, d, [&](const std::string& mode, const std::string& group, const Aggregate& a) {
    body << "<tr><td>" << esc(mode_name(mode)) << "</td><td>" << esc(group) << "</td><td>" << a.n << "</td><td>"
         << a.grasped << "</td><td>" << a.held << "</td><td>" << mean_sd(a.time) << "</td><td>" << mean_sd(a.nd, 3)
         << "</td><td>" << mean_sd(a.hand_error) << "</td></tr>\n";
  });
  body << "</table>\n";
  return body.str() + mode_times_section(run, d) + worst_objects_paragraph(run) + unit_caveat(run);
}

// The fidelity figures per mode and group (sim/README.md, section 4): nd_contact, the exact signed
// distances of blocked capsules and of the palm, at the grasp tick. Targets are set on these.
std::string fidelity_section(const ExperimentRun& run, const PageData& d) {
  std::ostringstream body;
  body << "<h2 id=\"fidelity\">Fidelity: ND at the contact and exact signed distances</h2>\n<p>At the grasp tick, "
          "over the blocked capsules: <code>nd_contact</code> (the paper's sweep taken toward the point of the "
          "capsule's axis nearest its contact) and the exact capsule-to-object signed distance; and the palm's "
          "exact signed distance. The paper comparison below uses <code>nd_midlength</code>; the fidelity targets "
          "(|nd_contact| median &le; 0.05 mm, p95 &le; 0.1 mm, nothing below -0.1 mm) are set on these.</p>\n"
          "<table class=\"numbers\"><tr><th>mode</th><th>group</th><th>blocked capsules</th><th>without "
          "nd_contact</th><th>|nd_contact| median (mm)</th><th>|nd_contact| p95 (mm)</th><th>min signed distance "
          "(mm)</th><th>capsules &lt; -0.1 mm</th><th>palm min signed distance (mm)</th><th>palms &lt; -0.1 "
          "mm</th></tr>\n";
  for_each_mode_and_group(run, d, [&](const std::string& mode, const std::string& group, const Aggregate& a) {
    const Fidelity& f = a.fidelity;
    body << "<tr><td>" << esc(mode_name(mode)) << "</td><td>" << esc(group) << "</td><td>" << f.blocked << "</td><td>"
         << f.blocked_without_contact << "</td><td>" << fmt(percentile(f.nd_contact_abs, 0.5), 3) << "</td><td>"
         << fmt(percentile(f.nd_contact_abs, 0.95), 3) << "</td><td>" << fmt(f.min_signed_distance, 3) << "</td><td>"
         << f.blocked_below << "</td><td>" << fmt(f.palm_min, 3) << "</td><td>" << f.palm_below << "</td></tr>\n";
  });
  body << "</table>\n";
  return body.str();
}

// The share of held grasps in force closure per object, one column per mode and group.
std::string force_closure_section(const ExperimentRun& run, const PageData& d) {
  std::ostringstream body;
  body << "<h2 id=\"force-closure\">Held grasps in force closure</h2>\n<p>Per object: held grasps whose contacts "
          "are in force closure (Ferrari-Canny epsilon &gt; 0 with the rig's friction, sim/README.md section 5) / "
          "held grasps, and the share. The contacts are the settled hold's, as the hand holds the object up: the "
          "grasp rule fires on the first contacts that hold, and the other fingers close after it (the grasp "
          "tick's quality is each record's <code>grasp_tick</code> in the JSON).</p>\n"
          "<table class=\"numbers\"><tr><th>object</th>";
  for (const std::string& mode : d.modes)
    for (const std::string& group : d.groups) body << "<th>" << esc(mode_name(mode)) << ", " << esc(group) << "</th>";
  body << "</tr>\n";
  auto cell = [](const Aggregate& a) {
    if (a.held == 0) return std::string(kNoData);
    return std::to_string(a.held_force_closure) + "/" + std::to_string(a.held) + " (" +
           fmt(100.0 * a.held_force_closure / a.held, 0) + " %)";
  };
  std::vector<std::string> rows = d.objects;
  rows.push_back("");  // all objects
  for (const std::string& object : rows) {
    body << "<tr><td>" << (object.empty() ? std::string("<b>all</b>") : esc(object)) << "</td>";
    for (const std::string& mode : d.modes)
      for (const std::string& group : d.groups)
        body << "<td>" << cell(aggregate(select(run, mode, group, object))) << "</td>";
    body << "</tr>\n";
  }
  body << "</table>\n";
  return body.str();
}

// Per grasp type (a rig that lists types; nothing otherwise): how often each was used, held,
// in force closure, how squarely the thumb opposed, and ND, per mode.
std::string grasp_types_section(const ExperimentRun& run, const PageData& d) {
  std::map<std::pair<std::string, std::string>, std::vector<const Record*>> by;  // (mode, type)
  bool typed = false;
  for (const Record& r : run.records) {
    if (!r.grasped || r.grasp_type.empty()) continue;
    by[{r.mode, r.grasp_type}].push_back(&r);
    typed |= r.grasp_type != "other";
  }
  if (!typed) return "";
  std::ostringstream body;
  body << "<h2 id=\"grasp-types\">Grasp types</h2>\n<p>The type each grasp closed with (chosen from the object's "
          "shape class, its width across the hand and the hand's pose; \"other\": the rig's own closing). Force "
          "closure is the settled hold's, as in the table above; opposition is the grasp tick's: the angle between "
          "the thumb's mean contact normal and the other fingers' (180&deg;: straight across).</p>\n"
          "<table class=\"numbers\"><tr><th>mode</th><th>grasp type</th><th>grasps</th><th>held after lift</th><th>in "
          "force closure</th><th>opposition median (&deg;)</th>"
          "<th>mean |ND| at mid-length (mm)</th></tr>\n";
  for (const std::string& mode : d.modes)
    for (const auto& [key, records] : by) {
      if (key.first != mode) continue;
      const nlohmann::json sum = summarize(records);
      auto num = [&](const char* k) { return sum.contains(k) && !sum[k].is_null() ? sum[k].get<double>() : NAN; };
      body << "<tr><td>" << esc(mode_name(mode)) << "</td><td>" << esc(key.second) << "</td><td>"
           << sum["grasped"].get<int>() << "</td><td>" << sum["held_after_lift"].get<int>() << "</td><td>"
           << fmt(100.0 * num("force_closure_share"), 0) << " %</td><td>" << fmt(num("opposition_median_deg"), 0)
           << "</td><td>" << fmt(num("nd_abs_mean_mm"), 3) << "</td></tr>\n";
    }
  body << "</table>\n";
  return body.str();
}

// Charts (1) to (3): one column per mode, so discrete and precise sit side by side.
std::string mode_charts_section(const PageData& d) {
  struct Kind {
    const char* id;
    const char* title;
    const char* y_label;
    bool time, overall;
  };
  const Kind kinds[] = {
      {"time_by_group", "Mean time to grasp per object and group", "Time [s]", true, false},
      {"nd_by_group",
       "Mean |ND| at mid-length (nd_midlength, the paper's ND) per object and group (capsules that hit, grasp tick)",
       "|ND| [mm]", false, false},
      {"time_overall", "Mean time to grasp per object, all participants", "Time [s]", true, true},
      {"nd_overall", "Mean |ND| at mid-length (nd_midlength) per object, all participants", "|ND| [mm]", false, true},
  };
  std::ostringstream body;
  for (const Kind& kind : kinds) {
    body << "<h2>" << kind.title << "</h2>\n<div class=\"row\">\n";
    for (const std::string& mode : d.modes) {
      Chart c{std::string(kind.id) + "." + mode,
              kind.title + std::string(", ") + mode_name(mode),
              kind.y_label,
              d.objects,
              d.labels,
              {},
              {}};
      if (kind.overall) {
        c.series.push_back(series_of(d, mode, "all", "All participants", group_colour("all", 0), kind.time));
      } else {
        for (std::size_t g = 0; g < d.groups.size(); ++g)
          c.series.push_back(series_of(d, mode, d.groups[g], d.groups[g], group_colour(d.groups[g], g), kind.time));
      }
      body << "<div class=\"col\"><h3>" << esc(mode_name(mode)) << "</h3>\n" << figure(c) << "</div>\n";
    }
    body << "</div>\n";
  }
  return body.str();
}

// Chart (4) for one of the paper's groups: the paper's time (or error) per object beside ours in
// every mode; the error chart's table adds our HandError.
Chart paper_chart(const std::vector<PaperRow>& paper, const PageData& d, const std::string& group, bool time) {
  const bool experienced = group == "experienced";
  Chart c{std::string(time ? "paper_time." : "paper_error.") + group,
          (time ? "Time to grasp, paper vs ours, "
                : "Error, paper's HandError vs our mean |ND| at mid-length (nd_midlength), ") +
              group,
          time ? "Time [s]" : "Error [mm]",
          d.objects,
          d.labels,
          {},
          {}};
  Series p{"paper", group, "paper", mode_colour("paper"), {}, {}, {}};
  for (const std::string& object : d.objects) {
    const PaperRow* row = find_paper(paper, object);
    const double v = !row   ? NAN
                     : time ? (experienced ? row->time_experienced : row->time_inexperienced)
                            : (experienced ? row->err_experienced : row->err_inexperienced);
    p.present.push_back(row != nullptr);
    p.values.push_back(v);
    p.cells.push_back(number(v, 3));
  }
  c.series.push_back(std::move(p));
  for (const std::string& mode : d.modes) {
    c.series.push_back(series_of(d, mode, group, "ours, " + mode_name(mode), mode_colour(mode), time));
    if (!time) {
      std::vector<std::string> cells;
      for (const Aggregate& a : d.agg.at(mode).at(group)) cells.push_back(mean_sd(a.hand_error));
      c.table_only.emplace_back("our HandError, " + mode_name(mode), std::move(cells));
    }
  }
  return c;
}

// Chart (4): the paper's published numbers beside ours, per group, every mode in one chart.
std::string paper_section(const std::vector<PaperRow>& paper, const PageData& d) {
  std::ostringstream body;
  body << "<h2>The paper's per-object results beside ours</h2>\n";
  if (paper.empty()) body << "<p>No paper results given.</p>\n";
  for (const std::string& group : d.groups) {
    if (paper.empty() || (group != "experienced" && group != "inexperienced")) continue;
    body << "<div class=\"row\">\n";
    for (const bool time : {true, false})
      body << "<div class=\"col\">\n" << figure(paper_chart(paper, d, group, time)) << "</div>\n";
    body << "</div>\n";
  }
  body << "<p>Paper: Oprea et al. 2019, figures \"average elapsed time\" and \"average error (mm)\" per object "
          "(<code>paper_results_per_object.csv</code>). Table cells of ours: mean &plusmn; sample sd (grasped/trials "
          "for time; grasps with a hit capsule for |ND|).</p>\n";
  return body.str();
}

}  // namespace

const Record* representative_grasp(const ExperimentRun& run, const std::string& object) {
  auto rank = [](const std::string& value, const char* first) { return value == first ? 0 : 1; };
  auto key = [&](const Record& r) {
    return std::make_tuple(!r.held_after_lift, rank(r.mode, "precise"), rank(r.group, "experienced"), r.participant,
                           r.trial);
  };
  const Record* best = nullptr;
  for (const Record& r : run.records)
    if (r.object == object && r.grasped && !r.grasp_tick_hand.empty() && (!best || key(r) < key(*best))) best = &r;
  return best;
}

std::string html_report(const ExperimentRun& run, const std::vector<PaperRow>& paper,
                        const QuestionnaireSummary* questionnaire, const GraspPictureInputs* pictures) {
  const PageData d = page_data(run, paper);
  std::string body = "<h1>telegrasp: the paper's grasping experiment (" + esc(run.protocol) + ")</h1>\n";
  body += run_section(run, d);
  body += overall_section(run, d);
  body += fidelity_section(run, d);
  body += force_closure_section(run, d);
  body += grasp_types_section(run, d);
  if (pictures) body += pictures_section(run, d, *pictures);
  body += mode_charts_section(d);
  body += paper_section(paper, d);
  body += paper_correlation_html(paper_correlation_json(run, paper));
  if (questionnaire) body += questionnaire_section(*questionnaire);
  return page("telegrasp experiment report", body);
}

std::string questionnaire_html_report(const QuestionnaireSummary& questionnaire) {
  return page("telegrasp questionnaire",
              "<h1>telegrasp: questionnaire scores</h1>\n" + questionnaire_section(questionnaire));
}

}  // namespace telegrasp::report
