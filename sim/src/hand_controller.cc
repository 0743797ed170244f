// The four components of the grasp system for one hand.
#include "telegrasp/sim/hand_controller.h"

#include "telegrasp/sim/grasp_rule.h"
#include "telegrasp/sim/hand_kinematics.h"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace telegrasp::sim {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
// A predicted advance (close_precise) may leave a capsule unaware of a graze this deep, as a
// fraction of the contact tolerance.
constexpr double kGrazeAllowance = 0.5;
// Precise mode gives up refining a contact after this many advancement steps in one tick; the
// finger then stops short (free, not blocked) and continues next tick.
constexpr int kMaxAdvancementSteps = 64;

bool in_unit_interval(double v) { return std::isfinite(v) && v >= 0.0 && v <= 1.0; }

// +1 when the joint closes towards larger angles, else -1.
double closing_sign(const PhalanxSpec& spec) { return spec.closed >= spec.open ? 1.0 : -1.0; }

// Distance from p (object frame) to the object's bounding box; 0 inside it.
double distance_to_bounds(const ObjectModel& model, const Eigen::Vector3d& p) {
  return (p - p.cwiseMax(model.p_ObjectMin).cwiseMin(model.p_ObjectMax)).norm();
}

// Contacts nearer than this to one already kept, with normals within ~2.6 degrees of its
// normal, are left out of the grasp quality: their wrenches nearly coincide, so the hull barely
// changes, and every contact left out saves time. (Speed only.)
constexpr double kQualityMergeDistance = 1e-3;
constexpr double kQualityMergeCos = 0.999;

// Blocked capsules lie within the contact tolerance (plus hysteresis) of the surface; searches
// for their closest point need look no farther than this beyond the radius.
constexpr double kTouchReach = 1e-3;

}  // namespace

std::string validate_input(const ControllerInput& input, const HandRig& rig) {
  if (!input.X_WorldPalm.matrix().allFinite()) return "pose: non-finite value";
  const Eigen::Matrix3d R = input.X_WorldPalm.linear();
  if (!((R.transpose() * R - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff() < 1e-6) || R.determinant() < 0)
    return "pose: rotation is not orthonormal (quaternion not unit?)";
  if (!in_unit_interval(input.trigger)) return "trigger: must be a finite value in [0, 1]";
  if (!input.curls.empty()) {
    if (input.curls.size() != rig.fingers().size())
      return "curls: expected " + std::to_string(rig.fingers().size()) + " values (one per finger), got " +
             std::to_string(input.curls.size());
    for (std::size_t i = 0; i < input.curls.size(); ++i)
      if (!in_unit_interval(input.curls[i]))
        return "curls[" + std::to_string(i) + "]: must be a finite value in [0, 1]";
  }
  return "";
}

struct HandController::Capsule {
  Eigen::Vector3d a, b;
  double radius;
};

struct HandController::Scratch {
  // Where a capsule was last checked (object frame) and whether it touched; an identical pose
  // gives the same answer without a query.
  struct TouchCache {
    ObjectId object;
    Eigen::Vector3d a{0, 0, 0}, b{0, 0, 0};
    bool touching = false;
    bool matches(ObjectId o, const Capsule& c, bool touch) const {
      return object.valid() && object == o && touching == touch && a == c.a && b == c.b;
    }
  };
  // The last exact closest pair found for a capsule and where the capsule was: the contact
  // search, the grasp tick's signed distances and the contacts all ask about the same resting
  // capsules, and a bit-identical pose has the identical answer (the one a new search would
  // give: the contact search makes the pair's triangle the capsule's hint).
  struct ClosestCache {
    ObjectId object;
    const MeshDistance* mesh = nullptr;
    Eigen::Vector3d a{0, 0, 0}, b{0, 0, 0};
    SegmentQuery pair;  // found
    bool matches(ObjectId o, const MeshDistance& m, const Eigen::Vector3d& pa, const Eigen::Vector3d& pb) const {
      return object.valid() && object == o && mesh == &m && a == pa && b == pb;
    }
  };
  // step_finger's work space, kept between ticks so that a tick allocates nothing.
  struct StepWork {
    std::vector<double> q0, delta, rate;  // per position along the finger
    std::vector<std::size_t> affected;
    // The predicted advance (close_precise): per position, the longest advance whose unseen
    // graze is certified below the allowance, and the last exact gap this step and where.
    std::vector<double> certified, last_s, last_gap, closing;
    std::vector<double> saved_bound;  // per position: the gap bounds before a predicted advance
    std::vector<int> blocked_now;  // phalanges blocked at the pose being probed
  };

  std::vector<TouchCache> touch;  // per phalanx
  std::vector<ClosestCache> closest;  // per phalanx
  StepWork work;
};

HandController::ScratchHolder::ScratchHolder() : scratch(std::make_unique<Scratch>()) {}
HandController::ScratchHolder::ScratchHolder(const ScratchHolder& other)
    : scratch(std::make_unique<Scratch>(*other.scratch)) {}
HandController::ScratchHolder& HandController::ScratchHolder::operator=(const ScratchHolder& other) {
  if (this != &other) scratch = std::make_unique<Scratch>(*other.scratch);
  return *this;
}
HandController::ScratchHolder::ScratchHolder(ScratchHolder&& other) noexcept = default;
HandController::ScratchHolder& HandController::ScratchHolder::operator=(ScratchHolder&& other) noexcept = default;
HandController::ScratchHolder::~ScratchHolder() = default;

namespace {

ResolverSettings resolver_settings(const GraspSettings& s) {
  ResolverSettings out;
  out.rejoin_speed = s.rejoin_speed;
  out.rejoin_turn = s.rejoin_turn;
  out.snap_distance = s.snap_distance;
  out.table_half_extent = s.table_half_extent;
  out.tolerance = s.contact_tolerance;
  out.fingers_may_rest_inside = s.mode == ClosingMode::kDiscrete;
  return out;
}

}  // namespace

HandController::HandController(std::shared_ptr<const HandRig> rig, GraspSettings settings)
    : rig_(std::move(rig)), settings_(settings), resolver_(resolver_settings(settings_)) {
  if (!(settings_.contact_tolerance > 0) || !std::isfinite(settings_.contact_tolerance))
    throw std::invalid_argument("GraspSettings.contact_tolerance must be a positive number of metres");
  if (!(settings_.speed_scale > 0) || !std::isfinite(settings_.speed_scale))
    throw std::invalid_argument("GraspSettings.speed_scale must be a positive number");
  const std::size_t n = rig_->phalanges().size();
  state_.q.resize(n);
  for (std::size_t i = 0; i < n; ++i) state_.q[i] = rig_->phalanges()[i].open;
  state_.blocked.assign(n, 0);
  state_.blocked_angle.assign(n, 0.0);
  scratch_->touch.assign(n, {});
  scratch_->closest.assign(n, {});
  hint_.assign(n, MeshDistance::kNoHint);
  gap_bound_.assign(n, -kInf);
  forward_kinematics(*rig_, state_.q, &state_.X_PalmPhalanx);
  // reach_[k][m] bounds |p - o_k| for any point p of capsule m's segment and the origin o_k of an
  // ancestor joint k, in any configuration (triangle inequality along the chain).
  reach_.assign(n, std::vector<double>(n, 0.0));
  palm_reach_.assign(n, 0.0);
  for (std::size_t m = 0; m < n; ++m) {
    const auto& cap = rig_->phalanges()[m].capsule;
    if (!cap) continue;
    double r = std::max(cap->p_PhalanxA.norm(), cap->p_PhalanxB.norm());
    for (int k = static_cast<int>(m); k >= 0; k = rig_->phalanges()[k].parent) {
      reach_[k][m] = r;
      r += rig_->phalanges()[k].X_ParentJoint.translation().norm();
    }
    palm_reach_[m] = r;  // past the root joint: from the palm origin
  }
  volumes_ = palm_volumes(rig_->palm_half_extent());
  palm_volume_count_ = volumes_.size();
  volumes_.resize(palm_volume_count_ + rig_->capsule_phalanges().size());
}

void HandController::update_finger_poses(int finger) {
  for (PhalanxId id : rig_->fingers()[finger].phalanges) {
    const PhalanxSpec& spec = rig_->phalanges()[id.value];
    const Eigen::Isometry3d X_PalmParent =
        spec.parent < 0 ? Eigen::Isometry3d::Identity() : state_.X_PalmPhalanx[spec.parent];
    state_.X_PalmPhalanx[id.value] = phalanx_pose(spec, X_PalmParent, state_.q[id.value]);
  }
}

HandController::Capsule HandController::capsule_in_object(PhalanxId id, const Eigen::Isometry3d& X_ObjectPalm) const {
  const CapsuleSpec& c = *rig_->phalanges()[id.value].capsule;
  const Eigen::Isometry3d X_ObjectPhalanx = X_ObjectPalm * state_.X_PalmPhalanx[id.value];
  return {X_ObjectPhalanx * c.p_PhalanxA, X_ObjectPhalanx * c.p_PhalanxB, c.radius};
}

void HandController::select_object(std::span<const ObjectView> objects) {
  const PalmSphere& sphere = rig_->selection_sphere();
  const Eigen::Vector3d p_WorldCenter = state_.X_WorldPalm * sphere.p_PalmCenter;
  struct Candidate {
    ObjectId id;
    const ObjectModel* model;
    Eigen::Vector3d p_ObjectCenter;
  };
  std::vector<Candidate> candidates;
  double best = kInf;
  ObjectId best_id;
  for (const ObjectView& view : objects) {
    const ObjectModel& model = *view.model;
    const Eigen::Vector3d c = view.X_WorldObject.inverse() * p_WorldCenter;
    if (distance_to_bounds(model, c) > sphere.radius) continue;  // cheap reject
    // Early-out overlap test (a point is a zero-length capsule); distances only to rank.
    if (!model.distance.capsule_overlaps(c, c, sphere.radius)) continue;
    candidates.push_back({view.id, &model, c});
  }
  if (candidates.size() == 1) {
    state_.selected = candidates.front().id;
    return;
  }
  for (const Candidate& cand : candidates) {
    const double key = settings_.selection == SelectionMetric::kOrigin
                           ? cand.p_ObjectCenter.norm()
                           : cand.model->distance.signed_distance(cand.p_ObjectCenter);
    if (key < best) {
      best = key;
      best_id = cand.id;
    }
  }
  state_.selected = best_id;
}

bool HandController::depenetrate(int finger, const Eigen::Isometry3d& X_ObjectPalm, const ObjectView& object) {
  const auto& chain = rig_->fingers()[finger].phalanges;
  const auto& specs = joints();
  const MeshDistance& mesh = object.model->distance;
  const double tol = settings_.contact_tolerance;
  std::vector<double> q0;
  for (PhalanxId id : chain) q0.push_back(state_.q[id.value]);
  // Extends the whole finger a fraction s of the way to its extension limit (past the open pose
  // if need be, as a finger pressed onto a surface bends back).
  auto set_opening = [&](double s) {
    for (std::size_t k = 0; k < chain.size(); ++k) {
      const int id = chain[k].value;
      const double extended = specs[id].closed >= specs[id].open ? specs[id].min : specs[id].max;
      state_.q[id] = q0[k] + s * (extended - q0[k]);
    }
    update_finger_poses(finger);
  };
  // Some capsule of the finger comes within `extra` of the surface (0: overlaps the solid).
  auto any_within = [&](double extra) {
    for (PhalanxId id : chain) {
      if (!specs[id.value].capsule) continue;
      const Capsule c = capsule_in_object(id, X_ObjectPalm);
      if (mesh.capsule_overlaps(c.a, c.b, c.radius + extra, hint_[id.value])) return true;
    }
    return false;
  };
  set_opening(1.0);
  if (any_within(0.0)) {  // the hand itself is in the object: extending the finger cannot help
    set_opening(0.0);
    return false;
  }
  // Bisection until the free end rests on the surface (within the tolerance).
  double lo = 0.0, hi = 1.0;  // penetrating at lo, free at hi
  for (int i = 0; i < 40; ++i) {
    const double mid = 0.5 * (lo + hi);
    set_opening(mid);
    if (any_within(0.0)) {
      lo = mid;
    } else {
      hi = mid;
      if (any_within(tol)) break;
    }
  }
  set_opening(hi);
  // The capsules now resting on the surface are blocked there.
  for (PhalanxId id : chain) {
    if (!specs[id.value].capsule) continue;
    const Capsule c = capsule_in_object(id, X_ObjectPalm);
    const bool touching = mesh.capsule_overlaps(c.a, c.b, c.radius + tol, hint_[id.value]);
    state_.blocked[id.value] = touching;
    state_.blocked_angle[id.value] = state_.q[id.value];
    scratch_->touch[id.value] = {object.id, c.a, c.b, touching};
  }
  return true;
}

// What one finger's step works on: its chain, the object it may touch and the closing settings.
struct HandController::FingerStep {
  int finger;
  const std::vector<PhalanxId>& chain;
  double u;
  const ObjectView* object;  // nullptr: the finger touches nothing this tick
  const Eigen::Isometry3d& X_ObjectPalm;
  double tol;
  bool precise;

  [[nodiscard]] std::size_t size() const { return chain.size(); }
  [[nodiscard]] int id(std::size_t k) const { return chain[k].value; }
};

void HandController::forget_bounds(const FingerStep& step) {
  for (PhalanxId id : step.chain) gap_bound_[id.value] = -kInf;
}

void HandController::set_fraction(const FingerStep& step, double s) {
  const Scratch::StepWork& work = scratch_->work;
  for (std::size_t k = 0; k < step.size(); ++k) state_.q[step.id(k)] = work.q0[k] + s * work.delta[k];
  update_finger_poses(step.finger);
}

void HandController::block(int id) {
  state_.blocked[id] = 1;
  state_.blocked_angle[id] = state_.q[id];
  scratch_->touch[id] = {};  // checked afresh next tick
}

// Interaction manager: unblock phalanges whose hand opened past them or whose contact ended.
// A capsule whose pose in the object frame is bit-identical to its last check (e.g. while the
// object is held) is still touching and needs no query.
bool HandController::unblock_phalanges(const FingerStep& step) {
  const auto& specs = joints();
  // A blocked capsule stays blocked while it touches: within the tolerance (precise, with 2x
  // hysteresis against rounding) or overlapping (discrete).
  const double release_gap = step.precise ? 2.0 * step.tol : 0.0;
  bool pushed_in = false;
  for (std::size_t k = 0; k < step.size(); ++k) {
    const int id = step.id(k);
    if (!state_.blocked[id]) continue;
    const double target = target_angle(specs[id], step.u);
    bool unblock = (target - state_.blocked_angle[id]) * closing_sign(specs[id]) < -1e-12 || step.object == nullptr;
    if (!unblock && specs[id].capsule) {
      const Capsule c = capsule_in_object(step.chain[k], step.X_ObjectPalm);
      Scratch::TouchCache& cache = scratch_->touch[id];
      if (cache.matches(step.object->id, c, true)) continue;
      const MeshDistance& mesh = step.object->model->distance;
      unblock = !mesh.capsule_overlaps(c.a, c.b, c.radius + release_gap, hint_[id]);
      cache = {step.object->id, c.a, c.b, !unblock};
      // Precise mode: the hand's own motion pushed this finger into the object (the capsule's
      // last closest pair, when taken at this very pose, spares the search).
      if (!unblock && step.precise && pushed_into(step, id, c)) pushed_in = true;
    }
    if (unblock) state_.blocked[id] = 0;
  }
  return pushed_in;
}

// Whether capsule c (phalanx id, posed in the object frame) overlaps the object by more than the
// tolerance: capsule_overlaps with the radius less the tolerance, helped by the capsule's last
// exact closest pair when it was taken at this very pose (the same answer, bit for bit).
bool HandController::pushed_into(const FingerStep& step, int id, const Capsule& c) const {
  const MeshDistance& mesh = step.object->model->distance;
  const Scratch::ClosestCache& cache = scratch_->closest[id];
  if (cache.matches(step.object->id, mesh, c.a, c.b))
    return mesh.capsule_overlaps(c.a, c.b, c.radius - step.tol, cache.pair, hint_[id]);
  return mesh.capsule_overlaps(c.a, c.b, c.radius - step.tol, hint_[id]);
}

// Finger movement: rate-limited steps toward the targets into the work space's delta, where
// joints up to `held` may only open; true when some joint moves (`closing`: some joint closes).
bool HandController::plan_motion(const FingerStep& step, double dt, int held, bool& closing) {
  const auto& specs = joints();
  std::vector<double>& delta = scratch_->work.delta;
  delta.assign(step.size(), 0.0);
  bool moving = false;
  closing = false;
  for (std::size_t k = 0; k < step.size(); ++k) {
    const PhalanxSpec& s = specs[step.id(k)];
    const double max_step = s.max_speed * settings_.speed_scale * dt;
    double d = std::clamp(target_angle(s, step.u) - state_.q[step.id(k)], -max_step, max_step);
    if (static_cast<int>(k) <= held && d * closing_sign(s) > 0) d = 0;
    delta[k] = d;
    moving |= d != 0;
    closing |= d * closing_sign(s) > 0;
  }
  return moving;
}

// A finger at rest still blocks where the hand's motion brought a capsule into contact.
void HandController::block_at_rest(const FingerStep& step) {
  if (step.object == nullptr) return;
  const auto& specs = rig_->phalanges();
  const double touch = step.precise ? step.tol : 0.0;
  for (std::size_t m = 0; m < step.size(); ++m) {
    const int id = step.id(m);
    if (state_.blocked[id] || !specs[id].capsule || gap_bound_[id] > touch) continue;
    const Capsule c = capsule_in_object(step.chain[m], step.X_ObjectPalm);
    Scratch::TouchCache& cache = scratch_->touch[id];
    if (cache.matches(step.object->id, c, false)) continue;
    const MeshDistance& mesh = step.object->model->distance;
    const bool touching = mesh.capsule_overlaps(c.a, c.b, c.radius + touch, hint_[id]);
    cache = {step.object->id, c.a, c.b, touching};
    if (!touching) continue;
    // Pushed in, not just touching: precise mode bends the finger back onto the surface.
    if (step.precise && pushed_into(step, id, c) &&
        depenetrate(step.finger, step.X_ObjectPalm, *step.object)) {
      forget_bounds(step);
      return;
    }
    state_.blocked[id] = 1;
    state_.blocked_angle[id] = state_.q[id];
  }
}

// The paper's discrete test: move the whole step, then block the capsules that overlap.
void HandController::close_discrete(const FingerStep& step) {
  const MeshDistance& mesh = step.object->model->distance;
  set_fraction(step, 1.0);
  forget_bounds(step);
  for (std::size_t m : scratch_->work.affected) {
    const Capsule c = capsule_in_object(step.chain[m], step.X_ObjectPalm);
    if (mesh.capsule_overlaps(c.a, c.b, c.radius, hint_[step.id(m)])) block(step.id(m));
  }
}

// Precise: conservative advancement along the step s in [0, 1]. A capsule point moves at most
// rate(m) per unit s, so advancing by (gap - tol/2) / rate never crosses the surface.
//
// The rate: joint k turns the points p of capsule m's segment at |delta_k| times their distance
// to its axis. That distance, largest at an end of the segment, is taken in the pose at the step's
// start and grows over the step by at most the motion the joints after k give p relative to k
// (each |delta_j| reach_[j][m]); reach_[k][m] bounds it in any pose, so the smaller is used.
void HandController::close_precise(const FingerStep& step) {
  Scratch::StepWork& work = scratch_->work;
  const std::vector<std::size_t>& affected = work.affected;
  std::vector<double>& rate = work.rate;
  rate.assign(step.size(), 0.0);
  set_fraction(step, 0.0);
  const auto& specs = rig_->phalanges();
  for (std::size_t m : affected) {
    const CapsuleSpec& cap = *specs[step.id(m)].capsule;
    const Eigen::Isometry3d& X_PalmM = state_.X_PalmPhalanx[step.id(m)];
    const Eigen::Vector3d a = X_PalmM * cap.p_PhalanxA, b = X_PalmM * cap.p_PhalanxB;
    double growth = 0;  // sum over j > k of |delta_j| reach_[j][m], built from the tip down
    for (std::size_t k = m + 1; k-- > 0;) {
      const Eigen::Isometry3d& X_PalmK = state_.X_PalmPhalanx[step.id(k)];
      const Eigen::Vector3d axis = X_PalmK.linear() * specs[step.id(k)].axis;
      const auto to_axis = [&](const Eigen::Vector3d& p) {
        const Eigen::Vector3d r = p - X_PalmK.translation();
        return (r - r.dot(axis) * axis).norm();
      };
      const double reach = std::min(reach_[step.id(k)][step.id(m)], std::max(to_axis(a), to_axis(b)) + growth);
      rate[m] += std::abs(work.delta[k]) * reach;
      growth += std::abs(work.delta[k]) * reach_[step.id(k)][step.id(m)];
    }
  }

  // The predicted advance: once a capsule's gap has been measured twice in this step, the next
  // advance may aim at contact by the rate the gap actually fell at (a secant) instead of the
  // rate's bound, up to the length certified_advance allows for a graze of kGrazeAllowance of
  // the tolerance, and is checked by a query at its end.
  std::vector<double>& certified = work.certified;
  certified.assign(step.size(), 0.0);
  work.last_s.assign(step.size(), -1.0);
  work.last_gap.assign(step.size(), kInf);
  work.closing.assign(step.size(), 0.0);
  for (std::size_t m : affected) {
    double turn = 0, reach = 0;
    for (std::size_t k = 0; k <= m; ++k) {
      turn += std::abs(work.delta[k]);
      reach = std::max(reach, reach_[step.id(k)][step.id(m)]);
    }
    certified[m] = certified_advance(rate[m], turn, reach, specs[step.id(m)].capsule->radius,
                                     kGrazeAllowance * step.tol);
  }

  // Each affected capsule carries a lower bound on its gap (from earlier ticks, or from its last
  // exact query this step, minus its motion since): while the bound exceeds the tolerance it
  // replaces the query.
  double s = 0;
  double s_before = 0;  // where the last advance started
  bool predicted = false;  // the last advance went past what the gap bounds guarantee
  bool may_predict = true;
  for (int iter = 0; iter < kMaxAdvancementSteps; ++iter) {
    set_fraction(step, s);
    double ds = kInf;
    double ds_safe = kInf;
    bool touched = false;
    bool overshot = false;
    work.blocked_now.clear();
    for (std::size_t m : affected) {
      const Probe probe = probe_capsule(step, m, s, rate[m], ds, ds_safe, may_predict ? certified[m] : 0.0, predicted);
      if (probe == Probe::kDepenetrated) return;
      touched |= probe == Probe::kBlocked;
      overshot |= probe == Probe::kOvershot;
    }
    if (overshot) {  // a predicted advance went into the object: back to its start, advancing safely
      for (int id : work.blocked_now) state_.blocked[id] = 0;
      for (std::size_t m : affected) gap_bound_[step.id(m)] = work.saved_bound[m];
      s = s_before;
      predicted = false;
      may_predict = false;
      continue;
    }
    if (touched || s >= 1.0) return;
    const double advance = std::isfinite(ds) ? std::min(1.0 - s, ds) : 1.0 - s;  // all free: to the end
    predicted = advance > ds_safe;
    if (predicted) {
      work.saved_bound.resize(step.size());
      for (std::size_t m : affected) work.saved_bound[m] = gap_bound_[step.id(m)];
    }
    for (std::size_t m : affected) gap_bound_[step.id(m)] -= rate[m] * advance;
    s_before = s;
    s += advance;
    if (s >= 1.0) {
      s = 1.0;
      if (!predicted) {  // the bounds prove every capsule free to the end
        set_fraction(step, 1.0);
        return;
      }
    }
  }
}

// One affected capsule m at fraction s of the step: its gap bound, refreshed by an exact query
// when it no longer proves the capsule free until the step's end; blocks the capsule on contact.
// Lowers `ds_safe` to the advance its gap bound allows and `ds` to that or, when longer, the
// predicted advance (at most `certified` past its last query); after a predicted advance
// (`predicted`) a capsule found inside reports kOvershot instead of blocking.
HandController::Probe HandController::probe_capsule(const FingerStep& step, std::size_t m, double s, double rate,
                                                    double& ds, double& ds_safe, double certified, bool predicted) {
  const double tol = step.tol;
  double& bound = gap_bound_[step.id(m)];
  const double horizon = rate * (1.0 - s) + tol;  // beyond it, no contact this step
  if (bound > horizon) return Probe::kFree;  // free for the rest of the step
  Scratch::StepWork& work = scratch_->work;
  // The advance a gap (bound) allows, and the predicted one when longer.
  const auto allow = [&](double gap) {
    const double safe = (gap - 0.5 * tol) / rate;
    ds = std::min(ds, std::max(safe, predicted_advance(m, s, certified, tol)));
    ds_safe = std::min(ds_safe, safe);
  };
  if (bound > tol) {
    allow(bound);
    return Probe::kFree;
  }
  const MeshDistance& mesh = step.object->model->distance;
  const Capsule c = capsule_in_object(step.chain[m], step.X_ObjectPalm);
  std::uint32_t& hint = hint_[step.id(m)];
  const SegmentQuery hit = mesh.closest_to_segment(c.a, c.b, c.radius + horizon, hint);
  if (!hit.found && !mesh.segment_inside(c.a)) {  // free for the rest of the step
    bound = horizon;
    return Probe::kFree;
  }
  if (hit.found) {
    hint = hit.triangle;
    scratch_->closest[step.id(m)] = {step.object->id, &mesh, c.a, c.b, hit};
  }
  const bool inside = !hit.found || hit.distance == 0 || (hit.point_on_segment - hit.point_on_mesh).dot(hit.normal) < 0;
  const double gap = inside ? -c.radius - (hit.found ? hit.distance : kInf) : hit.distance - c.radius;
  bound = gap;
  if (s == 0 && gap < -tol) {  // pushed in by the hand's motion before the fingers moved
    set_fraction(step, 0.0);
    forget_bounds(step);
    if (depenetrate(step.finger, step.X_ObjectPalm, *step.object)) return Probe::kDepenetrated;
    block(step.id(m));
    return Probe::kBlocked;
  }
  if (predicted && gap < 0) return Probe::kOvershot;
  if (gap <= tol) {
    block(step.id(m));
    work.blocked_now.push_back(step.id(m));
    return Probe::kBlocked;
  }
  if (work.last_s[m] >= 0 && s > work.last_s[m] && work.last_gap[m] > gap)
    work.closing[m] = (work.last_gap[m] - gap) / (s - work.last_s[m]);  // the gap's fall per unit s
  work.last_s[m] = s;
  work.last_gap[m] = gap;
  allow(gap);
  return Probe::kFree;
}

// The advance from s that takes capsule m's gap, falling as it did between its last two exact
// queries this step, to half the tolerance; no farther than `certified` past its last query.
double HandController::predicted_advance(std::size_t m, double s, double certified, double tol) const {
  const Scratch::StepWork& work = scratch_->work;
  if (!(work.closing[m] > 0)) return 0;  // set only from two queries
  const double gap = work.last_gap[m] - work.closing[m] * (s - work.last_s[m]);
  return std::min((gap - 0.5 * tol) / work.closing[m], work.last_s[m] + certified - s);
}

void HandController::step_finger(int finger, double u, double dt, const ObjectView* object,
                                 const Eigen::Isometry3d& X_ObjectPalm) {
  // A finger whose input is fully released holds nothing: it unblocks and opens without
  // touching anything (so a finger bent back past its open angle cannot keep a grasp).
  if (u <= 0.0) object = nullptr;
  const FingerStep step{finger,
                        rig_->fingers()[finger].phalanges,
                        u,
                        object,
                        X_ObjectPalm,
                        settings_.contact_tolerance,
                        settings_.mode == ClosingMode::kPrecise};
  const std::size_t n = step.size();

  if (unblock_phalanges(step) && depenetrate(finger, X_ObjectPalm, *object)) {
    forget_bounds(step);
    return;
  }

  int held = -1;  // the most distal blocked phalanx: it and every joint proximal to it hold
  for (std::size_t k = 0; k < n; ++k)
    if (state_.blocked[step.id(k)]) held = static_cast<int>(k);

  bool closing = false;
  if (!plan_motion(step, dt, held, closing)) {
    block_at_rest(step);
    return;
  }

  Scratch::StepWork& work = scratch_->work;
  work.q0.resize(n);
  for (std::size_t k = 0; k < n; ++k) work.q0[k] = state_.q[step.id(k)];
  // Free capsules this step can move into the object.
  std::vector<std::size_t>& affected = work.affected;
  affected.clear();
  for (std::size_t m = static_cast<std::size_t>(held + 1); m < n; ++m)
    if (rig_->phalanges()[step.id(m)].capsule && !state_.blocked[step.id(m)]) affected.push_back(m);

  if (!closing || object == nullptr || affected.empty()) {
    set_fraction(step, 1.0);
    forget_bounds(step);
    return;
  }
  // Capsules that move but are not advanced below (a held joint opening) lose their bounds.
  for (std::size_t m = 0; m < n; ++m)
    if (std::find(affected.begin(), affected.end(), m) == affected.end()) gap_bound_[step.id(m)] = -kInf;

  if (step.precise) {
    close_precise(step);
  } else {
    close_discrete(step);
  }
}

namespace {

// The input a tick uses in place of an invalid one: the hand's last pose, trigger and curls.
ControllerInput last_input(const HandState& state) {
  ControllerInput input;
  input.X_WorldPalm = state.X_WorldTracked;
  input.trigger = state.trigger;
  input.curls = state.curls;
  input.tracking_valid = state.has_pose;
  return input;
}

}  // namespace

// Pose and hand velocity (from the last resolved pose, zero when tracking is lost), trigger and
// curls. The resolved pose treats the hand as rigid this tick: the palm and every capsule as the
// fingers are posed now (precise fingers keep themselves out as they close).
void HandController::track(const ControllerInput& input, double dt, std::span<const ObjectView> objects) {
  if (input.tracking_valid) {
    Eigen::Isometry3d X_WorldResolved = input.X_WorldPalm;
    if (settings_.resolve_pose) {
      for (std::size_t i = 0; i < rig_->capsule_phalanges().size(); ++i) {
        const PhalanxId id = rig_->capsule_phalanges()[i];
        const CapsuleSpec& c = *rig_->phalanges()[id.value].capsule;
        const Eigen::Isometry3d& X = state_.X_PalmPhalanx[id.value];
        volumes_[palm_volume_count_ + i] = {X * c.p_PhalanxA, X * c.p_PhalanxB, c.radius, false};
      }
      X_WorldResolved = resolver_.resolve(state_.X_WorldPalm, state_.X_WorldTracked, input.X_WorldPalm, state_.has_pose,
                                          dt, volumes_, objects, state_.grasped);
    }
    if (state_.has_pose) {
      state_.v_WorldPalm = (X_WorldResolved.translation() - state_.X_WorldPalm.translation()) / dt;
      const Eigen::AngleAxisd dR(X_WorldResolved.linear() * state_.X_WorldPalm.linear().transpose());
      state_.w_WorldPalm = dR.axis() * (dR.angle() / dt);
    } else {
      state_.v_WorldPalm.setZero();
      state_.w_WorldPalm.setZero();
    }
    state_.X_WorldPalm = X_WorldResolved;
    state_.X_WorldTracked = input.X_WorldPalm;
    state_.has_pose = true;
  } else {
    state_.v_WorldPalm.setZero();
    state_.w_WorldPalm.setZero();
  }
  state_.trigger = input.trigger;
  state_.curls = input.curls;
}

// 1. Object selection (a grasped object stays selected, posed by the hand in `held_view`; one
// gone from `objects` is released). Returns the object the fingers work on, or nullptr.
const ObjectView* HandController::choose_object(std::span<const ObjectView> objects, ObjectView& held_view,
                                                HandTickEvents& events) {
  const ObjectView* object = nullptr;
  if (state_.grasped.valid()) {
    auto it = std::find_if(objects.begin(), objects.end(), [&](const ObjectView& v) { return v.id == state_.grasped; });
    if (it == objects.end()) {
      events.released = true;
      events.released_object = release();
    } else {
      held_view = *it;
      held_view.X_WorldObject = state_.X_WorldPalm * state_.X_PalmObject;
      object = &held_view;
    }
  }
  if (!state_.grasped.valid()) {
    select_object(objects);
    if (state_.selected.valid())
      object =
          &*std::find_if(objects.begin(), objects.end(), [&](const ObjectView& v) { return v.id == state_.selected; });
  }
  return object;
}

// 1b. The grasp type: from the object's shape and the hand's pose while nothing is blocked.
void HandController::choose_type(const ObjectView* object, const Eigen::Isometry3d& X_ObjectPalm) {
  if (std::any_of(state_.blocked.begin(), state_.blocked.end(), [](std::uint8_t b) { return b != 0; })) return;
  GraspType type = object ? choose_grasp_type(object->model->shape, X_ObjectPalm) : GraspType::kOther;
  state_.grasp_type = rig_->has_grasp_type(type) ? type : GraspType::kOther;
}

// Gap bounds carried over from the last tick shrink by how far the hand moved relative to the
// object: a capsule point p (palm frame) moves at most |dt| + angle(dR) |p|.
void HandController::carry_gap_bounds(const ObjectView* object, const Eigen::Isometry3d& X_ObjectPalm) {
  if (!object || object->id != bound_object_) {
    std::fill(gap_bound_.begin(), gap_bound_.end(), -kInf);
  } else {
    const double shift = (X_ObjectPalm.translation() - bound_X_ObjectPalm_.translation()).norm();
    const double turn = Eigen::AngleAxisd(X_ObjectPalm.linear() * bound_X_ObjectPalm_.linear().transpose()).angle();
    if (shift > 0 || turn > 0)
      for (std::size_t m = 0; m < gap_bound_.size(); ++m) gap_bound_[m] -= shift + turn * palm_reach_[m];
  }
  bound_object_ = object ? object->id : ObjectId();
  bound_X_ObjectPalm_ = X_ObjectPalm;
}

// 4. Grasping logic: the palm contact, then the grasp rule grasps or releases `object`.
void HandController::apply_grasp_rule(const ObjectView* object, const Eigen::Isometry3d& X_ObjectPalm,
                                      HandTickEvents& events) {
  state_.palm_contact = false;
  if (object) {
    const PalmSphere& palm = rig_->palm_contact();
    const Eigen::Vector3d c = X_ObjectPalm * palm.p_PalmCenter;
    const ObjectModel& model = *object->model;
    state_.palm_contact =
        distance_to_bounds(model, c) <= palm.radius && model.distance.capsule_overlaps(c, c, palm.radius);
  }
  const bool rule = object && evaluate_grasp_rule(rig_->grasp_rule(state_.grasp_type), state_.blocked, state_.palm_contact);
  if (rule && !state_.grasped.valid()) {
    state_.grasped = object->id;
    state_.X_PalmObject = state_.X_WorldPalm.inverse() * object->X_WorldObject;
    X_ObjectPalm_held_ = X_ObjectPalm;
    held_model_ = object->model;
    grasp_view_ = *object;
    // The hold metrics start as the grasp's, for as long as the hand keeps its shape: with
    // deferred metrics they come with set_grasp_metrics() (or hold_metrics() takes them if asked first).
    metrics_.reset();
    if (!defer_metrics_) metrics_ = measure(*object);
    hold_metrics_ = metrics_;
    hold_metrics_key_ = shape_key();
    refresh_contacts();
    ++grasp_serial_;
    hold_quality_ = kPendingQuality;
    if (metrics_) metrics_->quality = kPendingQuality;
    if (hold_metrics_) hold_metrics_->quality = kPendingQuality;
    events.grasped = true;
  } else if (!rule && state_.grasped.valid()) {
    events.released = true;
    events.released_object = state_.grasped;
    events.X_WorldReleased = *grasped_object_pose();
    state_.grasped = ObjectId();
    metrics_.reset();
  }
}

HandTickEvents HandController::tick(const ControllerInput& raw_input, double dt, std::span<const ObjectView> objects) {
  HandTickEvents events;
  grasp_view_.reset();
  if (!(dt > 0) || !std::isfinite(dt)) return events;  // no time passes
  // An invalid input (callers should have rejected it) keeps the hand as it was.
  ControllerInput fallback;
  const bool valid = validate_input(raw_input, *rig_).empty();
  if (!valid) fallback = last_input(state_);
  const ControllerInput& input = valid ? raw_input : fallback;
  track(input, dt, objects);

  ObjectView held_view;
  const ObjectView* object = choose_object(objects, held_view, events);
  const Eigen::Isometry3d X_ObjectPalm = !object ? Eigen::Isometry3d::Identity()
                                         : state_.grasped.valid()
                                             ? X_ObjectPalm_held_
                                             : object->X_WorldObject.inverse() * state_.X_WorldPalm;
  carry_gap_bounds(object, X_ObjectPalm);
  choose_type(object, X_ObjectPalm);

  // 2 + 3. Interaction manager and finger movement, finger by finger.
  for (std::size_t f = 0; f < rig_->fingers().size(); ++f) {
    const double u = input.curls.empty() ? input.trigger : input.curls[f];
    step_finger(static_cast<int>(f), u, dt, object, X_ObjectPalm);
  }

  apply_grasp_rule(object, X_ObjectPalm, events);
  return events;
}

ObjectId HandController::release() {
  const ObjectId released = state_.grasped;
  state_.grasped = ObjectId();
  state_.selected = ObjectId();
  std::fill(state_.blocked.begin(), state_.blocked.end(), 0);
  metrics_.reset();
  grasp_view_.reset();
  return released;
}

std::vector<double> HandController::shape_key() const {
  std::vector<double> key;
  key.reserve(state_.q.size() + state_.blocked.size() + 2);
  key.assign(state_.q.begin(), state_.q.end());
  key.insert(key.end(), state_.blocked.begin(), state_.blocked.end());
  key.push_back(state_.palm_contact);
  key.push_back(state_.grasped.value);
  return key;
}

std::optional<GraspMetrics> HandController::hold_metrics() const {
  const auto X_WorldObject = grasped_object_pose();
  if (!X_WorldObject) return std::nullopt;
  if (hold_metrics_key_ != shape_key() || !hold_metrics_) {
    hold_metrics_ = measure({state_.grasped, *X_WorldObject, held_model_});
    hold_metrics_key_ = shape_key();
    hold_metrics_->quality = hold_quality_;
  }
  return hold_metrics_;
}

std::optional<Eigen::Isometry3d> HandController::grasped_object_pose() const {
  if (!state_.grasped.valid()) return std::nullopt;
  return state_.X_WorldPalm * state_.X_PalmObject;
}

void HandController::reattach(const Eigen::Isometry3d& X_WorldObject) {
  if (!state_.grasped.valid()) return;
  state_.X_PalmObject = state_.X_WorldPalm.inverse() * X_WorldObject;
  X_ObjectPalm_held_ = X_WorldObject.inverse() * state_.X_WorldPalm;
  // The cached contacts and hold metrics were taken at the old hand-object pose.
  contacts_key_.clear();
  hold_metrics_key_.clear();
}

SegmentQuery HandController::closest_pair(PhalanxId id, ObjectId object, const MeshDistance& mesh,
                                          const Eigen::Vector3d& a, const Eigen::Vector3d& b, double reach) const {
  Scratch::ClosestCache& cache = scratch_->closest[id.value];
  if (cache.matches(object, mesh, a, b)) return cache.pair;
  SegmentQuery q;
  if (std::isfinite(reach)) q = mesh.closest_to_segment(a, b, reach, hint_[id.value]);
  if (!q.found) q = mesh.closest_to_segment(a, b, kInf, hint_[id.value]);
  if (q.found) cache = {object, &mesh, a, b, q};
  return q;
}

namespace {

// nd_contact (sim/README.md, section 4.2 "Where ND is taken"): the paper's sweep moved to the contact.
// From the capsule's exact closest pair (axis point A, surface point M): u is the unit direction
// from A to M (or minus the surface normal at M when A is not outside the solid), the sweep
// starts at Sp' = A - (|CTc - Sp| - r) u, so that the skin point CTc' = A + r u lies as CTc does
// (|CTc' - Sp'| = |CTc - Sp|), and ND_contact = (Ip - Sp') . u - |CTc' - Sp'|. The ray from A
// passes through M, so the sweep always hits within (|CTc - Sp| - r) + |AM| + nd_sweep_beyond;
// should rounding still miss, the sweep's limit for a point sphere (M itself) is taken.
struct NdContact {
  bool hit = false;
  double nd = 0;
};

// An axis crossing the surface has its nearest point on the surface: take instead the end of the
// axis deepest in the solid, with its closest surface point.
SegmentQuery contact_pair(const MeshDistance& mesh, const SegmentQuery& q, const Eigen::Vector3d& a,
                          const Eigen::Vector3d& b) {
  if (!q.found || q.distance > 0) return q;
  const PointQuery qa = mesh.closest_point(a), qb = mesh.closest_point(b);
  const bool a_deeper = qa.signed_distance <= qb.signed_distance;
  const PointQuery& deep = a_deeper ? qa : qb;
  if (!(deep.signed_distance < 0)) return q;
  SegmentQuery out = q;
  out.point_on_segment = a_deeper ? a : b;
  out.point_on_mesh = deep.point_on_mesh;
  out.normal = deep.normal;
  out.distance = deep.distance;
  return out;
}

NdContact nd_contact(const MeshDistance& mesh, const SegmentQuery& q, double radius, double sp_to_ctc,
                     double sweep_radius, double sweep_beyond) {
  if (!q.found) return {};
  const Eigen::Vector3d& a = q.point_on_segment;
  const Eigen::Vector3d am = q.point_on_mesh - a;
  const bool outside = q.distance > 0 && (a - q.point_on_mesh).dot(q.normal) > 0;
  const Eigen::Vector3d u = outside ? Eigen::Vector3d(am / am.norm()) : Eigen::Vector3d(-q.normal);
  const double back = sp_to_ctc - radius;
  const Eigen::Vector3d sp = a - back * u;
  const SweepHit hit = mesh.sphere_cast(sp, u, sweep_radius, back + (outside ? q.distance : 0.0) + sweep_beyond);
  const Eigen::Vector3d ip = hit.hit ? hit.point : q.point_on_mesh;
  return {true, (ip - sp).dot(u) - sp_to_ctc};
}

}  // namespace

HandController::NdSweep HandController::nd_midlength(PhalanxId id, const Eigen::Isometry3d& X_ObjectPalm,
                                                     const ObjectModel& model) const {
  const CapsuleSpec& cap = *rig_->phalanges()[id.value].capsule;
  const Eigen::Isometry3d X_ObjectPhalanx = X_ObjectPalm * state_.X_PalmPhalanx[id.value];
  const Eigen::Vector3d sp = X_ObjectPhalanx * cap.p_PhalanxSp;
  const Eigen::Vector3d ctc = X_ObjectPhalanx * cap.p_PhalanxCTc;
  const double length = (ctc - sp).norm();
  const Eigen::Vector3d dir = (ctc - sp) / length;
  const SweepHit hit = model.distance.sphere_cast(sp, dir, rig_->nd_sweep_radius(), length + rig_->nd_sweep_beyond());
  // ND = ((Ip - Sp) . (CTc - Sp)) / |CTc - Sp| - |CTc - Sp|
  return {hit.hit, hit.hit ? (hit.point - sp).dot(dir) - length : 0.0, length};
}

GraspMetrics HandController::measure(const ObjectView& object) const {
  GraspMetrics out;
  const ObjectModel& model = *object.model;
  const Eigen::Isometry3d X_ObjectPalm = object.X_WorldObject.inverse() * state_.X_WorldPalm;
  std::vector<double> finger_sum(rig_->fingers().size(), 0.0);
  std::vector<int> finger_count(rig_->fingers().size(), 0);
  out.capsules.reserve(rig_->capsule_phalanges().size());
  for (PhalanxId id : rig_->capsule_phalanges()) {
    const PhalanxSpec& spec = rig_->phalanges()[id.value];
    const CapsuleSpec& cap = *spec.capsule;
    const Eigen::Isometry3d X_ObjectPhalanx = X_ObjectPalm * state_.X_PalmPhalanx[id.value];
    CapsuleMetric m;
    m.phalanx = id;
    m.blocked = state_.blocked[id.value] != 0;
    const NdSweep nd = nd_midlength(id, X_ObjectPalm, model);
    m.hit = nd.hit;
    m.nd = nd.nd;
    // Exact capsule signed distance. Outside the solid it is the gap to the closest point (for a
    // blocked capsule, touching, a bounded search finds it fast); only a capsule reaching into the
    // solid needs the full computation.
    const Eigen::Vector3d a = X_ObjectPhalanx * cap.p_PhalanxA;
    const Eigen::Vector3d b = X_ObjectPhalanx * cap.p_PhalanxB;
    const double reach = m.blocked ? cap.radius + kTouchReach : kInf;
    const SegmentQuery q = closest_pair(id, object.id, model.distance, a, b, reach);
    m.signed_distance = q.distance > 0 && (q.point_on_segment - q.point_on_mesh).dot(q.normal) > 0
                            ? q.distance - cap.radius
                            : model.distance.capsule_signed_distance(a, b, cap.radius, hint_[id.value]);
    if (m.blocked) {
      const NdContact c = nd_contact(model.distance, contact_pair(model.distance, q, a, b), cap.radius, nd.length,
                                     rig_->nd_sweep_radius(), rig_->nd_sweep_beyond());
      m.contact_hit = c.hit;
      m.nd_contact = c.nd;
    }
    if (m.hit) {
      finger_count[spec.finger] += 1;
      finger_sum[spec.finger] += std::abs(m.nd);
    } else {
      ++out.capsules_without_hit;
    }
    out.capsules.push_back(m);
  }
  for (std::size_t f = 0; f < finger_sum.size(); ++f)
    if (finger_count[f] > 0) out.hand_error_mm += 1000.0 * finger_sum[f] / finger_count[f];
  // The palm volume is the one the resolved pose keeps outside (pose_resolver.h palm_volumes: the
  // palm box with rounded edges, as capsules): its exact signed distance is their lowest.
  out.palm_signed_distance = kInf;
  // A capsule can only lower it when its axis comes within (the lowest so far + its radius) of the
  // surface or lies inside: the early-out overlap test says when, without the exact search. The
  // capsules nearest the object's bounds go first, so the lowest is usually found first; they lie
  // side by side, so each search starts from the triangle the last one found.
  std::vector<std::pair<double, std::size_t>> order(palm_volume_count_);
  for (std::size_t v = 0; v < palm_volume_count_; ++v)
    order[v] = {distance_to_bounds(model, X_ObjectPalm * (0.5 * (volumes_[v].p_PalmA + volumes_[v].p_PalmB))), v};
  std::sort(order.begin(), order.end());
  std::uint32_t hint = MeshDistance::kNoHint;
  for (const auto& [key, v] : order) {
    const Eigen::Vector3d a = X_ObjectPalm * volumes_[v].p_PalmA, b = X_ObjectPalm * volumes_[v].p_PalmB;
    const double r = volumes_[v].radius, lowest = out.palm_signed_distance;
    if (std::isfinite(lowest) && lowest + r > 0 && !model.distance.capsule_overlaps(a, b, lowest + r, hint)) continue;
    const SegmentQuery q = model.distance.closest_to_segment(a, b, kInf, hint);
    hint = q.triangle;
    // Outside the solid (as capsule_signed_distance tells), the gap; otherwise the full computation.
    const double d = q.distance > 0 && (q.point_on_segment - q.point_on_mesh).dot(q.normal) > 0
                         ? q.distance - r
                         : model.distance.capsule_signed_distance(a, b, r, hint);
    out.palm_signed_distance = std::min(lowest, d);
  }
  return out;
}

void HandController::refresh_contacts() const {
  const ObjectModel& model = *held_model_;
  contacts_.clear();
  contacts_.reserve(rig_->capsule_phalanges().size() + 1);
  contacts_key_ = shape_key();
  const Eigen::Isometry3d& X_ObjectPalm = X_ObjectPalm_held_;
  // Each contact's ND is its capsule's, as measure() takes it (bit-identical to the grasp
  // metrics' on the grasp tick, to hold_metrics()' later).
  const Eigen::Isometry3d X_WorldObject = grasp_view_ ? grasp_view_->X_WorldObject : *grasped_object_pose();
  const Eigen::Isometry3d X_ObjectPalm_nd = X_WorldObject.inverse() * state_.X_WorldPalm;
  auto add = [&](PhalanxId id, const Eigen::Vector3d& p_Object, const Eigen::Vector3d& n_Object) {
    Contact c;
    c.phalanx = id;
    c.p_ObjectContact = p_Object;
    c.n_Object = n_Object;
    if (id.valid()) {
      const NdSweep nd = nd_midlength(id, X_ObjectPalm_nd, model);
      c.nd = nd.nd;
      c.nd_hit = nd.hit;
    }
    contacts_.push_back(c);
  };
  for (PhalanxId id : rig_->capsule_phalanges()) {
    if (!state_.blocked[id.value]) continue;
    const Capsule c = capsule_in_object(id, X_ObjectPalm);
    // A blocked capsule touches: its closest point lies within reach of a bounded search.
    const SegmentQuery q = closest_pair(id, state_.grasped, model.distance, c.a, c.b, c.radius + kTouchReach);
    add(id, q.point_on_mesh, q.normal);
  }
  if (state_.palm_contact) {
    // The palm volume touches: its centre lies within its radius of the surface, or inside.
    const PalmSphere& palm = rig_->palm_contact();
    const Eigen::Vector3d c = X_ObjectPalm * palm.p_PalmCenter;
    PointQuery q = model.distance.closest_point(c, palm.radius);
    if (!q.found) q = model.distance.closest_point(c);
    add(PhalanxId(), q.point_on_mesh, q.normal);
  }
}

std::vector<QualityContact> HandController::quality_contacts(std::span<const Contact> contacts) {
  std::vector<QualityContact> kept;
  kept.reserve(contacts.size());
  for (const Contact& c : contacts) {
    if (!c.p_ObjectContact.allFinite() || !c.n_Object.allFinite() || !(c.n_Object.norm() > 0.5)) continue;
    const bool near_kept = std::any_of(kept.begin(), kept.end(), [&](const QualityContact& k) {
      return (k.p - c.p_ObjectContact).norm() < kQualityMergeDistance && k.n.dot(c.n_Object) > kQualityMergeCos;
    });
    if (!near_kept) kept.push_back({c.p_ObjectContact, c.n_Object});
  }
  return kept;
}

std::optional<QualityJob> HandController::quality_inputs() const {
  if (!state_.grasped.valid()) return std::nullopt;
  if (contacts_key_ != shape_key()) refresh_contacts();
  QualityJob job;
  job.contacts = quality_contacts(contacts_);
  job.mu = held_model_->friction.value_or(rig_->friction());
  job.torque_scale = held_model_->max_radius;
  job.volume = settings_.quality_volume;
  return job;
}

std::optional<GraspMetrics> HandController::grasp_tick_metrics() const {
  if (!grasp_view_) return std::nullopt;
  return measure(*grasp_view_);
}

void HandController::set_grasp_metrics(std::uint64_t grasp, GraspMetrics metrics) {
  if (grasp != grasp_serial_ || !state_.grasped.valid()) return;
  metrics_ = std::move(metrics);
  if (!hold_metrics_) hold_metrics_ = metrics_;  // still the grasp tick's shape (else it was measured)
}

void HandController::set_quality(std::uint64_t grasp, const GraspQuality& quality, bool grasp_tick) {
  if (grasp != grasp_serial_ || !state_.grasped.valid()) return;
  hold_quality_ = quality;
  if (hold_metrics_) hold_metrics_->quality = quality;
  if (grasp_tick && metrics_) metrics_->quality = quality;
}

std::vector<Contact> HandController::contacts() const {
  const auto X_WorldObject = grasped_object_pose();
  if (!X_WorldObject) return {};
  if (contacts_key_ != shape_key()) refresh_contacts();
  std::vector<Contact> out = contacts_;
  for (Contact& c : out) {
    c.p_WorldContact = *X_WorldObject * c.p_ObjectContact;
    c.n_World = X_WorldObject->linear() * c.n_Object;
  }
  return out;
}

std::optional<ClosingMode> parse_closing_mode(std::string_view name) {
  if (name == "precise") return ClosingMode::kPrecise;
  if (name == "discrete") return ClosingMode::kDiscrete;
  return std::nullopt;
}

const char* closing_mode_name(ClosingMode mode) { return mode == ClosingMode::kDiscrete ? "discrete" : "precise"; }

}  // namespace telegrasp::sim
