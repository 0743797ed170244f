// telegrasp-echo: subscribes to a telegrasp server's outputs through telegrasp::client and prints
// one JSON object per sample and line on stdout, e.g.
//   {"topic":"GraspEvent","event_id":3,"kind":"grasp","hand":{"client_id":"bot-a","side":"right"},...}
// Field names follow the client types (types.h) with the unit of every quantity appended: lengths
// of positions in metres (_m), the grasp metrics in millimetres (nd_mm, signed_distance_mm,
// hand_error_mm), times in seconds (_s); the format is printed by --help (kUsage).
#include "client_json.h"
#include "telegrasp/client/client.h"
#include "telegrasp/idl/network_flags.h"

#include "telegrasp/idl/cli.h"

#include <nlohmann/json.hpp>

#include <atomic>
#include <chrono>
#include <csignal>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <map>
#include <mutex>
#include <optional>
#include <sstream>
#include <string>
#include <thread>
#include <unistd.h>

namespace {

namespace tc = telegrasp::client;
using Json = nlohmann::ordered_json;  // keeps "topic" first

// Set by SIGINT/SIGTERM; the main loop polls it.
volatile std::sig_atomic_t g_signalled = 0;
extern "C" void on_signal(int) { g_signalled = 1; }

// Topic names as printed and accepted by --topics, with their subscription bits.
const std::map<std::string, unsigned, std::less<>>& topic_bits() {
  static const std::map<std::string, unsigned, std::less<>> bits = {
      {"HandSkeleton", tc::kHandSkeletons},      {"GraspState", tc::kGraspStates},
      {"ContactSet", tc::kContactSets},          {"GraspEvent", tc::kGraspEvents},
      {"SceneState", tc::kSceneStates},          {"ServerStatus", tc::kServerStatuses},
      {"ObjectGeometry", tc::kObjectGeometries},
  };
  return bits;
}

constexpr const char* kUsage = R"(Usage: telegrasp-echo [options]

Prints every sample a telegrasp server publishes as one JSON object per line on stdout.

Options:
  --topics LIST    comma separated, from HandSkeleton,GraspState,ContactSet,GraspEvent,
                   SceneState,ServerStatus,ObjectGeometry (default: all; ObjectGeometry prints
                   a summary of each model's mesh, not the mesh)
  --domain N       DDS domain, 0..232 (default 0)
  --profile NAME   participant profile: loopback, shm, udp, lan, wan, secure (default loopback)
  --profiles FILE  Fast DDS XML profiles (default $TELEGRASP_PROFILES, else the shipped file)
  --scene NAME     the scene (room) to listen to (default $TELEGRASP_SCENE, else default)
  --discovery-server HOST[:PORT]
                   a Fast DDS discovery server; repeat in id order (telegrasp-server --help)
  --count N        exit after N lines
  --duration-s S   exit after S seconds
  --scenes         instead of samples: list the live servers of every scene from the scene
                   directory after --duration-s (default 3) of listening, one line each (scene,
                   host, serving, clients, hands, objects, tick p99, missed ticks, CPU, host
                   load); exit 1 when there is none
  --format F       with --scenes: text (default, a line per server) or json: one JSON array
                   instead, an object per server ("scene",
                   "host", "version", "incarnation", "started_unix_s", "serving", "clients",
                   "hands", "objects", "tick_rate_hz", "tick_us_p99", "missed_ticks",
                   "cpu_percent", "host_cores", "host_load")
  --pick NAME      with --scenes: print only the host to run scene NAME on: the host that
                   serves it, else the least loaded host (lowest load per core, then fewest
                   hands); exit 1 when no server is live
  -h, --help       this text

Output: one object per sample, "topic" first, field names as in the client library's types
with the unit appended to every quantity that has one. Frames as everywhere in telegrasp:
X_WorldObject is the object's pose in the world frame.
  pose            {"p_m":[x,y,z],"q_wxyz":[w,x,y,z]}: position in metres, unit quaternion
  hand            {"client_id":"...","side":"left"|"right"}
  every topic     "tick", "time_s" (server time), but ObjectGeometry
  SceneState and ServerStatus also "incarnation": the server run (16 hex digits, new after
                  every restart of the server; ticks, times and object ids of different runs
                  are not comparable)
  HandSkeleton    "hand", "rig", "input_sequence", "input_client_time_ns", "late_latched",
                  "frozen", "X_WorldPalm" (pose: the resolved pose, that grasps and is
                  shown), "X_WorldPhalanx" (poses, rig order), "joint_angles_rad",
                  "X_WorldTracked" (pose: the controller's), "resolve_offset_m" (resolved
                  minus tracked position, world frame), "resolve_angle_rad"
  GraspState      "hand", "selected_object", "grasped_object" (-1: none), "trigger" (0..1),
                  "blocked" (per phalanx), "palm_contact", "epsilon", "volume",
                  "force_closure" (the held grasp's quality; 0 and false when not holding),
                  "grasp_type" (how the hand closes; "other" for a rig without grasp types)
  ContactSet      "hand", "object_id", "X_WorldObject", "contacts"
  GraspEvent      "event_id", "kind" ("grasp"|"release"), "hand", "object_id", "object_name",
                  "object_spawn_time_s", "X_WorldObject", "input_sequence";
                  grasp: "hand_error_mm" (from nd_midlength), "capsules_without_hit",
                  "palm_signed_distance_mm" (the palm box's exact signed distance),
                  "epsilon", "volume", "force_closure", "grasp_type", "capsules", "contacts";
                  release: "v_WorldObject_m_per_s", "w_WorldObject_rad_per_s"
  SceneState      "objects": {"id","name","X_WorldObject","v_WorldObject_m_per_s","held",
                  "holder" (if held: the first), "holders" (if held: every hand holding
                  it, in grasp order; two may share one object), "spawn_time_s"}
  ServerStatus    "tick_rate_hz", "clients", "hands", "objects", "tick_us_p50", "tick_us_p99", "tick_us_max",
                  "missed_ticks", "rss_kib", "heap_kib" (the server's resident set and heap in
                  use), "inputs_accepted", "inputs_rejected", "rejected" (per reason),
                  "commands_accepted", "commands_rejected", "commands_rejected_by_reason"
                  (per reason), "notices_sent", "models"
  ObjectGeometry  a summary, never the mesh: "model", "content_hash" (16 hex digits),
                  "vertex_count", "triangle_count", "mesh_omitted", "p_ObjectMin_m",
                  "p_ObjectMax_m" (bounds, model frame), "mass_kg", "volume_m3",
                  "inertia_diagonal_kg_m2"
  capsule         {"phalanx","phalanx_name","hit","nd_midlength_mm","nd_mm","contact_hit",
                  "nd_contact_mm","signed_distance_mm","blocked"}: the paper's ND at
                  mid-length (null when "hit" is false; "nd_mm" is the same, an alias kept for
                  one release), ND toward the contact (blocked capsules; null when
                  "contact_hit" is false) and the exact signed distance
  contact         {"phalanx" (-1: palm),"p_WorldContact_m","n_World","p_ObjectContact_m",
                  "n_Object","nd_mm","nd_hit"}: point and unit normal in both frames, the
                  capsule's ND (null when "nd_hit" is false)
NaN prints as null.

Stops cleanly on SIGINT or SIGTERM, or when stdout is closed (e.g. piped into head).
Exit status: 0 done (count, seconds, a signal or a closed stdout), 1 a runtime failure (DDS could
not start, e.g. an unknown --profile; with --scenes --pick: no live server found), 2 a usage error
(a bad or missing option or value).
)";

// ---------------------------------------------------------------------------------------------
// JSON for the client types: their field names, with the unit of every quantity appended.

namespace form = telegrasp::tools::json_form;

// One line: the topic first, then the sample's JSON form (common/client_json.h).
Json with_topic(const char* topic, Json body) {
  Json j{{"topic", topic}};
  j.update(body);
  return j;
}

Json to_json(const tc::HandSkeleton& s) { return with_topic("HandSkeleton", form::hand_skeleton<Json>(s)); }
Json to_json(const tc::GraspState& s) { return with_topic("GraspState", form::grasp_state<Json>(s)); }
Json to_json(const tc::ContactSet& s) { return with_topic("ContactSet", form::contact_set<Json>(s)); }
Json to_json(const tc::GraspEvent& e) { return with_topic("GraspEvent", form::grasp_event<Json>(e)); }

Json to_json(const tc::SceneState& s) {
  Json j = with_topic("SceneState", form::scene_state<Json>(s));
  j["incarnation"] = telegrasp::cli::format_hex64(s.incarnation);
  return j;
}
Json to_json(const tc::ServerStatus& s) {
  Json j = with_topic("ServerStatus", form::server_status<Json>(s));
  j["incarnation"] = telegrasp::cli::format_hex64(s.incarnation);
  return j;
}
Json to_json(const tc::ObjectGeometry& g) { return with_topic("ObjectGeometry", form::object_geometry<Json>(g)); }

// ---------------------------------------------------------------------------------------------
// Command line.

struct Args {
  tc::ClientOptions options;
  std::optional<std::uint64_t> count;
  std::optional<double> seconds;
  bool scenes = false, json = false;
  std::optional<std::string> pick;
};

[[noreturn]] void usage_error(const std::string& what) { telegrasp::cli::usage_exit("telegrasp-echo", what); }

unsigned parse_topics(const std::string& list) {
  unsigned bits = 0;
  std::stringstream stream(list);
  for (std::string name; std::getline(stream, name, ',');) {
    const auto it = topic_bits().find(name);
    if (it == topic_bits().end())
      usage_error("--topics: unknown topic '" + name +
                  "' (known: HandSkeleton,GraspState,ContactSet,GraspEvent,SceneState,ServerStatus,ObjectGeometry)");
    bits |= it->second;
  }
  if (bits == 0) usage_error("--topics names no topic");
  return bits;
}

// Every flag is checked here, so the client library never sees a bad option.
Args parse_args(int argc, char** argv) {
  namespace cli = telegrasp::cli;
  Args args;
  args.options.client_id = "echo-" + std::to_string(::getpid());
  cli::for_each_option(argc, argv, kUsage, usage_error, [&](const std::string& a, const auto& value) {
    if (a == "--topics")
      args.options.topics = parse_topics(value());
    else if (telegrasp::idl::parse_network_flag(a, value, args.options, usage_error))
      ;
    else if (a == "--count")
      args.count = static_cast<std::uint64_t>(cli::parse_whole(a, value(), 1, 1'000'000'000'000, usage_error));
    else if (telegrasp::cli::is_flag("telegrasp-echo", a, "--duration-s", "--seconds"))
      args.seconds = cli::parse_number(a, value(), 0.001, 1e9, usage_error);
    else if (a == "--scenes")
      args.scenes = true;
    else if (a == "--format") {
      const std::string f = value();
      if (f != "json" && f != "text") usage_error("--format expects text or json, got '" + f + "'");
      args.json = f == "json";
    } else if (a == "--json") {  // the old spelling: every other tool's --json takes a file
      std::cerr << "telegrasp-echo: --json is deprecated, use --format json (every other tool's --json names a file)\n";
      args.json = true;
    }
    else if (a == "--pick") {
      args.pick = value();
      if (const std::string e = tc::scene_name_error(*args.pick); !e.empty()) usage_error("--pick: " + e);
    } else
      return false;
    return true;
  });
  if ((args.json || args.pick) && !args.scenes) usage_error("--format and --pick go with --scenes");
  if (args.scenes) args.options.topics = tc::kSceneDirectory;
  return args;
}

Json scene_json(const tc::SceneInfo& s) {
  return {{"scene", s.scene},
          {"host", s.host},
          {"version", s.version},
          {"incarnation", telegrasp::cli::format_hex64(s.incarnation)},
          {"started_unix_s", s.started},
          {"serving", s.serving},
          {"clients", s.clients},
          {"hands", s.hands},
          {"objects", s.objects},
          {"tick_rate_hz", s.tick_rate_hz},
          {"tick_us_p99", s.tick_us_p99},
          {"missed_ticks", s.missed_ticks},
          {"cpu_percent", s.cpu_percent},
          {"host_cores", s.host_cores},
          {"host_load", s.host_load}};
}

// --scenes: the directory after `seconds` of listening.
int list_scenes(const Args& args, tc::Client& client) {
  const auto until = std::chrono::steady_clock::now() + std::chrono::duration<double>(args.seconds.value_or(3.0));
  while (!g_signalled && std::chrono::steady_clock::now() < until)
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  const std::vector<tc::SceneInfo> scenes = client.scenes();
  if (args.pick) {
    std::optional<std::string> host;
    for (const tc::SceneInfo& s : scenes)
      if (s.scene == *args.pick) host = s.host;
    if (!host) host = tc::least_loaded_host(scenes);
    if (!host) {
      std::cerr << "telegrasp-echo: no live server on the scene directory\n";
      return telegrasp::cli::kExitFailure;
    }
    std::cout << *host << "\n";
    return 0;
  }
  if (args.json) {
    Json all = Json::array();
    for (const tc::SceneInfo& s : scenes) all.push_back(scene_json(s));
    std::cout << all.dump(2) << "\n";
  } else {
    std::printf("%-24s %-20s %-7s %7s %5s %7s %10s %6s %6s %9s\n", "scene", "host", "serving", "clients", "hands",
                "objects", "p99_ms", "missed", "cpu_%", "host_load");
    for (const tc::SceneInfo& s : scenes)
      std::printf("%-24s %-20s %-7s %7d %5d %7d %10.2f %6llu %6.1f %9.2f\n", s.scene.c_str(), s.host.c_str(),
                  s.serving ? "yes" : "no", s.clients, s.hands, s.objects, s.tick_us_p99 / 1000.0,
                  static_cast<unsigned long long>(s.missed_ticks), s.cpu_percent, s.host_load);
  }
  if (scenes.empty()) std::cerr << "telegrasp-echo: no live server on the scene directory\n";
  return scenes.empty() ? 3 : 0;
}

// Prints lines from any DDS thread, one whole line at a time, up to an optional count.
class LinePrinter {
 public:
  explicit LinePrinter(std::optional<std::uint64_t> count) : count_(count) {}

  template <class T>
  void print(const T& sample) {
    const std::string line = to_json(sample).dump();
    std::lock_guard lock(mutex_);
    if (done_) return;
    std::cout << line << '\n' << std::flush;
    ++printed_;
    // Enough, or stdout was closed (e.g. piped into head): a normal end either way.
    if (!std::cout || (count_ && printed_ >= *count_)) done_ = true;
  }

  bool done() const { return done_; }

 private:
  std::mutex mutex_;
  const std::optional<std::uint64_t> count_;
  std::uint64_t printed_ = 0;
  std::atomic<bool> done_{false};
};

}  // namespace

int main(int argc, char** argv) {
  const Args args = parse_args(argc, argv);
  std::signal(SIGINT, on_signal);
  std::signal(SIGTERM, on_signal);
  std::signal(SIGPIPE, SIG_IGN);  // a closed stdout shows up as a failed write instead

  std::optional<tc::Client> client;
  try {
    client.emplace(args.options);
  } catch (const std::exception& e) {
    std::cerr << "telegrasp-echo: " << e.what() << "\n";
    return telegrasp::cli::kExitFailure;
  }
  if (args.scenes) {
    const int status = list_scenes(args, *client);
    client.reset();
    return status;
  }
  LinePrinter printer(args.count);
  client->on_hand_skeleton([&](const tc::HandSkeleton& s) { printer.print(s); });
  client->on_grasp_state([&](const tc::GraspState& s) { printer.print(s); });
  client->on_contact_set([&](const tc::ContactSet& s) { printer.print(s); });
  client->on_grasp_event([&](const tc::GraspEvent& e) { printer.print(e); });
  client->on_scene_state([&](const tc::SceneState& s) { printer.print(s); });
  client->on_server_status([&](const tc::ServerStatus& s) { printer.print(s); });
  client->on_object_geometry([&](const std::shared_ptr<const tc::ObjectGeometry>& g) { printer.print(*g); });

  const auto start = std::chrono::steady_clock::now();
  const auto deadline = args.seconds ? start + std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                                                   std::chrono::duration<double>(*args.seconds))
                                     : std::chrono::steady_clock::time_point::max();
  while (!g_signalled && !printer.done() && std::chrono::steady_clock::now() < deadline) {
    client->take_grasp_events();  // printed by the callback; keep the polling queue empty
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  client.reset();  // no callback runs after this
  return 0;
}
