// telegrasp-echo: subscribes to a telegrasp server's outputs through telegrasp::client and prints
// one JSON object per sample and line on stdout, e.g.
//   {"topic":"GraspEvent","event_id":3,"kind":"grasp","hand":{"client_id":"bot-a","side":"right"},...}
// Poses are {"p":[x,y,z],"q":[w,x,y,z]} in metres; NaN prints as null.
#include "telegrasp/client/client.h"

#include <nlohmann/json.hpp>

#include <atomic>
#include <charconv>
#include <chrono>
#include <csignal>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <map>
#include <mutex>
#include <optional>
#include <set>
#include <sstream>
#include <string>
#include <string_view>
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
      {"HandSkeleton", tc::kHandSkeletons}, {"GraspState", tc::kGraspStates}, {"ContactSet", tc::kContactSets},
      {"GraspEvent", tc::kGraspEvents},     {"SceneState", tc::kSceneStates}, {"ServerStatus", tc::kServerStatuses},
      {"ObjectGeometry", tc::kObjectGeometries},
  };
  return bits;
}

constexpr const char* kUsage = R"(usage: telegrasp-echo [options]
Prints every sample a telegrasp server publishes as one JSON object per line on stdout.
  --topics LIST    comma separated, from HandSkeleton,GraspState,ContactSet,GraspEvent,
                   SceneState,ServerStatus,ObjectGeometry (default: all; ObjectGeometry prints
                   a summary of each model's mesh, not the mesh)
  --domain N       DDS domain, 0..232 (default 0)
  --profile NAME   participant profile: loopback, lan, wan (default loopback)
  --profiles FILE  Fast DDS XML profiles (default $TELEGRASP_PROFILES, else the shipped file)
  --count N        exit after N lines
  --seconds S      exit after S seconds
  --help           this text
Stops cleanly on SIGINT or SIGTERM.
)";

// ---------------------------------------------------------------------------------------------
// JSON for the client types (field names as in types.h).

Json to_json(const Eigen::Vector3d& v) { return Json::array({v.x(), v.y(), v.z()}); }

Json to_json(const Eigen::Isometry3d& X) {
  const Eigen::Quaterniond q(X.linear());
  return Json{{"p", to_json(Eigen::Vector3d(X.translation()))}, {"q", Json::array({q.w(), q.x(), q.y(), q.z()})}};
}

Json to_json(const tc::HandKey& hand) { return Json{{"client_id", hand.client_id}, {"side", tc::to_string(hand.side)}}; }

Json to_json(const tc::ContactPoint& c) {
  return Json{{"phalanx", c.phalanx},           {"p_WorldContact", to_json(c.p_WorldContact)},
              {"n_World", to_json(c.n_World)},  {"p_ObjectContact", to_json(c.p_ObjectContact)},
              {"n_Object", to_json(c.n_Object)}, {"nd", c.nd},
              {"nd_hit", c.nd_hit}};
}

Json to_json(const tc::CapsuleReport& r) {
  return Json{{"phalanx", r.phalanx}, {"phalanx_name", r.phalanx_name}, {"hit", r.hit},
              {"nd", r.nd},           {"signed_distance", r.signed_distance}, {"blocked", r.blocked}};
}

Json to_json(const tc::ObjectState& o) {
  Json j{{"id", o.id},
         {"name", o.name},
         {"X_WorldObject", to_json(o.X_WorldObject)},
         {"v_WorldObject", to_json(o.v_WorldObject)},
         {"held", o.held}};
  if (o.held) j["holder"] = to_json(o.holder);
  j["spawn_time"] = o.spawn_time;
  return j;
}

template <class T>
Json to_json_array(const std::vector<T>& items) {
  Json out = Json::array();
  for (const T& item : items) out.push_back(to_json(item));
  return out;
}

Json to_json(const tc::HandSkeleton& s) {
  return Json{{"topic", "HandSkeleton"},
              {"hand", to_json(s.hand)},
              {"rig", s.rig},
              {"tick", s.tick},
              {"time", s.time},
              {"input_sequence", s.input_sequence},
              {"input_client_time_ns", s.input_client_time_ns},
              {"late_latched", s.late_latched},
              {"frozen", s.frozen},
              {"X_WorldPalm", to_json(s.X_WorldPalm)},
              {"X_WorldPhalanx", to_json_array(s.X_WorldPhalanx)},
              {"joint_angles", s.joint_angles}};
}

Json to_json(const tc::GraspState& s) {
  return Json{{"topic", "GraspState"},
              {"hand", to_json(s.hand)},
              {"tick", s.tick},
              {"time", s.time},
              {"selected_object", s.selected_object},
              {"grasped_object", s.grasped_object},
              {"trigger", s.trigger},
              {"blocked", s.blocked},
              {"palm_contact", s.palm_contact}};
}

Json to_json(const tc::ContactSet& s) {
  return Json{{"topic", "ContactSet"},
              {"hand", to_json(s.hand)},
              {"tick", s.tick},
              {"time", s.time},
              {"object_id", s.object_id},
              {"X_WorldObject", to_json(s.X_WorldObject)},
              {"contacts", to_json_array(s.contacts)}};
}

Json to_json(const tc::GraspEvent& e) {
  Json j{{"topic", "GraspEvent"},
         {"event_id", e.event_id},
         {"kind", e.kind == tc::GraspEvent::Kind::kGrasp ? "grasp" : e.kind == tc::GraspEvent::Kind::kRelease ? "release" : "unknown"},
         {"hand", to_json(e.hand)},
         {"object_id", e.object_id},
         {"object_name", e.object_name},
         {"tick", e.tick},
         {"time", e.time},
         {"object_spawn_time", e.object_spawn_time},
         {"X_WorldObject", to_json(e.X_WorldObject)},
         {"input_sequence", e.input_sequence}};
  if (e.kind == tc::GraspEvent::Kind::kRelease) {
    j["v_WorldObject"] = to_json(e.v_WorldObject);
    j["w_WorldObject"] = to_json(e.w_WorldObject);
  } else {
    j["hand_error_mm"] = e.hand_error_mm;
    j["capsules_without_hit"] = e.capsules_without_hit;
    j["capsules"] = to_json_array(e.capsules);
    j["contacts"] = to_json_array(e.contacts);
  }
  return j;
}

Json to_json(const tc::SceneState& s) {
  return Json{{"topic", "SceneState"}, {"tick", s.tick}, {"time", s.time}, {"objects", to_json_array(s.objects)}};
}

Json to_json(const tc::ServerStatus& s) {
  Json rejected = Json::object();
  for (const auto& [reason, count] : s.rejected) rejected[reason] = count;
  return Json{{"topic", "ServerStatus"},
              {"tick", s.tick},
              {"time", s.time},
              {"tick_rate_hz", s.tick_rate_hz},
              {"clients", s.clients},
              {"hands", s.hands},
              {"objects", s.objects},
              {"tick_us_p50", s.tick_us_p50},
              {"tick_us_max", s.tick_us_max},
              {"missed_ticks", s.missed_ticks},
              {"inputs_accepted", s.inputs_accepted},
              {"inputs_rejected", s.inputs_rejected},
              {"rejected", rejected},
              {"commands_accepted", s.commands_accepted},
              {"commands_rejected", s.commands_rejected},
              {"models", s.models}};
}

// A summary: the mesh itself is too large for a line.
Json to_json(const tc::ObjectGeometry& g) {
  char hash[19];
  std::snprintf(hash, sizeof hash, "%016llx", static_cast<unsigned long long>(g.content_hash));
  return Json{{"topic", "ObjectGeometry"},     {"model", g.model},
              {"content_hash", hash},          {"vertex_count", g.vertex_count},
              {"triangle_count", g.triangle_count}, {"mesh_omitted", g.mesh_omitted},
              {"p_ObjectMin", to_json(g.p_ObjectMin)}, {"p_ObjectMax", to_json(g.p_ObjectMax)},
              {"mass_kg", g.mass_kg},          {"volume_m3", g.volume_m3},
              {"inertia_diagonal", to_json(g.inertia_diagonal)}};
}

// ---------------------------------------------------------------------------------------------
// Command line.

struct Args {
  tc::ClientOptions options;
  std::optional<std::uint64_t> count;
  std::optional<double> seconds;
  bool help = false;
};

[[noreturn]] void usage_error(const std::string& message) {
  std::cerr << "telegrasp-echo: " << message << "\n" << kUsage;
  std::exit(2);
}

template <class T>
T parse_number(std::string_view flag, std::string_view text) {
  T value{};
  const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), value);
  if (error != std::errc() || end != text.data() + text.size())
    usage_error(std::string(flag) + " expects a number, got '" + std::string(text) + "'");
  return value;
}

unsigned parse_topics(const std::string& list) {
  unsigned bits = 0;
  std::stringstream stream(list);
  for (std::string name; std::getline(stream, name, ',');) {
    const auto it = topic_bits().find(name);
    if (it == topic_bits().end())
      usage_error("unknown topic '" + name + "' in --topics (known: HandSkeleton,GraspState,ContactSet,GraspEvent,SceneState,ServerStatus,ObjectGeometry)");
    bits |= it->second;
  }
  if (bits == 0) usage_error("--topics names no topic");
  return bits;
}

Args parse_args(int argc, char** argv) {
  Args args;
  args.options.client_id = "echo-" + std::to_string(::getpid());
  for (int i = 1; i < argc; ++i) {
    const std::string_view flag = argv[i];
    if (flag == "--help" || flag == "-h") {
      args.help = true;
      continue;
    }
    static const std::set<std::string_view> kTakesValue = {"--topics", "--domain", "--profile", "--profiles", "--count", "--seconds"};
    if (!kTakesValue.contains(flag)) usage_error("unknown argument " + std::string(flag));
    if (i + 1 >= argc) usage_error(std::string(flag) + " needs a value");
    const std::string value = argv[++i];
    if (flag == "--topics") {
      args.options.topics = parse_topics(value);
    } else if (flag == "--domain") {
      args.options.domain = parse_number<int>(flag, value);
    } else if (flag == "--profile") {
      args.options.profile = value;
    } else if (flag == "--profiles") {
      args.options.profiles_file = value;
    } else if (flag == "--count") {
      args.count = parse_number<std::uint64_t>(flag, value);
      if (*args.count == 0) usage_error("--count must be at least 1");
    } else if (flag == "--seconds") {
      args.seconds = parse_number<double>(flag, value);
      if (!(*args.seconds > 0) || *args.seconds > 1e9) usage_error("--seconds must be in (0, 1e9]");
    }
  }
  return args;
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
  if (args.help) {
    std::cout << kUsage;
    return 0;
  }
  std::signal(SIGINT, on_signal);
  std::signal(SIGTERM, on_signal);
  std::signal(SIGPIPE, SIG_IGN);  // a closed stdout shows up as a failed write instead

  std::optional<tc::Client> client;
  try {
    client.emplace(args.options);
  } catch (const std::exception& e) {
    std::cerr << "telegrasp-echo: " << e.what() << "\n";
    return 1;
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
