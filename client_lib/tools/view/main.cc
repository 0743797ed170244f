// telegrasp-view: a bridge from a telegrasp server's DDS topics to the browser. It subscribes to
// every output through telegrasp::client and serves, on one port, the Foxglove WebSocket protocol
// (Foxglove and Lichtblick connect to ws://host:8765) and a built-in three.js page
// (http://host:8765/) speaking the same protocol. See client_lib/tools/view/README.md.
#include "channels.h"
#include "drive.h"
#include "telegrasp/idl/cli.h"
#include "mcap_recorder.h"
#include "step_messages.h"
#include "telegrasp/client/client.h"
#include "telegrasp/idl/network_flags.h"
#include "telegrasp/sim/data_paths.h"
#include "telegrasp/sim/hand_rig.h"
#include "view_model.h"
#include "web_server.h"

#include <boost/asio/io_context.hpp>
#include <boost/asio/ip/address.hpp>
#include <boost/asio/post.hpp>
#include <boost/asio/signal_set.hpp>
#include <boost/asio/steady_timer.hpp>

#include <sys/resource.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdlib>
#include <iostream>
#include <map>
#include <memory>
#include <optional>
#include <string>

namespace {

namespace asio = boost::asio;
namespace tc = telegrasp::client;
namespace sim = telegrasp::sim;
namespace view = telegrasp::view;

constexpr const char* kUsage = R"(Usage: telegrasp-view [options]

Subscribes to a telegrasp server's outputs over DDS and serves them on one port:
  ws://HOST:PORT   the Foxglove WebSocket protocol (foxglove.websocket.v1): open it in Foxglove or
                   Lichtblick ("Open connection" > Foxglove WebSocket); channels /scene
                   (foxglove.SceneUpdate), /tf (foxglove.FrameTransforms), /grasp_state,
                   /grasp_events and /server_status (JSON)
  http://HOST:PORT/  the built-in 3D page (three.js, served from this installation)
Prints the URL on stdout once it listens.

Options:
  --port N           TCP port, 0..65535; 0 picks a free one (default 8765)
  --address IP       address to listen on (default 0.0.0.0: every interface; 127.0.0.1: this
                     machine only)
  --rate HZ          messages per second at most, 1..240 (default 30): the newest state is sent,
                     what came between is skipped
  --domain N         DDS domain, 0..232 (default 0)
  --profile NAME     Fast DDS participant profile: loopback (default), udp, lan, wan, secure
  --profiles FILE    Fast DDS XML profiles (default: $TELEGRASP_PROFILES, else the shipped file)
  --scene NAME       the scene (room) to show (default $TELEGRASP_SCENE, else default)
  --discovery-server HOST[:PORT]
                     a Fast DDS discovery server; repeat in id order (telegrasp-server --help)
  --web DIR          the page's files and schemas (default: share/telegrasp/view of this
                     installation or build)
  --record FILE      also write every channel into the MCAP file FILE (Foxglove and Lichtblick
                     open it with a time line; log time: the wall clock when the view built the
                     message); a chunk goes to disk at least every second, so a killed view
                     leaves FILE readable up to then; closed cleanly on SIGINT/SIGTERM
  --stats S          every S seconds print a JSON line of the bridge's CPU, hand ticks, viewers,
                     bytes sent (and recorded, with the time spent recording) to stderr
  -h, --help         this text

Driving hands from a headset (the page http://HOST:PORT/xr; the contract for other clients is
in the view's README, "Driving hands"):
  --drive            connections may publish controller input (/controller_state): each gets a
                     client id of its own under --drive-prefix; start the server with
                     --relay PREFIX so that this bridge owns those ids
  --drive-token T    driving needs ?token=T in the page's URL; with --drive on an address other
                     than 127.0.0.1 and no token, one is generated and printed in the URL
  --drive-origin O   without a token, pages from Origin O (e.g. https://example.org:8443) may
                     drive too (repeat for more); the bridge's own pages always may
  --drive-prefix P   client ids P<tag>-<n> (default xr-)
  --tracking-grace-s S
                     a hand whose tracking is lost (or whose page stops sending) keeps its grasp
                     S seconds, then opens (default 2)
  --resume-window-s S
                     a connection whose link fails (not one the page closed) keeps its hands S
                     seconds for the page to reconnect with its resume token (default 5); a page
                     whose link died without a word gets them back within the tracking grace
  --tls-cert FILE    with --tls-key: the port also serves HTTPS and WSS with this certificate
  --tls-key FILE     chain and private key (PEM; deploy/make-cert.sh makes a self-signed pair for
                     a LAN host name or IP); plain HTTP keeps working on the same port. Headset
                     browsers give WebXR only to https:// pages (or http://localhost)

Exit status: 0 stopped by SIGINT or SIGTERM, 1 a runtime failure (DDS could not start, the port
is in use, the page or schema files are missing, the --record file is not writable), 2 a usage
error (a bad or missing option or value). A recording that fails later (disk full) stops with a
message; the view keeps serving.
)";

[[noreturn]] void usage_error(const std::string& what) { telegrasp::cli::usage_exit("telegrasp-view", what); }

struct Args {
  tc::ClientOptions client;
  std::string address = "0.0.0.0";
  std::uint16_t port = 8765;
  double rate_hz = 30;
  std::string web_dir;
  double stats_s = 0;
  std::string record_path;
  bool drive = false;
  std::string drive_token;
  std::vector<std::string> drive_origins;
  view::DriveOptions drive_options;
  std::string tls_cert, tls_key;
};

// Every flag is checked here, so the client library never sees a bad option.

// A chunk of the --record file reaches the disk at least this often.
constexpr std::uint64_t kRecordFlushNs = 1'000'000'000;
Args parse(int argc, char** argv) {
  namespace cli = telegrasp::cli;
  Args a;
  a.client.client_id = "view-" + std::to_string(::getpid());
  cli::for_each_option(argc, argv, kUsage, usage_error, [&](const std::string& flag, const auto& value) {
    if (flag == "--port")
      a.port = static_cast<std::uint16_t>(cli::parse_whole(flag, value(), 0, 65535, usage_error));
    else if (flag == "--address")
      a.address = value();
    else if (flag == "--rate")
      a.rate_hz = cli::parse_number(flag, value(), 1, 240, usage_error);
    else if (telegrasp::idl::parse_network_flag(flag, value, a.client, usage_error))
      ;
    else if (flag == "--web")
      a.web_dir = value();
    else if (flag == "--stats")
      a.stats_s = cli::parse_number(flag, value(), 0.1, 86400, usage_error);
    else if (flag == "--drive")
      a.drive = true;
    else if (flag == "--drive-token") {
      a.drive_token = value();
      if (a.drive_token.size() < 8 || a.drive_token.find_first_not_of(
                                          "abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789-_") !=
                                          std::string::npos)
        usage_error("--drive-token expects 8 or more letters, digits, '-' or '_'");
    } else if (flag == "--drive-origin")
      a.drive_origins.push_back(value());
    else if (flag == "--drive-prefix") {
      a.drive_options.prefix = value();
      if (a.drive_options.prefix.empty() || a.drive_options.prefix.size() > 32)
        usage_error("--drive-prefix expects 1..32 characters");
    } else if (telegrasp::cli::is_flag("telegrasp-view", flag, "--tracking-grace-s", "--tracking-grace"))
      a.drive_options.tracking_grace_s = cli::parse_number(flag, value(), 0, 60, usage_error);
    else if (telegrasp::cli::is_flag("telegrasp-view", flag, "--resume-window-s", "--resume-window"))
      a.drive_options.resume_window_s = cli::parse_number(flag, value(), 0, 600, usage_error);
    else if (flag == "--tls-cert")
      a.tls_cert = value();
    else if (flag == "--tls-key")
      a.tls_key = value();
    else if (flag == "--record") {
      a.record_path = value();
      if (a.record_path.empty()) usage_error("--record expects a file name, got ''");
    } else
      return false;
    return true;
  });
  if (a.drive) a.client.relay_prefix = a.drive_options.prefix;
  if (a.tls_cert.empty() != a.tls_key.empty()) usage_error("--tls-cert and --tls-key go together");
  return a;
}

bool is_loopback(const std::string& address) {
  boost::system::error_code ec;
  const auto a = boost::asio::ip::make_address(address, ec);
  return !ec && a.is_loopback();
}

std::uint64_t wall_ns() {
  return static_cast<std::uint64_t>(
      std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::system_clock::now().time_since_epoch())
          .count());
}

double cpu_seconds() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return static_cast<double>(usage.ru_utime.tv_sec + usage.ru_stime.tv_sec) +
         1e-6 * static_cast<double>(usage.ru_utime.tv_usec + usage.ru_stime.tv_usec);
}

std::uint64_t steady_ns() {
  return static_cast<std::uint64_t>(
      std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::steady_clock::now().time_since_epoch())
          .count());
}

using view::payload;

// The rigs HandSkeleton names, loaded once each from the shipped files; unknown ones are null.
class RigCache {
 public:
  const sim::HandRig* get(const std::string& name) {
    auto [it, added] = rigs_.try_emplace(name);
    if (added) {
      try {
        it->second = std::make_unique<sim::HandRig>(sim::HandRig::load(sim::HandRig::builtin_path(name)));
      } catch (const std::exception& e) {
        std::cerr << "telegrasp-view: hands of rig '" << name << "' are drawn as joint spheres: " << e.what() << "\n";
      }
    }
    return it->second.get();
  }

 private:
  std::map<std::string, std::unique_ptr<sim::HandRig>> rigs_;
};

// Counts for --stats: CPU of the whole process (DDS threads included) per hand tick.
struct Meter {
  double cpu_s = cpu_seconds();
  std::chrono::steady_clock::time_point wall = std::chrono::steady_clock::now();
  std::uint64_t hand_ticks = 0;
  std::uint64_t bytes_sent = 0;
  std::uint64_t bytes_recorded = 0;
  std::uint64_t steps = 0;
  std::uint64_t record_ns = 0;  ///< Steady-clock time spent in the recorder.
};

}  // namespace

int main(int argc, char** argv) {
  const Args args = parse(argc, argv);

  const std::filesystem::path web_root =
      args.web_dir.empty() ? sim::data_dir() / "view" : std::filesystem::path(args.web_dir);
  for (const char* needed : {"index.html", "vendor/three/build/three.module.js"}) {
    if (!std::filesystem::is_regular_file(web_root / needed)) {
      std::cerr
          << "telegrasp-view: " << (web_root / needed).string() << " not found (the build stages the page and "
          << "three.js from client_lib/tools/view/web/node_modules: run deploy/install-deps.sh, then build again)\n";
      return telegrasp::cli::kExitFailure;
    }
  }
  std::vector<view::Channel> channels;
  try {
    channels = view::view_channels(web_root / "schemas");
  } catch (const std::exception& e) {
    std::cerr << "telegrasp-view: " << e.what() << "\n";
    return telegrasp::cli::kExitFailure;
  }

  std::optional<view::McapRecorder> recorder;
  if (!args.record_path.empty()) {
    try {
      recorder.emplace(args.record_path, channels, view::McapRecorder::Options{.flush_interval_ns = kRecordFlushNs});
    } catch (const std::exception& e) {
      std::cerr << "telegrasp-view: --record: " << e.what() << "\n";
      return 1;
    }
  }

  std::optional<tc::Client> client;
  try {
    client.emplace(args.client);
  } catch (const std::exception& e) {
    std::cerr << "telegrasp-view: " << e.what() << "\n";
    return telegrasp::cli::kExitFailure;
  }

  RigCache rigs;
  view::ViewModel model([&](const std::string& name) { return rigs.get(name); });
  asio::io_context io;
  std::optional<view::WebServer> server;
  std::string drive_token = args.drive_token;
  if (args.drive && drive_token.empty() && !is_loopback(args.address))
    drive_token = view::random_hex(16);  // off this machine, driving always needs a token
  if (args.drive) channels.push_back(view::driven_hands_channel());
  try {
    view::WebServer::Options options;
    options.address = args.address;
    options.port = args.port;
    options.web_root = web_root;
    options.drive = args.drive;
    options.drive_token = drive_token;
    options.drive_origins = args.drive_origins;
    options.tls_cert = args.tls_cert;
    options.tls_key = args.tls_key;
    // Everything below runs on this thread (io.run()): the model needs no lock.
    server.emplace(io, options, std::move(channels), [&](std::uint32_t channel) {
      std::vector<std::shared_ptr<const std::string>> out;
      const std::uint64_t now = wall_ns();
      switch (channel) {
        case view::kSceneChannel:
          out.push_back(payload(model.scene_full(now)));
          break;
        case view::kTransformsChannel:
          if (auto tf = model.transforms_full(now)) out.push_back(payload(*tf));
          break;
        case view::kGraspStateChannel:
          for (const view::Json& s : model.grasp_states_full()) out.push_back(payload(s));
          break;
        case view::kGraspEventsChannel:
          for (const view::Json& e : model.event_history()) out.push_back(payload(e));
          break;
        case view::kServerStatusChannel:
          if (model.server_status()) out.push_back(payload(*model.server_status()));
          break;
        default:
          break;
      }
      return out;
    });
  } catch (const std::exception& e) {
    std::cerr << "telegrasp-view: " << e.what() << "\n";
    return telegrasp::cli::kExitFailure;
  }
  const std::string host = args.address == "0.0.0.0" ? "localhost" : args.address;
  std::cout << "telegrasp-view: http://" << host << ":" << server->port() << "/ (page), ws://" << host << ":"
            << server->port() << " (Foxglove WebSocket), DDS domain " << args.client.domain
            << (args.tls_cert.empty() ? "" : "; https:// and wss:// on the same port") << std::endl;

  // --drive: connections publish controller input, forwarded as client ids under the prefix.
  std::optional<view::Drive> drive;
  asio::steady_timer drive_timer(io);
  std::function<void()> drive_tick = [&] {
    drive->tick();
    drive_timer.expires_after(std::chrono::milliseconds(30));
    drive_timer.async_wait([&](boost::system::error_code ec) {
      if (!ec) drive_tick();
    });
  };
  if (args.drive) {
    drive.emplace(*client, *server, view::kDrivenHandsChannel, [&](const std::string& name) { return rigs.get(name); },
                  args.drive_options);
    server->set_drive_hooks(drive->hooks());
    const std::string prefix = args.drive_options.prefix;
    // DDS threads hand the driven hands' skeletons and refusals to the io thread as they arrive.
    client->on_hand_skeleton([&io, &drive, prefix](const tc::HandSkeleton& s) {
      if (s.hand.client_id.starts_with(prefix)) asio::post(io, [&drive, s] { drive->skeleton(s, wall_ns()); });
    });
    client->on_notice([&io, &drive, prefix](const tc::Notice& n) {
      if (n.client_id.starts_with(prefix)) asio::post(io, [&drive, n] { drive->notice(n); });
    });
    drive_tick();
    std::cout << "telegrasp-view: headsets drive hands at " << (args.tls_cert.empty() ? "http" : "https") << "://" << host << ":" << server->port() << "/xr"
              << (drive_token.empty() ? "" : "?token=" + drive_token) << " (client ids " << prefix
              << "*: start the server with --relay " << prefix << ")" << std::endl;
  }

  // One step per 1/rate: poll the client (newest of everything), update the model, publish.
  const auto period = std::chrono::duration_cast<std::chrono::steady_clock::duration>(
      std::chrono::duration<double>(1.0 / args.rate_hz));
  asio::steady_timer timer(io);
  Meter meter;
  std::optional<std::uint64_t> last_scene_tick;
  auto next_stats = std::chrono::steady_clock::now() + std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                                                           std::chrono::duration<double>(args.stats_s));
  std::function<void()> step = [&] {
    view::ClientSnapshot snap;
    snap.skeletons = client->latest_hand_skeletons();
    for (const tc::HandSkeleton& s : snap.skeletons) {
      if (auto g = client->latest_grasp_state(s.hand)) snap.grasp_states.emplace(s.hand, std::move(*g));
      if (auto c = client->latest_contact_set(s.hand)) snap.contact_sets.emplace(s.hand, std::move(*c));
    }
    snap.scene = client->latest_scene_state();
    snap.status = client->latest_server_status();
    snap.events = client->take_grasp_events();
    snap.geometries = client->object_geometries();
    if (snap.scene) {
      if (last_scene_tick && snap.scene->tick > *last_scene_tick)
        meter.hand_ticks += (snap.scene->tick - *last_scene_tick) * snap.skeletons.size();
      last_scene_tick = snap.scene->tick;
    }

    // One time for the step: the messages' stamps and, when recording, their log time.
    const std::uint64_t now = wall_ns();
    const view::ViewUpdate update = model.update(snap, now);
    const std::vector<view::StepMessage> messages = view::step_messages(update);
    for (const view::StepMessage& m : messages) {
      if (m.channel == view::kTransformsChannel && !update.transforms_complete)
        server->publish(m.channel, m.payload, now, [&] { return payload(*model.transforms_full(now)); });
      else
        server->publish(m.channel, m.payload, now);
    }
    ++meter.steps;
    if (recorder) {
      const std::uint64_t t0 = steady_ns();
      try {
        recorder->record(messages, model, now);
        recorder->flush_if_due(t0);
      } catch (const std::exception& e) {
        std::cerr << "telegrasp-view: recording stopped: " << e.what() << "\n";
        recorder.reset();
      }
      meter.record_ns += steady_ns() - t0;
    }

    if (args.stats_s > 0 && std::chrono::steady_clock::now() >= next_stats) {
      const view::WebServerStats s = server->stats();
      const double cpu = cpu_seconds(),
                   wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - meter.wall).count();
      const std::uint64_t ticks = meter.hand_ticks;
      const std::uint64_t recorded = recorder ? recorder->writer().bytes_written() : meter.bytes_recorded;
      view::Json line{{"viewers", s.viewers},
                        {"hands", snap.skeletons.size()},
                        {"objects", model.object_count()},
                        {"seconds", wall},
                        {"cpu_percent", 100 * (cpu - meter.cpu_s) / wall},
                        {"hand_ticks", ticks},
                        {"cpu_us_per_hand_tick", ticks ? 1e6 * (cpu - meter.cpu_s) / static_cast<double>(ticks) : 0.0},
                        {"sent_kb_per_s", static_cast<double>(s.bytes_sent - meter.bytes_sent) / 1024.0 / wall},
                        {"messages_sent", s.messages_sent},
                        {"messages_replaced", s.messages_replaced},
                        {"viewers_dropped", s.viewers_dropped},
                        {"recording", recorder.has_value()},
                        {"recorded_kb_per_s", static_cast<double>(recorded - meter.bytes_recorded) / 1024.0 / wall},
                        {"record_us_per_step",
                         meter.steps ? 1e-3 * static_cast<double>(meter.record_ns) / static_cast<double>(meter.steps)
                                     : 0.0}};
      if (drive) {
        const view::DriveStats d = drive->stats();
        line["drive"] = {{"connections", d.connections},         {"held", d.held},
                         {"samples_forwarded", d.samples_forwarded}, {"keepalives", d.keepalives},
                         {"resumed", d.resumed},                 {"notices", d.notices},
                         {"skeletons_sent", d.skeletons_sent},   {"refused_connections", s.drive_refused},
                         {"messages_rejected", s.client_messages_rejected},
                         {"closed_for_errors", s.closed_for_errors}};
      }
      std::cerr << line.dump() << std::endl;

      meter = Meter{};
      meter.bytes_sent = s.bytes_sent;
      meter.bytes_recorded = recorded;
      next_stats +=
          std::chrono::duration_cast<std::chrono::steady_clock::duration>(std::chrono::duration<double>(args.stats_s));
    }
    timer.expires_at(std::max(timer.expiry() + period, std::chrono::steady_clock::now()));
    timer.async_wait([&](boost::system::error_code ec) {
      if (!ec) step();
    });
  };
  timer.expires_after(period);
  timer.async_wait([&](boost::system::error_code ec) {
    if (!ec) step();
  });

  asio::signal_set signals(io, SIGINT, SIGTERM);
  signals.async_wait([&](boost::system::error_code, int) {
    timer.cancel();
    drive_timer.cancel();
    server->close();
    io.stop();
  });
  io.run();
  server.reset();
  client.reset();
  if (recorder) {
    try {
      recorder->close();
      std::cerr << "telegrasp-view: recorded " << recorder->writer().message_count() << " messages ("
                << telegrasp::cli::format_number(
                       std::round(static_cast<double>(recorder->writer().bytes_written()) / 1024.0))
                << " KiB) to " << args.record_path << "\n";
    } catch (const std::exception& e) {
      std::cerr << "telegrasp-view: closing the recording: " << e.what() << "\n";
    }
  }
  return 0;
}
