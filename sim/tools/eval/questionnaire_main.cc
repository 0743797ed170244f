// telegrasp-eval questionnaire FILE.csv: scores the paper's questionnaire
// (../shared/docs/GRASPING.md section 6) per participant and per group, beside the paper's Table 2.
#include "offline_commands.h"

#include "cli.h"
#include "experiment_report.h"
#include "questionnaire.h"

#include <cstdlib>
#include <exception>
#include <iostream>
#include <string>

namespace {

const char* kUsage =
    "usage: telegrasp-eval questionnaire FILE.csv [--json FILE] [--report FILE.html] [-h]\n"
    "\n"
    "FILE.csv: a header row naming id, group and Q1..Q14 (any order; other columns ignored), then one\n"
    "row per participant with integer answers -3..3. Blank lines and lines starting with # are skipped.\n"
    "Prints Motor Control, Finger Movement Realism, Interaction Realism and Embodiment per participant\n"
    "and per group (mean +- sample sd) beside the paper's values (embodiment 1.97 experienced, 2.19\n"
    "inexperienced). Rejected rows go to stderr with the line and column.\n"
    "  --json FILE         write the scores as JSON\n"
    "  --report FILE.html  write a self-contained HTML page with the scores\n"
    "Exit status: 0 all rows valid, 1 some rows rejected (the rest scored), 2 unusable input.\n";

}  // namespace

int telegrasp::eval::run_questionnaire(int argc, char** argv) {
  namespace report = telegrasp::report;
  std::string input, json_path, report_path;
  auto usage_error = [](const std::string& what) {
    std::cerr << "telegrasp-eval questionnaire: " << what << "\n(see telegrasp-eval questionnaire --help)\n";
    std::exit(2);
  };
  telegrasp::cli::for_each_option(argc, argv, kUsage, usage_error, [&](const std::string& a, const auto& value) {
    if (a == "--json") json_path = value();
    else if (a == "--report") report_path = value();
    else if (a.empty() || a[0] == '-') return false;
    else if (input.empty()) input = a;
    else usage_error("one answers file only (got " + input + " and " + a + ")");
    return true;
  });
  if (input.empty()) {
    std::cerr << "telegrasp-eval questionnaire: no answers file given\n" << kUsage;
    return 2;
  }

  report::QuestionnaireSummary summary;
  try {
    summary = report::score_questionnaire_csv(input);
  } catch (const std::exception& e) {
    std::cerr << "telegrasp-eval questionnaire: " << e.what() << "\n";
    return 2;
  }
  for (const report::RejectedRow& r : summary.rejected) std::cerr << "rejected: " << r.message << "\n";
  if (summary.participants.empty()) {
    std::cerr << "telegrasp-eval questionnaire: " << input << ": no valid participant rows to score\n";
    return 2;
  }
  report::print_questionnaire(summary, std::cout);

  try {
    if (!json_path.empty()) report::write_text_file(json_path, report::questionnaire_json(summary).dump(2) + "\n");
    if (!report_path.empty()) report::write_text_file(report_path, report::questionnaire_html_report(summary));
  } catch (const std::exception& e) {
    std::cerr << "telegrasp-eval questionnaire: " << e.what() << "\n";
    return 2;
  }
  return summary.rejected.empty() ? 0 : 1;
}
