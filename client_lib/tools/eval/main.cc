// telegrasp-eval: grasp evaluation. In-process runs, the paper's protocol over DDS, and the
// questionnaire's scoring; see commands.h.
#include "commands.h"

#include <string>

int main(int argc, char** argv) {
  using namespace telegrasp::eval;
  if (argc > 1 && std::string(argv[1]) == "questionnaire") return run_questionnaire(argc - 1, argv + 1);
  if (argc > 1 && std::string(argv[1]) == "nd-bound") return run_nd_bound(argc - 1, argv + 1);
  if (argc > 1 && std::string(argv[1]) == "participant") return run_participant(argc - 1, argv + 1);
  for (int i = 1; i < argc; ++i)
    if (std::string(argv[i]) == "--protocol") return run_protocol(argc, argv);
  return run_in_process(argc, argv);
}
