#include "controller_input.h"

#include "telegrasp/sim/hand_rig.h"

#include <nlohmann/json.hpp>

#include <cmath>

namespace telegrasp::view {
namespace {

using Json = nlohmann::json;

constexpr double kMaxCoordinate = 100.0;  // m, as the server's input limits
constexpr double kUnitTolerance = 1e-3;  // |q| - 1, as the server's

// The number at `object[key]` ("where.key" in errors), finite; nullopt and `error` set otherwise.
std::optional<double> number(const Json& object, const char* key, const std::string& where, std::string& error) {
  const auto it = object.find(key);
  if (it == object.end() || !it->is_number()) {
    error = where + key + ": expected a number";
    return std::nullopt;
  }
  const double v = it->get<double>();
  if (!std::isfinite(v)) {
    error = where + key + ": expected a finite number";
    return std::nullopt;
  }
  return v;
}

std::optional<double> unit_interval(const Json& object, const char* key, const std::string& where,
                                    std::string& error) {
  const std::optional<double> v = number(object, key, where, error);
  if (v && (*v < 0 || *v > 1)) {
    error = where + key + ": expected a value in [0, 1], got " + std::to_string(*v);
    return std::nullopt;
  }
  return v;
}

}  // namespace

std::optional<ControllerInput> parse_controller_input(std::string_view text, std::string& error) {
  if (text.size() > kMaxControllerInputBytes) {
    error = "message of " + std::to_string(text.size()) + " bytes; at most " +
            std::to_string(kMaxControllerInputBytes);
    return std::nullopt;
  }
  const Json m = Json::parse(text, nullptr, false);
  if (m.is_discarded() || !m.is_object()) {
    error = "not a JSON object";
    return std::nullopt;
  }
  ControllerInput in;
  if (const auto v = m.find("version"); v != m.end()) {
    if (!v->is_number_integer() || v->get<long long>() < 1 || v->get<long long>() > kControllerInputVersion) {
      error = "version: this bridge speaks telegrasp.ControllerInput version 1.." +
              std::to_string(kControllerInputVersion);
      return std::nullopt;
    }
  }
  const auto side = m.find("side");
  if (side == m.end() || !side->is_string() || (*side != "right" && *side != "left")) {
    error = "side: expected \"right\" or \"left\"";
    return std::nullopt;
  }
  in.side = *side == "right" ? client::HandSide::kRight : client::HandSide::kLeft;

  const auto pose = m.find("pose");
  if (pose == m.end() || !pose->is_object() || !pose->contains("position") || !(*pose)["position"].is_object() ||
      !pose->contains("orientation") || !(*pose)["orientation"].is_object()) {
    error = "pose: expected {\"position\": {x, y, z}, \"orientation\": {x, y, z, w}}";
    return std::nullopt;
  }
  const Json& p = (*pose)["position"];
  const Json& o = (*pose)["orientation"];
  Eigen::Vector3d position;
  for (int i = 0; i < 3; ++i) {
    const char* key = i == 0 ? "x" : i == 1 ? "y" : "z";
    const std::optional<double> v = number(p, key, "pose.position.", error);
    if (!v) return std::nullopt;
    if (std::abs(*v) > kMaxCoordinate) {
      error = std::string("pose.position.") + key + ": farther than " + std::to_string(int(kMaxCoordinate)) +
              " m from the origin";
      return std::nullopt;
    }
    position[i] = *v;
  }
  double q[4];
  for (int i = 0; i < 4; ++i) {
    const char* key = i == 0 ? "x" : i == 1 ? "y" : i == 2 ? "z" : "w";
    const std::optional<double> v = number(o, key, "pose.orientation.", error);
    if (!v) return std::nullopt;
    q[i] = *v;
  }
  const Eigen::Quaterniond rotation(q[3], q[0], q[1], q[2]);
  if (std::abs(rotation.norm() - 1) > kUnitTolerance) {
    error = "pose.orientation: not a unit quaternion (norm " + std::to_string(rotation.norm()) + ")";
    return std::nullopt;
  }
  in.X_WorldGrip.linear() = rotation.normalized().toRotationMatrix();
  in.X_WorldGrip.translation() = position;

  const std::optional<double> trigger = unit_interval(m, "trigger", "", error);
  if (!trigger) return std::nullopt;
  in.trigger = *trigger;
  if (const auto curls = m.find("curls"); curls != m.end() && !curls->is_null()) {
    if (!curls->is_array() || (!curls->empty() && curls->size() != 5)) {
      error = "curls: expected 5 values in [0, 1] (thumb first) or none";
      return std::nullopt;
    }
    for (std::size_t i = 0; i < curls->size(); ++i) {
      const Json& c = (*curls)[i];
      if (!c.is_number() || !std::isfinite(c.get<double>()) || c.get<double>() < 0 || c.get<double>() > 1) {
        error = "curls[" + std::to_string(i) + "]: expected a value in [0, 1]";
        return std::nullopt;
      }
      in.curls.push_back(c.get<double>());
    }
  }
  if (const auto tracking = m.find("tracking"); tracking != m.end()) {
    if (!tracking->is_boolean()) {
      error = "tracking: expected true or false";
      return std::nullopt;
    }
    in.tracking = tracking->get<bool>();
  }
  const auto seq = m.find("seq");
  if (seq == m.end() || !seq->is_number_unsigned() || seq->get<std::uint64_t>() == 0) {
    error = "seq: expected an integer >= 1, increasing per hand";
    return std::nullopt;
  }
  in.seq = seq->get<std::uint64_t>();
  if (const auto stamp = m.find("stamp"); stamp != m.end()) {
    if (!stamp->is_object() || !(*stamp)["sec"].is_number_integer() || !(*stamp)["nsec"].is_number_integer()) {
      error = "stamp: expected {\"sec\": integer, \"nsec\": integer}";
      return std::nullopt;
    }
    in.stamp_ns = (*stamp)["sec"].get<std::int64_t>() * 1'000'000'000 + (*stamp)["nsec"].get<std::int64_t>();
  }
  return in;
}

Eigen::Isometry3d grip_to_palm(const sim::HandRig& rig, client::HandSide side) {
  // Columns: the grip's axes in the palm frame.
  Eigen::Matrix3d R_PalmGrip;
  if (side == client::HandSide::kLeft)
    R_PalmGrip << 0, -1, 0,  //
        0, 0, 1,             //
        -1, 0, 0;
  else
    R_PalmGrip << 0, -1, 0,  //
        0, 0, -1,            //
        1, 0, 0;
  Eigen::Isometry3d X_PalmGrip = Eigen::Isometry3d::Identity();
  X_PalmGrip.linear() = R_PalmGrip;
  X_PalmGrip.translation() = rig.p_PalmGraspCenter();
  return X_PalmGrip.inverse();
}

}  // namespace telegrasp::view
