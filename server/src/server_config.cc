#include "server_config.h"

#include "server_config.pb.h"

#include "telegrasp/idl/cli.h"
#include "telegrasp/idl/network.h"

#include <google/protobuf/io/tokenizer.h>
#include <google/protobuf/text_format.h>

#include <cmath>
#include <fstream>
#include <optional>
#include <sstream>
#include <stdexcept>

namespace telegrasp::server {
namespace {

// Collects parse errors with their line and column.
class ErrorCollector : public google::protobuf::io::ErrorCollector {
 public:
  void AddError(int line, int column, const std::string& message) override {
    if (text.empty()) text = "line " + std::to_string(line + 1) + ":" + std::to_string(column + 1) + ": " + message;
  }
  std::string text;
};

// Applies the fields present in `c` onto `s`, then validates; errors start with `origin`.
void apply_config(const proto::ServerConfig& c, ServerSettings& s, const std::string& origin) {
  const auto* d = c.GetDescriptor();
  const auto* r = c.GetReflection();
  // Every scalar is `optional`: a field written in the file, even as 0, replaces the default.
  auto has = [&](const char* field) { return r->HasField(c, d->FindFieldByName(field)); };
  if (has("domain")) s.domain = c.domain();
  if (has("profile")) s.profile = c.profile();
  if (has("profiles_file")) s.profiles_file = c.profiles_file();
  if (has("scene")) s.scene = c.scene();
  if (c.discovery_servers_size() > 0) s.discovery_servers.assign(c.discovery_servers().begin(), c.discovery_servers().end());
  if (has("claim_wait_s")) s.claim_wait_s = c.claim_wait_s();
  if (has("tick_hz")) s.tick_hz = c.tick_hz();
  if (has("objects_dir")) s.objects_dir = c.objects_dir();
  if (has("fill_standins")) s.fill_standins = c.fill_standins();
  for (const auto& o : c.objects()) {
    if (o.model().empty()) throw std::runtime_error(origin + ": objects.model must name a model");
    s.objects.push_back({o.model(), o.x(), o.y(), o.yaw(), {}, {}});
    if (o.has_friction()) s.objects.back().friction = o.friction();
    if (o.has_shape()) {
      s.objects.back().shape = sim::parse_shape_class(o.shape());
      if (!s.objects.back().shape)
        throw std::runtime_error(origin + ": objects '" + o.model() +
                                 "': shape must be sphere, cylinder, box, thin or other, got '" + o.shape() + "'");
    }
  }
  if (has("empty_scene")) s.empty_scene = c.empty_scene();
  if (has("quality_volume")) s.quality_volume = c.quality_volume();
  if (has("quality_delay_ticks")) s.quality_delay_ticks = c.quality_delay_ticks();
  if (has("right_rig")) s.right_rig = c.right_rig();
  if (has("left_rig")) s.left_rig = c.left_rig();
  if (has("closing_mode")) {
    const std::optional<sim::ClosingMode> mode = sim::parse_closing_mode(c.closing_mode());
    if (!mode)
      throw std::runtime_error(origin + ": closing_mode must be precise or discrete, got '" + c.closing_mode() + "'");
    s.closing_mode = *mode;
  }
  if (has("two_hand_mode")) {
    const std::optional<sim::TwoHandMode> mode = sim::parse_two_hand_mode(c.two_hand_mode());
    if (!mode)
      throw std::runtime_error(origin + ": two_hand_mode must be share or takeover, got '" + c.two_hand_mode() + "'");
    s.two_hand_mode = *mode;
  }
  if (has("freeze_after_s")) s.freeze_after_s = c.freeze_after_s();
  if (has("remove_after_s")) s.remove_after_s = c.remove_after_s();
  if (has("late_latch")) s.late_latch = c.late_latch();
  if (has("status_period_s")) s.status_period_s = c.status_period_s();
  if (has("max_hands")) s.max_hands = c.max_hands();
  if (has("lockstep")) s.lockstep = c.lockstep();
  if (has("record")) s.record_path = c.record();
  for (const auto& id : c.operators()) s.operators.push_back(id);
  if (has("open_scene")) s.open_scene = c.open_scene();
  if (has("max_objects_per_client")) s.max_objects_per_client = c.max_objects_per_client();
  if (has("max_hands_per_participant")) s.max_hands_per_participant = c.max_hands_per_participant();
  for (const auto& r : c.relays()) s.relays.push_back({r.prefix(), r.max_hands() == 0 ? 64 : r.max_hands()});
  if (has("max_input_rate_hz")) s.max_input_rate_hz = c.max_input_rate_hz();
  if (has("max_command_rate_hz")) s.max_command_rate_hz = c.max_command_rate_hz();
  if (has("snapshot")) s.snapshot_path = c.snapshot();
  validate_settings(s, origin);
}

}  // namespace

void load_server_config(const std::string& path, ServerSettings& s) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error("server config " + path + ": cannot open");
  std::stringstream buffer;
  buffer << in.rdbuf();
  proto::ServerConfig c;
  google::protobuf::TextFormat::Parser parser;
  ErrorCollector errors;
  parser.RecordErrorsTo(&errors);
  if (!parser.ParseFromString(buffer.str(), &c)) throw std::runtime_error("server config " + path + ": " + errors.text);
  apply_config(c, s, "server config " + path);
}

void validate_settings(const ServerSettings& s, const std::string& origin) {
  auto fail = [&](const std::string& what) { throw std::runtime_error(origin + ": " + what); };
  if (s.domain < 0 || s.domain > 232) fail("domain must be in [0, 232], got " + std::to_string(s.domain));
  if (s.profile.empty()) fail("profile must not be empty");
  if (!s.scene.empty())
    if (const std::string e = idl::scene_name_error(s.scene); !e.empty()) fail("scene: " + e);
  if (!(s.claim_wait_s >= 0 && s.claim_wait_s <= 60)) fail("claim_wait_s must be in [0, 60]");
  if (!(s.tick_hz >= 1 && s.tick_hz <= 2000))
    fail("tick_hz must be in [1, 2000], got " + cli::format_number(s.tick_hz));
  if (!(s.freeze_after_s > 0)) fail("freeze_after_s must be > 0");
  if (!(s.remove_after_s >= s.freeze_after_s)) fail("remove_after_s must be >= freeze_after_s");
  if (!(s.remove_after_s <= 0.9))
    fail("remove_after_s must be <= 0.9 (a silent client's object is released within 1 s)");
  if (!(s.status_period_s > 0)) fail("status_period_s must be > 0");
  if (s.max_hands < 1 || s.max_hands > 4096) fail("max_hands must be in [1, 4096]");
  if (s.quality_delay_ticks < 0 || s.quality_delay_ticks > 90) fail("quality_delay_ticks must be in [0, 90]");
  for (const auto& o : s.objects)
    if (!std::isfinite(o.x) || !std::isfinite(o.y) || !std::isfinite(o.yaw))
      fail("objects '" + o.model + "': x, y, yaw must be finite");
  for (const auto& o : s.objects)
    if (o.friction && !(*o.friction >= 0 && std::isfinite(*o.friction)))
      fail("objects '" + o.model + "': friction must be a finite value >= 0");
  if (s.empty_scene && !s.objects.empty()) fail("empty_scene and objects exclude each other");
  for (const auto& id : s.operators)
    if (id.empty() || id.size() > 64) fail("operators: a client id has 1..64 characters, got '" + id + "'");
  if (s.max_objects_per_client < 0 || s.max_objects_per_client > 128)
    fail("max_objects_per_client must be in [0, 128]");
  if (s.max_hands_per_participant < 1 || s.max_hands_per_participant > 4096)
    fail("max_hands_per_participant must be in [1, 4096]");
  for (const Relay& r : s.relays) {
    if (r.prefix.empty() || r.prefix.size() > 32)
      fail("relays: a prefix has 1..32 characters, got '" + r.prefix + "'");
    if (r.max_hands < 1 || r.max_hands > 4096) fail("relays '" + r.prefix + "': max_hands must be in [1, 4096]");
    for (const Relay& other : s.relays)
      if (&other != &r && other.prefix.starts_with(r.prefix))
        fail("relays '" + r.prefix + "' and '" + other.prefix + "': one prefix starts the other");
  }
  if (!(s.max_input_rate_hz >= 1 && std::isfinite(s.max_input_rate_hz)))
    fail("max_input_rate_hz must be a finite value >= 1");
  if (!(s.max_command_rate_hz >= 0.1 && std::isfinite(s.max_command_rate_hz)))
    fail("max_command_rate_hz must be a finite value >= 0.1");
}

proto::ServerConfig to_proto(const ServerSettings& s) {
  proto::ServerConfig c;
  c.set_domain(s.domain);
  c.set_profile(s.profile);
  c.set_profiles_file(s.profiles_file);
  c.set_scene(s.scene);
  for (const auto& server : s.discovery_servers) c.add_discovery_servers(server);
  c.set_claim_wait_s(s.claim_wait_s);
  c.set_tick_hz(s.tick_hz);
  c.set_objects_dir(s.objects_dir);
  c.set_fill_standins(s.fill_standins);
  for (const auto& o : s.objects) {
    proto::SceneObject* p = c.add_objects();
    p->set_model(o.model);
    p->set_x(o.x);
    p->set_y(o.y);
    p->set_yaw(o.yaw);
    if (o.friction) p->set_friction(*o.friction);
    if (o.shape) p->set_shape(sim::shape_class_name(*o.shape));
  }
  c.set_empty_scene(s.empty_scene);
  c.set_right_rig(s.right_rig);
  c.set_left_rig(s.left_rig);
  c.set_closing_mode(sim::closing_mode_name(s.closing_mode));
  c.set_two_hand_mode(sim::two_hand_mode_name(s.two_hand_mode));
  c.set_freeze_after_s(s.freeze_after_s);
  c.set_remove_after_s(s.remove_after_s);
  c.set_late_latch(s.late_latch);
  c.set_quality_volume(s.quality_volume);
  c.set_quality_delay_ticks(s.quality_delay_ticks);
  c.set_status_period_s(s.status_period_s);
  c.set_max_hands(s.max_hands);
  c.set_lockstep(s.lockstep);
  c.set_record(s.record_path);
  for (const auto& id : s.operators) c.add_operators(id);
  c.set_open_scene(s.open_scene);
  c.set_max_objects_per_client(s.max_objects_per_client);
  c.set_max_hands_per_participant(s.max_hands_per_participant);
  for (const Relay& r : s.relays) {
    proto::Relay* relay = c.add_relays();
    relay->set_prefix(r.prefix);
    relay->set_max_hands(r.max_hands);
  }
  c.set_max_input_rate_hz(s.max_input_rate_hz);
  c.set_max_command_rate_hz(s.max_command_rate_hz);
  c.set_snapshot(s.snapshot_path);
  return c;
}

ServerSettings settings_from_proto(const proto::ServerConfig& config, const std::string& origin) {
  ServerSettings s;
  apply_config(config, s, origin);
  return s;
}

}  // namespace telegrasp::server
