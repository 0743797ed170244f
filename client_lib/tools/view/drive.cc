#include "drive.h"

#include "foxglove_json.h"
#include "telegrasp/sim/hand_rig.h"

#include <iostream>
#include <random>
#include <sstream>

namespace telegrasp::view {
namespace {

constexpr auto kSilentAfter = std::chrono::milliseconds(100);  // a page this quiet counts as not tracking
constexpr auto kQuietForTakeover = std::chrono::milliseconds(500);  // a resume may take over a connection this quiet
constexpr auto kReleaseFor = std::chrono::milliseconds(300);  // the open hand is sent this long after the grace
constexpr std::size_t kRecent = 64;  // samples remembered per hand for skeleton -> page matching

// A sample whose fingers are all open.
void open(client::ControllerSample& sample) {
  sample.trigger = 0;
  sample.curls.assign(sample.curls.size(), 0.0);
}

std::chrono::steady_clock::duration seconds(double s) {
  return std::chrono::duration_cast<std::chrono::steady_clock::duration>(std::chrono::duration<double>(s));
}

}  // namespace

std::string random_hex(std::size_t bytes) {
  std::random_device device;
  static constexpr char kDigits[] = "0123456789abcdef";
  std::string out;
  for (std::size_t i = 0; i < bytes; ++i) {
    const unsigned v = device() & 0xff;
    out += kDigits[v >> 4];
    out += kDigits[v & 15];
  }
  return out;
}

Drive::Drive(client::Client& client, WebServer& server, std::uint32_t hands_channel,
             std::function<const sim::HandRig*(const std::string&)> rig, DriveOptions options)
    : client_(client),
      server_(server),
      hands_channel_(hands_channel),
      rig_(std::move(rig)),
      options_(std::move(options)),
      tag_(random_hex(3)) {}

WebServer::DriveHooks Drive::hooks() {
  return {[this](std::uint64_t c, const std::map<std::string, std::string>& q) { return opened(c, q); },
          [this](std::uint64_t c, std::string_view payload) { return message(c, payload); },
          [this](std::uint64_t c, bool clean) { closed(c, clean); }};
}

std::map<std::string, std::string> Drive::opened(std::uint64_t connection,
                                                 const std::map<std::string, std::string>& query) {
  Driver* driver = nullptr;
  if (const auto resume = query.find("resume"); resume != query.end()) {
    // A dropped link's id, or one whose old connection has gone quiet (a link that died without
    // a word: the new connection takes over, the old one is closed).
    const Clock::time_point now = Clock::now();
    for (auto& [id, d] : drivers_) {
      if (d->resume_token != resume->second) continue;
      bool quiet = true;
      for (const auto& [side, hand] : d->hands) quiet = quiet && now - hand.received > kQuietForTakeover;
      if (d->connection != 0 && !quiet) break;  // the page is alive: a second tab gets its own id
      driver = d.get();
      if (d->connection != 0) {
        const std::uint64_t old = d->connection;
        by_connection_.erase(old);
        d->connection = 0;
        server_.close(old);
      }
    }
    if (driver) {
      ++stats_.resumed;
      for (auto& [side, hand] : driver->hands) hand.page_seq = 0;  // a reloaded page numbers anew
    }
  }
  if (!driver) {
    auto fresh = std::make_unique<Driver>();
    fresh->client_id = options_.prefix + tag_ + "-" + std::to_string(next_id_++);
    fresh->resume_token = random_hex(16);
    driver = drivers_.emplace(fresh->client_id, std::move(fresh)).first->second.get();
  }
  driver->connection = connection;
  by_connection_[connection] = driver;
  std::ostringstream grace, window;
  grace << options_.tracking_grace_s;
  window << options_.resume_window_s;
  return {{"client_id", driver->client_id},
          {"resume_token", driver->resume_token},
          {"resume_window_s", window.str()},
          {"tracking_grace_s", grace.str()}};
}

void Drive::closed(std::uint64_t connection, bool clean) {
  const auto it = by_connection_.find(connection);
  if (it == by_connection_.end()) return;
  Driver* driver = it->second;
  by_connection_.erase(it);
  if (clean) {
    // A closed tab lets go at once: one last sample opens each hand where it was (the server
    // releases at its next tick), then no more: the server removes the silent hands within 0.5 s.
    std::cerr << "telegrasp-view: " << driver->client_id << " closed; its hands let go and leave\n";
    for (auto& [side, hand] : driver->hands) {
      if (hand.seq == 0) continue;
      open(hand.sample);
      send(*driver, hand, side, 0, 0);
    }
    drivers_.erase(driver->client_id);
    return;
  }
  std::cerr << "telegrasp-view: " << driver->client_id << "'s link dropped; its hands are held " << options_.resume_window_s
            << " s for its resume token\n";
  driver->connection = 0;
  driver->detached = Clock::now();
}

Eigen::Isometry3d Drive::grip_to_palm(client::HandSide side) {
  const auto known = rig_names_.find(side);
  const sim::HandRig* rig = rig_(known != rig_names_.end() ? known->second : "human_" + client::to_string(side));
  if (!rig) rig = rig_("human_" + client::to_string(side));
  return rig ? view::grip_to_palm(*rig, side) : Eigen::Isometry3d::Identity();
}

std::string Drive::message(std::uint64_t connection, std::string_view payload) {
  const auto it = by_connection_.find(connection);
  if (it == by_connection_.end()) return "this connection drives no hands";
  Driver& driver = *it->second;
  std::string error;
  const std::optional<ControllerInput> in = parse_controller_input(payload, error);
  if (!in) return error;
  Hand& hand = driver.hands[in->side];
  if (in->seq <= hand.page_seq)
    return "seq " + std::to_string(in->seq) + " of the " + client::to_string(in->side) + " hand is not above the last, " +
           std::to_string(hand.page_seq);
  hand.page_seq = in->seq;
  if (hand.seq == 0 && !in->tracking) return "";  // no pose yet: the hand joins once tracked
  hand.received = Clock::now();
  hand.sample.side = in->side;
  if (in->tracking) hand.sample.X_WorldPalm = in->X_WorldGrip * grip_to_palm(in->side);
  hand.sample.tracking_valid = in->tracking;
  hand.sample.trigger = in->trigger;
  hand.sample.curls = in->curls;
  if (in->tracking) {
    hand.lost_since.reset();
    hand.released = false;
  } else if (!hand.lost_since) {
    hand.lost_since = hand.received;
  }
  if (hand.released) open(hand.sample);  // past the grace without tracking: the hand stays open
  send(driver, hand, in->side, in->seq, in->stamp_ns);
  ++stats_.samples_forwarded;
  return "";
}

void Drive::send(Driver& driver, Hand& hand, client::HandSide side, std::uint64_t page_seq,
                 std::int64_t page_stamp_ns) {
  hand.sample.side = side;
  hand.sample.sequence_number = ++hand.seq;
  hand.sample.client_time_ns = 0;  // stamped now, on this machine's clock, like every client's
  try {
    client_.publish_as(driver.client_id, hand.sample);
  } catch (const std::exception& e) {
    std::cerr << "telegrasp-view: forwarding " << driver.client_id << ": " << e.what() << "\n";
    return;
  }
  hand.recent.emplace_back(hand.seq, page_seq, page_stamp_ns);
  if (hand.recent.size() > kRecent) hand.recent.pop_front();
}

void Drive::tick() {
  const Clock::time_point now = Clock::now();
  for (auto d = drivers_.begin(); d != drivers_.end();) {
    Driver& driver = *d->second;
    const bool detached = driver.connection == 0;
    if (detached && now - driver.detached > seconds(options_.resume_window_s) + kReleaseFor) {
      d = drivers_.erase(d);  // the token expired; the hands fall silent and leave
      continue;
    }
    // A dropped link holds its hands for the resume window, a silent or untracked one for the grace.
    const auto hold = seconds(detached ? options_.resume_window_s : options_.tracking_grace_s);
    for (auto& [side, hand] : driver.hands) {
      if (hand.seq == 0) continue;
      const bool silent = detached || now - hand.received > kSilentAfter;
      if (!silent && hand.sample.tracking_valid) continue;  // the page's own samples keep it going
      if (!hand.lost_since) hand.lost_since = detached ? driver.detached : hand.received;
      const auto lost = now - *hand.lost_since;
      if (lost > hold && !hand.released) {
        hand.released = true;  // let go
        open(hand.sample);
      }
      if (lost > hold + kReleaseFor || !silent) continue;  // opened long enough: let it fall silent
      hand.sample.tracking_valid = false;
      send(driver, hand, side, 0, 0);
      ++stats_.keepalives;
    }
    ++d;
  }
}

void Drive::skeleton(const client::HandSkeleton& s, std::uint64_t stamp_ns) {
  if (!s.hand.client_id.starts_with(options_.prefix)) return;
  rig_names_[s.hand.side] = s.rig;
  const auto d = drivers_.find(s.hand.client_id);
  if (d == drivers_.end() || d->second->connection == 0) return;
  Json page_seq = nullptr, page_stamp = nullptr;
  if (const auto hand = d->second->hands.find(s.hand.side); hand != d->second->hands.end())
    for (const auto& [seq, seq_page, stamp_page] : hand->second.recent)
      if (seq == s.input_sequence && seq_page != 0) {
        page_seq = seq_page;
        page_stamp = stamp_page == 0 ? Json(nullptr) : stamp(static_cast<std::uint64_t>(stamp_page));
      }
  Json phalanges = Json::array(), names = Json::array();
  for (const Eigen::Isometry3d& X : s.X_WorldPhalanx) phalanges.push_back(pose(X));
  if (const sim::HandRig* rig = rig_(s.rig); rig && rig->phalanges().size() == s.X_WorldPhalanx.size())
    for (const sim::PhalanxSpec& p : rig->phalanges()) names.push_back(p.name);
  const Json message{{"client_id", s.hand.client_id},
                     {"side", client::to_string(s.hand.side)},
                     {"rig", s.rig},
                     {"tick", s.tick},
                     {"input_seq", page_seq},
                     {"input_stamp", page_stamp},
                     {"late_latched", s.late_latched},
                     {"frozen", s.frozen},
                     {"palm", pose(s.X_WorldPalm)},
                     {"tracked_palm", pose(s.X_WorldTracked)},
                     {"resolve_offset_m", {s.resolve_offset.x(), s.resolve_offset.y(), s.resolve_offset.z()}},
                     {"resolve_angle_rad", s.resolve_angle},
                     {"phalanges", std::move(phalanges)},
                     {"phalanx_names", std::move(names)},
                     {"joint_angles_rad", s.joint_angles}};
  server_.send_to(d->second->connection, hands_channel_, std::make_shared<const std::string>(message.dump()), stamp_ns,
                  static_cast<std::uint32_t>(s.hand.side));
  ++stats_.skeletons_sent;
}

void Drive::notice(const client::Notice& n) {
  const auto d = drivers_.find(n.client_id);
  if (d == drivers_.end() || d->second->connection == 0) return;
  server_.status_to(d->second->connection, 1,
                    "the server refused " + n.client_id + ": " + n.reason + (n.detail.empty() ? "" : " (" + n.detail + ")"));
  ++stats_.notices;
}

DriveStats Drive::stats() const {
  DriveStats s = stats_;
  s.connections = by_connection_.size();
  s.held = drivers_.size() - by_connection_.size();
  return s;
}

}  // namespace telegrasp::view
