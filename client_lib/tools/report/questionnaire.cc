#include "questionnaire.h"

#include "grasp_report.h"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <fstream>
#include <map>
#include <optional>
#include <ostream>
#include <stdexcept>

namespace telegrasp::report {
namespace {

using nlohmann::json;

std::string trim(const std::string& s) {
  const auto first = s.find_first_not_of(" \t\r\n");
  if (first == std::string::npos) return "";
  const auto last = s.find_last_not_of(" \t\r\n");
  return s.substr(first, last - first + 1);
}

std::string lower(std::string s) {
  for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

// Splits one CSV line on commas; a cell may be double-quoted (with "" for a quote), as
// spreadsheets write cells that contain commas.
std::vector<std::string> split_csv_line(const std::string& line) {
  std::vector<std::string> cells;
  std::string cell;
  bool quoted = false;
  for (std::size_t i = 0; i < line.size(); ++i) {
    const char c = line[i];
    if (quoted) {
      if (c == '"' && i + 1 < line.size() && line[i + 1] == '"') {
        cell += '"';
        ++i;
      } else if (c == '"') {
        quoted = false;
      } else {
        cell += c;
      }
    } else if (c == '"') {
      quoted = true;
    } else if (c == ',') {
      cells.push_back(trim(cell));
      cell.clear();
    } else {
      cell += c;
    }
  }
  cells.push_back(trim(cell));
  return cells;
}

ScoreStat stat(const std::vector<double>& v) {
  ScoreStat s;
  s.n = static_cast<int>(v.size());
  if (v.empty()) return {0, NAN, NAN};
  double sum = 0;
  for (double x : v) sum += x;
  s.mean = sum / static_cast<double>(v.size());
  if (v.size() < 2) {
    s.sd = NAN;  // One participant has no spread; not zero.
    return s;
  }
  double sq = 0;
  for (double x : v) sq += (x - s.mean) * (x - s.mean);
  s.sd = std::sqrt(sq / static_cast<double>(v.size() - 1));
  return s;
}

json num(double v) { return std::isfinite(v) ? json(v) : json(nullptr); }

json stat_json(const ScoreStat& s) { return {{"mean", num(s.mean)}, {"sd", num(s.sd)}, {"n", s.n}}; }

json scores_json(const QuestionnaireScores& s) {
  return {{"motor_control", s.motor_control},
          {"finger_movement_realism", s.finger_movement_realism},
          {"interaction_realism", s.interaction_realism},
          {"embodiment", s.embodiment}};
}

// The next line of `in` that is neither blank nor a comment ('#'), split into cells; counts every
// line read in `line_no`. Nothing at the end of `in`.
std::optional<std::vector<std::string>> next_row(std::istream& in, int& line_no) {
  for (std::string line; std::getline(in, line);) {
    ++line_no;
    const std::string t = trim(line);
    if (t.empty() || t[0] == '#') continue;
    return split_csv_line(t);
  }
  return std::nullopt;
}

// Column index of each header name (lower case); other columns (notes, dates) are ignored.
// Throws naming the line when a column appears twice or id, group or one of Q1..Q14 is missing.
std::map<std::string, std::size_t> header_columns(const std::vector<std::string>& header, const std::string& source,
                                                  int line_no) {
  std::vector<std::string> required = {"id", "group"};
  for (int q = 1; q <= kQuestionCount; ++q) required.push_back("Q" + std::to_string(q));
  std::map<std::string, std::size_t> column;  // lower-case name -> index
  for (std::size_t i = 0; i < header.size(); ++i) {
    const std::string name = lower(header[i]);
    if (name.empty()) continue;
    if (column.count(name))
      throw std::runtime_error(source + " line " + std::to_string(line_no) + ": header column '" + header[i] +
                               "' appears twice");
    column[name] = i;
  }
  for (const std::string& name : required)
    if (!column.count(lower(name)))
      throw std::runtime_error(source + " line " + std::to_string(line_no) + ": header has no column '" + name +
                               "' (expected id,group,Q1..Q14 in any order)");
  return column;
}

// Reads the id, group and answers of one data row into `p`; returns what is wrong with the row
// (missing cells, answers that are not integers in -3..3), empty when nothing is.
std::vector<std::string> read_row(const std::vector<std::string>& cells,
                                  const std::map<std::string, std::size_t>& column, QuestionnaireParticipant& p) {
  auto cell = [&](const std::string& name) -> std::string {
    const std::size_t i = column.at(lower(name));
    return i < cells.size() ? cells[i] : std::string();
  };
  p.id = cell("id");
  p.group = cell("group");
  std::vector<std::string> problems;
  if (p.id.empty()) problems.push_back("id is missing");
  if (p.group.empty()) problems.push_back("group is missing");
  for (int q = 1; q <= kQuestionCount; ++q) {
    const std::string name = "Q" + std::to_string(q);
    const std::string v = cell(name);
    if (v.empty()) {
      problems.push_back(name + " is missing");
      continue;
    }
    // Integers only, with an optional sign: "2.5", "2x" or "agree" are not Likert answers.
    int value = 0;
    const char* begin = v.data() + (v[0] == '+' ? 1 : 0);
    const auto [end, ec] = std::from_chars(begin, v.data() + v.size(), value);
    if (ec != std::errc() || end != v.data() + v.size()) {
      problems.push_back(name + " = '" + v + "' is not an integer");
      continue;
    }
    if (value < -3 || value > 3) {
      problems.push_back(name + " = " + v + " is outside -3..3");
      continue;
    }
    p.answers[static_cast<std::size_t>(q - 1)] = value;
  }
  return problems;
}

// A row not scored, its message naming the source, the line, the participant if known and every problem.
RejectedRow rejected_row(const std::string& source, int line_no, const std::string& id,
                         const std::vector<std::string>& problems) {
  std::string message = source + " line " + std::to_string(line_no);
  if (!id.empty()) message += " (participant " + id + ")";
  message += ": ";
  for (std::size_t i = 0; i < problems.size(); ++i) message += (i ? "; " : "") + problems[i];
  return {line_no, id, message};
}

// The mean and sample sd of each score over a group's participants.
QuestionnaireGroup group_stats(const std::string& name, const std::vector<QuestionnaireScores>& scores) {
  QuestionnaireGroup g;
  g.group = name;
  g.n = static_cast<int>(scores.size());
  auto collect = [&](double QuestionnaireScores::*field) {
    std::vector<double> v;
    for (const QuestionnaireScores& s : scores) v.push_back(s.*field);
    return stat(v);
  };
  g.motor_control = collect(&QuestionnaireScores::motor_control);
  g.finger_movement_realism = collect(&QuestionnaireScores::finger_movement_realism);
  g.interaction_realism = collect(&QuestionnaireScores::interaction_realism);
  g.embodiment = collect(&QuestionnaireScores::embodiment);
  return g;
}

}  // namespace

QuestionnaireScores score_answers(const std::array<int, kQuestionCount>& a) {
  // a[i] is Q(i+1). Q3, Q4, Q10 and Q11 are worded negatively, hence subtracted.
  auto q = [&](int n) { return static_cast<double>(a[static_cast<std::size_t>(n - 1)]); };
  QuestionnaireScores s;
  s.motor_control = ((q(1) + q(2)) - (q(3) + q(4))) / 4.0;
  s.finger_movement_realism = (q(5) + q(6) + q(7)) / 3.0;
  s.interaction_realism = ((q(8) + q(9)) - (q(10) + q(11)) + q(12) + q(13) + q(14)) / 7.0;
  s.embodiment = (s.motor_control + s.finger_movement_realism + 2.0 * s.interaction_realism) / 4.0;
  return s;
}

const PaperQuestionnaireRow* paper_questionnaire_row(const std::string& group) {
  for (const PaperQuestionnaireRow& row : kPaperQuestionnaire)
    if (lower(group) == row.group) return &row;
  return nullptr;
}

QuestionnaireSummary score_questionnaire_csv(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error(path + ": cannot open the questionnaire file");
  return score_questionnaire(in, path);
}

QuestionnaireSummary score_questionnaire(std::istream& in, const std::string& source) {
  QuestionnaireSummary out;
  out.source = source;
  int line_no = 0;
  const std::optional<std::vector<std::string>> header = next_row(in, line_no);
  if (!header) throw std::runtime_error(source + ": no header row (expected id,group,Q1..Q14)");
  const std::map<std::string, std::size_t> column = header_columns(*header, source, line_no);

  // Every row scored or rejected, the scores gathered per group in order of first appearance.
  std::map<std::string, int> first_line_of_id;
  std::map<std::string, std::size_t> group_index;
  std::vector<std::vector<QuestionnaireScores>> group_scores;
  while (const std::optional<std::vector<std::string>> cells = next_row(in, line_no)) {
    QuestionnaireParticipant p;
    p.line = line_no;
    std::vector<std::string> problems = read_row(*cells, column, p);
    if (!p.id.empty() && first_line_of_id.count(p.id))
      problems.push_back("duplicate id, first on line " + std::to_string(first_line_of_id[p.id]));
    if (!problems.empty()) {
      out.rejected.push_back(rejected_row(source, line_no, p.id, problems));
      continue;
    }
    first_line_of_id[p.id] = line_no;
    p.scores = score_answers(p.answers);
    auto [it, inserted] = group_index.emplace(p.group, group_scores.size());
    if (inserted) group_scores.emplace_back();
    group_scores[it->second].push_back(p.scores);
    out.participants.push_back(std::move(p));
  }

  out.groups.resize(group_scores.size());
  for (const auto& [name, index] : group_index) out.groups[index] = group_stats(name, group_scores[index]);
  return out;
}

json questionnaire_json(const QuestionnaireSummary& s) {
  json participants = json::array(), groups = json::array(), rejected = json::array();
  for (const QuestionnaireParticipant& p : s.participants) {
    json row = {{"id", p.id}, {"group", p.group}, {"line", p.line}, {"answers", p.answers}};
    row.update(scores_json(p.scores));
    participants.push_back(std::move(row));
  }
  for (const QuestionnaireGroup& g : s.groups) {
    const PaperQuestionnaireRow* paper = paper_questionnaire_row(g.group);
    groups.push_back({{"group", g.group},
                      {"n", g.n},
                      {"motor_control", stat_json(g.motor_control)},
                      {"finger_movement_realism", stat_json(g.finger_movement_realism)},
                      {"interaction_realism", stat_json(g.interaction_realism)},
                      {"embodiment", stat_json(g.embodiment)},
                      {"paper", paper ? scores_json(paper->scores) : json(nullptr)}});
  }
  for (const RejectedRow& r : s.rejected) rejected.push_back({{"line", r.line}, {"id", r.id}, {"message", r.message}});
  return {{"source", s.source}, {"participants", participants}, {"groups", groups}, {"rejected", rejected}};
}

void print_questionnaire(const QuestionnaireSummary& s, std::ostream& out) {
  auto cell = [](const std::string& text, std::size_t width) {
    return text.size() >= width ? text + " " : text + std::string(width - text.size(), ' ');
  };
  std::size_t id_width = 12, group_width = 14;
  for (const QuestionnaireParticipant& p : s.participants) {
    id_width = std::max(id_width, p.id.size() + 2);
    group_width = std::max(group_width, p.group.size() + 2);
  }
  out << "Per participant (" << s.source << ")\n"
      << cell("id", id_width) << cell("group", group_width) << cell("MotorCtl", 10) << cell("FingerMov", 11)
      << cell("Interact", 10) << "Embodiment\n";
  for (const QuestionnaireParticipant& p : s.participants)
    out << cell(p.id, id_width) << cell(p.group, group_width) << cell(fmt(p.scores.motor_control), 10)
        << cell(fmt(p.scores.finger_movement_realism), 11) << cell(fmt(p.scores.interaction_realism), 10)
        << fmt(p.scores.embodiment) << "\n";

  // Group means with sample sd, and the paper's Table 2 value in brackets where the group is one
  // of the paper's.
  auto with_sd = [](const ScoreStat& st) { return fmt(st.mean) + (std::isfinite(st.sd) ? " +- " + fmt(st.sd) : ""); };
  out << "\nPer group: mean +- sd (paper's value in brackets)\n"
      << cell("group", group_width) << cell("n", 4) << cell("MotorCtl", 22) << cell("FingerMov", 22)
      << cell("Interact", 22) << "Embodiment\n";
  for (const QuestionnaireGroup& g : s.groups) {
    const PaperQuestionnaireRow* paper = paper_questionnaire_row(g.group);
    auto paper_value = [&](double QuestionnaireScores::*field) {
      return paper ? " [" + fmt(paper->scores.*field) + "]" : std::string();
    };
    out << cell(g.group, group_width) << cell(std::to_string(g.n), 4)
        << cell(with_sd(g.motor_control) + paper_value(&QuestionnaireScores::motor_control), 22)
        << cell(with_sd(g.finger_movement_realism) + paper_value(&QuestionnaireScores::finger_movement_realism), 22)
        << cell(with_sd(g.interaction_realism) + paper_value(&QuestionnaireScores::interaction_realism), 22)
        << with_sd(g.embodiment) << paper_value(&QuestionnaireScores::embodiment) << "\n";
  }
  out << "Paper (Oprea et al. 2019, Table 2): embodiment 1.97 experienced, 2.19 inexperienced.\n";
  if (!s.rejected.empty()) out << s.rejected.size() << " row(s) rejected and not scored (see stderr).\n";
}

}  // namespace telegrasp::report
