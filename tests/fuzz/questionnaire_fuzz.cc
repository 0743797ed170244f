// Fuzzes the questionnaire answers CSV of telegrasp-eval (client_lib/tools/report/questionnaire.cc):
// score_questionnaire, then its JSON and the printed tables (what telegrasp-eval questionnaire
// writes).
#include "fuzz_common.h"
#include "questionnaire.h"

#include <sstream>
#include <stdexcept>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  std::istringstream in(std::string(reinterpret_cast<const char*>(data), size));
  try {
    const telegrasp::report::QuestionnaireSummary summary = telegrasp::report::score_questionnaire(in, "fuzz.csv");
    (void)telegrasp::report::questionnaire_json(summary).dump();
    std::ostringstream tables;
    telegrasp::report::print_questionnaire(summary, tables);
  } catch (const std::runtime_error&) {
    // No usable header: refused with a message.
  } catch (const nlohmann::json::exception&) {
    // An id or group that is not UTF-8 cannot be written as JSON: telegrasp-eval questionnaire
    // reports it as an error (its main catches std::exception), as here.
  }
  return 0;
}
