// The resolved hand pose: outside every object and the table, rejoining the tracked pose at a
// bounded speed.
#include "telegrasp/sim/pose_resolver.h"

#include "telegrasp/sim/object_view.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace telegrasp::sim {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
// Sub-steps of one tick's motion, at most: beyond, the hand stops where the last one left it.
constexpr int kMaxSubSteps = 64;
// Push-outs after one sub-step, at most: a hand caught between surfaces stays where it was.
constexpr int kMaxPushes = 8;

// Distance from c to the segment [p, q].
double distance_to_segment(const Eigen::Vector3d& c, const Eigen::Vector3d& p, const Eigen::Vector3d& q) {
  const Eigen::Vector3d d = q - p;
  const double len_sq = d.squaredNorm();
  const double t = len_sq > 0 ? std::clamp((c - p).dot(d) / len_sq, 0.0, 1.0) : 0.0;
  return (p + t * d - c).norm();
}

}  // namespace

std::vector<HandVolume> palm_volumes(const Eigen::Vector3d& h) {
  const double r = h.z();
  const double x = std::max(0.0, h.x() - r), y = std::max(0.0, h.y() - r);
  const int n = y > 0 ? static_cast<int>(std::ceil(2.0 * y / (1.2 * r))) + 1 : 1;
  std::vector<HandVolume> out;
  for (int i = 0; i < n; ++i) {
    const double yi = n > 1 ? -y + 2.0 * y * i / (n - 1) : 0.0;
    out.push_back({{-x, yi, 0}, {x, yi, 0}, r, true});
  }
  return out;
}

// The tracked pose carrying last tick's offset (resolved relative to tracked), shortened by the
// rejoin speed: the resolved pose follows the controller's motion and closes the offset gradually.
Eigen::Isometry3d PoseResolver::candidate(const Eigen::Isometry3d& X_WorldResolved,
                                          const Eigen::Isometry3d& X_WorldTrackedBefore,
                                          const Eigen::Isometry3d& X_WorldTracked, double dt) const {
  Eigen::Vector3d d = X_WorldResolved.translation() - X_WorldTrackedBefore.translation();
  const double len = d.norm(), step = settings_.rejoin_speed * dt;
  d = len > step ? Eigen::Vector3d(d * ((len - step) / len)) : Eigen::Vector3d::Zero();
  const Eigen::Matrix3d R_offset = X_WorldResolved.linear() * X_WorldTrackedBefore.linear().transpose();
  const Eigen::AngleAxisd aa(R_offset);
  const double turn = settings_.rejoin_turn * dt;
  const Eigen::Matrix3d R_left = aa.angle() > turn ? Eigen::AngleAxisd(aa.angle() - turn, aa.axis()).toRotationMatrix()
                                                   : Eigen::Matrix3d::Identity();
  Eigen::Isometry3d X = X_WorldTracked;
  X.translation() += d;
  X.linear() = R_left * X_WorldTracked.linear();
  // Held back by a surface last tick: no nearer to it than the hand is now (it would only be
  // pushed back out), until the tracked pose and offset come out on their own.
  if (pushed_) {
    const double in = (X.translation() - X_WorldResolved.translation()).dot(push_normal_);
    if (in < 0) X.translation() -= in * push_normal_;
  }
  return X;
}

// The obstacles the hand can reach moving from X0 to X1 (bounding spheres, so far objects cost
// nothing), and fresh per-pair bounds, floors and hints.
void PoseResolver::gather(const Eigen::Isometry3d& X0, const Eigen::Isometry3d& X1, std::span<const HandVolume> volumes,
                          std::span<const ObjectView> objects, ObjectId held) {
  volumes_ = volumes;
  reach_.resize(volumes.size());
  double hand_radius = 0;
  for (std::size_t v = 0; v < volumes.size(); ++v) {
    reach_[v] = std::max(volumes[v].p_PalmA.norm(), volumes[v].p_PalmB.norm());
    hand_radius = std::max(hand_radius, reach_[v] + volumes[v].radius);
  }
  const Eigen::Vector3d p0 = X0.translation(), p1 = X1.translation();
  const double margin = hand_radius + settings_.tolerance;
  std::vector<Obstacle> last = std::move(obstacles_);
  std::vector<double> last_bound = std::move(bound_);
  std::vector<std::uint32_t> last_hint = std::move(hint_);
  obstacles_.clear();
  const double H = settings_.table_half_extent;
  if (H > 0 && std::min(p0.z(), p1.z()) < margin && std::min(std::abs(p0.x()), std::abs(p1.x())) < H + margin &&
      std::min(std::abs(p0.y()), std::abs(p1.y())) < H + margin)
    obstacles_.push_back({});
  for (const ObjectView& view : objects) {
    if (view.id == held || !view.model) continue;
    const ObjectModel& m = *view.model;
    const Eigen::Vector3d c = view.X_WorldObject * (0.5 * (m.p_ObjectMin + m.p_ObjectMax));
    const double r = 0.5 * (m.p_ObjectMax - m.p_ObjectMin).norm();
    if (distance_to_segment(c, p0, p1) < r + margin) obstacles_.push_back({&m, view.X_WorldObject.inverse(), view.id});
  }
  const std::size_t pairs = obstacles_.size() * volumes.size();
  bound_.assign(pairs, -kInf);
  floor_.assign(pairs, 0.0);
  hint_.assign(pairs, MeshDistance::kNoHint);
  if (last_volumes_.size() == volumes.size()) carry_over(last, last_bound, last_hint, last_volumes_);
  last_volumes_.assign(volumes.begin(), volumes.end());
}

// Last tick's gap bounds and hints, for obstacles that have not moved, less how far each volume
// moved in the palm frame (the fingers); the hand starts where last tick's resolve left it.
void PoseResolver::carry_over(const std::vector<Obstacle>& last, const std::vector<double>& last_bound,
                              const std::vector<std::uint32_t>& last_hint,
                              const std::vector<HandVolume>& last_volumes) {
  const std::size_t nv = volumes_.size();
  for (std::size_t o = 0; o < obstacles_.size(); ++o)
    for (std::size_t l = 0; l < last.size(); ++l) {
      if (last[l].id != obstacles_[o].id || last[l].model != obstacles_[o].model) continue;
      const bool still = last[l].X_ObjectWorld.matrix() == obstacles_[o].X_ObjectWorld.matrix();
      for (std::size_t v = 0; v < nv; ++v) {
        hint_[o * nv + v] = last_hint[l * nv + v];
        const double moved = std::max((volumes_[v].p_PalmA - last_volumes[v].p_PalmA).norm(),
                                      (volumes_[v].p_PalmB - last_volumes[v].p_PalmB).norm());
        if (still && volumes_[v].radius == last_volumes[v].radius) bound_[o * nv + v] = last_bound[l * nv + v] - moved;
      }
    }
}

// The gap between volume v at X_WorldPalm and obstacle o, exact when within `horizon`.
PoseResolver::Gap PoseResolver::gap(std::size_t o, std::size_t v, const Eigen::Isometry3d& X_WorldPalm,
                                    double horizon) {
  const HandVolume& vol = volumes_[v];
  const Obstacle& obs = obstacles_[o];
  if (!obs.model) {  // the table: a plane, nearest at an end point over the top
    Gap g{horizon, {0, 0, 1}, true};  // neither end over the top: no nearer than the horizon
    const double H = settings_.table_half_extent + vol.radius;
    for (const Eigen::Vector3d& p : {X_WorldPalm * vol.p_PalmA, X_WorldPalm * vol.p_PalmB})
      if (std::abs(p.x()) <= H && std::abs(p.y()) <= H) g.gap = std::min(g.gap, p.z() - vol.radius);
    g.far = g.gap >= horizon;
    return g;
  }
  const MeshDistance& mesh = obs.model->distance;
  const Eigen::Isometry3d X_ObjectPalm = obs.X_ObjectWorld * X_WorldPalm;
  const Eigen::Vector3d a = X_ObjectPalm * vol.p_PalmA, b = X_ObjectPalm * vol.p_PalmB;
  std::uint32_t& hint = hint_[o * volumes_.size() + v];
  // A volume last seen near the surface is searched for at once; others first by the early-out test.
  const double last = bound_[o * volumes_.size() + v];
  if (!(last > -kInf && last < 0.5 * horizon) && !mesh.capsule_overlaps(a, b, vol.radius + horizon, hint))
    return {horizon, {0, 0, 1}, true};
  SegmentQuery q = mesh.closest_to_segment(a, b, vol.radius + horizon, hint);
  if (!q.found && last > -kInf && last < 0.5 * horizon && !mesh.capsule_overlaps(a, b, vol.radius + horizon, hint))
    return {horizon, {0, 0, 1}, true};
  if (q.found) hint = q.triangle;
  const Eigen::Matrix3d R_WorldObject = obs.X_ObjectWorld.linear().transpose();
  if (q.found && q.distance > 0 && (q.point_on_segment - q.point_on_mesh).dot(q.normal) > 0)
    return {q.distance - vol.radius, R_WorldObject * ((q.point_on_segment - q.point_on_mesh) / q.distance), false};
  // Inside: the exact depth, pushed out along the normal of the nearest surface.
  if (!q.found) q = mesh.closest_to_segment(a, b, kInf, hint);
  return {mesh.capsule_signed_distance(a, b, vol.radius, hint), R_WorldObject * q.normal, false};
}

// Palm volumes, and fingers against objects in precise mode, may not go below a zero gap; a
// finger against the table (which fingers close through) or resting inside in discrete mode may
// not go deeper than it starts.
void PoseResolver::set_floors(const Eigen::Isometry3d& X_WorldPalm) {
  const double tol = settings_.tolerance;
  for (std::size_t o = 0; o < obstacles_.size(); ++o)
    for (std::size_t v = 0; v < volumes_.size(); ++v) {
      const std::size_t ov = o * volumes_.size() + v;
      const bool object = obstacles_[o].model != nullptr;
      if (volumes_[v].palm) continue;
      if (object && !settings_.fingers_may_rest_inside) continue;
      floor_[ov] = std::min(0.0, gap(o, v, X_WorldPalm, tol).gap);
    }
}

// Pushes the hand out along the normal of its deepest volume until every gap is at or above its
// floor; false if that takes more than kMaxPushes (X_WorldPalm is then left moved).
bool PoseResolver::push_out(Eigen::Isometry3d& X_WorldPalm) {
  const std::size_t nv = volumes_.size();
  for (int iter = 0; iter <= kMaxPushes; ++iter) {
    double worst = 0;
    Eigen::Vector3d n{0, 0, 1};
    for (std::size_t o = 0; o < obstacles_.size(); ++o)
      for (std::size_t v = 0; v < nv; ++v) {
        double& bound = bound_[o * nv + v];
        const double floor = floor_[o * nv + v];
        if (bound >= floor) continue;
        const Gap g = gap(o, v, X_WorldPalm, std::max(floor, 0.0) + horizon_);
        bound = g.gap;  // exact, or the horizon when farther
        if (!g.far && floor - g.gap > worst) {
          worst = floor - g.gap;
          n = g.n_World;
        }
      }
    if (worst <= 0) return true;
    if (iter == kMaxPushes) break;
    const double shift = worst + 0.5 * settings_.tolerance;
    X_WorldPalm.translation() += shift * n;
    pushed_ = true;
    push_normal_ = n;
    for (double& b : bound_) b -= shift;
  }
  return false;
}

bool PoseResolver::unchanged(const Eigen::Isometry3d& X0, const Eigen::Isometry3d& X1,
                             std::span<const ObjectView> objects, ObjectId held) const {
  if (!last_valid_ || X0.matrix() != X1.matrix()) return false;
  std::size_t i = 0;
  for (const ObjectView& view : objects) {
    if (view.id == held) continue;
    if (i >= last_objects_.size() || last_objects_[i].first != view.id ||
        last_objects_[i].second.matrix() != view.X_WorldObject.matrix())
      return false;
    ++i;
  }
  return i == last_objects_.size();
}

Eigen::Isometry3d PoseResolver::resolve(const Eigen::Isometry3d& X_WorldResolved,
                                        const Eigen::Isometry3d& X_WorldTrackedBefore,
                                        const Eigen::Isometry3d& X_WorldTracked, bool has_previous, double dt,
                                        std::span<const HandVolume> volumes, std::span<const ObjectView> objects,
                                        ObjectId held) {
  if (has_previous && settings_.snap_distance > 0 && !held.valid() &&
      (X_WorldTracked.translation() - X_WorldResolved.translation()).norm() > settings_.snap_distance) {
    // Caught far behind: at the tracked pose if nothing has to be pushed out there.
    const bool pushed = pushed_;
    const Eigen::Vector3d push_normal = push_normal_;
    last_valid_ = false;  // last tick's bounds hold where it left the hand, not there
    const Eigen::Isometry3d X = resolve(X_WorldTracked, X_WorldTracked, X_WorldTracked, false, dt, volumes, objects, held);
    if (!pushed_ && X.matrix() == X_WorldTracked.matrix()) return X;
    last_valid_ = false;  // the bounds now hold at the tracked pose
    pushed_ = pushed;
    push_normal_ = push_normal;
  }
  const Eigen::Isometry3d X1 =
      has_previous ? candidate(X_WorldResolved, X_WorldTrackedBefore, X_WorldTracked, dt) : X_WorldTracked;
  const Eigen::Isometry3d X0 = has_previous ? X_WorldResolved : X1;
  // Nothing moved relative to anything: last tick's answer stands (fingers keep themselves out).
  if (unchanged(X0, X1, objects, held)) return X0;
  last_objects_.clear();
  for (const ObjectView& view : objects)
    if (view.id != held) last_objects_.emplace_back(view.id, view.X_WorldObject);
  // Last tick's bounds hold where last tick's resolve left the hand, X0.
  if (!has_previous || !last_valid_) last_volumes_.clear();
  gather(X0, X1, volumes, objects, held);
  last_valid_ = true;
  pushed_ = false;
  if (obstacles_.empty()) return X1;
  set_floors(X0);

  // The motion in sub-steps, each moving no volume point by more than 0.9 of its radius: the axis of
  // a volume outside before a sub-step stays outside after it, so the push-out finds the side it
  // came from (no tunnelling through thin objects).
  const Eigen::Vector3d dp = X1.translation() - X0.translation();
  const Eigen::AngleAxisd turn(X1.linear() * X0.linear().transpose());
  double max_rate = 0;
  int n = 1;
  for (std::size_t v = 0; v < volumes.size(); ++v) {
    const double rate = dp.norm() + turn.angle() * reach_[v];
    max_rate = std::max(max_rate, rate);
    // A jump too far to sub-step (or a non-finite rate: palm poses ~1e308 apart overflow) takes
    // the most sub-steps; converting it to int was undefined (found by telegrasp-fuzz-controller-state).
    const double steps = std::ceil(rate / (0.9 * volumes[v].radius));
    n = std::max(n, steps < kMaxSubSteps ? static_cast<int>(steps) : kMaxSubSteps);
  }
  n = std::min(n, kMaxSubSteps);
  const Eigen::Matrix3d R_step = Eigen::AngleAxisd(turn.angle() / n, turn.axis()).toRotationMatrix();
  Eigen::Isometry3d X = X0;
  horizon_ = max_rate + settings_.tolerance;
  if (!push_out(X)) {  // inside from the start and no way out
    last_valid_ = false;
    if (!has_previous) return X0;
    // Start afresh at the tracked pose (pushed out if it can be): a hand left inside, such as one
    // idle at the origin in the table before its first input, must not stay there for ever.
    last_objects_.clear();
    return resolve(X_WorldTracked, X_WorldTracked, X_WorldTracked, false, dt, volumes, objects, held);
  }
  for (int k = 1; k <= n; ++k) {
    const Eigen::Isometry3d before = X;
    X.translation() += dp / n;
    X.linear() = R_step * X.linear();
    for (std::size_t o = 0; o < obstacles_.size(); ++o)
      for (std::size_t v = 0; v < volumes.size(); ++v)
        bound_[o * volumes.size() + v] -= (dp.norm() + turn.angle() * reach_[v]) / n;
    horizon_ = max_rate * (n - k) / n + settings_.tolerance;
    if (!push_out(X)) {  // caught between surfaces: stop where the last sub-step left the hand
      last_valid_ = false;
      last_volumes_.clear();
      return before;
    }
  }
  return X;
}

}  // namespace telegrasp::sim
