#include "replay.h"

#include "scene_server.h"
#include "server_config.pb.h"
#include "telegrasp/idl/topics.h"
#include "telegrasp/sim/mesh_loading.h"
#include "telegrasp/sim/standin_objects.h"

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cstdio>
#include <cstring>
#include <deque>
#include <filesystem>
#include <fstream>
#include <memory>
#include <sstream>

namespace telegrasp::server {
namespace {

constexpr std::uint64_t kProgressEvery = 4096;  // records between progress callbacks

// Shortest text that reads back to the same double (std::to_chars without a precision).
std::string number(double v) {
  char buffer[32];
  const auto r = std::to_chars(buffer, buffer + sizeof buffer, v);
  return std::string(buffer, r.ptr);
}
std::string text(double v) { return number(v); }
std::string text(bool v) { return v ? "true" : "false"; }
std::string text(const std::string& v) { return "'" + v + "'"; }
template <std::size_t N>
std::string text(const eprosima::fastrtps::fixed_string<N>& v) { return text(v.to_string()); }
template <class T>
  requires std::is_integral_v<T> || std::is_enum_v<T>
std::string text(T v) { return std::to_string(static_cast<long long>(v)); }
std::string text(std::uint64_t v) { return std::to_string(v); }

std::string hand_text(const std::string& client_id, unsigned side) {
  return "client '" + client_id + "' " + (side == idl::kHandLeft ? "left" : side == idl::kHandRight ? "right" : "side " + std::to_string(side)) +
         " hand";
}

// The first field in which two decoded messages differ, with both values; later calls do nothing
// once one is found, so a whole message can be walked without early returns.
struct FieldDiff {
  std::string field, recorded, replayed;

  bool found() const { return !field.empty(); }
  template <class T>
  void value(const std::string& name, const T& a, const T& b) {
    if (found() || a == b) return;
    field = name;
    recorded = text(a);
    replayed = text(b);
  }
  template <class T, class F>
  void sequence(const std::string& name, const std::vector<T>& a, const std::vector<T>& b, F&& element) {
    if (found()) return;
    value(name + ".size", static_cast<std::uint64_t>(a.size()), static_cast<std::uint64_t>(b.size()));
    for (std::size_t i = 0; i < a.size() && i < b.size() && !found(); ++i) element(name + "[" + std::to_string(i) + "]", a[i], b[i]);
  }
  template <class T>
  void values(const std::string& name, const std::vector<T>& a, const std::vector<T>& b) {
    sequence(name, a, b, [this](const std::string& n, const T& x, const T& y) { value(n, static_cast<T>(x), static_cast<T>(y)); });
  }
  void values(const std::string& name, const std::vector<bool>& a, const std::vector<bool>& b) {
    if (found()) return;
    value(name + ".size", static_cast<std::uint64_t>(a.size()), static_cast<std::uint64_t>(b.size()));
    for (std::size_t i = 0; i < a.size() && i < b.size(); ++i) value(name + "[" + std::to_string(i) + "]", bool(a[i]), bool(b[i]));
  }

  void vec3(const std::string& n, const msg::Vec3& a, const msg::Vec3& b) {
    value(n + ".x", a.x(), b.x());
    value(n + ".y", a.y(), b.y());
    value(n + ".z", a.z(), b.z());
  }
  void pose(const std::string& n, const msg::Pose3& a, const msg::Pose3& b) {
    vec3(n + ".position", a.position(), b.position());
    value(n + ".orientation.w", a.orientation().w(), b.orientation().w());
    value(n + ".orientation.x", a.orientation().x(), b.orientation().x());
    value(n + ".orientation.y", a.orientation().y(), b.orientation().y());
    value(n + ".orientation.z", a.orientation().z(), b.orientation().z());
  }
  void contact(const std::string& n, const msg::ContactPoint& a, const msg::ContactPoint& b) {
    value(n + ".phalanx", a.phalanx(), b.phalanx());
    vec3(n + ".p_world", a.p_world(), b.p_world());
    vec3(n + ".n_world", a.n_world(), b.n_world());
    vec3(n + ".p_object", a.p_object(), b.p_object());
    vec3(n + ".n_object", a.n_object(), b.n_object());
    value(n + ".nd", a.nd(), b.nd());
    value(n + ".nd_hit", a.nd_hit(), b.nd_hit());
  }

  void fields(const msg::HandSkeleton& a, const msg::HandSkeleton& b) {
    value("client_id", a.client_id(), b.client_id());
    value("hand_side", a.hand_side(), b.hand_side());
    value("rig", a.rig(), b.rig());
    value("tick", a.tick(), b.tick());
    value("time", a.time(), b.time());
    value("input_sequence", a.input_sequence(), b.input_sequence());
    value("input_client_time_ns", a.input_client_time_ns(), b.input_client_time_ns());
    value("late_latched", a.late_latched(), b.late_latched());
    value("frozen", a.frozen(), b.frozen());
    pose("palm", a.palm(), b.palm());
    sequence("phalanges", a.phalanges(), b.phalanges(), [this](const std::string& n, const auto& x, const auto& y) { pose(n, x, y); });
    values("joint_angles", a.joint_angles(), b.joint_angles());
  }
  void fields(const msg::GraspState& a, const msg::GraspState& b) {
    value("client_id", a.client_id(), b.client_id());
    value("hand_side", a.hand_side(), b.hand_side());
    value("tick", a.tick(), b.tick());
    value("time", a.time(), b.time());
    value("selected_object", a.selected_object(), b.selected_object());
    value("grasped_object", a.grasped_object(), b.grasped_object());
    value("trigger", a.trigger(), b.trigger());
    values("blocked", a.blocked(), b.blocked());
    value("palm_contact", a.palm_contact(), b.palm_contact());
  }
  void fields(const msg::ContactSet& a, const msg::ContactSet& b) {
    value("client_id", a.client_id(), b.client_id());
    value("hand_side", a.hand_side(), b.hand_side());
    value("tick", a.tick(), b.tick());
    value("time", a.time(), b.time());
    value("object_id", a.object_id(), b.object_id());
    pose("object_pose", a.object_pose(), b.object_pose());
    sequence("contacts", a.contacts(), b.contacts(), [this](const std::string& n, const auto& x, const auto& y) { contact(n, x, y); });
  }
  void fields(const msg::GraspEvent& a, const msg::GraspEvent& b) {
    value("event_id", a.event_id(), b.event_id());
    value("kind", a.kind(), b.kind());
    value("client_id", a.client_id(), b.client_id());
    value("hand_side", a.hand_side(), b.hand_side());
    value("object_id", a.object_id(), b.object_id());
    value("object_name", a.object_name(), b.object_name());
    value("tick", a.tick(), b.tick());
    value("time", a.time(), b.time());
    value("object_spawn_time", a.object_spawn_time(), b.object_spawn_time());
    pose("object_pose", a.object_pose(), b.object_pose());
    value("input_sequence", a.input_sequence(), b.input_sequence());
    value("hand_error_mm", a.hand_error_mm(), b.hand_error_mm());
    value("capsules_without_hit", a.capsules_without_hit(), b.capsules_without_hit());
    sequence("capsules", a.capsules(), b.capsules(), [this](const std::string& n, const msg::CapsuleReport& x, const msg::CapsuleReport& y) {
      value(n + ".phalanx", x.phalanx(), y.phalanx());
      value(n + ".phalanx_name", x.phalanx_name(), y.phalanx_name());
      value(n + ".hit", x.hit(), y.hit());
      value(n + ".nd", x.nd(), y.nd());
      value(n + ".signed_distance", x.signed_distance(), y.signed_distance());
      value(n + ".blocked", x.blocked(), y.blocked());
    });
    sequence("contacts", a.contacts(), b.contacts(), [this](const std::string& n, const auto& x, const auto& y) { contact(n, x, y); });
    vec3("release_velocity", a.release_velocity(), b.release_velocity());
    vec3("release_angular_velocity", a.release_angular_velocity(), b.release_angular_velocity());
  }
  void fields(const msg::SceneState& a, const msg::SceneState& b) {
    value("tick", a.tick(), b.tick());
    value("time", a.time(), b.time());
    sequence("objects", a.objects(), b.objects(), [this](const std::string& n, const msg::ObjectState& x, const msg::ObjectState& y) {
      value(n + ".id", x.id(), y.id());
      value(n + ".name", x.name(), y.name());
      pose(n + ".pose", x.pose(), y.pose());
      vec3(n + ".linear_velocity", x.linear_velocity(), y.linear_velocity());
      value(n + ".held", x.held(), y.held());
      value(n + ".holder_client", x.holder_client(), y.holder_client());
      value(n + ".holder_hand", x.holder_hand(), y.holder_hand());
      value(n + ".spawn_time", x.spawn_time(), y.spawn_time());
    });
  }
};

// Which instance a message is about, for the divergence report.
std::string key_of(const msg::HandSkeleton& m) { return hand_text(m.client_id().to_string(), m.hand_side()); }
std::string key_of(const msg::GraspState& m) { return hand_text(m.client_id().to_string(), m.hand_side()); }
std::string key_of(const msg::ContactSet& m) {
  return hand_text(m.client_id().to_string(), m.hand_side()) + ", object " + std::to_string(m.object_id());
}
std::string key_of(const msg::GraspEvent& m) {
  return "event " + std::to_string(m.event_id()) + " (" + (m.kind() == msg::GRASP_EVENT_GRASP ? "grasp" : "release") + ", " +
         hand_text(m.client_id().to_string(), m.hand_side()) + "), object " + std::to_string(m.object_id()) + " '" +
         m.object_name().to_string() + "'";
}
std::string key_of(const msg::SceneState& m) { return "scene at tick " + std::to_string(m.tick()); }

// An output the replayed scene published, as the Recorder would have recorded it.
struct Produced {
  proto::OutputType type = proto::OUTPUT_UNSPECIFIED;
  std::string cdr;
  HandAddress removed;
};

// Collects what the replayed SceneServer publishes, in order, until it is compared.
class CaptureSink : public OutputSink {
 public:
  std::deque<Produced> produced;

  void publish(const msg::HandSkeleton& m) override { add(proto::OUTPUT_HAND_SKELETON, to_cdr(m)); }
  void publish(const msg::GraspState& m) override { add(proto::OUTPUT_GRASP_STATE, to_cdr(m)); }
  void publish(const msg::ContactSet& m) override { add(proto::OUTPUT_CONTACT_SET, to_cdr(m)); }
  void publish(const msg::GraspEvent& m) override { add(proto::OUTPUT_GRASP_EVENT, to_cdr(m)); }
  void publish(const msg::SceneState& m) override { add(proto::OUTPUT_SCENE_STATE, to_cdr(m)); }
  void publish(const msg::ServerStatus&) override {}  // the server publishes it, not the scene; never compared
  void hand_removed(const HandAddress& hand) override { produced.push_back({proto::OUTPUT_HAND_REMOVED, "", hand}); }

 private:
  void add(proto::OutputType type, std::string cdr) { produced.push_back({type, std::move(cdr), {}}); }
};

template <class T>
std::string key_of_cdr(const std::string& cdr) {
  T m;
  return from_cdr(cdr, m) ? key_of(m) : "undecodable";
}

// The key of an output (recorded or replayed) from its type and bytes.
std::string key_of_output(proto::OutputType type, const std::string& cdr, const HandAddress& removed) {
  switch (type) {
    case proto::OUTPUT_HAND_SKELETON: return key_of_cdr<msg::HandSkeleton>(cdr);
    case proto::OUTPUT_GRASP_STATE: return key_of_cdr<msg::GraspState>(cdr);
    case proto::OUTPUT_CONTACT_SET: return key_of_cdr<msg::ContactSet>(cdr);
    case proto::OUTPUT_GRASP_EVENT: return key_of_cdr<msg::GraspEvent>(cdr);
    case proto::OUTPUT_SCENE_STATE: return key_of_cdr<msg::SceneState>(cdr);
    case proto::OUTPUT_HAND_REMOVED: return hand_text(removed.client_id, removed.side);
    default: return "";
  }
}

HandAddress address(const proto::HandAddress& a) { return {a.client_id(), static_cast<std::uint8_t>(a.side())}; }

// Decodes both: true if the messages are equal, else names the first differing field in `diff`
// (or says in `why` that one does not decode).
template <class T>
bool diff_cdr(const std::string& recorded, const std::string& replayed, FieldDiff& diff, std::string& key, std::string& why) {
  T a, b;
  if (!from_cdr(recorded, a)) {
    why = "the recorded bytes do not decode with this build's IDL";
    return false;
  }
  key = key_of(a);
  if (!from_cdr(replayed, b)) {
    why = "the replayed bytes do not decode";  // cannot happen: to_cdr wrote them
    return false;
  }
  // Equal messages (e.g. written by a build that left CDR padding unzeroed) are the same output.
  if (a == b) return true;
  diff.fields(a, b);
  if (!diff.found()) why = "the messages differ in a field the comparison does not name";
  return false;
}

// Compares a recorded output with the replayed one; fills `d` (all but record/tick) if they differ.
bool same_output(const proto::Output& recorded, const Produced& replayed, Divergence& d) {
  d.type = output_type_name(recorded.type());
  if (recorded.type() != replayed.type) {
    d.key = key_of_output(recorded.type(), recorded.cdr(), address(recorded.removed()));
    d.message = "the recording has a " + d.type + " (" + d.key + ") where the replay published a " + output_type_name(replayed.type) +
                " (" + key_of_output(replayed.type, replayed.cdr, replayed.removed) + ")";
    return false;
  }
  if (recorded.type() == proto::OUTPUT_HAND_REMOVED) {
    const HandAddress a = address(recorded.removed());
    if (a == replayed.removed) return true;
    d.key = hand_text(a.client_id, a.side);
    d.field = "removed";
    d.message = "the recording removes the " + d.key + ", the replay the " + hand_text(replayed.removed.client_id, replayed.removed.side);
    return false;
  }
  if (recorded.cdr() == replayed.cdr) return true;
  FieldDiff diff;
  std::string why;
  bool same = false;
  switch (recorded.type()) {
    case proto::OUTPUT_HAND_SKELETON: same = diff_cdr<msg::HandSkeleton>(recorded.cdr(), replayed.cdr, diff, d.key, why); break;
    case proto::OUTPUT_GRASP_STATE: same = diff_cdr<msg::GraspState>(recorded.cdr(), replayed.cdr, diff, d.key, why); break;
    case proto::OUTPUT_CONTACT_SET: same = diff_cdr<msg::ContactSet>(recorded.cdr(), replayed.cdr, diff, d.key, why); break;
    case proto::OUTPUT_GRASP_EVENT: same = diff_cdr<msg::GraspEvent>(recorded.cdr(), replayed.cdr, diff, d.key, why); break;
    case proto::OUTPUT_SCENE_STATE: same = diff_cdr<msg::SceneState>(recorded.cdr(), replayed.cdr, diff, d.key, why); break;
    default: why = "unknown output type " + std::to_string(recorded.type());
  }
  if (same) return true;
  d.field = diff.field;
  d.message = d.type + (d.key.empty() ? "" : " of " + d.key) + " differs: " +
              (diff.found() ? diff.field + " is " + diff.recorded + " in the recording, " + diff.replayed + " in the replay" : why);
  return false;
}

std::string join(const std::vector<std::string>& parts, const char* sep) {
  std::string out;
  for (const auto& p : parts) out += (out.empty() ? "" : sep) + p;
  return out;
}

std::string hex64(std::uint64_t v) {
  char buffer[17];
  std::snprintf(buffer, sizeof buffer, "%016llx", static_cast<unsigned long long>(v));
  return buffer;
}

// A CSV field: quoted only when it must be (RFC 4180).
std::string csv_field(const std::string& s) {
  if (s.find_first_of(",\"\r\n") == std::string::npos) return s;
  std::string out = "\"";
  for (char c : s) out += c == '"' ? std::string("\"\"") : std::string(1, c);
  return out + "\"";
}

}  // namespace

std::string output_type_name(proto::OutputType type) {
  switch (type) {
    case proto::OUTPUT_HAND_SKELETON: return "HandSkeleton";
    case proto::OUTPUT_GRASP_STATE: return "GraspState";
    case proto::OUTPUT_CONTACT_SET: return "ContactSet";
    case proto::OUTPUT_GRASP_EVENT: return "GraspEvent";
    case proto::OUTPUT_SCENE_STATE: return "SceneState";
    case proto::OUTPUT_SERVER_STATUS: return "ServerStatus";
    case proto::OUTPUT_HAND_REMOVED: return "hand removal";
    default: return "output type " + std::to_string(static_cast<int>(type));
  }
}

SceneAssets load_recorded_assets(const proto::RecordingHeader& header, const std::string& recording_path, const std::string& objects_dir) {
  namespace fs = std::filesystem;
  const std::string origin = "recording " + recording_path;
  SceneAssets a;
  // Rigs from the embedded text, never from the file it names: that file may have changed since.
  auto rig = [&](const proto::RigText& r, const char* field, std::string& path, std::string& text) {
    if (r.text().empty()) throw RecordingError(origin + ": header." + field + " holds no rig text");
    path = r.path();
    text = r.text();
    try {
      return std::make_shared<const sim::HandRig>(sim::HandRig::parse(r.text(), origin + ": header." + field + " (" + r.path() + ")"));
    } catch (const sim::RigError& e) {
      throw RecordingError(e.what());
    }
  };
  a.right_rig = rig(header.right_rig(), "right_rig", a.right_rig_path, a.right_rig_text);
  a.left_rig = rig(header.left_rig(), "left_rig", a.left_rig_path, a.left_rig_text);

  const proto::ModelSource& ms = header.models();
  if (ms.builtin_standins()) {
    for (const auto& o : sim::protocol_objects()) a.models.push_back(sim::make_standin_model(o));
  } else {
    const std::string dir = objects_dir.empty() ? ms.objects_dir() : objects_dir;
    a.model_source.objects_dir = dir;
    // Every file is checked before any is loaded, so one message names all that are wrong.
    std::vector<std::string> problems, paths;
    for (const proto::MeshFile& f : ms.files()) {
      const std::string path = (fs::path(dir) / f.name()).string();
      MeshFileInfo info;
      try {
        info = describe_file(path);
      } catch (const std::runtime_error&) {
        problems.push_back(path + " is missing");
        continue;
      }
      if (info.size != f.size() || info.fnv1a64 != f.fnv1a64()) {
        problems.push_back(path + " changed (" + std::to_string(info.size) + " bytes, FNV-1a " + hex64(info.fnv1a64) + "; recorded " +
                           std::to_string(f.size()) + " bytes, " + hex64(f.fnv1a64()) + ")");
        continue;
      }
      a.model_source.files.push_back(info);
      paths.push_back(path);
    }
    if (!problems.empty())
      throw RecordingError(origin + ": the meshes it was recorded with are not in " + dir + ": " + join(problems, "; "));
    for (const std::string& path : paths) {
      try {
        a.models.push_back(sim::load_protocol_object_model(path));
      } catch (const sim::MeshLoadError& e) {
        throw RecordingError(origin + ": " + e.what());
      }
    }
    for (const std::string& name : ms.standin_names()) {
      const auto& all = sim::protocol_objects();
      auto it = std::find_if(all.begin(), all.end(), [&](const sim::ProtocolObject& o) { return o.name == name; });
      if (it == all.end()) throw RecordingError(origin + ": header.models.standin_names: '" + name + "' is not a protocol object");
      a.models.push_back(sim::make_standin_model(*it));
      a.model_source.standins.push_back(name);
    }
  }
  // The scene's object ids and default layout follow the model order: it must be the recorded one.
  const auto& names = ms.model_names();
  for (std::size_t i = 0; i < std::max<std::size_t>(a.models.size(), names.size()); ++i) {
    const std::string rebuilt = i < a.models.size() ? "'" + a.models[i]->name + "'" : "none";
    const std::string recorded = i < static_cast<std::size_t>(names.size()) ? "'" + names[static_cast<int>(i)] + "'" : "none";
    if (rebuilt != recorded)
      throw RecordingError(origin + ": header.models.model_names[" + std::to_string(i) + "] is " + recorded + ", the rebuilt model is " +
                           rebuilt);
  }
  return a;
}

std::string ReplayResult::summary() const {
  std::string s;
  if (divergence) {
    s = "divergence: " + divergence->message + "\n";
  } else {
    s = "identical: " + std::to_string(outputs_compared) + " outputs over " + std::to_string(ticks) + " ticks (" +
        std::to_string(records) + " records; " + std::to_string(statuses_skipped) + " ServerStatus not compared)\n";
  }
  if (damage) s += damage->message + (divergence ? "\n" : "; replayed up to it\n");
  for (const auto& w : warnings) s += "warning: " + w + "\n";
  return s;
}

int ReplayResult::exit_code() const {
  if (divergence) return 1;
  if (damage) return 3;
  return 0;
}

ReplayResult replay_recording(const std::string& path, const ReplayOptions& options) {
  RecordingReader reader(path);
  const proto::RecordingHeader& header = reader.header();
  ReplayResult result;
  if (header.idl_sha256() != idl_sha256())
    result.warnings.push_back("recorded with another idl/telegrasp.idl (SHA-256 " + header.idl_sha256() + ", this build's is " +
                              idl_sha256() + "): messages may not decode or compare");
  if (header.telegrasp_version() != telegrasp_version())
    result.warnings.push_back("recorded by telegrasp " + header.telegrasp_version() + ", replayed by " + telegrasp_version() +
                              ": the simulation may differ");

  ServerSettings settings;
  try {
    settings = settings_from_proto(header.config(), "recording " + path + ": header.config");
  } catch (const std::runtime_error& e) {
    throw RecordingError(e.what());
  }
  const SceneAssets assets = load_recorded_assets(header, path, options.objects_dir);
  // A fresh mailbox: the scene only asks it to forget removed hands and for the status counts.
  InputMailbox mailbox({assets.left_rig->fingers().size(), assets.right_rig->fingers().size()}, settings.max_hands,
                       [](const std::string&) {});
  CaptureSink sink;
  std::unique_ptr<SceneServer> scene;
  try {
    scene = std::make_unique<SceneServer>(settings, assets.models, assets.right_rig, assets.left_rig, mailbox, sink);
  } catch (const std::runtime_error& e) {
    throw RecordingError("recording " + path + ": the scene cannot be rebuilt from the header: " + e.what());
  }

  auto diverge = [&](std::uint64_t record, Divergence d) {
    d.record = record;
    d.tick = scene->world().tick();
    d.message = "record " + std::to_string(record) + " (tick " + std::to_string(d.tick) + "): " + d.message;
    result.divergence = std::move(d);
  };
  // The replay published something the recording does not have before its next call (or end).
  auto extra_output = [&](std::uint64_t record) {
    const Produced& p = sink.produced.front();
    Divergence d;
    d.type = output_type_name(p.type);
    d.key = key_of_output(p.type, p.cdr, p.removed);
    d.message = "the replay published a " + d.type + " (" + d.key + ") that the recording does not have";
    diverge(record, std::move(d));
  };

  proto::Record r;
  while (!result.divergence && reader.next(r)) {
    const std::uint64_t index = reader.records() - 1;
    if (options.progress && reader.records() % kProgressEvery == 0) options.progress(reader);
    if (r.has_output()) {
      const proto::Output& out = r.output();
      if (out.type() == proto::OUTPUT_SERVER_STATUS) {
        ++result.statuses_skipped;  // wall-clock loop timings: not reproducible
        continue;
      }
      if (sink.produced.empty()) {
        Divergence d;
        d.type = output_type_name(out.type());
        d.key = key_of_output(out.type(), out.cdr(), address(out.removed()));
        d.message = "the recording has a " + d.type + " (" + d.key + ") that the replay did not publish";
        diverge(index, std::move(d));
        break;
      }
      Divergence d;
      if (!same_output(out, sink.produced.front(), d)) {
        diverge(index, std::move(d));
        break;
      }
      sink.produced.pop_front();
      ++result.outputs_compared;
      continue;
    }
    // A call: everything the previous call published must have been matched by now.
    if (!sink.produced.empty()) {
      extra_output(index);
      break;
    }
    if (r.has_inputs()) {
      std::vector<InputSample> samples;
      for (const proto::InputSample& p : r.inputs().samples()) {
        InputSample s;
        s.hand = address(p.hand());
        s.received_ns = p.received_ns();
        if (!from_cdr(p.controller_state_cdr(), s.state)) {
          Divergence d;
          d.type = "ControllerState";
          d.key = hand_text(s.hand.client_id, s.hand.side);
          d.message = "the recorded ControllerState of the " + d.key + " does not decode with this build's IDL";
          diverge(index, std::move(d));
          break;
        }
        samples.push_back(std::move(s));
      }
      if (result.divergence) break;
      scene->on_inputs(std::move(samples), r.inputs().now_ns());
    } else if (r.has_command()) {
      msg::SceneCommand c;
      if (!from_cdr(r.command().scene_command_cdr(), c)) {
        Divergence d;
        d.type = "SceneCommand";
        d.message = "the recorded SceneCommand does not decode with this build's IDL";
        diverge(index, std::move(d));
        break;
      }
      scene->apply_command(c);
    } else if (r.has_tick()) {
      scene->tick(r.tick().now_ns());
      ++result.ticks;
    }
  }
  result.records = reader.records();
  result.damage = reader.damage();
  // A complete recording holds every output of its last call; a damaged one may end among them.
  if (!result.divergence && !result.damage && !sink.produced.empty()) extra_output(result.records);
  if (options.progress) options.progress(reader);
  return result;
}

const char* const kContactCsvHeader =
    "event_id,client_id,hand,object_id,object_name,tick,time,phalanx,phalanx_name,"
    "p_world_x,p_world_y,p_world_z,n_world_x,n_world_y,n_world_z,"
    "p_object_x,p_object_y,p_object_z,n_object_x,n_object_y,n_object_z,nd_m,nd_hit";

ContactExport export_contacts_csv(const std::string& recording_path, const std::string& csv_path) {
  RecordingReader reader(recording_path);
  // Phalanx names from the recorded rigs; a rig this build cannot parse leaves them empty.
  std::vector<std::string> phalanx_names[2];
  auto names_of = [&](const proto::RigText& r, std::vector<std::string>& out) {
    try {
      const sim::HandRig rig = sim::HandRig::parse(r.text(), r.path());
      for (const auto& p : rig.phalanges()) out.push_back(p.name);
    } catch (const sim::RigError&) {
    }
  };
  names_of(reader.header().left_rig(), phalanx_names[idl::kHandLeft]);
  names_of(reader.header().right_rig(), phalanx_names[idl::kHandRight]);

  std::ofstream out(csv_path, std::ios::binary);
  if (!out) throw RecordingError("contacts CSV " + csv_path + ": cannot write (" + std::strerror(errno) + ")");
  out << kContactCsvHeader << "\n";
  ContactExport e;
  proto::Record r;
  while (reader.next(r)) {
    if (!r.has_output() || r.output().type() != proto::OUTPUT_GRASP_EVENT) continue;
    msg::GraspEvent ev;
    if (!from_cdr(r.output().cdr(), ev))
      throw RecordingError("recording " + recording_path + ": record " + std::to_string(reader.records() - 1) +
                           ": the GraspEvent does not decode with this build's IDL");
    if (ev.kind() != msg::GRASP_EVENT_GRASP) continue;
    ++e.events;
    const unsigned side = ev.hand_side();
    const std::string prefix = std::to_string(ev.event_id()) + "," + csv_field(ev.client_id().to_string()) + "," +
                               (side == idl::kHandLeft ? "left" : side == idl::kHandRight ? "right" : std::to_string(side)) + "," +
                               std::to_string(ev.object_id()) + "," + csv_field(ev.object_name().to_string()) + "," +
                               std::to_string(ev.tick()) + "," + number(ev.time()) + ",";
    for (const msg::ContactPoint& c : ev.contacts()) {
      std::string name;
      if (c.phalanx() < 0) name = "palm";
      else if (side < 2 && static_cast<std::size_t>(c.phalanx()) < phalanx_names[side].size()) name = phalanx_names[side][c.phalanx()];
      auto v = [](const msg::Vec3& p) { return number(p.x()) + "," + number(p.y()) + "," + number(p.z()); };
      out << prefix << c.phalanx() << "," << csv_field(name) << "," << v(c.p_world()) << "," << v(c.n_world()) << "," << v(c.p_object())
          << "," << v(c.n_object()) << "," << number(c.nd()) << "," << (c.nd_hit() ? 1 : 0) << "\n";
      ++e.rows;
    }
  }
  e.damage = reader.damage();
  out.close();
  if (!out) throw RecordingError("contacts CSV " + csv_path + ": write failed (" + std::strerror(errno) + ")");
  return e;
}

}  // namespace telegrasp::server
