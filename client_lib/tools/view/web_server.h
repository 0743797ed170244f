// WebServer: one TCP port that serves the built-in page's files over HTTP and the Foxglove
// WebSocket protocol v1 (subprotocol foxglove.websocket.v1) to any number of viewers, with
// Boost.Beast on one io_context thread. Every viewer has its own bounded outgoing queue: a
// message of a "latest only" channel replaces that channel's unsent older one (newest wins), so
// a slow viewer skips frames and never slows the others or its caller; other messages are kept,
// and a viewer whose queue still grows past the bound is disconnected.
#pragma once

#include <boost/asio/io_context.hpp>

#include <cstdint>
#include <filesystem>
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <vector>

namespace telegrasp::view {

/// One advertised channel: JSON messages with a JSON schema.
struct Channel {
  std::uint32_t id = 0;
  std::string topic;
  std::string schema_name;
  std::string schema;  ///< JSON Schema text.
  bool latest_only = false;  ///< Each message is complete: an unsent older one may be dropped.
};

struct WebServerStats {
  std::size_t viewers = 0;  ///< Connected WebSocket viewers now.
  std::uint64_t viewers_total = 0;  ///< Since start.
  std::uint64_t messages_sent = 0;  ///< WebSocket messages written.
  std::uint64_t bytes_sent = 0;  ///< WebSocket payload bytes written (headers of TCP/WS aside).
  std::uint64_t messages_replaced = 0;  ///< Dropped for a newer one (slow viewers).
  std::uint64_t viewers_dropped = 0;  ///< Disconnected for a queue past the bound.
  std::uint64_t http_requests = 0;
  std::uint64_t drivers_total = 0;  ///< Connections allowed to publish, since start.
  std::uint64_t drive_refused = 0;  ///< Connections with --drive that may only view (no token, foreign Origin).
  std::uint64_t client_messages = 0;  ///< Published by connections and taken by DriveHooks::message.
  std::uint64_t client_messages_rejected = 0;  ///< Refused (bad op, channel, field, size), each told by a status.
  std::uint64_t closed_for_errors = 0;  ///< Connections closed for breaking the protocol too often or too big a message.
};

class WebServer {
 public:
  struct Options {
    std::string address = "0.0.0.0";
    std::uint16_t port = 8765;  ///< 0: any free port (see port()).
    std::filesystem::path web_root;  ///< The page's files; "/" is index.html.
    std::size_t max_queued_bytes = 64u << 20;  ///< Per viewer, messages kept (not latest only).
    std::string name = "telegrasp-view";
    /// Connections may publish on drive_topic (encoding json, schema drive_schema_name).
    bool drive = false;
    std::string drive_topic = "/controller_state";
    std::string drive_schema_name = "telegrasp.ControllerInput";
    /// Not empty: publishing needs ?token=<this> in the WebSocket URL (compared in constant time).
    std::string drive_token;
    /// Empty token: the Origins that may publish besides the bridge's own pages (http(s)://Host);
    /// a connection with no Origin header (not a browser) may too.
    std::vector<std::string> drive_origins;
    /// A client message larger than this closes the connection.
    std::size_t max_client_message_bytes = 16384;
    /// A connection that sends this many bad messages is closed.
    int max_protocol_errors = 32;
    /// Both set: the port also speaks TLS (HTTPS, WSS) with this certificate chain and private key
    /// (PEM); a connection that does not start with a TLS handshake is served plain.
    std::filesystem::path tls_cert, tls_key;
  };
  /// What a publishing connection brings; all called on the io_context's thread.
  struct DriveHooks {
    /// A connection that may publish opened; `query` holds its URL's query parameters. Returns the
    /// metadata of its serverInfo (its client id, a resume token).
    std::function<std::map<std::string, std::string>(std::uint64_t connection,
                                                     const std::map<std::string, std::string>& query)>
        opened;
    /// A message on drive_topic: "" taken, else what is wrong (told in a status, counted).
    std::function<std::string(std::uint64_t connection, std::string_view payload)> message;
    /// A publishing connection ended; `clean`: its peer ended it (a WebSocket close, or its TCP
    /// connection closed: the page went away), not a link that failed otherwise.
    std::function<void(std::uint64_t connection, bool clean)> closed;
  };
  /// Called on the server thread when a viewer subscribes to `channel`: the messages (payloads)
  /// that bring it up to date, sent to that viewer only, before anything published later.
  using OnSubscribe = std::function<std::vector<std::shared_ptr<const std::string>>(std::uint32_t channel)>;

  /// Binds and listens; throws std::runtime_error naming the address and port when it cannot.
  WebServer(boost::asio::io_context& io, Options options, std::vector<Channel> channels, OnSubscribe on_subscribe);
  ~WebServer();
  WebServer(const WebServer&) = delete;
  WebServer& operator=(const WebServer&) = delete;

  /// The port listened on.
  std::uint16_t port() const;
  /// Builds a complete message of a channel whose messages are deltas; called at most once.
  using Complete = std::function<std::shared_ptr<const std::string>()>;

  /// Sends `payload` on `channel` to every viewer subscribed to it, stamped `stamp_ns`. Call on
  /// the io_context's thread. For a latest-only channel whose messages are deltas (/tf carries
  /// only the frames that moved), `complete` gives the complete message that replaces an unsent
  /// older one in a slow viewer's queue, so that viewer misses no change.
  void publish(std::uint32_t channel, std::shared_ptr<const std::string> payload, std::uint64_t stamp_ns,
               const Complete& complete = {});
  /// Sets the hooks of publishing connections (before any connects).
  void set_drive_hooks(DriveHooks hooks);
  /// Sends `payload` on `channel` to `connection` alone, if it subscribed to it; an unsent older
  /// message of the same channel and `key` in its queue is replaced (newest wins).
  void send_to(std::uint64_t connection, std::uint32_t channel, std::shared_ptr<const std::string> payload,
               std::uint64_t stamp_ns, std::uint32_t key);
  /// Closes `connection` (its hooks' closed() follows, as for any end).
  void close(std::uint64_t connection);
  /// A status message (level 0 info, 1 warning, 2 error) to `connection`.
  void status_to(std::uint64_t connection, int level, const std::string& message);
  /// Closes the listener and every connection (on the io_context's thread).
  void close();
  WebServerStats stats() const;

  /// What the connections share (web_server.cc).
  struct Hub;

 private:
  std::shared_ptr<Hub> hub_;
};

}  // namespace telegrasp::view
