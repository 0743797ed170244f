// telegrasp-eval <subcommand>: grasp evaluation. In-process runs, the oracle ND bound, the
// questionnaire's scoring, the paper's protocol over DDS and its participant processes; see
// commands.h.
#include "telegrasp/idl/cli.h"
#include "commands.h"

#include <cstring>
#include <iostream>
#include <string>

namespace {

constexpr const char* kUsage = R"(Usage: telegrasp-eval <subcommand> [options]

Grasp evaluation: scripted operators grasp objects with the telegrasp hand, and reports tell
how fast, how often and how exactly.

Subcommands (each has its own --help):
  run             scripted grasps in-process, no network: per-object success, time to grasp
                  and the paper's ND error metric
  protocol        the paper's 30-object experiment through telegrasp-server over DDS, with
                  CSV, JSON and HTML reports
  nd-bound        the lowest ND an oracle pose search finds for the rig on each object
  questionnaire   scores the paper's questionnaire from a CSV of answers
  participant     one participant process of a protocol run (started by `protocol`)

Exit status: 0 success, 1 a runtime failure (a missing file or folder, no server found, an I/O
error), 2 a usage error (a bad or missing option or value); each subcommand's --help says more.
)";

using Command = int (*)(int, char**);

struct Subcommand {
  const char* name;
  Command run;
};

constexpr Subcommand kSubcommands[] = {
    {"run", telegrasp::eval::run_in_process},          {"protocol", telegrasp::eval::run_protocol},
    {"nd-bound", telegrasp::eval::run_nd_bound},       {"questionnaire", telegrasp::eval::run_questionnaire},
    {"participant", telegrasp::eval::run_participant},
};

}  // namespace

int main(int argc, char** argv) {
  if (argc > 1 && (std::strcmp(argv[1], "-h") == 0 || std::strcmp(argv[1], "--help") == 0)) {
    std::cout << kUsage;
    return 0;
  }
  if (argc > 1)
    for (const Subcommand& s : kSubcommands)
      if (std::strcmp(argv[1], s.name) == 0) return s.run(argc - 1, argv + 1);
  // The spellings of the previous release: no subcommand runs in-process, and --protocol
  // anywhere runs the protocol. Kept for one release.
  for (int i = 1; i < argc; ++i)
    if (std::strcmp(argv[i], "--protocol") == 0) {
      std::cerr << "telegrasp-eval: deprecated: use `telegrasp-eval protocol [options]`\n";
      return telegrasp::eval::run_protocol(argc, argv);
    }
  if (argc > 1 && argv[1][0] != '-')
    telegrasp::cli::usage_exit("telegrasp-eval", std::string("unknown subcommand '") + argv[1] + "'");
  std::cerr << "telegrasp-eval: deprecated: use `telegrasp-eval run [options]`\n";
  return telegrasp::eval::run_in_process(argc, argv);
}
