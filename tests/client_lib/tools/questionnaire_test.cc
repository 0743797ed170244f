// Tests questionnaire.h: the paper's scoring formulas against hand-computed answers (including the
// reversed items Q3, Q4, Q10, Q11), group statistics, and which rows and headers are rejected.
#include "questionnaire.h"

#include <gtest/gtest.h>

#include <cmath>
#include <sstream>
#include <stdexcept>
#include <string>

namespace telegrasp::report {
namespace {

constexpr double kTol = 1e-12;  // the scores are a few exact divisions

using Answers = std::array<int, kQuestionCount>;

// "id,group,Q1,...,Q14"
std::string header() {
  std::string h = "id,group";
  for (int q = 1; q <= kQuestionCount; ++q) h += ",Q" + std::to_string(q);
  return h + "\n";
}

std::string row(const std::string& id, const std::string& group, const Answers& a) {
  std::string r = id + "," + group;
  for (int v : a) r += "," + std::to_string(v);
  return r + "\n";
}

// Every answer +3: the reversed items cancel their positive partners.
//   MC  = ((3 + 3) - (3 + 3)) / 4           = 0
//   FMR = (3 + 3 + 3) / 3                   = 3
//   IR  = ((3 + 3) - (3 + 3) + 3 + 3 + 3)/7 = 9/7
//   E   = (0 + 3 + 2 * 9/7) / 4 = (21/7 + 18/7) / 4 = 39/28
const Answers kAllThree = {3, 3, 3, 3, 3, 3, 3, 3, 3, 3, 3, 3, 3, 3};

// The ideal respondent agrees fully with the positive items and disagrees fully with the reversed
// ones (Q3, Q4, Q10, Q11 = -3): every aspect reaches the maximum.
//   MC  = ((3 + 3) - (-3 - 3)) / 4              = 12/4 = 3
//   FMR = 9/3                                    = 3
//   IR  = ((3 + 3) - (-3 - 3) + 3 + 3 + 3) / 7   = 21/7 = 3
//   E   = (3 + 3 + 2 * 3) / 4                    = 3
const Answers kIdeal = {3, 3, -3, -3, 3, 3, 3, 3, 3, -3, -3, 3, 3, 3};

// Mixed answers Q1..Q14 = 1, 2, -1, 0 | 2, 3, 1 | 0, 1, -2, -1, 2, 1, 3:
//   MC  = ((1 + 2) - (-1 + 0)) / 4                = 4/4 = 1
//   FMR = (2 + 3 + 1) / 3                         = 2
//   IR  = ((0 + 1) - (-2 - 1) + 2 + 1 + 3) / 7    = (1 + 3 + 6)/7 = 10/7
//   E   = (1 + 2 + 2 * 10/7) / 4 = (21/7 + 20/7) / 4 = 41/28
const Answers kMixed = {1, 2, -1, 0, 2, 3, 1, 0, 1, -2, -1, 2, 1, 3};

// Expects the four aspect scores of `answers`.
void expect_scores(const Answers& answers, double motor_control, double finger_movement_realism,
                   double interaction_realism, double embodiment) {
  const QuestionnaireScores s = score_answers(answers);
  EXPECT_NEAR(s.motor_control, motor_control, kTol);
  EXPECT_NEAR(s.finger_movement_realism, finger_movement_realism, kTol);
  EXPECT_NEAR(s.interaction_realism, interaction_realism, kTol);
  EXPECT_NEAR(s.embodiment, embodiment, kTol);
}

TEST(QuestionnaireScoreTest, AllThreeCancelsTheReversedItems) {
  expect_scores(kAllThree, 0.0, 3.0, 9.0 / 7.0, 39.0 / 28.0);
}

TEST(QuestionnaireScoreTest, IdealRespondentScoresThreeEverywhere) { expect_scores(kIdeal, 3.0, 3.0, 3.0, 3.0); }

TEST(QuestionnaireScoreTest, MixedAnswers) { expect_scores(kMixed, 1.0, 2.0, 10.0 / 7.0, 41.0 / 28.0); }

TEST(QuestionnaireScoreTest, EachReversedItemLowersItsAspect) {
  // From all zeros, +1 on a reversed item lowers its aspect by 1/4 (MC) or 1/7 (IR), and the
  // embodiment by 1/16 or 2/28.
  for (int q : {3, 4}) {
    Answers a{};
    a[static_cast<std::size_t>(q - 1)] = 1;
    EXPECT_NEAR(score_answers(a).motor_control, -0.25, kTol) << "Q" << q;
    EXPECT_NEAR(score_answers(a).embodiment, -0.25 / 4, kTol) << "Q" << q;
  }
  for (int q : {10, 11}) {
    Answers a{};
    a[static_cast<std::size_t>(q - 1)] = 1;
    EXPECT_NEAR(score_answers(a).interaction_realism, -1.0 / 7.0, kTol) << "Q" << q;
    EXPECT_NEAR(score_answers(a).embodiment, -2.0 / 28.0, kTol) << "Q" << q;
  }
}

TEST(QuestionnaireParseTest, ScoresParticipantsAndGroups) {
  std::istringstream in(header() + row("p1", "experienced", kAllThree) + row("p2", "inexperienced", kIdeal) +
                        row("p3", "experienced", kMixed));
  const QuestionnaireSummary s = score_questionnaire(in, "answers.csv");
  EXPECT_TRUE(s.rejected.empty());
  ASSERT_EQ(s.participants.size(), 3u);
  EXPECT_EQ(s.participants[0].id, "p1");
  EXPECT_EQ(s.participants[0].line, 2);
  EXPECT_NEAR(s.participants[2].scores.embodiment, 41.0 / 28.0, kTol);

  // Groups in order of first appearance.
  ASSERT_EQ(s.groups.size(), 2u);
  const QuestionnaireGroup& exp = s.groups[0];
  EXPECT_EQ(exp.group, "experienced");
  EXPECT_EQ(exp.n, 2);
  // MC: mean of 0 and 1 = 0.5; sample sd of two values = |a - b| / sqrt(2).
  EXPECT_NEAR(exp.motor_control.mean, 0.5, kTol);
  EXPECT_NEAR(exp.motor_control.sd, 1.0 / std::sqrt(2.0), kTol);
  // E: (39/28 + 41/28) / 2 = 40/28 = 10/7; sd = (2/28) / sqrt(2).
  EXPECT_NEAR(exp.embodiment.mean, 10.0 / 7.0, kTol);
  EXPECT_NEAR(exp.embodiment.sd, (2.0 / 28.0) / std::sqrt(2.0), kTol);
  EXPECT_NEAR(exp.interaction_realism.mean, (9.0 / 7.0 + 10.0 / 7.0) / 2, kTol);
  EXPECT_NEAR(exp.finger_movement_realism.mean, 2.5, kTol);

  // One participant: the mean is the score and the spread undefined (not zero).
  const QuestionnaireGroup& inexp = s.groups[1];
  EXPECT_EQ(inexp.n, 1);
  EXPECT_NEAR(inexp.embodiment.mean, 3.0, kTol);
  EXPECT_TRUE(std::isnan(inexp.embodiment.sd));

  // JSON: NaN as null, and the paper's Table 2 row beside the paper's groups.
  const nlohmann::json j = questionnaire_json(s);
  EXPECT_TRUE(j["groups"][1]["embodiment"]["sd"].is_null());
  EXPECT_DOUBLE_EQ(j["groups"][0]["paper"]["embodiment"].get<double>(), 1.97);
  EXPECT_DOUBLE_EQ(j["groups"][1]["paper"]["embodiment"].get<double>(), 2.19);
  EXPECT_EQ(j["participants"].size(), 3u);
}

TEST(QuestionnaireParseTest, ColumnsInAnyOrderCommentsAndBlankLines) {
  // Header reversed, an extra column, quotes, a leading "+" sign, CRLF line ends.
  std::string h = "notes";
  for (int q = kQuestionCount; q >= 1; --q) h += ",q" + std::to_string(q);
  h += ",Group,ID\r\n";
  std::string r = "\"late, tired\"";
  for (int q = kQuestionCount; q >= 1; --q)
    r += "," + (kMixed[static_cast<std::size_t>(q - 1)] > 0 ? std::string("+") : "") +
         std::to_string(kMixed[static_cast<std::size_t>(q - 1)]);
  r += ",experienced,p9\r\n";
  std::istringstream in("# answers of the pilot\n\n" + h + "\n# first participant\n" + r);
  const QuestionnaireSummary s = score_questionnaire(in, "pilot.csv");
  ASSERT_TRUE(s.rejected.empty()) << s.rejected[0].message;
  ASSERT_EQ(s.participants.size(), 1u);
  EXPECT_EQ(s.participants[0].id, "p9");
  EXPECT_EQ(s.participants[0].line, 6);
  EXPECT_EQ(s.participants[0].answers, kMixed);
  EXPECT_NEAR(s.participants[0].scores.embodiment, 41.0 / 28.0, kTol);
}

TEST(QuestionnaireParseTest, RejectsBadRowsNamingLineAndColumnAndScoresTheRest) {
  Answers q7_out = kAllThree;
  q7_out[6] = 4;
  std::string q2_missing = row("p4", "experienced", kAllThree);
  q2_missing.replace(q2_missing.find(",3,3"), 4, ",3,");  // Q1 stays 3, Q2 becomes empty
  std::string q9_fraction = row("p5", "inexperienced", kMixed);
  q9_fraction.replace(q9_fraction.find(",0,1,-2"), 7, ",0,2.5,-2");  // Q8 = 0, Q9 = 2.5
  std::string short_row = "p6,experienced,1,1,1,1,1,1,1,1,1,1\n";  // Q11..Q14 absent
  std::string no_group = row("p7", "", kMixed);
  std::string answer_word = row("p8", "experienced", kMixed);
  answer_word.replace(answer_word.rfind(",3"), 2, ",agree");  // Q14

  std::istringstream in(header() +  // line 1
                        row("p1", "experienced", kAllThree) +  // line 2: valid
                        "\n" +  // line 3: skipped
                        "# a comment\n" +  // line 4: skipped
                        row("p3", "experienced", q7_out) +  // line 5
                        q2_missing +  // line 6
                        q9_fraction +  // line 7
                        row("p1", "inexperienced", kIdeal) +  // line 8: duplicate id
                        short_row +  // line 9
                        no_group +  // line 10
                        answer_word +  // line 11
                        row("p2", "inexperienced", kIdeal));  // line 12: valid
  const QuestionnaireSummary s = score_questionnaire(in, "answers.csv");

  ASSERT_EQ(s.participants.size(), 2u);
  EXPECT_EQ(s.participants[0].id, "p1");
  EXPECT_EQ(s.participants[1].id, "p2");
  ASSERT_EQ(s.rejected.size(), 7u);
  EXPECT_EQ(s.rejected[0].message, "answers.csv line 5 (participant p3): Q7 = 4 is outside -3..3");
  EXPECT_EQ(s.rejected[0].line, 5);
  EXPECT_EQ(s.rejected[1].message, "answers.csv line 6 (participant p4): Q2 is missing");
  EXPECT_EQ(s.rejected[2].message, "answers.csv line 7 (participant p5): Q9 = '2.5' is not an integer");
  EXPECT_EQ(s.rejected[3].message, "answers.csv line 8 (participant p1): duplicate id, first on line 2");
  EXPECT_EQ(s.rejected[4].message,
            "answers.csv line 9 (participant p6): Q11 is missing; Q12 is missing; Q13 is missing; Q14 is missing");
  EXPECT_EQ(s.rejected[5].message, "answers.csv line 10 (participant p7): group is missing");
  EXPECT_EQ(s.rejected[6].message, "answers.csv line 11 (participant p8): Q14 = 'agree' is not an integer");

  // The groups are built from the valid rows only.
  ASSERT_EQ(s.groups.size(), 2u);
  EXPECT_EQ(s.groups[0].n, 1);
  EXPECT_NEAR(s.groups[0].embodiment.mean, 39.0 / 28.0, kTol);
  EXPECT_EQ(s.groups[1].n, 1);
}

TEST(QuestionnaireParseTest, MissingHeaderColumnIsFatalAndNamed) {
  std::string h = header();
  h.replace(h.find(",Q12"), 4, "");
  std::istringstream in("# comment first\n" + h + row("p1", "experienced", kAllThree));
  try {
    score_questionnaire(in, "answers.csv");
    FAIL() << "expected an error for the missing Q12 column";
  } catch (const std::runtime_error& e) {
    EXPECT_EQ(std::string(e.what()),
              "answers.csv line 2: header has no column 'Q12' (expected id,group,Q1..Q14 in any order)");
  }
}

TEST(QuestionnaireParseTest, RepeatedHeaderColumnAndEmptyFileAreFatal) {
  std::istringstream repeated(header().substr(0, header().size() - 1) + ",Q3\n");
  EXPECT_THROW(score_questionnaire(repeated, "a.csv"), std::runtime_error);
  std::istringstream empty("\n# nothing\n");
  EXPECT_THROW(score_questionnaire(empty, "a.csv"), std::runtime_error);
  EXPECT_THROW(score_questionnaire_csv("/nonexistent/answers.csv"), std::runtime_error);
}

TEST(QuestionnaireParseTest, PrintedTableShowsThePapersValues) {
  std::istringstream in(header() + row("p1", "experienced", kAllThree) + row("p2", "inexperienced", kIdeal));
  std::ostringstream out;
  print_questionnaire(score_questionnaire(in, "answers.csv"), out);
  EXPECT_NE(out.str().find("[1.97]"), std::string::npos) << out.str();
  EXPECT_NE(out.str().find("[2.19]"), std::string::npos) << out.str();
  EXPECT_NE(out.str().find("1.39"), std::string::npos) << out.str();  // 39/28 = 1.392...
}

}  // namespace
}  // namespace telegrasp::report
