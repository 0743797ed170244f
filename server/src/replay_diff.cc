#include "replay_diff.h"

#include "telegrasp/idl/topics.h"

#include <charconv>
#include <type_traits>
#include <vector>

namespace telegrasp::server {
namespace {

std::string text(double v) { return shortest_number(v); }
std::string text(bool v) { return v ? "true" : "false"; }
std::string text(const std::string& v) { return "'" + v + "'"; }
template <std::size_t N>
std::string text(const eprosima::fastrtps::fixed_string<N>& v) {
  return text(v.to_string());
}
template <class T>
requires std::is_integral_v<T> || std::is_enum_v<T> std::string text(T v) {
  return std::to_string(static_cast<long long>(v));
}
std::string text(std::uint64_t v) { return std::to_string(v); }

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
    for (std::size_t i = 0; i < a.size() && i < b.size() && !found(); ++i)
      element(name + "[" + std::to_string(i) + "]", a[i], b[i]);
  }
  template <class T>
  void values(const std::string& name, const std::vector<T>& a, const std::vector<T>& b) {
    sequence(name, a, b,
             [this](const std::string& n, const T& x, const T& y) { value(n, static_cast<T>(x), static_cast<T>(y)); });
  }
  void values(const std::string& name, const std::vector<bool>& a, const std::vector<bool>& b) {
    if (found()) return;
    value(name + ".size", static_cast<std::uint64_t>(a.size()), static_cast<std::uint64_t>(b.size()));
    for (std::size_t i = 0; i < a.size() && i < b.size(); ++i)
      value(name + "[" + std::to_string(i) + "]", bool(a[i]), bool(b[i]));
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

  // The fields that open GraspState and ContactSet: the hand, then the tick and its time.
  template <class M>
  void hand_and_tick(const M& a, const M& b) {
    value("client_id", a.client_id(), b.client_id());
    value("hand_side", a.hand_side(), b.hand_side());
    value("tick", a.tick(), b.tick());
    value("time", a.time(), b.time());
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
    sequence("phalanges", a.phalanges(), b.phalanges(),
             [this](const std::string& n, const auto& x, const auto& y) { pose(n, x, y); });
    values("joint_angles", a.joint_angles(), b.joint_angles());
    pose("tracked_palm", a.tracked_palm(), b.tracked_palm());
    vec3("resolve_offset", a.resolve_offset(), b.resolve_offset());
    value("resolve_angle", a.resolve_angle(), b.resolve_angle());
  }
  void fields(const msg::GraspState& a, const msg::GraspState& b) {
    hand_and_tick(a, b);
    value("selected_object", a.selected_object(), b.selected_object());
    value("grasped_object", a.grasped_object(), b.grasped_object());
    value("trigger", a.trigger(), b.trigger());
    values("blocked", a.blocked(), b.blocked());
    value("palm_contact", a.palm_contact(), b.palm_contact());
    value("epsilon", a.epsilon(), b.epsilon());
    value("volume", a.volume(), b.volume());
    value("force_closure", a.force_closure(), b.force_closure());
    value("grasp_type", a.grasp_type(), b.grasp_type());
  }
  void fields(const msg::ContactSet& a, const msg::ContactSet& b) {
    hand_and_tick(a, b);
    value("object_id", a.object_id(), b.object_id());
    pose("object_pose", a.object_pose(), b.object_pose());
    sequence("contacts", a.contacts(), b.contacts(),
             [this](const std::string& n, const auto& x, const auto& y) { contact(n, x, y); });
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
    sequence("capsules", a.capsules(), b.capsules(),
             [this](const std::string& n, const msg::CapsuleReport& x, const msg::CapsuleReport& y) {
               value(n + ".phalanx", x.phalanx(), y.phalanx());
               value(n + ".phalanx_name", x.phalanx_name(), y.phalanx_name());
               value(n + ".hit", x.hit(), y.hit());
               value(n + ".nd", x.nd(), y.nd());
               value(n + ".signed_distance", x.signed_distance(), y.signed_distance());
               value(n + ".blocked", x.blocked(), y.blocked());
               value(n + ".contact_hit", x.contact_hit(), y.contact_hit());
               value(n + ".nd_contact", x.nd_contact(), y.nd_contact());
             });
    value("palm_signed_distance", a.palm_signed_distance(), b.palm_signed_distance());
    value("epsilon", a.epsilon(), b.epsilon());
    value("volume", a.volume(), b.volume());
    value("force_closure", a.force_closure(), b.force_closure());
    sequence("contacts", a.contacts(), b.contacts(),
             [this](const std::string& n, const auto& x, const auto& y) { contact(n, x, y); });
    vec3("release_velocity", a.release_velocity(), b.release_velocity());
    vec3("release_angular_velocity", a.release_angular_velocity(), b.release_angular_velocity());
    value("grasp_type", a.grasp_type(), b.grasp_type());
  }
  void fields(const msg::SceneState& a, const msg::SceneState& b) {
    value("tick", a.tick(), b.tick());
    value("time", a.time(), b.time());
    sequence("objects", a.objects(), b.objects(),
             [this](const std::string& n, const msg::ObjectState& x, const msg::ObjectState& y) {
               value(n + ".id", x.id(), y.id());
               value(n + ".name", x.name(), y.name());
               pose(n + ".pose", x.pose(), y.pose());
               vec3(n + ".linear_velocity", x.linear_velocity(), y.linear_velocity());
               value(n + ".held", x.held(), y.held());
               value(n + ".holder_client", x.holder_client(), y.holder_client());
               value(n + ".holder_hand", x.holder_hand(), y.holder_hand());
               value(n + ".spawn_time", x.spawn_time(), y.spawn_time());
               sequence(n + ".holders", x.holders(), y.holders(),
                        [this](const std::string& m, const msg::ObjectHolder& p, const msg::ObjectHolder& q) {
                          value(m + ".client_id", p.client_id(), q.client_id());
                          value(m + ".hand_side", p.hand_side(), q.hand_side());
                        });
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
  return "event " + std::to_string(m.event_id()) + " (" + (m.kind() == msg::GRASP_EVENT_GRASP ? "grasp" : "release") +
         ", " + hand_text(m.client_id().to_string(), m.hand_side()) + "), object " + std::to_string(m.object_id()) +
         " '" + m.object_name().to_string() + "'";
}
std::string key_of(const msg::SceneState& m) { return "scene at tick " + std::to_string(m.tick()); }

template <class T>
std::string key_of_cdr(const std::string& cdr) {
  T m;
  return from_cdr(cdr, m) ? key_of(m) : "undecodable";
}

// Decodes both: true if the messages are equal, else names the first differing field in `diff`
// (or says in `why` that one does not decode).
template <class T>
bool diff_cdr(const std::string& recorded, const std::string& replayed, FieldDiff& diff, std::string& key,
              std::string& why) {
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

}  // namespace

std::string shortest_number(double v) {
  char buffer[32];
  const auto r = std::to_chars(buffer, buffer + sizeof buffer, v);
  return std::string(buffer, r.ptr);
}

std::string hand_text(const std::string& client_id, unsigned side) {
  return "client '" + client_id + "' " +
         (side == idl::kHandLeft    ? "left"
          : side == idl::kHandRight ? "right"
                                    : "side " + std::to_string(side)) +
         " hand";
}

HandAddress hand_address(const proto::HandAddress& a) { return {a.client_id(), static_cast<std::uint8_t>(a.side())}; }

std::string key_of_output(proto::OutputType type, const std::string& cdr, const HandAddress& removed) {
  switch (type) {
    case proto::OUTPUT_HAND_SKELETON:
      return key_of_cdr<msg::HandSkeleton>(cdr);
    case proto::OUTPUT_GRASP_STATE:
      return key_of_cdr<msg::GraspState>(cdr);
    case proto::OUTPUT_CONTACT_SET:
      return key_of_cdr<msg::ContactSet>(cdr);
    case proto::OUTPUT_GRASP_EVENT:
      return key_of_cdr<msg::GraspEvent>(cdr);
    case proto::OUTPUT_SCENE_STATE:
      return key_of_cdr<msg::SceneState>(cdr);
    case proto::OUTPUT_HAND_REMOVED:
      return hand_text(removed.client_id, removed.side);
    default:
      return "";
  }
}

std::string output_type_name(proto::OutputType type) {
  switch (type) {
    case proto::OUTPUT_HAND_SKELETON:
      return "HandSkeleton";
    case proto::OUTPUT_GRASP_STATE:
      return "GraspState";
    case proto::OUTPUT_CONTACT_SET:
      return "ContactSet";
    case proto::OUTPUT_GRASP_EVENT:
      return "GraspEvent";
    case proto::OUTPUT_SCENE_STATE:
      return "SceneState";
    case proto::OUTPUT_SERVER_STATUS:
      return "ServerStatus";
    case proto::OUTPUT_HAND_REMOVED:
      return "hand removal";
    default:
      return "output type " + std::to_string(static_cast<int>(type));
  }
}

bool same_output(const proto::Output& recorded, const ReplayedOutput& replayed, Divergence& d) {
  d.type = output_type_name(recorded.type());
  if (recorded.type() != replayed.type) {
    d.key = key_of_output(recorded.type(), recorded.cdr(), hand_address(recorded.removed()));
    d.message = "the recording has a " + d.type + " (" + d.key + ") where the replay published a " +
                output_type_name(replayed.type) + " (" + key_of_output(replayed.type, replayed.cdr, replayed.removed) +
                ")";
    return false;
  }
  if (recorded.type() == proto::OUTPUT_HAND_REMOVED) {
    const HandAddress a = hand_address(recorded.removed());
    if (a == replayed.removed) return true;
    d.key = hand_text(a.client_id, a.side);
    d.field = "removed";
    d.message = "the recording removes the " + d.key + ", the replay the " +
                hand_text(replayed.removed.client_id, replayed.removed.side);
    return false;
  }
  if (recorded.cdr() == replayed.cdr) return true;
  FieldDiff diff;
  std::string why;
  bool same = false;
  switch (recorded.type()) {
    case proto::OUTPUT_HAND_SKELETON:
      same = diff_cdr<msg::HandSkeleton>(recorded.cdr(), replayed.cdr, diff, d.key, why);
      break;
    case proto::OUTPUT_GRASP_STATE:
      same = diff_cdr<msg::GraspState>(recorded.cdr(), replayed.cdr, diff, d.key, why);
      break;
    case proto::OUTPUT_CONTACT_SET:
      same = diff_cdr<msg::ContactSet>(recorded.cdr(), replayed.cdr, diff, d.key, why);
      break;
    case proto::OUTPUT_GRASP_EVENT:
      same = diff_cdr<msg::GraspEvent>(recorded.cdr(), replayed.cdr, diff, d.key, why);
      break;
    case proto::OUTPUT_SCENE_STATE:
      same = diff_cdr<msg::SceneState>(recorded.cdr(), replayed.cdr, diff, d.key, why);
      break;
    default:
      why = "unknown output type " + std::to_string(recorded.type());
  }
  if (same) return true;
  d.field = diff.field;
  d.message =
      d.type + (d.key.empty() ? "" : " of " + d.key) + " differs: " +
      (diff.found() ? diff.field + " is " + diff.recorded + " in the recording, " + diff.replayed + " in the replay"
                    : why);
  return false;
}

}  // namespace telegrasp::server
