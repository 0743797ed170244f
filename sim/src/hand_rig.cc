// Loading, validating and mirroring hand rigs.
#include "telegrasp/sim/hand_rig.h"

#include "telegrasp/sim/data_paths.h"

#include "hand_rig.pb.h"  // generated from sim/proto/hand_rig.proto

#include <google/protobuf/io/tokenizer.h>
#include <google/protobuf/text_format.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <numbers>
#include <set>
#include <sstream>

namespace telegrasp::sim {
namespace {

constexpr double kDeg = std::numbers::pi / 180.0;

class CollectErrors : public google::protobuf::io::ErrorCollector {
 public:
  void AddError(int line, int column, const std::string& message) override {
    if (text.empty()) text = "line " + std::to_string(line + 1) + ":" + std::to_string(column + 1) + ": " + message;
  }
  void AddWarning(int, int, const std::string&) override {}
  std::string text;
};

[[noreturn]] void fail(const std::string& source, const std::string& field, const std::string& what) {
  throw RigError(source + ": field '" + field + "': " + what);
}

Eigen::Vector3d to_eigen(const proto::Vec3& v) { return {v.x(), v.y(), v.z()}; }

bool finite(const Eigen::Vector3d& v) { return v.allFinite(); }

Eigen::Isometry3d to_isometry(const proto::Transform& t, const std::string& source, const std::string& field) {
  Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
  X.translation() = to_eigen(t.translation());
  if (!finite(X.translation())) fail(source, field + ".translation", "must be finite");
  for (int i = 0; i < t.rotation_size(); ++i) {
    const std::string rfield = field + ".rotation[" + std::to_string(i) + "]";
    const Eigen::Vector3d axis = to_eigen(t.rotation(i).axis());
    if (!finite(axis) || axis.norm() < 1e-9) fail(source, rfield + ".axis", "must be a non-zero finite vector");
    if (!std::isfinite(t.rotation(i).angle_deg())) fail(source, rfield + ".angle_deg", "must be finite");
    X.linear() = X.linear() * Eigen::AngleAxisd(t.rotation(i).angle_deg() * kDeg, axis.normalized()).toRotationMatrix();
  }
  return X;
}

PalmSphere to_sphere(const proto::Sphere& s, const std::string& source, const std::string& field, bool required) {
  PalmSphere out{to_eigen(s.center()), s.radius()};
  if (!finite(out.p_PalmCenter)) fail(source, field + ".center", "must be finite");
  if (required && !(out.radius > 0))
    fail(source, field + ".radius", "must be > 0 (got " + std::to_string(s.radius()) + ")");
  return out;
}

// A joint's part of the closing input (Joint.closes_from/closes_until, or a grasp type's).
void check_closing_range(const std::string& source, const std::string& field, double from, double until) {
  if (!(from >= 0 && from < until && until <= 1))
    fail(source, field + ".closes_from/closes_until",
         "must satisfy 0 <= closes_from < closes_until <= 1 (got " + std::to_string(from) + " and " +
             std::to_string(until) + ")");
}

// The groups of a grasp rule, each member a phalanx of `rig` with a capsule, or "palm".
template <typename Groups>
std::vector<std::vector<GraspTerm>> parse_rule(const HandRig& rig, const Groups& groups, const std::string& source,
                                               const std::string& field) {
  std::vector<std::vector<GraspTerm>> rule;
  for (int g = 0; g < groups.size(); ++g) {
    const std::string gfield = field + "[" + std::to_string(g) + "].members";
    std::vector<GraspTerm> group;
    if (groups.Get(g).members().empty()) fail(source, gfield, "group is empty");
    for (const auto& member : groups.Get(g).members()) {
      if (member == "palm") {
        group.push_back({true, {}});
        continue;
      }
      const PhalanxId id = rig.find(member);
      if (!id.valid()) fail(source, gfield, "unknown phalanx '" + member + "'");
      if (!rig.phalanges()[id.value].capsule)
        fail(source, gfield, "phalanx '" + member + "' has no capsule trigger, so it can never block");
      group.push_back({false, id});
    }
    rule.push_back(std::move(group));
  }
  return rule;
}

}  // namespace

std::string HandRig::builtin_path(const std::string& name) {
  return (data_dir() / "rigs" / (name + ".textproto")).string();
}

std::string HandRig::default_human(HandSide side) {
  return side == HandSide::kLeft ? "human_left_opposable" : "human_right_opposable";
}

HandRig HandRig::load(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw RigError(path + ": cannot open rig file");
  std::stringstream buffer;
  buffer << in.rdbuf();
  return parse(buffer.str(), path);
}

HandRig HandRig::parse(const std::string& text, const std::string& source) {
  proto::HandRig msg;
  google::protobuf::TextFormat::Parser parser;
  CollectErrors errors;
  parser.RecordErrorsTo(&errors);
  if (!parser.ParseFromString(text, &msg))
    throw RigError(source + ": " + (errors.text.empty() ? "not a HandRig text file" : errors.text));

  HandRig rig;
  rig.name_ = msg.name();
  if (rig.name_.empty()) fail(source, "name", "must not be empty");
  rig.side_ = msg.side() == proto::HAND_SIDE_LEFT    ? HandSide::kLeft
              : msg.side() == proto::HAND_SIDE_RIGHT ? HandSide::kRight
                                                     : HandSide::kUnspecified;
  rig.selection_sphere_ = to_sphere(msg.palm_selection_sphere(), source, "palm_selection_sphere", true);
  rig.palm_contact_ = to_sphere(msg.palm_contact_volume(), source, "palm_contact_volume", true);
  rig.nd_sweep_radius_ = msg.nd_sweep_radius();
  if (!(rig.nd_sweep_radius_ >= 0) || !std::isfinite(rig.nd_sweep_radius_))
    fail(source, "nd_sweep_radius", "must be >= 0");
  rig.nd_sweep_beyond_ = msg.nd_sweep_beyond();
  if (!(rig.nd_sweep_beyond_ > 0) || !std::isfinite(rig.nd_sweep_beyond_))
    fail(source, "nd_sweep_beyond", "must be > 0");
  if (msg.has_friction()) rig.friction_ = msg.friction();
  if (!(rig.friction_ >= 0) || !std::isfinite(rig.friction_))
    fail(source, "friction", "must be a finite value >= 0 (got " + std::to_string(rig.friction_) + ")");
  rig.palm_half_extent_ = to_eigen(msg.palm_half_extent());
  if (!finite(rig.palm_half_extent_) || rig.palm_half_extent_.minCoeff() <= 0)
    fail(source, "palm_half_extent", "must be positive in x, y and z");
  rig.p_PalmGraspCenter_ = to_eigen(msg.grasp_center());
  if (!finite(rig.p_PalmGraspCenter_)) fail(source, "grasp_center", "must be finite");
  const double default_speed = msg.default_max_speed_deg_s();
  if (!(default_speed > 0) || !std::isfinite(default_speed)) fail(source, "default_max_speed_deg_s", "must be > 0");
  if (msg.fingers().empty()) fail(source, "fingers", "a rig needs at least one finger");

  std::set<std::string> names;
  for (int f = 0; f < msg.fingers_size(); ++f) {
    const auto& finger = msg.fingers(f);
    const std::string ffield = "fingers[" + std::to_string(f) + "]";
    if (finger.name().empty()) fail(source, ffield + ".name", "must not be empty");
    if (finger.phalanges().empty())
      fail(source, ffield + ".phalanges", "finger '" + finger.name() + "' has no phalanx");
    FingerSpec fs{finger.name(), {}};
    for (int p = 0; p < finger.phalanges_size(); ++p) {
      const auto& ph = finger.phalanges(p);
      const std::string field = ffield + ".phalanges[" + std::to_string(p) + "]";
      PhalanxSpec spec;
      spec.name = ph.name();
      if (spec.name.empty()) fail(source, field + ".name", "must not be empty");
      if (spec.name == "palm") fail(source, field + ".name", "'palm' is reserved for the palm contact volume");
      if (!names.insert(spec.name).second) fail(source, field + ".name", "duplicate phalanx name '" + spec.name + "'");
      spec.finger = f;
      spec.parent = p == 0 ? -1 : static_cast<int>(rig.phalanges_.size()) - 1;
      spec.X_ParentJoint = to_isometry(ph.rest(), source, field + ".rest");
      const auto& j = ph.joint();
      const Eigen::Vector3d axis = to_eigen(j.axis());
      if (!finite(axis) || axis.norm() < 1e-9) fail(source, field + ".joint.axis", "must be a non-zero finite vector");
      spec.axis = axis.normalized();
      for (double v : {j.open_deg(), j.closed_deg(), j.min_deg(), j.max_deg(), j.max_speed_deg_s()})
        if (!std::isfinite(v)) fail(source, field + ".joint", "angles and speed must be finite");
      if (j.min_deg() > j.max_deg()) fail(source, field + ".joint.min_deg", "must be <= max_deg");
      for (auto [v, n] : {std::pair{j.open_deg(), "open_deg"}, std::pair{j.closed_deg(), "closed_deg"}})
        if (v < j.min_deg() || v > j.max_deg())
          fail(source, field + ".joint." + n,
               "must lie within [min_deg, max_deg] = [" + std::to_string(j.min_deg()) + ", " +
                   std::to_string(j.max_deg()) + "]");
      if (j.max_speed_deg_s() < 0) fail(source, field + ".joint.max_speed_deg_s", "must be >= 0");
      spec.open = j.open_deg() * kDeg;
      spec.closed = j.closed_deg() * kDeg;
      spec.min = j.min_deg() * kDeg;
      spec.max = j.max_deg() * kDeg;
      spec.max_speed = (j.max_speed_deg_s() > 0 ? j.max_speed_deg_s() : default_speed) * kDeg;
      spec.closes_from = j.has_closes_from() ? j.closes_from() : 0.0;
      spec.closes_until = j.has_closes_until() ? j.closes_until() : 1.0;
      check_closing_range(source, field + ".joint", spec.closes_from, spec.closes_until);
      spec.length = ph.length();
      if (!(spec.length >= 0) || !std::isfinite(spec.length))
        fail(source, field + ".length", "must be >= 0 (0: one more axis of the next phalanx's joint)");
      if (ph.has_capsule()) {
        const auto& c = ph.capsule();
        CapsuleSpec cs{to_eigen(c.a()), to_eigen(c.b()), c.radius(), to_eigen(c.ctc()), to_eigen(c.sp())};
        if (!finite(cs.p_PhalanxA) || !finite(cs.p_PhalanxB)) fail(source, field + ".capsule.a/b", "must be finite");
        if ((cs.p_PhalanxA - cs.p_PhalanxB).norm() < 1e-6)
          fail(source, field + ".capsule.b", "must differ from capsule.a");
        if (!(cs.radius > 0) || !std::isfinite(cs.radius)) fail(source, field + ".capsule.radius", "must be > 0");
        if (!finite(cs.p_PhalanxCTc) || !finite(cs.p_PhalanxSp))
          fail(source, field + ".capsule.ctc/sp", "must be finite");
        if ((cs.p_PhalanxCTc - cs.p_PhalanxSp).norm() < 1e-6)
          fail(source, field + ".capsule.sp", "must differ from ctc (Sp -> CTc gives the sweep direction)");
        spec.capsule = cs;
      }
      fs.phalanges.push_back(PhalanxId(static_cast<int>(rig.phalanges_.size())));
      rig.phalanges_.push_back(std::move(spec));
    }
    rig.fingers_.push_back(std::move(fs));
  }

  if (msg.grasp_rule().empty()) fail(source, "grasp_rule", "needs at least one group");
  rig.grasp_rule_ = parse_rule(rig, msg.grasp_rule(), source, "grasp_rule");

  for (int t = 0; t < msg.grasp_types_size(); ++t) {
    const auto& type_msg = msg.grasp_types(t);
    const std::string tfield = "grasp_types[" + std::to_string(t) + "]";
    const std::optional<GraspType> type = parse_grasp_type(type_msg.type());
    if (!type || *type == GraspType::kOther)
      fail(source, tfield + ".type",
           "must be power_sphere, tripod, small_wrap, medium_wrap, large_wrap, disk, prismatic or lateral_pinch "
           "(got '" + type_msg.type() + "')");
    auto& slot = rig.types_[static_cast<std::size_t>(*type)];
    if (slot) fail(source, tfield + ".type", "type '" + type_msg.type() + "' is listed twice");
    TypeClosing closing;
    for (const PhalanxSpec& p : rig.phalanges_) closing.joints.push_back({p.open, p.closed, p.closes_from, p.closes_until});
    for (int j = 0; j < type_msg.joints_size(); ++j) {
      const auto& jm = type_msg.joints(j);
      const std::string jfield = tfield + ".joints[" + std::to_string(j) + "]";
      const PhalanxId id = rig.find(jm.phalanx());
      if (!id.valid()) fail(source, jfield + ".phalanx", "unknown phalanx '" + jm.phalanx() + "'");
      const PhalanxSpec& spec = rig.phalanges_[id.value];
      JointClosing& c = closing.joints[id.value];
      if (jm.has_open_deg()) c.open = jm.open_deg() * kDeg;
      if (jm.has_closed_deg()) c.closed = jm.closed_deg() * kDeg;
      if (jm.has_closes_from()) c.closes_from = jm.closes_from();
      if (jm.has_closes_until()) c.closes_until = jm.closes_until();
      for (auto [v, n] : {std::pair{c.open, "open_deg"}, std::pair{c.closed, "closed_deg"}})
        if (!(v >= spec.min - 1e-12 && v <= spec.max + 1e-12))
          fail(source, jfield + "." + n,
               "must lie within the joint's [min_deg, max_deg] = [" + std::to_string(spec.min / kDeg) + ", " +
                   std::to_string(spec.max / kDeg) + "]");
      check_closing_range(source, jfield, c.closes_from, c.closes_until);
    }
    if (!type_msg.grasp_rule().empty())
      closing.grasp_rule = parse_rule(rig, type_msg.grasp_rule(), source, tfield + ".grasp_rule");
    slot = std::move(closing);
  }
  rig.finish(source);
  return rig;
}

void HandRig::finish(const std::string&) {
  capsule_phalanges_.clear();
  for (std::size_t i = 0; i < phalanges_.size(); ++i)
    if (phalanges_[i].capsule) capsule_phalanges_.push_back(PhalanxId(static_cast<int>(i)));
  for (auto& type : types_) {
    if (!type) continue;
    type->phalanges = phalanges_;
    for (std::size_t i = 0; i < phalanges_.size(); ++i) {
      const JointClosing& c = type->joints[i];
      PhalanxSpec& p = type->phalanges[i];
      p.open = c.open;
      p.closed = c.closed;
      p.closes_from = c.closes_from;
      p.closes_until = c.closes_until;
    }
  }
}

bool HandRig::has_grasp_type(GraspType type) const {
  return type == GraspType::kOther || types_[static_cast<std::size_t>(type)].has_value();
}

bool HandRig::has_grasp_types() const {
  return std::any_of(types_.begin(), types_.end(), [](const auto& t) { return t.has_value(); });
}

const std::vector<PhalanxSpec>& HandRig::phalanges(GraspType type) const {
  const auto& t = types_[static_cast<std::size_t>(type)];
  return t ? t->phalanges : phalanges_;
}

const std::vector<std::vector<GraspTerm>>& HandRig::grasp_rule(GraspType type) const {
  const auto& t = types_[static_cast<std::size_t>(type)];
  return t && !t->grasp_rule.empty() ? t->grasp_rule : grasp_rule_;
}

PhalanxId HandRig::find(const std::string& name) const {
  for (std::size_t i = 0; i < phalanges_.size(); ++i)
    if (phalanges_[i].name == name) return PhalanxId(static_cast<int>(i));
  return {};
}

HandRig HandRig::mirrored() const {
  // Reflection M = diag(1, -1, 1). Points map by M; a rotation R maps to M R M; a joint axis
  // (a pseudo-vector) maps to -M a so that the same angle gives the mirrored motion.
  const Eigen::Matrix3d M = Eigen::Vector3d(1, -1, 1).asDiagonal();
  HandRig out = *this;
  out.side_ = side_ == HandSide::kLeft ? HandSide::kRight : side_ == HandSide::kRight ? HandSide::kLeft : side_;
  auto mirror_point = [&](const Eigen::Vector3d& p) -> Eigen::Vector3d { return M * p; };
  out.selection_sphere_.p_PalmCenter = mirror_point(selection_sphere_.p_PalmCenter);
  out.palm_contact_.p_PalmCenter = mirror_point(palm_contact_.p_PalmCenter);
  out.p_PalmGraspCenter_ = mirror_point(p_PalmGraspCenter_);
  for (auto& ph : out.phalanges_) {
    ph.X_ParentJoint.linear() = M * ph.X_ParentJoint.linear() * M;
    ph.X_ParentJoint.translation() = mirror_point(ph.X_ParentJoint.translation());
    ph.axis = -(M * ph.axis);
    if (ph.capsule) {
      auto& c = *ph.capsule;
      c.p_PhalanxA = mirror_point(c.p_PhalanxA);
      c.p_PhalanxB = mirror_point(c.p_PhalanxB);
      c.p_PhalanxCTc = mirror_point(c.p_PhalanxCTc);
      c.p_PhalanxSp = mirror_point(c.p_PhalanxSp);
    }
  }
  out.finish(name_);  // the grasp types' phalanges from the mirrored ones
  return out;
}

}  // namespace telegrasp::sim
