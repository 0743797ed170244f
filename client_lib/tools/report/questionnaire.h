// The paper's questionnaire (Oprea et al. 2019, Table 1; sim/README.md, section 10):
// 14 answers on a 7-point Likert scale (-3..3) per participant, scored into Motor Control, Finger
// Movement Realism, Interaction Realism and the Embodiment score, per participant and per group.
#pragma once

#include <nlohmann/json.hpp>

#include <array>
#include <iosfwd>
#include <string>
#include <vector>

namespace telegrasp::report {

/// Number of questions; answers[0] is Q1.
inline constexpr int kQuestionCount = 14;

/// The four scores of one participant, each in -3..3.
struct QuestionnaireScores {
  double motor_control = 0;  ///< ((Q1 + Q2) - (Q3 + Q4)) / 4; Q3, Q4 reversed.
  double finger_movement_realism = 0;  ///< (Q5 + Q6 + Q7) / 3.
  double interaction_realism = 0;  ///< ((Q8 + Q9) - (Q10 + Q11) + Q12 + Q13 + Q14) / 7; Q10, Q11 reversed.
  double embodiment = 0;  ///< (MC + FMR + 2 * IR) / 4.
};

/// Scores one participant's answers (answers[i] is Q(i+1), each -3..3; not checked here).
QuestionnaireScores score_answers(const std::array<int, kQuestionCount>& answers);

/// One valid row of the answers file.
struct QuestionnaireParticipant {
  std::string id, group;
  int line = 0;  ///< 1-based line in the file.
  std::array<int, kQuestionCount> answers{};
  QuestionnaireScores scores;
};

/// Mean, sample standard deviation (n - 1; NaN for n < 2) and count.
struct ScoreStat {
  int n = 0;
  double mean = 0, sd = 0;
};

/// The scores of one group over its valid participants.
struct QuestionnaireGroup {
  std::string group;
  int n = 0;
  ScoreStat motor_control, finger_movement_realism, interaction_realism, embodiment;
};

/// A row that was not scored, with the message naming file, line, participant and column.
struct RejectedRow {
  int line = 0;
  std::string id;  ///< "" when the id itself is missing.
  std::string message;  ///< e.g. "answers.csv line 5 (participant p3): Q7 = 4 is outside -3..3".
};

/// Everything read from one answers file.
struct QuestionnaireSummary {
  std::string source;  ///< The file name as given.
  std::vector<QuestionnaireParticipant> participants;  ///< Valid rows, in file order.
  std::vector<QuestionnaireGroup> groups;  ///< In order of first appearance.
  std::vector<RejectedRow> rejected;  ///< In file order.
};

/// The paper's Table 2 (average score per aspect and group), for comparison.
struct PaperQuestionnaireRow {
  const char* group;
  QuestionnaireScores scores;
};
inline constexpr PaperQuestionnaireRow kPaperQuestionnaire[] = {
    {"experienced", {1.85, 2.33, 1.84, 1.97}},
    {"inexperienced", {2.34, 2.51, 1.95, 2.19}},
};
/// The paper's row for `group` (case-insensitive), or nullptr.
const PaperQuestionnaireRow* paper_questionnaire_row(const std::string& group);

/// Reads and scores a CSV with a header row naming id, group and Q1..Q14 in any order (names
/// case-insensitive; other columns ignored). Blank lines and lines starting with '#' are skipped.
/// Rows with a missing, non-integer or out-of-range answer, a missing id or group, or a duplicate
/// id are rejected (listed in `rejected`) and the others scored. Throws std::runtime_error naming
/// the file when it cannot be used at all: unreadable, no header, a header column missing or
/// repeated.
QuestionnaireSummary score_questionnaire_csv(const std::string& path);
/// As above from a stream; `source` names it in messages.
QuestionnaireSummary score_questionnaire(std::istream& in, const std::string& source);

/// {"source","participants":[{"id","group","line","answers":[..14],"motor_control",...}],
///  "groups":[{"group","n","motor_control":{"mean","sd","n"},...,"paper":{...}|null}],
///  "rejected":[{"line","id","message"}]}; NaN is written as null.
nlohmann::json questionnaire_json(const QuestionnaireSummary& summary);

/// Prints the per-participant and per-group tables, the group rows beside the paper's values.
void print_questionnaire(const QuestionnaireSummary& summary, std::ostream& out);

}  // namespace telegrasp::report
