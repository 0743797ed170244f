// telegrasp-eval protocol: the paper's experiment through the server over DDS. Every
// (mode, participant) pair is a job: a telegrasp-server in lockstep on its own DDS domain and a
// participant process (participant.cc) driving it. Jobs run in parallel, as many as --jobs.
// Records come from the GraspEvent topic, via the participants.
#include "child_process.h"
#include "eval_inputs.h"
#include "telegrasp/idl/cli.h"
#include "commands.h"
#include "experiment_report.h"
#include "progress_line.h"
#include "grasp_report.h"
#include "paper_correlation.h"
#include "protocol_common.h"
#include "protocol_in_process.h"
#include "questionnaire.h"
#include "telegrasp/idl/network_flags.h"
#include "telegrasp/sim/hand_controller.h"
#include "telegrasp/sim/hand_rig.h"
#include "telegrasp/sim/standin_objects.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <memory>
#include <optional>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include <poll.h>
#include <unistd.h>

namespace telegrasp::eval {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using Clock = std::chrono::steady_clock;

constexpr const char* kUsage = R"(Usage: telegrasp-eval protocol [options]

Runs the paper's experiment (sim/README.md, section 10) through telegrasp servers over DDS: the 30
protocol objects are spawned one at a time with SceneCommand, in the paper's order, resting at a
random place and yaw in a bounded area in front of the operator (x 0.40..0.55 m, y -0.10..0.10 m);
a bot participant reacts, reaches, grasps, lifts 10 cm, holds 1 s and releases each. Each grasp's
time from spawn to grasp, per-capsule ND, HandError, exact signed distances and contacts come
from the server's GraspEvent topic.

Operators: the group's skill profile, fitted to the paper's mean times (README, "Calibration"):
reaction 0.22 / 0.28 s (experienced / inexperienced), Fitts's-law reach (a 0.05 s, b 0.0643 /
0.0325 s/bit) with a stand-off and an extra 1 s per m growing with the object's size, a
corrective submovement to within 4 mm (less on thin objects), practice slowing the first grasps
(gain 0.1 / 2.0), squeeze 0.30 / 0.40 s, pose error 4 mm / 3 deg and 8 mm / 6 deg; scaled per
participant by a speed factor ~ lognormal(0, 0.15) (reach speed x; reaction, squeeze and reach
times /) and a precision factor ~ lognormal(0, 0.2) (pose errors x), drawn from the seed: a
participant is the same person, and sees the same placements, in every mode.

Each (mode, participant) runs on its own server, in lockstep: the server ticks as soon as the
participant has answered the last tick, so runs go faster than real time and the physics and
metrics are the same however many run in parallel and however loaded the machine is: the same
seed gives the same records.

Options:
  --protocol paper       the protocol (only "paper", the default)
  --participants N|E,I   participants per group, or experienced,inexperienced (default 4,6 as
                         in the paper)
  --objects DIR          meshes of the protocol objects (file stem = YCB name, e.g.
                         014_lemon.ply); objects with no mesh there use the built-in stand-in,
                         and the report says which (default: all stand-ins)
  --mode M               precise | discrete | both (default precise)
  --count N              only the first N objects of the order (default 30)
  --seed S               random seed: placements, operators (default 1)
  --jobs J               (mode, participant) runs at a time (default: the number of cores)
  --json FILE            every grasp record (as telegrasp-eval writes them, plus "group",
                         "participant", "contacts", "grasp_tick_hand") and the aggregates
  --csv FILE             one row per grasp; FILE's stem + _by_object.csv: per object and group
  --report FILE.html     self-contained HTML report with a picture of one grasp per object, bar
                         charts, the paper's numbers beside ours
  --questionnaire FILE   questionnaire answers (see telegrasp-eval questionnaire --help) to score
                         into the report
  --domain N             first DDS domain of the servers; job slot k uses N + k (default: from
                         the process id, in 100..200, so that two runs rarely meet; a
                         participant that finds a used scene on its domain fails the run)
  --profile NAME         Fast DDS participant profile (default loopback)
  --profiles FILE        Fast DDS XML profiles (default: the shipped file)
  --scene NAME           the scene (room) of the servers and participants (default
                         $TELEGRASP_SCENE, else default)
  --discovery-server HOST[:PORT]
                         a Fast DDS discovery server for servers and participants; repeat in
                         server-id order
  --record DIR           each server records its run (telegrasp-server --record) to
                         DIR/<mode>-p<participant>.tgrec, for telegrasp-replay
  --keep-logs DIR        keep each server's and participant's log and records in DIR
  --rig FILE             the right-hand rig of the servers and the participants' planning
                         (default: built-in human_right_opposable; the flat thumb:
                         sim/rigs/human_right.textproto)
  --skills FILE          skill profiles overriding the built-in ones: "[experienced]" then
                         "key = value" lines (OperatorSkill's fields, orientation_error_deg in
                         degrees; see README, "Calibration")
  --in-process           run every participant in this process against a sim::World set up as
                         the lockstep server's, no DDS (same simulated times, for fitting; the
                         records have no contacts or grasp pictures)
  -h, --help             this text

Progress goes to stderr (in place on a terminal, a line every few seconds in a log); the
per-group summary and the worst objects to stdout.
Exit status: 0 every grasp was run (held or not), 1 a runtime failure (a run failed; the --objects
folder, a mesh or the questionnaire missing or unreadable; telegrasp-server not found next to
telegrasp-eval; a folder or output not writable), 2 a usage error (a bad or missing option or
value).
)";

struct Options {
  int experienced = 4, inexperienced = 6, count = 30, jobs = 2, domain = -1;
  std::vector<std::string> modes{sim::closing_mode_name(sim::ClosingMode::kPrecise)};  // names, as records write them
  std::string objects_dir, json_path, csv_path, report_path, questionnaire_path, profile = "loopback", profiles_file,
                                                                                 logs_dir, record_dir, skills_path,
                                                                                 rig_path, scene;
  std::vector<std::string> discovery_servers;
  std::uint64_t seed = 1;
  bool in_process = false;
  std::vector<sim::OperatorSkill> skills;  // from --skills
};

constexpr const char* kTool = "telegrasp-eval protocol";

[[noreturn]] void usage_error(const std::string& what) { cli::usage_exit(kTool, what); }

Options parse(int argc, char** argv) {
  Options o;
  o.jobs = std::max(1u, std::thread::hardware_concurrency());
  telegrasp::cli::for_each_option(argc, argv, kUsage, usage_error, [&](const std::string& a, const auto& value) {
    if (a == "--protocol") {
      if (const std::string p = value(); p != "paper") usage_error("--protocol expects paper, got '" + p + "'");
    } else if (a == "--participants") {
      const std::string v = value();
      const auto comma = v.find(',');
      if (comma == std::string::npos) {
        o.experienced = o.inexperienced = static_cast<int>(cli::parse_whole(a, v, 0, 100, usage_error));
      } else {
        o.experienced = static_cast<int>(cli::parse_whole(a, v.substr(0, comma), 0, 100, usage_error));
        o.inexperienced = static_cast<int>(cli::parse_whole(a, v.substr(comma + 1), 0, 100, usage_error));
      }
      if (o.experienced + o.inexperienced == 0) usage_error("--participants: at least one participant");
    } else if (a == "--mode") {
      const std::string m = value();
      using sim::ClosingMode;
      if (m == "both")
        o.modes = {closing_mode_name(ClosingMode::kPrecise), closing_mode_name(ClosingMode::kDiscrete)};
      else if (const std::optional<ClosingMode> mode = sim::parse_closing_mode(m))
        o.modes = {closing_mode_name(*mode)};
      else
        usage_error("--mode expects precise, discrete or both, got '" + m + "'");
    } else if (cli::text_flag(a, value,
                              {{"--objects", &o.objects_dir}, {"--json", &o.json_path}, {"--csv", &o.csv_path},
                               {"--report", &o.report_path}, {"--questionnaire", &o.questionnaire_path},
                               {"--keep-logs", &o.logs_dir}, {"--record", &o.record_dir},
                               {"--skills", &o.skills_path}, {"--rig", &o.rig_path}}))
      ;
    else if (a == "--count")
      o.count = static_cast<int>(cli::parse_whole(a, value(), 1, 30, usage_error));
    else if (a == "--seed")
      o.seed = static_cast<std::uint64_t>(cli::parse_whole(a, value(), 0, 1L << 50, usage_error));
    else if (a == "--jobs")
      o.jobs = static_cast<int>(cli::parse_whole(a, value(), 1, 64, usage_error));
    else if (telegrasp::idl::parse_network_flag(a, value, o, usage_error))
      ;
    else if (a == "--in-process")
      o.in_process = true;
    else
      return false;
    return true;
  });
  if (o.domain < 0) o.domain = 100 + static_cast<int>(getpid() % 101);
  if (o.domain + o.jobs - 1 > idl::kMaxDomain)
    usage_error("--domain " + std::to_string(o.domain) + " + --jobs " + std::to_string(o.jobs) + " exceeds domain " +
                std::to_string(idl::kMaxDomain));
  return o;
}

struct Job {
  std::string mode, group;
  int participant = 0;
  int slot = -1;
  tools::ChildProcess server, bot;  // the participant's stdout on a pipe: its "grasp ..." lines
  std::string buffer;  // partial line of the participant's stdout
  int grasps_done = 0;
  bool finished = false, failed = false;
  std::string error;
  std::vector<report::Record> records;
};

std::string self_dir() {
  std::error_code ec;
  const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  return ec ? std::string(".") : exe.parent_path().string();
}

// "[#####.....] 123/600 grasps, 2 run(s) going, 45 s": the progress line.
std::string progress_text(int done, int total, double seconds, int running) {
  const int width = 30;
  const int filled = total ? done * width / total : width;
  char text[160];
  std::snprintf(text, sizeof text, "[%s%s] %d/%d grasps, %d run(s) going, %.0f s", std::string(filled, '#').c_str(),
                std::string(width - filled, '.').c_str(), done, total, running, seconds);
  return text;
}

// The three slowest and the three least exact objects of each mode, from aggregate_json.
void print_worst_objects(const json& aggregates) {
  for (const json& w : aggregates.value("worst_objects", json::array())) {
    std::printf("\nworst objects (%s):", w.value("mode", "").c_str());
    for (const char* key : {"by_time", "by_nd"}) {
      std::printf("\n  %s:", key);
      int shown = 0;
      for (const json& o : w.value(key, json::array())) {
        if (shown++ == 3) break;
        std::printf(" %s", o.is_object() ? o.value("object", "?").c_str() : o.dump().c_str());
        if (o.is_object())
          for (const char* v : {"time_to_grasp_mean_s", "nd_abs_mean_mm"})
            if (o.contains(v) && o[v].is_number()) std::printf(" (%s %s)", v, report::fmt(o[v].get<double>()).c_str());
      }
    }
    std::printf("\n");
  }
}

// ---------------------------------------------------------------------------------------------
// Set-up

// The paper's per-object numbers, named as the protocol names the objects.
std::vector<report::PaperRow> load_paper_rows() {
  std::vector<report::PaperRow> paper = report::load_paper_results(report::default_paper_results_path());
  // The paper's table writes 072_a_toy_airplane; the protocol's name is YCB's 072-a_toy_airplane.
  for (report::PaperRow& row : paper)
    for (const sim::ProtocolObject& o : sim::protocol_objects()) {
      std::string underscored = o.name;
      std::replace(underscored.begin(), underscored.end(), '-', '_');
      if (underscored == row.object) row.object = o.name;
    }
  return paper;
}

// What the reports need besides the records.
struct ReportInputs {
  std::vector<std::string> standins;  // protocol objects with no mesh in --objects
  std::optional<report::QuestionnaireSummary> questionnaire;
  std::vector<report::PaperRow> paper;
  report::GraspPictureInputs pictures;  // the models and the participants' rig, to draw the grasps
};

// Loads the objects (to fail early, naming a bad mesh), the questionnaire and the paper's numbers;
// nothing (said on stderr) when one cannot be used.
std::optional<ReportInputs> load_report_inputs(const Options& opt) {
  ReportInputs in;
  try {
    in.pictures.models = protocol_models(opt.objects_dir, &in.standins);  // fails early, naming a bad mesh
  } catch (const std::exception& e) {  // MeshLoadError, naming the folder or the file in it
    std::cerr << kTool << ": --objects " << e.what() << "\n";
    return std::nullopt;
  }
  try {
    if (!opt.questionnaire_path.empty()) {
      in.questionnaire = report::score_questionnaire_csv(opt.questionnaire_path);
      for (const auto& r : in.questionnaire->rejected) std::cerr << kTool << ": --questionnaire: " << r.message << "\n";
    }
    in.paper = load_paper_rows();
    in.pictures.rig = std::make_shared<const sim::HandRig>(
        sim::HandRig::load(rig_path_or_default(opt.rig_path)));
  } catch (const std::exception& e) {
    std::cerr << kTool << ": " << e.what() << "\n";
    return std::nullopt;
  }
  return in;
}

// The programs every job runs and the folder for their logs and records.
struct Setup {
  std::string server_bin, self_bin;  // telegrasp-server and telegrasp-eval, next to this program
  fs::path work;  // --keep-logs, or a temporary folder removed at the end
};

// Checks the server is there and makes the --record folder and the work folder; nothing (said on
// stderr) without a server or a folder.
std::optional<Setup> prepare_setup(const Options& opt) {
  Setup s;
  const std::string bin = self_dir();
  s.server_bin = bin + "/telegrasp-server";
  s.self_bin = bin + "/telegrasp-eval";
  if (access(s.server_bin.c_str(), X_OK) != 0) {
    std::cerr << kTool << ": " << s.server_bin
              << " not found: the protocol runs the server built next to telegrasp-eval\n";
    return std::nullopt;
  }
  auto make_folder = [](const char* flag, const std::string& dir) {
    std::error_code ec;
    fs::create_directories(dir, ec);
    if (ec) std::cerr << kTool << ": " << flag << " " << dir << ": " << ec.message() << "\n";
    return !ec;
  };
  if (!opt.record_dir.empty() && !make_folder("--record", opt.record_dir)) return std::nullopt;
  if (!opt.logs_dir.empty()) {
    if (!make_folder("--keep-logs", opt.logs_dir)) return std::nullopt;
    s.work = opt.logs_dir;
  } else {
    char tmpl[] = "/tmp/telegrasp-protocol-XXXXXX";
    if (!mkdtemp(tmpl)) {
      std::cerr << kTool << ": cannot make a temporary folder: " << std::strerror(errno) << "\n";
      return std::nullopt;
    }
    s.work = tmpl;
  }
  return s;
}

// One job per mode and participant; participants 1..E are experienced, the rest inexperienced.
std::vector<Job> make_jobs(const Options& opt) {
  std::vector<Job> jobs;
  for (const std::string& mode : opt.modes)
    for (int p = 1; p <= opt.experienced + opt.inexperienced; ++p) {
      Job j;
      j.mode = mode;
      j.group = p <= opt.experienced ? "experienced" : "inexperienced";
      j.participant = p;
      jobs.push_back(std::move(j));
    }
  return jobs;
}

void print_plan(const Options& opt, int total, std::size_t standins) {
  std::cerr << kTool << ": paper, " << opt.count << " objects x (" << opt.experienced << " experienced + "
            << opt.inexperienced << " inexperienced) participants x " << opt.modes.size() << " mode(s) = " << total
            << " grasps, " << opt.jobs << " at a time";
  if (standins) std::cerr << "; " << standins << " object(s) as built-in stand-ins";
  std::cerr << "\n";
}

// ---------------------------------------------------------------------------------------------
// Running the jobs

// The stem of a job's files in the work folder (and of its recording), e.g. "precise-p3".
std::string job_name(const Job& j) { return j.mode + "-p" + std::to_string(j.participant); }

// Starts job `j` on DDS domain opt.domain + slot: a lockstep server and the participant driving
// it, each logging into the work folder. The server computes grasp qualities within the tick
// (the participant takes a grasp's GraspEvent before it answers that tick) and with the volume,
// as telegrasp-eval in process does: an evaluation has no frame budget to keep.
void start_job(Job& j, int slot, const Options& opt, const Setup& setup) {
  j.slot = slot;
  const std::string name = job_name(j);
  const std::vector<std::string> network =
      idl::network_args(idl::NetworkFlags{opt.domain + slot, opt.profile, opt.profiles_file, opt.scene,
                                          opt.discovery_servers});
  std::vector<std::string> server = {setup.server_bin, "--lockstep", "--empty-scene", "--mode", j.mode,
                                     "--quality-delay-ticks", "0", "--quality-volume"};
  std::vector<std::string> bot = {setup.self_bin,  "participant",
                                  "--group",       j.group,
                                  "--participant", std::to_string(j.participant),
                                  "--seed",        std::to_string(opt.seed),
                                  "--mode",        j.mode,
                                  "--count",       std::to_string(opt.count),
                                  "--json",        (setup.work / (name + ".json")).string()};
  if (!opt.objects_dir.empty()) {
    for (const char* a : {"--objects", opt.objects_dir.c_str()}) server.push_back(a), bot.push_back(a);
    server.push_back("--fill-standins");
  }
  server.insert(server.end(), network.begin(), network.end());
  bot.insert(bot.end(), network.begin(), network.end());
  if (!opt.skills_path.empty()) bot.insert(bot.end(), {"--skills", opt.skills_path});
  if (!opt.rig_path.empty()) {  // the servers' right hand, by a configuration file
    const fs::path config = setup.work / (name + ".config.textproto");
    std::ofstream(config) << "right_rig: \"" << fs::absolute(opt.rig_path).string() << "\"\n";
    server.insert(server.end(), {"--config", config.string()});
    bot.insert(bot.end(), {"--rig", opt.rig_path});
  }
  if (!opt.record_dir.empty())
    server.insert(server.end(), {"--record", (fs::path(opt.record_dir) / (name + ".tgrec")).string()});
  j.server.start(server, (setup.work / (name + ".server.log")).string());
  j.bot.start(bot, (setup.work / (name + ".participant.log")).string(), true);
}

// Ends a job whose participant exited with `bot_status`: stops its server, then reads the records
// the participant wrote, or marks the job failed with the end of both logs.
void finish_job(Job& j, int bot_status, const fs::path& work) {
  const std::string name = job_name(j);
  j.server.stop();
  j.finished = true;
  if (bot_status != 0) {
    j.failed = true;
    j.error = "participant " + std::to_string(j.participant) + " (" + j.mode + ") failed; its log:\n" +
              j.bot.log_tail(5) + "  server log:\n" + j.server.log_tail(5);
    return;
  }
  try {
    std::ifstream in(work / (name + ".json"));
    for (const json& r : json::parse(in)) j.records.push_back(report::record_from_json(r));
  } catch (const std::exception& e) {
    j.failed = true;
    j.error = "participant " + std::to_string(j.participant) + " (" + j.mode + "): unreadable records: " + e.what();
  }
}

// Where the jobs are: which slots (DDS domains) are taken, how many runs are going, how many
// grasps are done.
struct Progress {
  std::vector<bool> slot_busy;
  int running = 0, done_grasps = 0;
};

// Reads what a participant printed so far; returns how many more grasps it reported ("grasp ..." lines).
int read_grasp_lines(Job& j) {
  int grasps = 0;
  char buf[4096];
  for (ssize_t n; (n = read(j.bot.stdout_fd(), buf, sizeof buf)) > 0;)
    j.buffer.append(buf, static_cast<std::size_t>(n));
  for (std::size_t nl; (nl = j.buffer.find('\n')) != std::string::npos; j.buffer.erase(0, nl + 1))
    if (j.buffer.compare(0, 6, "grasp ") == 0) ++grasps;
  return grasps;
}

// Waits up to 200 ms for output of the running participants, counts their grasps and finishes
// the jobs whose participant has exited, freeing their slots.
void poll_jobs(std::vector<Job>& jobs, Progress& progress, const Options& opt, const Setup& setup) {
  std::vector<pollfd> fds;
  std::vector<Job*> polled;
  for (Job& j : jobs)
    if (j.slot >= 0 && !j.finished) {
      fds.push_back({j.bot.stdout_fd(), POLLIN, 0});
      polled.push_back(&j);
    }
  poll(fds.data(), fds.size(), 200);
  for (std::size_t i = 0; i < fds.size(); ++i) {
    Job& j = *polled[i];
    const int grasps = read_grasp_lines(j);
    j.grasps_done += grasps;
    progress.done_grasps += grasps;
    if (const int status = j.bot.wait(std::chrono::milliseconds(0)); status >= 0) {
      finish_job(j, status, setup.work);
      progress.slot_busy[static_cast<std::size_t>(j.slot)] = false;
      --progress.running;
      progress.done_grasps += opt.count - j.grasps_done;  // a failed run's missing grasps count as done for the bar
    }
  }
}

// Runs every job, opt.jobs at a time, with a progress bar on stderr (ProgressLine: in place on a
// terminal, a line every few seconds in a log); returns the wall time (s).
double run_jobs(std::vector<Job>& jobs, const Options& opt, const Setup& setup, int total) {
  std::signal(SIGPIPE, SIG_IGN);
  const auto t0 = Clock::now();
  tools::ProgressLine line;
  Progress progress{std::vector<bool>(static_cast<std::size_t>(opt.jobs), false)};
  std::size_t next = 0;
  while (true) {
    for (int s = 0; s < opt.jobs && next < jobs.size(); ++s)
      if (!progress.slot_busy[static_cast<std::size_t>(s)]) {
        start_job(jobs[next++], s, opt, setup);
        progress.slot_busy[static_cast<std::size_t>(s)] = true;
        ++progress.running;
      }
    if (progress.running == 0) break;
    poll_jobs(jobs, progress, opt, setup);
    const double seconds = std::chrono::duration<double>(Clock::now() - t0).count();
    if (line.due()) line.show(progress_text(progress.done_grasps, total, seconds, progress.running));
  }
  const double wall = std::chrono::duration<double>(Clock::now() - t0).count();
  line.finish(progress_text(progress.done_grasps, total, wall, 0));
  return wall;
}

// Runs every job in this process (--in-process), opt.jobs threads at a time; returns the wall time (s).
double run_jobs_in_process(std::vector<Job>& jobs, const Options& opt, const ReportInputs& in) {
  const auto t0 = Clock::now();
  std::atomic<std::size_t> next{0};
  auto worker = [&] {
    for (std::size_t k = next++; k < jobs.size(); k = next++) {
      Job& j = jobs[k];
      InProcessParticipant p{j.mode,    j.group,  j.participant,
                             opt.count, opt.seed, participant_skill(j.group, opt.seed, j.participant, &opt.skills)};
      try {
        j.records = run_participant_in_process(p, in.pictures.models, in.pictures.rig);
      } catch (const std::exception& e) {
        j.failed = true;
        j.error = "participant " + std::to_string(j.participant) + " (" + j.mode + ") failed: " + e.what() + "\n";
      }
      j.finished = true;
    }
  };
  std::vector<std::thread> pool;
  for (int i = 0; i < opt.jobs; ++i) pool.emplace_back(worker);
  for (std::thread& t : pool) t.join();
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

// ---------------------------------------------------------------------------------------------
// Collection and reports

// Every job's records, in job order; says on stderr why each failed run failed and counts them.
std::vector<report::Record> collect_records(const std::vector<Job>& jobs, int& failures) {
  std::vector<report::Record> records;
  for (const Job& j : jobs) {
    if (j.failed) {
      ++failures;
      std::cerr << kTool << ": " << j.error;
    }
    records.insert(records.end(), j.records.begin(), j.records.end());
  }
  return records;
}

// Per mode and group: the same table and summary keys as the in-process run, on stdout. Returns
// the summaries.
json print_summaries(const std::vector<report::Record>& records, const Options& opt) {
  json summaries = json::array();
  for (const std::string& mode : opt.modes)
    for (const char* group : {"experienced", "inexperienced"}) {
      std::vector<report::ObjectRows> rows;
      std::vector<const report::Record*> all;
      for (const std::string& object : paper_object_order()) {
        report::ObjectRows row{object, {}};
        for (const report::Record& r : records)
          if (r.mode == mode && r.group == group && r.object == object) row.records.push_back(&r), all.push_back(&r);
        if (!row.records.empty()) rows.push_back(std::move(row));
      }
      if (all.empty()) continue;
      std::printf("\n== %s, %s (%zu grasps) ==\n", mode.c_str(), group, all.size());
      report::print_object_table(rows);
      json s = report::summarize(all);
      s["mode"] = mode;
      s["group"] = group;
      std::printf("summary: %s\n", s.dump().c_str());
      summaries.push_back(std::move(s));
    }
  return summaries;
}

// The run as the reports describe it, created now.
report::ExperimentRun experiment_run(int argc, char** argv, const Options& opt, double wall,
                                     const std::vector<std::string>& standins, std::vector<report::Record> records) {
  report::ExperimentRun run;
  run.protocol = "paper";
  for (int i = 0; i < argc; ++i) run.command_line += (i ? " " : "") + std::string(argv[i]);
  run.seed = opt.seed;
  run.wall_seconds = wall;
  char created[32];
  const std::time_t now = std::time(nullptr);
  std::strftime(created, sizeof created, "%Y-%m-%dT%H:%M:%SZ", std::gmtime(&now));
  run.created = created;
  run.modes = opt.modes;
  run.objects.assign(paper_object_order().begin(), paper_object_order().begin() + opt.count);
  for (const std::string& s : standins)
    if (std::find(run.objects.begin(), run.objects.end(), s) != run.objects.end()) run.standin_objects.push_back(s);
  run.participants = {{"experienced", opt.experienced}, {"inexperienced", opt.inexperienced}};
  run.records = std::move(records);
  return run;
}

// Writes the --json, --csv and --report files asked for; false (said on stderr) when one cannot be.
bool write_reports(const report::ExperimentRun& run, const json& summaries, const ReportInputs& in,
                   const Options& opt) {
  try {
    if (!opt.json_path.empty()) {
      json grasps = json::array();
      for (const report::Record& r : run.records) grasps.push_back(report::record_json(r));
      report::write_text_file(opt.json_path, json{{"grasps", grasps},
                                                  {"summaries", summaries},
                                                  {"aggregates", report::aggregate_json(run)},
                                                  {"paper_correlation", report::paper_correlation_json(run, in.paper)},
                                                  {"standin_objects", run.standin_objects}}
                                                     .dump(1) +
                                                 "\n");
      std::cerr << "wrote " << opt.json_path << "\n";
    }
    if (!opt.csv_path.empty()) {
      const std::string by_object = report::write_csv(run, opt.csv_path);
      std::cerr << "wrote " << opt.csv_path << " and " << by_object << "\n";
    }
    if (!opt.report_path.empty()) {
      report::write_text_file(
          opt.report_path,
          report::html_report(run, in.paper, in.questionnaire ? &*in.questionnaire : nullptr, &in.pictures));
      std::cerr << "wrote " << opt.report_path << "\n";
    }
  } catch (const std::exception& e) {
    std::cerr << kTool << ": " << e.what() << "\n";
    return false;
  }
  return true;
}

}  // namespace

int run_protocol(int argc, char** argv) {
  Options opt = parse(argc, argv);
  if (!load_skills_flag(opt.skills_path, opt.skills, kTool)) return cli::kExitFailure;
  const std::optional<ReportInputs> inputs = load_report_inputs(opt);
  if (!inputs) return cli::kExitFailure;
  std::optional<Setup> setup;
  if (!opt.in_process && !(setup = prepare_setup(opt))) return cli::kExitFailure;
  std::vector<Job> jobs = make_jobs(opt);
  const int total = static_cast<int>(jobs.size()) * opt.count;
  print_plan(opt, total, inputs->standins.size());

  const double wall = opt.in_process ? run_jobs_in_process(jobs, opt, *inputs) : run_jobs(jobs, opt, *setup, total);
  int failures = 0;
  std::vector<report::Record> records = collect_records(jobs, failures);
  if (setup && opt.logs_dir.empty()) fs::remove_all(setup->work);
  std::cerr << kTool << ": " << records.size() << " grasp records in " << report::fmt(wall, 1) << " s"
            << (failures ? ", " + std::to_string(failures) + " run(s) failed" : "") << "\n";

  const json summaries = print_summaries(records, opt);
  const report::ExperimentRun run = experiment_run(argc, argv, opt, wall, inputs->standins, std::move(records));
  print_worst_objects(report::aggregate_json(run));
  report::print_paper_correlation(report::paper_correlation_json(run, inputs->paper));
  if (!write_reports(run, summaries, *inputs, opt)) return cli::kExitFailure;
  return failures ? cli::kExitFailure : 0;
}

}  // namespace telegrasp::eval
