// telegrasp-eval questionnaire FILE.csv: scores the paper's questionnaire
// (sim/README.md, section 10 The evaluation protocol) per participant and per group, beside the paper's Table 2.
#include "commands.h"

#include "telegrasp/idl/cli.h"
#include "experiment_report.h"
#include "questionnaire.h"

#include <cstdlib>
#include <exception>
#include <iostream>
#include <string>

namespace {

constexpr const char* kTool = "telegrasp-eval questionnaire";

constexpr const char* kUsage = R"(Usage: telegrasp-eval questionnaire FILE.csv [options]

FILE.csv: a header row naming id, group and Q1..Q14 (any order; other columns ignored), then one
row per participant with integer answers -3..3. Blank lines and lines starting with # are skipped.
Prints Motor Control, Finger Movement Realism, Interaction Realism and Embodiment per participant
and per group (mean +- sample sd) beside the paper's values (embodiment 1.97 experienced, 2.19
inexperienced). Rejected rows go to stderr with the line and column.

Options:
  --json FILE         write the scores as JSON
  --report FILE.html  write a self-contained HTML page with the scores
  -h, --help          this text

Exit status: 0 every row scored, 1 a runtime failure (FILE.csv missing, unreadable or with no
valid row, an output not writable), 2 a usage error (a bad or missing option or value), 3 some
rows rejected (the rest scored and written).
)";

[[noreturn]] void usage_error(const std::string& what) { telegrasp::cli::usage_exit(kTool, what); }

// Some rows were rejected, the others scored: a result, but not a clean one.
constexpr int kExitRowsRejected = 3;

}  // namespace

int telegrasp::eval::run_questionnaire(int argc, char** argv) {
  namespace report = telegrasp::report;
  namespace cli = telegrasp::cli;
  std::string input, json_path, report_path;
  cli::for_each_option(argc, argv, kUsage, usage_error, [&](const std::string& a, const auto& value) {
    if (cli::text_flag(a, value, {{"--json", &json_path}, {"--report", &report_path}}))
      ;
    else if (cli::is_option(a))
      return false;
    else if (input.empty())
      input = a;
    else
      usage_error("one answers file only (got '" + input + "' and '" + a + "')");
    return true;
  });
  if (input.empty()) usage_error("no answers file given");

  report::QuestionnaireSummary summary;
  try {
    summary = report::score_questionnaire_csv(input);
  } catch (const std::exception& e) {
    std::cerr << kTool << ": " << e.what() << "\n";
    return cli::kExitFailure;
  }
  for (const report::RejectedRow& r : summary.rejected) std::cerr << "rejected: " << r.message << "\n";
  if (summary.participants.empty()) {
    std::cerr << kTool << ": " << input << ": no valid participant rows to score\n";
    return cli::kExitFailure;
  }
  report::print_questionnaire(summary, std::cout);

  try {
    if (!json_path.empty()) report::write_text_file(json_path, report::questionnaire_json(summary).dump(2) + "\n");
    if (!report_path.empty()) report::write_text_file(report_path, report::questionnaire_html_report(summary));
  } catch (const std::exception& e) {
    std::cerr << kTool << ": " << e.what() << "\n";
    return cli::kExitFailure;
  }
  return summary.rejected.empty() ? 0 : kExitRowsRejected;
}
