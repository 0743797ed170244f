// telegrasp-replay: re-runs a telegrasp-server recording in-process and reports the first
// divergence, or exports every grasp's contacts as CSV, or the run as an MCAP file with
// telegrasp-view's channels.
#include "replay.h"
#include "replay_export.h"
#include "replay_export_mcap.h"

#include "telegrasp/idl/cli.h"
#include "progress_line.h"

#include <nlohmann/json.hpp>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <string>

namespace {

using namespace telegrasp::server;

constexpr const char* kUsage = R"(Usage: telegrasp-replay FILE [options]

Re-runs a recording made with `telegrasp-server --record FILE`: the scene is rebuilt from the
recording's header (settings, rigs, models) and driven by the recorded inputs, commands and
ticks; every message it publishes is compared, in order, with the recorded one (ServerStatus
is skipped: it holds wall-clock timings). Prints "identical: ..." or the first divergence: the
record, tick, message type, hand or object, and the first differing field.

Options:
  --objects DIR            the mesh folder, if not where the recording says (the meshes are
                           checked against the recorded sizes and hashes)
  --export-contacts CSV    instead of replaying, write every grasp's contacts to CSV, one row
                           per contact (world and object frames, phalanx, ND); needs no meshes
  --export-mcap FILE       instead of replaying, write the run as an MCAP file with the channels
                           of telegrasp-view (/scene, /tf, /grasp_state, /grasp_events,
                           /server_status), for Foxglove or Lichtblick; log time: the recording's
                           start plus the server time of the samples; needs no meshes
  --mcap-rate HZ           with --export-mcap: view updates per second of server time, 1..240
                           (default 30, as telegrasp-view)
  --json FILE              also write the result as JSON
  -h, --help               this text

Exit status (the same meanings in every telegrasp tool):
  0  identical (or exported)
  1  a runtime failure: the recording's header cannot be read, the scene rebuilt or an output
     file written
  2  a usage error (a bad or missing option or value)
  3  the recording is truncated or corrupt: everything before the damage was replayed
     (exported) and reported
  6  the replay diverges from the recording
)";

[[noreturn]] void usage_error(const std::string& what) { telegrasp::cli::usage_exit("telegrasp-replay", what); }

// Progress on stderr for files big enough to take a while.
class Progress {
 public:
  void operator()(const RecordingReader& r) {
    if (r.file_size() < (8u << 20)) return;
    const bool last = r.offset() >= r.file_size() || r.damage() || r.complete();
    if (!last && !line_.due()) return;
    char text[96];
    std::snprintf(text, sizeof text, "telegrasp-replay: %3.0f%% (%llu records)",
                  100.0 * static_cast<double>(r.offset()) / static_cast<double>(r.file_size()),
                  static_cast<unsigned long long>(r.records()));
    if (last)
      line_.finish(text);
    else
      line_.show(text);
  }

 private:
  telegrasp::tools::ProgressLine line_;
};

nlohmann::json damage_json(const std::optional<RecordingDamage>& d) {
  if (!d) return nullptr;
  return {{"record", d->record}, {"byte", d->byte}, {"truncated", d->truncated}, {"message", d->message}};
}

void write_json(const std::string& path, const nlohmann::json& j) {
  std::ofstream out(path);
  out << j.dump(2) << "\n";
  if (!out) {
    std::cerr << "telegrasp-replay: " << path << ": cannot write the JSON result\n";
    std::exit(telegrasp::cli::kExitFailure);
  }
}

struct Args {
  std::string recording, objects_dir, csv_path, mcap_path, json_path;
  McapExportOptions mcap_options;
};

Args parse(int argc, char** argv) {
  Args o;
  bool mcap_rate_given = false;
  telegrasp::cli::for_each_option(argc, argv, kUsage, usage_error, [&](const std::string& a, const auto& value) {
    if (telegrasp::cli::text_flag(a, value,
                                  {{"--objects", &o.objects_dir},
                                   {"--export-contacts", &o.csv_path},
                                   {"--export-mcap", &o.mcap_path},
                                   {"--json", &o.json_path}}))
      ;
    else if (a == "--mcap-rate") {
      o.mcap_options.rate_hz = telegrasp::cli::parse_number(a, value(), 1, 240, usage_error);
      mcap_rate_given = true;
    } else if (telegrasp::cli::is_option(a))
      return false;
    else if (o.recording.empty())
      o.recording = a;
    else
      usage_error("one recording at a time (got '" + o.recording + "' and '" + a + "')");
    return true;
  });
  if (o.recording.empty()) usage_error("no recording given");
  if (!o.csv_path.empty() && !o.mcap_path.empty())
    usage_error("--export-contacts and --export-mcap: one export at a time");
  if (mcap_rate_given && o.mcap_path.empty()) usage_error("--mcap-rate goes with --export-mcap");
  return o;
}

// The end of an export: the damage said, the result (`j`, with the recording, the damage and the
// exit status) written to --json, and that exit status returned.
int finish_export(const Args& o, nlohmann::json j, const std::optional<RecordingDamage>& damage) {
  const int status = damage ? telegrasp::cli::kExitDamaged : 0;
  if (damage) std::cout << damage->message << "\n";
  if (!o.json_path.empty()) {
    j["recording"] = o.recording;
    j["damage"] = damage_json(damage);
    j["exit_code"] = status;
    write_json(o.json_path, j);
  }
  return status;
}

int export_contacts(const Args& o) {
  const ContactExport e = export_contacts_csv(o.recording, o.csv_path);
  std::cout << "exported " << e.rows << " contacts of " << e.events << " grasps to " << o.csv_path << "\n";
  return finish_export(o, {{"csv", o.csv_path}, {"grasps", e.events}, {"contacts", e.rows}}, e.damage);
}

int export_mcap_file(const Args& o) {
  const McapExport e = export_mcap(o.recording, o.mcap_path, o.mcap_options);
  const double seconds = static_cast<double>(e.end_time_ns - e.start_time_ns) * 1e-9;
  std::cout << "exported " << e.outputs << " outputs as " << e.messages << " messages (" << e.steps << " view updates, "
            << telegrasp::cli::format_number(std::round(seconds * 10) / 10) << " s, "
            << telegrasp::cli::format_number(std::round(static_cast<double>(e.bytes) / 1024.0)) << " KiB) to "
            << o.mcap_path << "\n";
  return finish_export(o,
                       {{"mcap", o.mcap_path},
                        {"outputs", e.outputs},
                        {"view_updates", e.steps},
                        {"messages", e.messages},
                        {"bytes", e.bytes},
                        {"start_time_ns", e.start_time_ns},
                        {"end_time_ns", e.end_time_ns}},
                       e.damage);
}

int replay(const Args& o) {
  Progress progress;
  ReplayOptions options;
  options.objects_dir = o.objects_dir;
  options.progress = [&](const RecordingReader& r) { progress(r); };
  const ReplayResult r = replay_recording(o.recording, options);
  std::cout << r.summary();
  if (!o.json_path.empty()) {
    nlohmann::json d = nullptr;
    if (r.divergence)
      d = {{"record", r.divergence->record}, {"tick", r.divergence->tick},   {"type", r.divergence->type},
           {"key", r.divergence->key},       {"field", r.divergence->field}, {"message", r.divergence->message}};
    write_json(o.json_path, {{"recording", o.recording},
                             {"identical", !r.divergence},
                             {"records", r.records},
                             {"ticks", r.ticks},
                             {"outputs_compared", r.outputs_compared},
                             {"statuses_skipped", r.statuses_skipped},
                             {"divergence", d},
                             {"damage", damage_json(r.damage)},
                             {"warnings", r.warnings},
                             {"exit_code", r.exit_code()}});
  }
  return r.exit_code();
}

}  // namespace

int main(int argc, char** argv) {
  const Args args = parse(argc, argv);
  try {
    if (!args.csv_path.empty()) return export_contacts(args);
    if (!args.mcap_path.empty()) return export_mcap_file(args);
    return replay(args);
  } catch (const std::exception& e) {  // RecordingError: the header, the assets, the CSV or MCAP file
    std::cerr << "telegrasp-replay: " << e.what() << "\n";
    return telegrasp::cli::kExitFailure;
  }
}
