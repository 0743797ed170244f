#include "web_server.h"

#include <boost/asio/ip/tcp.hpp>
#include <boost/asio/ssl.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/core/detect_ssl.hpp>
#include <boost/beast/http.hpp>
#include <boost/beast/ssl.hpp>
#include <boost/beast/websocket.hpp>
#include <boost/beast/websocket/ssl.hpp>
#include <nlohmann/json.hpp>

#include <array>
#include <chrono>
#include <deque>
#include <iostream>
#include <map>
#include <optional>
#include <set>
#include <stdexcept>

namespace telegrasp::view {
namespace {

namespace asio = boost::asio;
namespace beast = boost::beast;
namespace http = beast::http;
namespace websocket = beast::websocket;
using tcp = asio::ip::tcp;
namespace ssl = asio::ssl;
using TlsStream = beast::ssl_stream<beast::tcp_stream>;
using Json = nlohmann::json;

constexpr const char* kSubprotocol = "foxglove.websocket.v1";
constexpr std::size_t kMaxRequestBytes = 1 << 20;  // an HTTP request

// What the hub asks of a viewer, whether its connection is plain or TLS.
class Viewer {
 public:
  virtual ~Viewer() = default;
  virtual void offer(std::uint32_t channel, const std::shared_ptr<const std::string>& payload, std::uint64_t stamp_ns,
                     bool latest_only, const WebServer::Complete& complete = {}, std::uint32_t key = 0) = 0;
  virtual void status(int level, const std::string& message) = 0;
  virtual void close() = 0;
};

std::string_view mime_type(const std::filesystem::path& path) {
  const std::string ext = path.extension().string();
  if (ext == ".html") return "text/html; charset=utf-8";
  if (ext == ".js" || ext == ".mjs") return "text/javascript; charset=utf-8";
  if (ext == ".css") return "text/css; charset=utf-8";
  if (ext == ".json") return "application/json";
  if (ext == ".png") return "image/png";
  if (ext == ".svg") return "image/svg+xml";
  return "application/octet-stream";
}

// Whether a Sec-WebSocket-Protocol header value lists `wanted` (comma separated).
bool lists_protocol(std::string_view header, std::string_view wanted) {
  while (!header.empty()) {
    const std::size_t comma = header.find(',');
    std::string_view item = header.substr(0, comma);
    while (!item.empty() && item.front() == ' ') item.remove_prefix(1);
    while (!item.empty() && item.back() == ' ') item.remove_suffix(1);
    if (item == wanted) return true;
    if (comma == std::string_view::npos) break;
    header.remove_prefix(comma + 1);
  }
  return false;
}

// The query parameters of a request target ("/?a=1&b=2"), undecoded (tokens are hex).
std::map<std::string, std::string> query_of(std::string_view target) {
  std::map<std::string, std::string> query;
  const std::size_t question = target.find('?');
  if (question == std::string_view::npos) return query;
  std::string_view rest = target.substr(question + 1);
  while (!rest.empty()) {
    const std::size_t amp = rest.find('&');
    const std::string_view item = rest.substr(0, amp);
    const std::size_t eq = item.find('=');
    if (eq != std::string_view::npos) query[std::string(item.substr(0, eq))] = std::string(item.substr(eq + 1));
    if (amp == std::string_view::npos) break;
    rest.remove_prefix(amp + 1);
  }
  return query;
}

// Equal in a time that depends on the lengths only, not on where the first difference is.
bool constant_time_equal(std::string_view a, std::string_view b) {
  unsigned char diff = a.size() == b.size() ? 0 : 1;
  for (std::size_t i = 0; i < a.size(); ++i) diff |= static_cast<unsigned char>(a[i] ^ (i < b.size() ? b[i] : 0));
  return diff == 0;
}

}  // namespace

// What every session shares: options, channels, the registry of viewers, the counters.
struct WebServer::Hub {
  asio::io_context& io;
  Options options;
  std::vector<Channel> channels;
  std::map<std::uint32_t, const Channel*> channel_by_id;
  OnSubscribe on_subscribe;
  tcp::acceptor acceptor;
  std::set<std::shared_ptr<Viewer>> viewers;
  std::optional<ssl::context> tls;  // with a certificate: TLS connections are served too
  WebServerStats stats;
  std::string advertise;  // the Advertise message, the same for every viewer
  Json server_info;  // the Server Info message, without a connection's own capabilities and metadata
  DriveHooks drive_hooks;
  std::uint64_t next_connection = 1;
  std::map<std::uint64_t, Viewer*> by_id;  // the live sessions of `viewers`
  bool closed = false;

  Hub(asio::io_context& io_, Options o, std::vector<Channel> c, OnSubscribe s)
      : io(io_), options(std::move(o)), channels(std::move(c)), on_subscribe(std::move(s)), acceptor(io_) {}
};

namespace {

// One WebSocket viewer speaking foxglove.websocket.v1.
// `Stream`: beast::tcp_stream, or TlsStream.
template <class Stream>
class ViewerSession : public Viewer, public std::enable_shared_from_this<ViewerSession<Stream>> {
 public:
  using std::enable_shared_from_this<ViewerSession<Stream>>::shared_from_this;
  // `drive`: this connection may publish (else `why_not_drive` says why, if driving is on).
  ViewerSession(Stream&& stream, WebServer::Hub& hub, std::uint64_t id, bool drive, std::string why_not_drive,
                std::map<std::string, std::string> query)
      : ws_(std::move(stream)),
        hub_(hub),
        id_(id),
        drive_(drive),
        why_not_drive_(std::move(why_not_drive)),
        query_(std::move(query)) {}

  std::uint64_t id() const { return id_; }

  void start(http::request<http::string_body> request) {
    ws_.set_option(websocket::stream_base::timeout::suggested(beast::role_type::server));
    ws_.set_option(websocket::stream_base::decorator([name = hub_.options.name](websocket::response_type& res) {
      res.set(http::field::server, name);
      res.set(http::field::sec_websocket_protocol, kSubprotocol);
    }));
    ws_.read_message_max(hub_.options.max_client_message_bytes);
    ws_.async_accept(request, [self = shared_from_this()](beast::error_code ec) { self->on_accept(ec); });
  }

  // Queues a Message Data frame of `channel` if this viewer subscribed to it.
  void offer(std::uint32_t channel, const std::shared_ptr<const std::string>& payload, std::uint64_t stamp_ns,
             bool latest_only, const WebServer::Complete& complete = {}, std::uint32_t key = 0) override {
    const auto sub = subscription_of_channel_.find(channel);
    if (sub == subscription_of_channel_.end()) return;
    enqueue(Out{message_header(sub->second, stamp_ns), payload, false, static_cast<std::int64_t>(channel), latest_only,
                key},
            complete);
  }

  void status(int level, const std::string& message) override {
    send_text(Json{{"op", "status"}, {"level", level}, {"message", message}}.dump());
  }

  void close() override {
    if (closing_) return;
    closing_ = true;
    beast::error_code ec;
    beast::get_lowest_layer(ws_).socket().shutdown(tcp::socket::shutdown_both, ec);
    beast::get_lowest_layer(ws_).close();
  }

 private:
  struct Out {
    std::string header;  // the binary Message Data header (13 bytes); empty for a text message
    std::shared_ptr<const std::string> payload;
    bool text = false;
    std::int64_t channel = -1;  // -1: a protocol message
    bool latest_only = false;
    std::uint32_t key = 0;  // latest only: replaces an unsent message of the same channel and key
    std::size_t size() const { return header.size() + payload->size(); }
  };

  static std::string message_header(std::uint32_t subscription, std::uint64_t stamp_ns) {
    std::string h(13, '\0');
    h[0] = 0x01;  // Message Data
    for (int i = 0; i < 4; ++i) h[1 + i] = static_cast<char>((subscription >> (8 * i)) & 0xff);
    for (int i = 0; i < 8; ++i) h[5 + i] = static_cast<char>((stamp_ns >> (8 * i)) & 0xff);
    return h;
  }

  void send_text(std::string text) {
    enqueue(Out{"", std::make_shared<const std::string>(std::move(text)), true, -1, false});
  }

  void on_accept(beast::error_code ec) {
    if (ec) return finish(false);
    Json info = hub_.server_info;
    if (drive_) {
      ++hub_.stats.drivers_total;
      info["capabilities"] = Json::array({"clientPublish"});
      info["supportedEncodings"] = Json::array({"json"});
      if (hub_.drive_hooks.opened)
        for (const auto& [key, value] : hub_.drive_hooks.opened(id_, query_)) info["metadata"][key] = value;
    }
    send_text(info.dump());
    send_text(hub_.advertise);
    if (!why_not_drive_.empty()) {
      ++hub_.stats.drive_refused;
      status(1, "this connection may view, not drive: " + why_not_drive_);
    }
    read();
  }

  void read() {
    ws_.async_read(in_, [self = shared_from_this()](beast::error_code ec, std::size_t) { self->on_read(ec); });
  }

  void on_read(beast::error_code ec) {
    if (ec) {
      if (ec == websocket::error::message_too_big) {
        ++hub_.stats.closed_for_errors;
        std::cerr << "telegrasp-view: closed a connection that sent a message over "
                  << hub_.options.max_client_message_bytes << " bytes\n";
      }
      // The peer ended it (a close frame, or its TCP connection closed: a tab that went away), or
      // the link failed otherwise, whose hands wait for a resume.
      return finish(ec == websocket::error::closed || ec == asio::error::eof || ec == asio::error::connection_reset);
    }
    const std::string data = beast::buffers_to_string(in_.data());
    in_.consume(in_.size());
    if (ws_.got_text())
      handle(data);
    else
      handle_binary(data);
    if (!closing_) read();
  }

  // A message this connection should not have sent: told, counted, and after too many, closed.
  void protocol_error(const std::string& what) {
    ++hub_.stats.client_messages_rejected;
    status(2, what);
    if (++errors_ >= hub_.options.max_protocol_errors) {
      ++hub_.stats.closed_for_errors;
      std::cerr << "telegrasp-view: closed a connection after " << errors_ << " bad messages (last: " << what << ")\n";
      close();
    }
  }

  // Client publishing: a Message Data frame (opcode 0x01, u32 client channel id, payload).
  void handle_binary(const std::string& data) {
    if (!drive_)
      return protocol_error(why_not_drive_.empty() ? "telegrasp-view accepts client publishing only with --drive"
                                                   : "this connection may not drive: " + why_not_drive_);
    if (data.size() < 5 || static_cast<unsigned char>(data[0]) != 0x01)
      return protocol_error("binary messages: expected Message Data (opcode 0x01, u32 channel id, payload)");
    std::uint32_t channel = 0;
    for (int i = 0; i < 4; ++i) channel |= static_cast<std::uint32_t>(static_cast<unsigned char>(data[1 + i])) << (8 * i);
    if (!client_channels_.contains(channel))
      return protocol_error("message on channel " + std::to_string(channel) + ", which this connection did not advertise");
    const std::string error =
        hub_.drive_hooks.message ? hub_.drive_hooks.message(id_, std::string_view(data).substr(5)) : "";
    if (!error.empty()) return protocol_error(hub_.options.drive_topic + ": " + error);
    ++hub_.stats.client_messages;
  }

  void advertise(const Json& request) {
    if (!drive_)
      return protocol_error(why_not_drive_.empty() ? "telegrasp-view accepts client publishing only with --drive"
                                                   : "this connection may not drive: " + why_not_drive_);
    if (!request.contains("channels") || !request["channels"].is_array())
      return protocol_error("advertise: expected 'channels', an array");
    const WebServer::Options& o = hub_.options;
    for (const Json& c : request["channels"]) {
      const auto text = [&](const char* key) {
        return c.is_object() && c.contains(key) && c[key].is_string() ? c[key].get<std::string>() : std::string();
      };
      if (!c.is_object() || !c.contains("id") || !c["id"].is_number_unsigned())
        protocol_error("advertise: each channel needs an unsigned 'id'");
      else if (text("topic") != o.drive_topic)
        protocol_error("advertise: topic '" + text("topic") + "': this bridge takes " + o.drive_topic + " only");
      else if (text("encoding") != "json")
        protocol_error("advertise: encoding '" + text("encoding") + "': expected json");
      else if (text("schemaName") != o.drive_schema_name)
        protocol_error("advertise: schemaName '" + text("schemaName") + "': expected " + o.drive_schema_name);
      else if (client_channels_.size() >= 8)
        protocol_error("advertise: at most 8 client channels per connection");
      else
        client_channels_.insert(c["id"].get<std::uint32_t>());
    }
  }

  // A client's JSON request: subscribe and unsubscribe; anything else gets a warning status.
  void handle(const std::string& text) {
    const Json request = Json::parse(text, nullptr, false);
    const std::string op = request.is_object() && request.contains("op") && request["op"].is_string()
                               ? request["op"].get<std::string>()
                               : "";
    if (op == "subscribe" && request.contains("subscriptions") && request["subscriptions"].is_array()) {
      for (const Json& s : request["subscriptions"]) {
        if (!s.is_object() || !s.contains("id") || !s.contains("channelId") || !s["id"].is_number_unsigned() ||
            !s["channelId"].is_number_unsigned()) {
          status(2, "subscribe: each subscription needs unsigned 'id' and 'channelId'");
          continue;
        }
        const auto id = s["id"].get<std::uint32_t>();
        const auto channel = s["channelId"].get<std::uint32_t>();
        if (!hub_.channel_by_id.contains(channel)) {
          status(2, "subscribe: no channel " + std::to_string(channel));
        } else if (channel_of_subscription_.contains(id)) {
          status(2, "subscribe: subscription id " + std::to_string(id) + " is in use");
        } else if (subscription_of_channel_.contains(channel)) {
          status(2, "subscribe: channel " + std::to_string(channel) + " is already subscribed");
        } else {
          channel_of_subscription_[id] = channel;
          subscription_of_channel_[channel] = id;
          // Bring the new subscriber up to date before anything newer.
          const std::uint64_t now = static_cast<std::uint64_t>(
              std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::system_clock::now().time_since_epoch())
                  .count());
          if (hub_.on_subscribe)
            for (const auto& payload : hub_.on_subscribe(channel)) offer(channel, payload, now, false);
        }
      }
    } else if (op == "unsubscribe" && request.contains("subscriptionIds") && request["subscriptionIds"].is_array()) {
      for (const Json& id : request["subscriptionIds"]) {
        if (!id.is_number_unsigned()) continue;
        const auto it = channel_of_subscription_.find(id.get<std::uint32_t>());
        if (it == channel_of_subscription_.end()) continue;
        subscription_of_channel_.erase(it->second);
        channel_of_subscription_.erase(it);
      }
    } else if (op == "advertise") {
      advertise(request);
    } else if (op == "unadvertise" && request.contains("channelIds") && request["channelIds"].is_array()) {
      for (const Json& id : request["channelIds"])
        if (id.is_number_unsigned()) client_channels_.erase(id.get<std::uint32_t>());
    } else {
      protocol_error("telegrasp-view does not serve op '" + op + "' (it serves subscribe, unsubscribe" +
                     (drive_ ? ", advertise and unadvertise)" : ")"));
    }
  }

  void enqueue(Out out, const WebServer::Complete& complete = {}) {
    if (closing_) return;
    if (out.latest_only) {
      // Newest wins: replace an unsent message of the same channel (never the one being written),
      // by the complete message when the channel sends deltas.
      for (std::size_t i = writing_ ? 1 : 0; i < queue_.size(); ++i) {
        if (queue_[i].channel == out.channel && queue_[i].latest_only && queue_[i].key == out.key) {
          if (complete) out.payload = complete();
          queued_bytes_ = queued_bytes_ - queue_[i].size() + out.size();
          queue_[i] = std::move(out);
          ++hub_.stats.messages_replaced;
          return;
        }
      }
    }
    queued_bytes_ += out.size();
    queue_.push_back(std::move(out));
    if (queued_bytes_ > hub_.options.max_queued_bytes) {
      std::cerr << "telegrasp-view: a viewer fell " << queued_bytes_ << " bytes behind; disconnecting it\n";
      ++hub_.stats.viewers_dropped;
      close();
      return;
    }
    if (!writing_) write();
  }

  void write() {
    writing_ = true;
    const Out& out = queue_.front();
    ws_.text(out.text);
    const std::array<asio::const_buffer, 2> buffers{asio::buffer(out.header), asio::buffer(*out.payload)};
    ws_.async_write(buffers, [self = shared_from_this()](beast::error_code ec, std::size_t) { self->on_write(ec); });
  }

  void on_write(beast::error_code ec) {
    writing_ = false;
    if (ec) return finish(false);
    ++hub_.stats.messages_sent;
    hub_.stats.bytes_sent += queue_.front().size();
    queued_bytes_ -= queue_.front().size();
    queue_.pop_front();
    if (!queue_.empty()) write();
  }

  // `clean`: the peer closed with a close frame.
  void finish(bool clean) {
    if (!finished_) {
      finished_ = true;
      closing_ = true;
      queue_.clear();
      hub_.by_id.erase(id_);
      if (drive_ && hub_.drive_hooks.closed) hub_.drive_hooks.closed(id_, clean);
      hub_.viewers.erase(shared_from_this());
    }
  }

  websocket::stream<Stream> ws_;
  beast::flat_buffer in_;
  WebServer::Hub& hub_;
  const std::uint64_t id_;
  const bool drive_;
  const std::string why_not_drive_;
  const std::map<std::string, std::string> query_;
  std::deque<Out> queue_;
  std::size_t queued_bytes_ = 0;
  bool writing_ = false, closing_ = false, finished_ = false;
  int errors_ = 0;
  std::map<std::uint32_t, std::uint32_t> channel_of_subscription_, subscription_of_channel_;
  std::set<std::uint32_t> client_channels_;  // advertised by this connection
};

// One HTTP connection: files of the page, or the upgrade to a ViewerSession.
template <class Stream>
class HttpSession : public std::enable_shared_from_this<HttpSession<Stream>> {
 public:
  using std::enable_shared_from_this<HttpSession<Stream>>::shared_from_this;
  // `buffer`: bytes already read (the TLS detection's).
  HttpSession(Stream&& stream, beast::flat_buffer buffer, WebServer::Hub& hub)
      : stream_(std::move(stream)), buffer_(std::move(buffer)), hub_(hub) {}

  void read() {
    parser_.emplace();
    parser_->body_limit(kMaxRequestBytes);
    beast::get_lowest_layer(stream_).expires_after(std::chrono::seconds(30));
    http::async_read(stream_, buffer_, *parser_,
                     [self = shared_from_this()](beast::error_code ec, std::size_t) { self->on_read(ec); });
  }

 private:
  void on_read(beast::error_code ec) {
    if (ec) return;  // closed, timed out or malformed: drop the connection
    ++hub_.stats.http_requests;
    http::request<http::string_body> request = parser_->release();
    if (websocket::is_upgrade(request)) {
      const auto offered = request[http::field::sec_websocket_protocol];
      if (!lists_protocol(std::string_view(offered.data(), offered.size()), kSubprotocol))
        return reply_text(request, http::status::bad_request,
                          std::string("this WebSocket speaks the subprotocol ") + kSubprotocol + " only\n");
      beast::get_lowest_layer(stream_).expires_never();
      std::map<std::string, std::string> query = query_of(std::string_view(request.target().data(), request.target().size()));
      const std::string why_not = why_not_drive(request, query);
      const std::uint64_t id = hub_.next_connection++;
      auto viewer = std::make_shared<ViewerSession<Stream>>(std::move(stream_), hub_, id,
                                                            hub_.options.drive && why_not.empty(), why_not,
                                                            std::move(query));
      hub_.viewers.insert(viewer);
      hub_.by_id[id] = viewer.get();
      ++hub_.stats.viewers_total;
      viewer->start(std::move(request));
      return;
    }
    if (request.method() != http::verb::get && request.method() != http::verb::head)
      return reply_text(request, http::status::method_not_allowed, "GET only\n");
    std::string target(request.target().substr(0, request.target().find('?')));
    if (target == "/") target = "/index.html";
    if (target == "/xr") target = "/xr.html";
    // Files under the web root only.
    if (target.empty() || target[0] != '/' || target.find("..") != std::string::npos ||
        target.find('\\') != std::string::npos)
      return reply_text(request, http::status::bad_request, "bad path\n");
    const std::filesystem::path path = hub_.options.web_root / target.substr(1);
    std::error_code fs_ec;
    if (!std::filesystem::is_regular_file(path, fs_ec))
      return reply_text(request, http::status::not_found, "not found\n");
    http::file_body::value_type body;
    beast::error_code open_ec;
    body.open(path.c_str(), beast::file_mode::scan, open_ec);
    if (open_ec) return reply_text(request, http::status::not_found, "not found\n");
    auto response =
        std::make_shared<http::response<http::file_body>>(std::piecewise_construct, std::make_tuple(std::move(body)),
                                                          std::make_tuple(http::status::ok, request.version()));
    response->set(http::field::server, hub_.options.name);
    response->set(http::field::content_type, std::string(mime_type(path)));
    response->set(http::field::cache_control, "no-cache");
    response->content_length(response->body().size());
    response->keep_alive(request.keep_alive());
    if (request.method() == http::verb::head) {
      auto head = std::make_shared<http::response<http::empty_body>>(http::status::ok, request.version());
      head->base() = response->base();
      return send(head);
    }
    send(response);
  }

  // "" when a WebSocket upgrade may publish (or driving is off), else why not: the token when
  // one is set, else the page's Origin (the bridge's own pages, a configured one, or none at all:
  // not a browser), so that a web site open in the user's browser cannot drive through localhost.
  std::string why_not_drive(const http::request<http::string_body>& request,
                            const std::map<std::string, std::string>& query) const {
    const WebServer::Options& o = hub_.options;
    if (!o.drive) return "";
    if (!o.drive_token.empty()) {
      const auto token = query.find("token");
      if (token == query.end()) return "driving needs the token: open the URL telegrasp-view printed (?token=...)";
      if (!constant_time_equal(token->second, o.drive_token)) return "wrong token";
      return "";
    }
    const auto origin_field = request.find(http::field::origin);
    if (origin_field == request.end()) return "";
    const std::string origin(origin_field->value());
    const std::string host(request[http::field::host]);
    if (origin == "http://" + host || origin == "https://" + host) return "";
    for (const std::string& allowed : o.drive_origins)
      if (origin == allowed) return "";
    return "Origin " + origin + " is not this bridge's (" + host + ") nor one given with --drive-origin";
  }

  void reply_text(const http::request<http::string_body>& request, http::status status, std::string text) {
    auto response = std::make_shared<http::response<http::string_body>>(status, request.version());
    response->set(http::field::server, hub_.options.name);
    response->set(http::field::content_type, "text/plain; charset=utf-8");
    response->body() = std::move(text);
    response->prepare_payload();
    response->keep_alive(request.keep_alive());
    send(response);
  }

  template <class Response>
  void send(std::shared_ptr<Response> response) {
    http::async_write(stream_, *response, [self = shared_from_this(), response](beast::error_code ec, std::size_t) {
      if (ec || !response->keep_alive()) {
        beast::error_code ignored;
        beast::get_lowest_layer(self->stream_).socket().shutdown(tcp::socket::shutdown_send, ignored);
        return;
      }
      self->read();
    });
  }

  Stream stream_;
  beast::flat_buffer buffer_;
  std::optional<http::request_parser<http::string_body>> parser_;
  WebServer::Hub& hub_;
};

// With a certificate, one port serves both: a TLS handshake goes on as HTTPS/WSS, anything else
// as plain HTTP/WS.
void detect_tls(const std::shared_ptr<WebServer::Hub>& hub, beast::tcp_stream stream) {
  auto state = std::make_shared<std::pair<beast::tcp_stream, beast::flat_buffer>>(std::move(stream), beast::flat_buffer());
  state->first.expires_after(std::chrono::seconds(30));
  beast::async_detect_ssl(state->first, state->second, [hub, state](beast::error_code ec, bool tls) {
    if (ec || hub->closed) return;
    if (!tls) {
      std::make_shared<HttpSession<beast::tcp_stream>>(std::move(state->first), std::move(state->second), *hub)->read();
      return;
    }
    auto secure = std::make_shared<TlsStream>(std::move(state->first), *hub->tls);
    secure->async_handshake(ssl::stream_base::server, state->second.data(),
                            [hub, state, secure](beast::error_code ec, std::size_t used) {
                              if (ec || hub->closed) return;  // a bad handshake: dropped
                              state->second.consume(used);
                              std::make_shared<HttpSession<TlsStream>>(std::move(*secure), std::move(state->second), *hub)
                                  ->read();
                            });
  });
}

void accept(const std::shared_ptr<WebServer::Hub>& hub) {
  hub->acceptor.async_accept([hub](beast::error_code ec, tcp::socket socket) {
    if (hub->closed) return;
    if (!ec) {
      // Small messages go out at once (a skeleton must not wait for the last one's ACK).
      beast::error_code ignored;
      socket.set_option(tcp::no_delay(true), ignored);
      if (hub->tls)
        detect_tls(hub, beast::tcp_stream(std::move(socket)));
      else
        std::make_shared<HttpSession<beast::tcp_stream>>(beast::tcp_stream(std::move(socket)), beast::flat_buffer(), *hub)
            ->read();
    }
    accept(hub);
  });
}

}  // namespace

WebServer::WebServer(asio::io_context& io, Options options, std::vector<Channel> channels, OnSubscribe on_subscribe)
    : hub_(std::make_shared<Hub>(io, std::move(options), std::move(channels), std::move(on_subscribe))) {
  Json advertised = Json::array();
  for (const Channel& c : hub_->channels) {
    hub_->channel_by_id[c.id] = &c;
    advertised.push_back(Json{{"id", c.id},
                              {"topic", c.topic},
                              {"encoding", "json"},
                              {"schemaName", c.schema_name},
                              {"schema", c.schema},
                              {"schemaEncoding", "jsonschema"}});
  }
  hub_->advertise = Json{{"op", "advertise"}, {"channels", std::move(advertised)}}.dump();
  const auto session =
      std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::system_clock::now().time_since_epoch());
  hub_->server_info = Json{{"op", "serverInfo"},
                           {"name", hub_->options.name},
                           {"capabilities", Json::array()},
                           {"metadata", Json::object()},
                           {"sessionId", std::to_string(session.count())}};

  if (!hub_->options.tls_cert.empty()) {
    hub_->tls.emplace(ssl::context::tls_server);
    hub_->tls->set_options(ssl::context::default_workarounds | ssl::context::no_sslv2 | ssl::context::no_sslv3 |
                           ssl::context::no_tlsv1 | ssl::context::no_tlsv1_1);
    for (const auto& [flag, file] : {std::pair{"--tls-cert", hub_->options.tls_cert}, {"--tls-key", hub_->options.tls_key}})
      if (!std::filesystem::is_regular_file(file)) throw std::runtime_error(std::string(flag) + " " + file.string() + ": no such file");
    beast::error_code ec;
    hub_->tls->use_certificate_chain_file(hub_->options.tls_cert.string(), ec);
    if (ec)
      throw std::runtime_error("--tls-cert " + hub_->options.tls_cert.string() +
                               ": not a PEM certificate chain (" + ec.message() + "); deploy/make-cert.sh makes one");
    hub_->tls->use_private_key_file(hub_->options.tls_key.string(), ssl::context::pem, ec);
    if (ec)
      throw std::runtime_error("--tls-key " + hub_->options.tls_key.string() + ": not a PEM private key (" +
                               ec.message() + ")");
  }
  const std::string where = hub_->options.address + ":" + std::to_string(hub_->options.port);
  beast::error_code ec;
  const asio::ip::address address = asio::ip::make_address(hub_->options.address, ec);
  if (ec) throw std::runtime_error("--address '" + hub_->options.address + "' is not an IP address");
  const tcp::endpoint endpoint(address, hub_->options.port);
  hub_->acceptor.open(endpoint.protocol(), ec);
  if (!ec) hub_->acceptor.set_option(asio::socket_base::reuse_address(true), ec);
  if (!ec) hub_->acceptor.bind(endpoint, ec);
  if (!ec) hub_->acceptor.listen(asio::socket_base::max_listen_connections, ec);
  if (ec) throw std::runtime_error("cannot listen on " + where + ": " + ec.message());
  accept(hub_);
}

WebServer::~WebServer() { close(); }

std::uint16_t WebServer::port() const {
  beast::error_code ec;
  const tcp::endpoint endpoint = hub_->acceptor.local_endpoint(ec);
  return ec ? 0 : endpoint.port();
}

void WebServer::publish(std::uint32_t channel, std::shared_ptr<const std::string> payload, std::uint64_t stamp_ns,
                        const Complete& complete) {
  const auto it = hub_->channel_by_id.find(channel);
  if (it == hub_->channel_by_id.end()) return;
  const bool latest_only = it->second->latest_only;
  // Built once, for the first slow viewer that needs it.
  std::shared_ptr<const std::string> built;
  Complete once;
  if (complete)
    once = [&] {
      if (!built) built = complete();
      return built;
    };
  // A viewer may drop out of the set while offered a message (a full queue): iterate a copy.
  const std::vector<std::shared_ptr<Viewer>> viewers(hub_->viewers.begin(), hub_->viewers.end());
  for (const auto& viewer : viewers) viewer->offer(channel, payload, stamp_ns, latest_only, once);
}

void WebServer::set_drive_hooks(DriveHooks hooks) { hub_->drive_hooks = std::move(hooks); }

void WebServer::send_to(std::uint64_t connection, std::uint32_t channel, std::shared_ptr<const std::string> payload,
                        std::uint64_t stamp_ns, std::uint32_t key) {
  const auto it = hub_->by_id.find(connection);
  if (it != hub_->by_id.end()) it->second->offer(channel, payload, stamp_ns, true, {}, key);
}

void WebServer::close(std::uint64_t connection) {
  const auto it = hub_->by_id.find(connection);
  if (it != hub_->by_id.end()) it->second->close();
}

void WebServer::status_to(std::uint64_t connection, int level, const std::string& message) {
  const auto it = hub_->by_id.find(connection);
  if (it != hub_->by_id.end()) it->second->status(level, message);
}

void WebServer::close() {
  if (hub_->closed) return;
  hub_->closed = true;
  beast::error_code ec;
  hub_->acceptor.close(ec);
  const std::vector<std::shared_ptr<Viewer>> viewers(hub_->viewers.begin(), hub_->viewers.end());
  for (const auto& viewer : viewers) viewer->close();
}

WebServerStats WebServer::stats() const {
  WebServerStats s = hub_->stats;
  s.viewers = hub_->viewers.size();
  return s;
}

}  // namespace telegrasp::view
