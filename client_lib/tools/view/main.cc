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
#include <stdexcept>
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
    else if (cli::text_flag(flag, value,
                            {{"--address", &a.address}, {"--web", &a.web_dir}, {"--tls-cert", &a.tls_cert},
                             {"--tls-key", &a.tls_key}}))
      ;
    else if (flag == "--rate")
      a.rate_hz = cli::parse_number(flag, value(), 1, 240, usage_error);
    else if (telegrasp::idl::parse_network_flag(flag, value, a.client, usage_error))
      ;
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

// A failure before serving: its message, then exit 1.
struct Failure : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// The running bridge. Everything but the client library's DDS threads runs on one thread
// (io_.run()), so the model needs no lock.
class Bridge {
 public:
  explicit Bridge(const Args& args) : args_(args) {}

  // The page, the channels, the recording, the DDS client and the web server; throws Failure.
  void open() {
    const std::filesystem::path web_root =
        args_.web_dir.empty() ? sim::data_dir() / "view" : std::filesystem::path(args_.web_dir);
    for (const char* needed : {"index.html", "vendor/three/build/three.module.js"})
      if (!std::filesystem::is_regular_file(web_root / needed))
        throw Failure((web_root / needed).string() + " not found (the build stages the page and " +
                      "three.js from client_lib/tools/view/web/node_modules: run deploy/install-deps.sh, then build again)");
    std::vector<view::Channel> channels;
    try {
      channels = view::view_channels(web_root / "schemas");
    } catch (const std::exception& e) {
      throw Failure(e.what());
    }
    if (!args_.record_path.empty()) {
      try {
        recorder_.emplace(args_.record_path, channels, view::McapRecorder::Options{.flush_interval_ns = kRecordFlushNs});
      } catch (const std::exception& e) {
        throw Failure(std::string("--record: ") + e.what());
      }
    }
    try {
      client_.emplace(args_.client);
    } catch (const std::exception& e) {
      throw Failure(e.what());
    }
    drive_token_ = args_.drive_token;
    if (args_.drive && drive_token_.empty() && !is_loopback(args_.address))
      drive_token_ = view::random_hex(16);  // off this machine, driving always needs a token
    if (args_.drive) channels.push_back(view::driven_hands_channel());
    try {
      view::WebServer::Options options;
      options.address = args_.address;
      options.port = args_.port;
      options.web_root = web_root;
      options.drive = args_.drive;
      options.drive_token = drive_token_;
      options.drive_origins = args_.drive_origins;
      options.tls_cert = args_.tls_cert;
      options.tls_key = args_.tls_key;
      server_.emplace(io_, options, std::move(channels), [this](std::uint32_t channel) { return full(channel); });
    } catch (const std::exception& e) {
      throw Failure(e.what());
    }
    host_ = args_.address == "0.0.0.0" ? "localhost" : args_.address;
    std::cout << "telegrasp-view: http://" << host_ << ":" << server_->port() << "/ (page), ws://" << host_ << ":"
              << server_->port() << " (Foxglove WebSocket), DDS domain " << args_.client.domain
              << (args_.tls_cert.empty() ? "" : "; https:// and wss:// on the same port") << std::endl;
  }

  // --drive: connections publish controller input, forwarded as client ids under the prefix.
  void start_drive() {
    if (!args_.drive) return;
    drive_.emplace(*client_, *server_, view::kDrivenHandsChannel, [this](const std::string& name) { return rigs_.get(name); },
                   args_.drive_options);
    server_->set_drive_hooks(drive_->hooks());
    const std::string prefix = args_.drive_options.prefix;
    // DDS threads hand the driven hands' skeletons and refusals to the io thread as they arrive.
    client_->on_hand_skeleton([this, prefix](const tc::HandSkeleton& s) {
      if (s.hand.client_id.starts_with(prefix)) asio::post(io_, [this, s] { drive_->skeleton(s, wall_ns()); });
    });
    client_->on_notice([this, prefix](const tc::Notice& n) {
      if (n.client_id.starts_with(prefix)) asio::post(io_, [this, n] { drive_->notice(n); });
    });
    drive_tick();
    std::cout << "telegrasp-view: headsets drive hands at " << (args_.tls_cert.empty() ? "http" : "https") << "://"
              << host_ << ":" << server_->port() << "/xr" << (drive_token_.empty() ? "" : "?token=" + drive_token_)
              << " (client ids " << prefix << "*: start the server with --relay " << prefix << ")" << std::endl;
  }

  // Steps every 1/--rate until SIGINT or SIGTERM, then closes the server and the client.
  void run() {
    meter_ = Meter{};
    next_stats_ = std::chrono::steady_clock::now() + seconds(args_.stats_s);
    timer_.expires_after(period());
    timer_.async_wait([this](boost::system::error_code ec) {
      if (!ec) step();
    });
    asio::signal_set signals(io_, SIGINT, SIGTERM);
    signals.async_wait([this](boost::system::error_code, int) {
      timer_.cancel();
      drive_timer_.cancel();
      server_->close();
      io_.stop();
    });
    io_.run();
    server_.reset();
    client_.reset();
  }

  void close_recording() {
    if (!recorder_) return;
    try {
      recorder_->close();
      std::cerr << "telegrasp-view: recorded " << recorder_->writer().message_count() << " messages ("
                << telegrasp::cli::format_number(
                       std::round(static_cast<double>(recorder_->writer().bytes_written()) / 1024.0))
                << " KiB) to " << args_.record_path << "\n";
    } catch (const std::exception& e) {
      std::cerr << "telegrasp-view: closing the recording: " << e.what() << "\n";
    }
  }

 private:
  static std::chrono::steady_clock::duration seconds(double s) {
    return std::chrono::duration_cast<std::chrono::steady_clock::duration>(std::chrono::duration<double>(s));
  }
  std::chrono::steady_clock::duration period() const { return seconds(1.0 / args_.rate_hz); }

  // A channel's whole state, for a viewer that subscribes to it.
  std::vector<std::shared_ptr<const std::string>> full(std::uint32_t channel) {
    std::vector<std::shared_ptr<const std::string>> out;
    const std::uint64_t now = wall_ns();
    switch (channel) {
      case view::kSceneChannel:
        out.push_back(payload(model_.scene_full(now)));
        break;
      case view::kTransformsChannel:
        if (auto tf = model_.transforms_full(now)) out.push_back(payload(*tf));
        break;
      case view::kGraspStateChannel:
        for (const view::Json& s : model_.grasp_states_full()) out.push_back(payload(s));
        break;
      case view::kGraspEventsChannel:
        for (const view::Json& e : model_.event_history()) out.push_back(payload(e));
        break;
      case view::kServerStatusChannel:
        if (model_.server_status()) out.push_back(payload(*model_.server_status()));
        break;
      default:
        break;
    }
    return out;
  }

  void drive_tick() {
    drive_->tick();
    drive_timer_.expires_after(std::chrono::milliseconds(30));
    drive_timer_.async_wait([this](boost::system::error_code ec) {
      if (!ec) drive_tick();
    });
  }

  // One step: poll the client (newest of everything), update the model, publish, record.
  void step() {
    view::ClientSnapshot snap;
    snap.skeletons = client_->latest_hand_skeletons();
    for (const tc::HandSkeleton& s : snap.skeletons) {
      if (auto g = client_->latest_grasp_state(s.hand)) snap.grasp_states.emplace(s.hand, std::move(*g));
      if (auto c = client_->latest_contact_set(s.hand)) snap.contact_sets.emplace(s.hand, std::move(*c));
    }
    snap.scene = client_->latest_scene_state();
    snap.status = client_->latest_server_status();
    snap.events = client_->take_grasp_events();
    snap.geometries = client_->object_geometries();
    if (snap.scene) {
      if (last_scene_tick_ && snap.scene->tick > *last_scene_tick_)
        meter_.hand_ticks += (snap.scene->tick - *last_scene_tick_) * snap.skeletons.size();
      last_scene_tick_ = snap.scene->tick;
    }

    // One time for the step: the messages' stamps and, when recording, their log time.
    const std::uint64_t now = wall_ns();
    const view::ViewUpdate update = model_.update(snap, now);
    const std::vector<view::StepMessage> messages = view::step_messages(update);
    for (const view::StepMessage& m : messages) {
      if (m.channel == view::kTransformsChannel && !update.transforms_complete)
        server_->publish(m.channel, m.payload, now, [&] { return payload(*model_.transforms_full(now)); });
      else
        server_->publish(m.channel, m.payload, now);
    }
    ++meter_.steps;
    if (recorder_) {
      const std::uint64_t t0 = steady_ns();
      try {
        recorder_->record(messages, model_, now);
        recorder_->flush_if_due(t0);
      } catch (const std::exception& e) {
        std::cerr << "telegrasp-view: recording stopped: " << e.what() << "\n";
        recorder_.reset();
      }
      meter_.record_ns += steady_ns() - t0;
    }
    if (args_.stats_s > 0 && std::chrono::steady_clock::now() >= next_stats_) print_stats(snap.skeletons.size());
    timer_.expires_at(std::max(timer_.expiry() + period(), std::chrono::steady_clock::now()));
    timer_.async_wait([this](boost::system::error_code ec) {
      if (!ec) step();
    });
  }

  // --stats: one JSON line on stderr over the period since the last.
  void print_stats(std::size_t hands) {
    const view::WebServerStats s = server_->stats();
    const double cpu = cpu_seconds(),
                 wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - meter_.wall).count();
    const std::uint64_t ticks = meter_.hand_ticks;
    const std::uint64_t recorded = recorder_ ? recorder_->writer().bytes_written() : meter_.bytes_recorded;
    view::Json line{{"viewers", s.viewers},
                    {"hands", hands},
                    {"objects", model_.object_count()},
                    {"seconds", wall},
                    {"cpu_percent", 100 * (cpu - meter_.cpu_s) / wall},
                    {"hand_ticks", ticks},
                    {"cpu_us_per_hand_tick", ticks ? 1e6 * (cpu - meter_.cpu_s) / static_cast<double>(ticks) : 0.0},
                    {"sent_kb_per_s", static_cast<double>(s.bytes_sent - meter_.bytes_sent) / 1024.0 / wall},
                    {"messages_sent", s.messages_sent},
                    {"messages_replaced", s.messages_replaced},
                    {"viewers_dropped", s.viewers_dropped},
                    {"recording", recorder_.has_value()},
                    {"recorded_kb_per_s", static_cast<double>(recorded - meter_.bytes_recorded) / 1024.0 / wall},
                    {"record_us_per_step",
                     meter_.steps ? 1e-3 * static_cast<double>(meter_.record_ns) / static_cast<double>(meter_.steps)
                                  : 0.0}};
    if (drive_) {
      const view::DriveStats d = drive_->stats();
      line["drive"] = {{"connections", d.connections},         {"held", d.held},
                       {"samples_forwarded", d.samples_forwarded}, {"keepalives", d.keepalives},
                       {"resumed", d.resumed},                 {"notices", d.notices},
                       {"skeletons_sent", d.skeletons_sent},   {"refused_connections", s.drive_refused},
                       {"messages_rejected", s.client_messages_rejected},
                       {"closed_for_errors", s.closed_for_errors}};
    }
    std::cerr << line.dump() << std::endl;
    meter_ = Meter{};
    meter_.bytes_sent = s.bytes_sent;
    meter_.bytes_recorded = recorded;
    next_stats_ += seconds(args_.stats_s);
  }

  const Args& args_;
  RigCache rigs_;
  view::ViewModel model_{[this](const std::string& name) { return rigs_.get(name); }};
  asio::io_context io_;
  std::optional<view::McapRecorder> recorder_;
  std::optional<tc::Client> client_;
  std::optional<view::WebServer> server_;
  std::optional<view::Drive> drive_;
  asio::steady_timer drive_timer_{io_};
  asio::steady_timer timer_{io_};
  std::string drive_token_, host_;
  Meter meter_;
  std::optional<std::uint64_t> last_scene_tick_;
  std::chrono::steady_clock::time_point next_stats_;
};

}  // namespace

int main(int argc, char** argv) {
  const Args args = parse(argc, argv);
  Bridge bridge(args);
  try {
    bridge.open();
  } catch (const Failure& e) {
    std::cerr << "telegrasp-view: " << e.what() << "\n";
    return telegrasp::cli::kExitFailure;
  }
  bridge.start_drive();
  bridge.run();
  bridge.close_recording();
  return 0;
}
