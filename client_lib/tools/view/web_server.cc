#include "web_server.h"

#include <boost/asio/ip/tcp.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>
#include <boost/beast/websocket.hpp>
#include <nlohmann/json.hpp>

#include <array>
#include <chrono>
#include <deque>
#include <iostream>
#include <map>
#include <set>
#include <stdexcept>

namespace telegrasp::view {
namespace {

namespace asio = boost::asio;
namespace beast = boost::beast;
namespace http = beast::http;
namespace websocket = beast::websocket;
using tcp = asio::ip::tcp;
using Json = nlohmann::json;

constexpr const char* kSubprotocol = "foxglove.websocket.v1";
constexpr std::size_t kMaxRequestBytes = 1 << 20;  // a client's JSON request or HTTP request

class ViewerSession;

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

}  // namespace

// What every session shares: options, channels, the registry of viewers, the counters.
struct WebServer::Hub {
  asio::io_context& io;
  Options options;
  std::vector<Channel> channels;
  std::map<std::uint32_t, const Channel*> channel_by_id;
  OnSubscribe on_subscribe;
  tcp::acceptor acceptor;
  std::set<std::shared_ptr<ViewerSession>> viewers;
  WebServerStats stats;
  std::string advertise;  // the Advertise message, the same for every viewer
  std::string server_info;  // the Server Info message
  bool closed = false;

  Hub(asio::io_context& io_, Options o, std::vector<Channel> c, OnSubscribe s)
      : io(io_), options(std::move(o)), channels(std::move(c)), on_subscribe(std::move(s)), acceptor(io_) {}
};

namespace {

// One WebSocket viewer speaking foxglove.websocket.v1.
class ViewerSession : public std::enable_shared_from_this<ViewerSession> {
 public:
  ViewerSession(tcp::socket socket, WebServer::Hub& hub) : ws_(std::move(socket)), hub_(hub) {}

  void start(http::request<http::string_body> request) {
    ws_.set_option(websocket::stream_base::timeout::suggested(beast::role_type::server));
    ws_.set_option(websocket::stream_base::decorator([name = hub_.options.name](websocket::response_type& res) {
      res.set(http::field::server, name);
      res.set(http::field::sec_websocket_protocol, kSubprotocol);
    }));
    ws_.read_message_max(kMaxRequestBytes);
    ws_.async_accept(request, [self = shared_from_this()](beast::error_code ec) { self->on_accept(ec); });
  }

  // Queues a Message Data frame of `channel` if this viewer subscribed to it.
  void offer(std::uint32_t channel, const std::shared_ptr<const std::string>& payload, std::uint64_t stamp_ns,
             bool latest_only, const WebServer::Complete& complete = {}) {
    const auto sub = subscription_of_channel_.find(channel);
    if (sub == subscription_of_channel_.end()) return;
    enqueue(Out{message_header(sub->second, stamp_ns), payload, false, static_cast<std::int64_t>(channel), latest_only},
            complete);
  }

  void close() {
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

  void status(int level, const std::string& message) {
    send_text(Json{{"op", "status"}, {"level", level}, {"message", message}}.dump());
  }

  void on_accept(beast::error_code ec) {
    if (ec) return finish();
    send_text(hub_.server_info);
    send_text(hub_.advertise);
    read();
  }

  void read() {
    ws_.async_read(in_, [self = shared_from_this()](beast::error_code ec, std::size_t) { self->on_read(ec); });
  }

  void on_read(beast::error_code ec) {
    if (ec) return finish();
    if (!ws_.got_text()) {
      status(1, "telegrasp-view does not accept client publishing or service calls");
    } else {
      handle(beast::buffers_to_string(in_.data()));
    }
    in_.consume(in_.size());
    read();
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
    } else {
      status(1, "telegrasp-view ignores op '" + op + "' (it serves subscribe and unsubscribe)");
    }
  }

  void enqueue(Out out, const WebServer::Complete& complete = {}) {
    if (closing_) return;
    if (out.latest_only) {
      // Newest wins: replace an unsent message of the same channel (never the one being written),
      // by the complete message when the channel sends deltas.
      for (std::size_t i = writing_ ? 1 : 0; i < queue_.size(); ++i) {
        if (queue_[i].channel == out.channel && queue_[i].latest_only) {
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
    if (ec) return finish();
    ++hub_.stats.messages_sent;
    hub_.stats.bytes_sent += queue_.front().size();
    queued_bytes_ -= queue_.front().size();
    queue_.pop_front();
    if (!queue_.empty()) write();
  }

  void finish() {
    if (!finished_) {
      finished_ = true;
      closing_ = true;
      queue_.clear();
      hub_.viewers.erase(shared_from_this());
    }
  }

  websocket::stream<beast::tcp_stream> ws_;
  beast::flat_buffer in_;
  WebServer::Hub& hub_;
  std::deque<Out> queue_;
  std::size_t queued_bytes_ = 0;
  bool writing_ = false, closing_ = false, finished_ = false;
  std::map<std::uint32_t, std::uint32_t> channel_of_subscription_, subscription_of_channel_;
};

// One HTTP connection: files of the page, or the upgrade to a ViewerSession.
class HttpSession : public std::enable_shared_from_this<HttpSession> {
 public:
  HttpSession(tcp::socket socket, WebServer::Hub& hub) : stream_(std::move(socket)), hub_(hub) {}

  void read() {
    parser_.emplace();
    parser_->body_limit(kMaxRequestBytes);
    stream_.expires_after(std::chrono::seconds(30));
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
      stream_.expires_never();
      auto viewer = std::make_shared<ViewerSession>(stream_.release_socket(), hub_);
      hub_.viewers.insert(viewer);
      ++hub_.stats.viewers_total;
      viewer->start(std::move(request));
      return;
    }
    if (request.method() != http::verb::get && request.method() != http::verb::head)
      return reply_text(request, http::status::method_not_allowed, "GET only\n");
    std::string target(request.target().substr(0, request.target().find('?')));
    if (target == "/") target = "/index.html";
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
        self->stream_.socket().shutdown(tcp::socket::shutdown_send, ignored);
        return;
      }
      self->read();
    });
  }

  beast::tcp_stream stream_;
  beast::flat_buffer buffer_;
  std::optional<http::request_parser<http::string_body>> parser_;
  WebServer::Hub& hub_;
};

void accept(const std::shared_ptr<WebServer::Hub>& hub) {
  hub->acceptor.async_accept([hub](beast::error_code ec, tcp::socket socket) {
    if (hub->closed) return;
    if (!ec) std::make_shared<HttpSession>(std::move(socket), *hub)->read();
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
                           {"sessionId", std::to_string(session.count())}}
                          .dump();

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
  const std::vector<std::shared_ptr<ViewerSession>> viewers(hub_->viewers.begin(), hub_->viewers.end());
  for (const auto& viewer : viewers) viewer->offer(channel, payload, stamp_ns, latest_only, once);
}

void WebServer::close() {
  if (hub_->closed) return;
  hub_->closed = true;
  beast::error_code ec;
  hub_->acceptor.close(ec);
  const std::vector<std::shared_ptr<ViewerSession>> viewers(hub_->viewers.begin(), hub_->viewers.end());
  for (const auto& viewer : viewers) viewer->close();
}

WebServerStats WebServer::stats() const {
  WebServerStats s = hub_->stats;
  s.viewers = hub_->viewers.size();
  return s;
}

}  // namespace telegrasp::view
