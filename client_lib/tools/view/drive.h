// Drive: what telegrasp-view --drive does with the connections that publish controller input.
// Each connection gets a client id of its own under the relay prefix (a page never picks one),
// and each of its samples goes to the server as that id's ControllerState (newest wins, never
// queued) with the rig's grip-to-palm offset applied. The server's refusals for the id come back
// to the connection as status messages, and the skeletons of its hands as they arrive.
// A hand whose page stops sending or reports tracking lost keeps its last pose and grasp for the
// tracking grace, then opens. A page that reconnects with its resume token gets its id and hands
// back, taking over from its old connection if that has gone quiet (a link that died without a
// word) or failed (then the hands are held for the resume window); a page that closes (a
// WebSocket close, or its TCP connection closed) opens its hands with one last sample and stops
// them (the server removes silent hands within 0.5 s).
// Everything runs on the bridge's io_context thread.
#pragma once

#include "controller_input.h"
#include "web_server.h"

#include "telegrasp/client/client.h"

#include <chrono>
#include <cstdint>
#include <deque>
#include <functional>
#include <map>
#include <memory>
#include <string>

namespace telegrasp::sim {
class HandRig;
}

namespace telegrasp::view {

/// `bytes` random bytes (std::random_device) as hex: tokens.
std::string random_hex(std::size_t bytes);

struct DriveOptions {
  std::string prefix = "xr-";  ///< Client ids are prefix + bridge tag + "-" + n (the server's --relay PREFIX).
  /// A hand with no tracking (or no samples: a paused session, or a link that died without a
  /// word, until the page resumes) keeps its grasp this long.
  double tracking_grace_s = 2.0;
  double resume_window_s = 5.0;  ///< A failed link's hands are held this long for its resume token.
};

struct DriveStats {
  std::size_t connections = 0;  ///< Driving now.
  std::size_t held = 0;  ///< Dropped links held for their resume token.
  std::uint64_t samples_forwarded = 0;  ///< Page samples sent to the server.
  std::uint64_t keepalives = 0;  ///< Samples the bridge sent for silent or untracked hands.
  std::uint64_t resumed = 0;  ///< Reconnections that got their id back.
  std::uint64_t notices = 0;  ///< Server refusals told to connections.
  std::uint64_t skeletons_sent = 0;  ///< Skeletons offered to the connections driving them.
};

class Drive {
 public:
  /// `rig(name)`: a rig by name (nullptr if unknown). Skeletons of driven hands go out on
  /// `hands_channel` of `server`.
  Drive(client::Client& client, WebServer& server, std::uint32_t hands_channel,
        std::function<const sim::HandRig*(const std::string&)> rig, DriveOptions options);

  /// The WebServer's hooks, bound to this.
  WebServer::DriveHooks hooks();
  /// Keep-alives and releases of silent, untracked and dropped hands: call every ~30 ms.
  void tick();
  /// A skeleton from the server (any hand; those this bridge drives go to their connection).
  void skeleton(const client::HandSkeleton& s, std::uint64_t stamp_ns);
  /// A refusal from the server for one of this bridge's ids.
  void notice(const client::Notice& n);
  DriveStats stats() const;

 private:
  using Clock = std::chrono::steady_clock;
  struct Hand {
    client::ControllerSample sample;  ///< As last sent (palm pose, trigger, curls).
    std::uint64_t page_seq = 0;  ///< The page's newest.
    Clock::time_point received{};  ///< When the page's newest arrived.
    std::optional<Clock::time_point> lost_since;  ///< No tracking (or no samples) since.
    std::uint64_t seq = 0;  ///< The bridge's numbering on the wire.
    bool released = false;  ///< Opened after the grace; still sent a little, then silent.
    /// (wire seq, page seq, page stamp) of recent samples: a skeleton's input_sequence -> the page's.
    std::deque<std::tuple<std::uint64_t, std::uint64_t, std::int64_t>> recent;
  };
  struct Driver {
    std::string client_id;
    std::string resume_token;
    std::uint64_t connection = 0;  ///< 0: the link dropped, held for its token.
    Clock::time_point detached{};
    std::map<client::HandSide, Hand> hands;
  };

  std::map<std::string, std::string> opened(std::uint64_t connection, const std::map<std::string, std::string>& query);
  std::string message(std::uint64_t connection, std::string_view payload);
  void closed(std::uint64_t connection, bool clean);
  void send(Driver& driver, Hand& hand, client::HandSide side, std::uint64_t page_seq, std::int64_t page_stamp_ns);
  Eigen::Isometry3d grip_to_palm(client::HandSide side);

  client::Client& client_;
  WebServer& server_;
  const std::uint32_t hands_channel_;
  std::function<const sim::HandRig*(const std::string&)> rig_;
  const DriveOptions options_;
  const std::string tag_;  ///< This bridge run's part of the ids.
  std::uint64_t next_id_ = 1;
  std::map<std::string, std::unique_ptr<Driver>> drivers_;  ///< By client id.
  std::map<std::uint64_t, Driver*> by_connection_;
  std::map<client::HandSide, std::string> rig_names_;  ///< Learnt from the server's skeletons.
  DriveStats stats_;
};

}  // namespace telegrasp::view
