// telegrasp-eval protocol: the paper's experiment through the server over DDS. Every
// (mode, participant) pair is a job: a telegrasp-server in lockstep on its own DDS domain and a
// participant process (participant.cc) driving it. Jobs run in parallel, as many as --jobs.
// Records come from the GraspEvent topic, via the participants.
#include "cli.h"
#include "commands.h"
#include "experiment_report.h"
#include "grasp_report.h"
#include "protocol_common.h"
#include "questionnaire.h"
#include "telegrasp/sim/standin_objects.h"

#include <nlohmann/json.hpp>

#include <algorithm>
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
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include <fcntl.h>
#include <poll.h>
#include <sys/wait.h>
#include <unistd.h>

namespace telegrasp::eval {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using Clock = std::chrono::steady_clock;

constexpr const char* kUsage = R"(Usage: telegrasp-eval protocol [options]

Runs the paper's experiment (GRASPING.md section 6) through telegrasp servers over DDS: the 30
protocol objects are spawned one at a time with SceneCommand, in the paper's order, resting at a
random place and yaw in a bounded area in front of the operator (x 0.40..0.55 m, y -0.10..0.10 m);
a bot participant reacts, reaches, grasps, lifts 10 cm, holds 1 s and releases each. Each grasp's
time from spawn to grasp, per-capsule ND, HandError, exact signed distances and contacts come
from the server's GraspEvent topic.

Operators: the group's skill profile (experienced: pose error 4 mm / 3 deg, reach 0.6 m/s,
reaction 0.25 s, squeeze 0.30 s; inexperienced: 8 mm / 6 deg, 0.4 m/s, 0.40 s, 0.45 s), scaled
per participant by a speed factor ~ lognormal(0, 0.15) (reach speed x, reaction and squeeze
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
                         "participant", "contacts") and the aggregates
  --csv FILE             one row per grasp; FILE's stem + _by_object.csv: per object and group
  --report FILE.html     self-contained HTML report with bar charts, the paper's numbers beside ours
  --questionnaire FILE   questionnaire answers (see telegrasp-eval questionnaire --help) to score
                         into the report
  --domain N             first DDS domain of the servers; job slot k uses N + k (default: from
                         the process id, in 100..200, so that two runs rarely meet; a
                         participant that finds a used scene on its domain fails the run)
  --profile NAME         Fast DDS participant profile (default loopback)
  --profiles FILE        Fast DDS XML profiles (default: the shipped file)
  --record DIR           each server records its run (telegrasp-server --record) to
                         DIR/<mode>-p<participant>.tgrec, for telegrasp-replay
  --keep-logs DIR        keep each server's and participant's log and records in DIR
  -h, --help             this text

Progress goes to stderr; the per-group summary and the worst objects to stdout.
Exit status: 0 when every grasp was run (held or not), 1 if a run failed, 2 for a bad option.
)";

struct Options {
  int experienced = 4, inexperienced = 6, count = 30, jobs = 2, domain = -1;
  std::vector<std::string> modes{"precise"};
  std::string objects_dir, json_path, csv_path, report_path, questionnaire_path, profile = "loopback", profiles_file, logs_dir, record_dir;
  std::uint64_t seed = 1;
};

[[noreturn]] void usage_error(const std::string& what) {
  std::cerr << "telegrasp-eval: " << what << "\n(see telegrasp-eval protocol --help)\n";
  std::exit(2);
}

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
      if (m == "both") o.modes = {"precise", "discrete"};
      else if (m == "precise" || m == "discrete") o.modes = {m};
      else usage_error("--mode expects precise, discrete or both, got '" + m + "'");
    }
    else if (a == "--objects") o.objects_dir = value();
    else if (a == "--count") o.count = static_cast<int>(cli::parse_whole(a, value(), 1, 30, usage_error));
    else if (a == "--seed") o.seed = static_cast<std::uint64_t>(cli::parse_whole(a, value(), 0, 1L << 50, usage_error));
    else if (a == "--jobs") o.jobs = static_cast<int>(cli::parse_whole(a, value(), 1, 64, usage_error));
    else if (a == "--json") o.json_path = value();
    else if (a == "--csv") o.csv_path = value();
    else if (a == "--report") o.report_path = value();
    else if (a == "--questionnaire") o.questionnaire_path = value();
    else if (a == "--domain") o.domain = static_cast<int>(cli::parse_whole(a, value(), 0, 232, usage_error));
    else if (a == "--profile") o.profile = value();
    else if (a == "--profiles") o.profiles_file = value();
    else if (a == "--keep-logs") o.logs_dir = value();
    else if (a == "--record") o.record_dir = value();
    else return false;
    return true;
  });
  if (o.domain < 0) o.domain = 100 + static_cast<int>(getpid() % 101);
  if (o.domain + o.jobs - 1 > 232) usage_error("--domain " + std::to_string(o.domain) + " + --jobs " + std::to_string(o.jobs) + " exceeds domain 232");
  return o;
}

// A child process with its stdout on a pipe (or a file) and its stderr in a file.
struct Child {
  pid_t pid = -1;
  int out_fd = -1;  // read end of its stdout, or -1
};

Child spawn(const std::vector<std::string>& args, const std::string& log_path, bool pipe_stdout) {
  int fds[2] = {-1, -1};
  if (pipe_stdout && pipe(fds) != 0) throw std::runtime_error(std::string("pipe: ") + std::strerror(errno));
  const pid_t pid = fork();
  if (pid < 0) throw std::runtime_error(std::string("fork: ") + std::strerror(errno));
  if (pid == 0) {
    const int log = open(log_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    if (log >= 0) {
      dup2(log, STDERR_FILENO);
      if (!pipe_stdout) dup2(log, STDOUT_FILENO);
    }
    if (pipe_stdout) {
      dup2(fds[1], STDOUT_FILENO);
      close(fds[0]);
      close(fds[1]);
    }
    std::vector<char*> argv;
    for (const auto& a : args) argv.push_back(const_cast<char*>(a.c_str()));
    argv.push_back(nullptr);
    execv(argv[0], argv.data());
    std::fprintf(stderr, "cannot run %s: %s\n", argv[0], std::strerror(errno));
    _exit(127);
  }
  Child c;
  c.pid = pid;
  if (pipe_stdout) {
    close(fds[1]);
    c.out_fd = fds[0];
    fcntl(c.out_fd, F_SETFL, O_NONBLOCK);
  }
  return c;
}

// Stops a child with SIGTERM (SIGKILL after 5 s); returns its exit status.
int stop(pid_t pid) {
  kill(pid, SIGTERM);
  int status = 0;
  for (int i = 0; i < 500; ++i) {
    if (waitpid(pid, &status, WNOHANG) == pid) return status;
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  kill(pid, SIGKILL);
  waitpid(pid, &status, 0);
  return status;
}

std::string tail(const std::string& path, std::size_t lines) {
  std::ifstream in(path);
  std::vector<std::string> all;
  for (std::string l; std::getline(in, l);) all.push_back(l);
  std::string out;
  for (std::size_t i = all.size() > lines ? all.size() - lines : 0; i < all.size(); ++i) out += "    " + all[i] + "\n";
  return out;
}

struct Job {
  std::string mode, group;
  int participant = 0;
  int slot = -1;
  Child server, bot;
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

// "[#####.....] 123/600 grasps  45 s" on one stderr line.
void draw_progress(int done, int total, double seconds, int running) {
  const int width = 30;
  const int filled = total ? done * width / total : width;
  std::fprintf(stderr, "\r[%s%s] %d/%d grasps, %d run(s) going, %.0f s ", std::string(filled, '#').c_str(),
               std::string(width - filled, '.').c_str(), done, total, running, seconds);
  std::fflush(stderr);
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

}  // namespace

int run_protocol(int argc, char** argv) {
  const Options opt = parse(argc, argv);
  std::vector<std::string> standins;
  std::optional<report::QuestionnaireSummary> questionnaire;
  std::vector<report::PaperRow> paper;
  try {
    protocol_models(opt.objects_dir, &standins);  // fails early, naming a bad mesh
  } catch (const std::exception& e) {
    std::cerr << "telegrasp-eval: --objects " << opt.objects_dir << ": " << e.what() << "\n";
    return 2;
  }
  try {
    if (!opt.questionnaire_path.empty()) {
      questionnaire = report::score_questionnaire_csv(opt.questionnaire_path);
      for (const auto& r : questionnaire->rejected) std::cerr << "telegrasp-eval: questionnaire: " << r.message << "\n";
    }
    paper = report::load_paper_results(report::default_paper_results_path());
    // The paper's table writes 072_a_toy_airplane; the protocol's name is YCB's 072-a_toy_airplane.
    for (report::PaperRow& row : paper)
      for (const sim::ProtocolObject& o : sim::protocol_objects()) {
        std::string underscored = o.name;
        std::replace(underscored.begin(), underscored.end(), '-', '_');
        if (underscored == row.object) row.object = o.name;
      }
  } catch (const std::exception& e) {
    std::cerr << "telegrasp-eval: " << e.what() << "\n";
    return 2;
  }
  const std::string bin = self_dir();
  const std::string server_bin = bin + "/telegrasp-server", self_bin = bin + "/telegrasp-eval";
  if (access(server_bin.c_str(), X_OK) != 0) {
    std::cerr << "telegrasp-eval: " << server_bin << " not found: the protocol runs the server built next to telegrasp-eval\n";
    return 2;
  }
  if (!opt.record_dir.empty()) {
    std::error_code ec;
    fs::create_directories(opt.record_dir, ec);
    if (ec) usage_error("--record " + opt.record_dir + ": " + ec.message());
  }
  fs::path work;
  if (!opt.logs_dir.empty()) {
    work = opt.logs_dir;
    std::error_code ec;
    fs::create_directories(work, ec);
    if (ec) usage_error("--keep-logs " + opt.logs_dir + ": " + ec.message());
  } else {
    char tmpl[] = "/tmp/telegrasp-protocol-XXXXXX";
    if (!mkdtemp(tmpl)) usage_error(std::string("cannot make a temporary folder: ") + std::strerror(errno));
    work = tmpl;
  }

  std::vector<Job> jobs;
  for (const std::string& mode : opt.modes)
    for (int p = 1; p <= opt.experienced + opt.inexperienced; ++p) {
      Job j;
      j.mode = mode;
      j.group = p <= opt.experienced ? "experienced" : "inexperienced";
      j.participant = p;
      jobs.push_back(std::move(j));
    }
  const int total = static_cast<int>(jobs.size()) * opt.count;
  std::cerr << "telegrasp-eval: protocol paper, " << opt.count << " objects x (" << opt.experienced << " experienced + "
            << opt.inexperienced << " inexperienced) participants x " << opt.modes.size() << " mode(s) = " << total << " grasps, "
            << opt.jobs << " at a time";
  if (!standins.empty()) std::cerr << "; " << standins.size() << " object(s) as built-in stand-ins";
  std::cerr << "\n";

  std::signal(SIGPIPE, SIG_IGN);
  const auto t0 = Clock::now();
  std::vector<bool> slot_busy(static_cast<std::size_t>(opt.jobs), false);
  std::size_t next = 0;
  int running = 0, done_grasps = 0;
  auto start_job = [&](Job& j, int slot) {
    j.slot = slot;
    const std::string name = j.mode + "-p" + std::to_string(j.participant);
    const std::string domain = std::to_string(opt.domain + slot);
    std::vector<std::string> server = {server_bin, "--lockstep", "--empty-scene", "--mode", j.mode, "--domain", domain, "--profile", opt.profile};
    std::vector<std::string> bot = {self_bin, "participant", "--domain", domain, "--profile", opt.profile, "--group", j.group,
                                    "--participant", std::to_string(j.participant), "--seed", std::to_string(opt.seed), "--mode", j.mode,
                                    "--count", std::to_string(opt.count), "--json", (work / (name + ".json")).string()};
    if (!opt.objects_dir.empty()) {
      for (const char* a : {"--objects", opt.objects_dir.c_str()}) server.push_back(a), bot.push_back(a);
      server.push_back("--fill-standins");
    }
    if (!opt.profiles_file.empty())
      for (const char* a : {"--profiles", opt.profiles_file.c_str()}) server.push_back(a), bot.push_back(a);
    if (!opt.record_dir.empty()) server.insert(server.end(), {"--record", (fs::path(opt.record_dir) / (name + ".tgrec")).string()});
    j.server = spawn(server, (work / (name + ".server.log")).string(), false);
    j.bot = spawn(bot, (work / (name + ".participant.log")).string(), true);
    slot_busy[static_cast<std::size_t>(slot)] = true;
    ++running;
  };
  auto finish_job = [&](Job& j, int bot_status) {
    const std::string name = j.mode + "-p" + std::to_string(j.participant);
    stop(j.server.pid);
    close(j.bot.out_fd);
    slot_busy[static_cast<std::size_t>(j.slot)] = false;
    --running;
    j.finished = true;
    if (!WIFEXITED(bot_status) || WEXITSTATUS(bot_status) != 0) {
      j.failed = true;
      j.error = "participant " + std::to_string(j.participant) + " (" + j.mode + ") failed; its log:\n" +
                tail((work / (name + ".participant.log")).string(), 5) + "  server log:\n" + tail((work / (name + ".server.log")).string(), 5);
      return;
    }
    try {
      std::ifstream in(work / (name + ".json"));
      for (const json& r : json::parse(in)) j.records.push_back(report::record_from_json(r));
    } catch (const std::exception& e) {
      j.failed = true;
      j.error = "participant " + std::to_string(j.participant) + " (" + j.mode + "): unreadable records: " + e.what();
    }
  };

  while (true) {
    for (int s = 0; s < opt.jobs && next < jobs.size(); ++s)
      if (!slot_busy[static_cast<std::size_t>(s)]) start_job(jobs[next++], s);
    if (running == 0) break;
    std::vector<pollfd> fds;
    std::vector<Job*> polled;
    for (Job& j : jobs)
      if (j.slot >= 0 && !j.finished) {
        fds.push_back({j.bot.out_fd, POLLIN, 0});
        polled.push_back(&j);
      }
    poll(fds.data(), fds.size(), 200);
    for (std::size_t i = 0; i < fds.size(); ++i) {
      Job& j = *polled[i];
      char buf[4096];
      for (ssize_t n; (n = read(j.bot.out_fd, buf, sizeof buf)) > 0;) j.buffer.append(buf, static_cast<std::size_t>(n));
      for (std::size_t nl; (nl = j.buffer.find('\n')) != std::string::npos; j.buffer.erase(0, nl + 1))
        if (j.buffer.compare(0, 6, "grasp ") == 0) ++j.grasps_done, ++done_grasps;
      int status = 0;
      if (waitpid(j.bot.pid, &status, WNOHANG) == j.bot.pid) {
        finish_job(j, status);
        done_grasps += opt.count - j.grasps_done;  // a failed run's missing grasps count as done for the bar
      }
    }
    draw_progress(done_grasps, total, std::chrono::duration<double>(Clock::now() - t0).count(), running);
  }
  const double wall = std::chrono::duration<double>(Clock::now() - t0).count();
  std::fprintf(stderr, "\n");

  std::vector<report::Record> records;
  int failures = 0;
  for (const Job& j : jobs) {
    if (j.failed) {
      ++failures;
      std::cerr << "telegrasp-eval: " << j.error;
    }
    records.insert(records.end(), j.records.begin(), j.records.end());
  }
  if (opt.logs_dir.empty()) fs::remove_all(work);
  std::cerr << "telegrasp-eval: " << records.size() << " grasp records in " << report::fmt(wall, 1) << " s"
            << (failures ? ", " + std::to_string(failures) + " run(s) failed" : "") << "\n";

  // Per mode and group: the same table and summary keys as the in-process run.
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
  print_worst_objects(report::aggregate_json(run));
  try {
    if (!opt.json_path.empty()) {
      json grasps = json::array();
      for (const report::Record& r : run.records) grasps.push_back(report::record_json(r));
      report::write_text_file(opt.json_path, json{{"grasps", grasps}, {"summaries", summaries}, {"aggregates", report::aggregate_json(run)},
                                                  {"standin_objects", run.standin_objects}}.dump(1) + "\n");
      std::cerr << "wrote " << opt.json_path << "\n";
    }
    if (!opt.csv_path.empty()) {
      const std::string by_object = report::write_csv(run, opt.csv_path);
      std::cerr << "wrote " << opt.csv_path << " and " << by_object << "\n";
    }
    if (!opt.report_path.empty()) {
      report::write_text_file(opt.report_path, report::html_report(run, paper, questionnaire ? &*questionnaire : nullptr));
      std::cerr << "wrote " << opt.report_path << "\n";
    }
  } catch (const std::exception& e) {
    std::cerr << "telegrasp-eval: " << e.what() << "\n";
    return 1;
  }
  return failures ? 1 : 0;
}

}  // namespace telegrasp::eval
