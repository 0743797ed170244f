// The exact signed distance of a box (the palm volume) to an object's solid.
#include "palm_distance.h"

#include <algorithm>
#include <array>
#include <limits>
#include <optional>
#include <vector>

namespace telegrasp::sim {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
// A box edge or mesh vertex this close to the other counts as touching: the box overlaps.
constexpr double kTouching = 1e-9;
// Projected descent: starts kept after the first evaluation, iterations, smallest step (m).
constexpr std::size_t kDescentStarts = 2;
constexpr std::size_t kSeeds = 8;
constexpr int kDescentIterations = 24;
constexpr double kMinStep = 1e-5;

struct Box {
  Eigen::Isometry3d X_ObjectBox;
  Eigen::Vector3d h;

  [[nodiscard]] Eigen::Vector3d corner(int i) const {
    return X_ObjectBox * Eigen::Vector3d(i & 1 ? h.x() : -h.x(), i & 2 ? h.y() : -h.y(), i & 4 ? h.z() : -h.z());
  }
  // The box point nearest p (object frame).
  [[nodiscard]] Eigen::Vector3d clamp(const Eigen::Vector3d& p) const {
    const Eigen::Vector3d l = X_ObjectBox.inverse() * p;
    return X_ObjectBox * Eigen::Vector3d(l.cwiseMax(-h).cwiseMin(h));
  }
};

// Closest distance between the box's 12 edges and the surface; edge points touching it are seeds.
double edge_distance(const MeshDistance& mesh, const Box& box, std::vector<Eigen::Vector3d>& seeds) {
  double best = kInf;
  for (int i = 0; i < 8; ++i)
    for (int axis = 0; axis < 3; ++axis) {
      const int j = i | (1 << axis);
      if (j == i) continue;
      const SegmentQuery q = mesh.closest_to_segment(box.corner(i), box.corner(j), best);
      if (!q.found) continue;
      best = std::min(best, q.distance);
      if (q.distance <= kTouching) seeds.push_back(q.point_on_segment);
    }
  return best;
}

// min(best, distance from the box to the mesh vertices); vertices in the box are seeds. A vertex
// farther than `best` from the box's bounding box (object frame) is skipped without the transform.
double vertex_distance(const TriangleMesh& mesh, const Box& box, double best, std::vector<Eigen::Vector3d>& seeds) {
  const Eigen::Matrix3d R_BoxObject = box.X_ObjectBox.linear().transpose();
  const Eigen::Vector3d c = box.X_ObjectBox.translation();
  const Eigen::Vector3d e = box.X_ObjectBox.linear().cwiseAbs() * box.h;
  for (const Eigen::Vector3d& v : mesh.vertices) {
    if (((v - c).cwiseAbs() - e).maxCoeff() > best) continue;
    const Eigen::Vector3d l = R_BoxObject * (v - c);
    const double d = (l - l.cwiseMax(-box.h).cwiseMin(box.h)).norm();
    best = std::min(best, d);
    if (d <= kTouching) seeds.push_back(v);
  }
  return best;
}

// The closest point to p if p's signed distance is below `f`, else nothing. With f < 0 a search
// bounded by |f| first rejects, cheaply, every point whose surface lies nearer than that.
std::optional<PointQuery> lower(const MeshDistance& mesh, const Eigen::Vector3d& p, double f) {
  if (f < 0 && mesh.closest_point(p, -f).found) return std::nullopt;
  const PointQuery q = mesh.closest_point(p);
  if (!(q.signed_distance < f)) return std::nullopt;
  return q;
}

// Projected descent of the signed distance over the box from x: steps away from the nearest
// surface point inside the solid (toward it outside), clamped to the box, kept when lower.
double descend(const MeshDistance& mesh, const Box& box, Eigen::Vector3d x) {
  PointQuery q = mesh.closest_point(x);
  double step = box.h.maxCoeff();
  for (int it = 0; it < kDescentIterations && step > kMinStep; ++it) {
    Eigen::Vector3d g = x - q.point_on_mesh;
    const double n = g.norm();
    g = n > 0 ? Eigen::Vector3d(g / n) : Eigen::Vector3d(-q.normal);
    if (q.signed_distance > 0) g = -g;
    const Eigen::Vector3d y = box.clamp(x + step * g);
    if (const auto qy = lower(mesh, y, q.signed_distance)) {
      x = y;
      q = *qy;
    } else {
      step *= 0.5;
    }
  }
  return q.signed_distance;
}

// The lowest signed distance over the box: descent from the lowest few of the corners, face
// centres, centre and (up to kSeeds of) the seeds.
double deepest(const MeshDistance& mesh, const Box& box, std::vector<Eigen::Vector3d> starts) {
  if (starts.size() > kSeeds) starts.resize(kSeeds);
  for (int i = 0; i < 8; ++i) starts.push_back(box.corner(i));
  for (int axis = 0; axis < 3; ++axis)
    for (double s : {-1.0, 1.0}) {
      Eigen::Vector3d l = Eigen::Vector3d::Zero();
      l[axis] = s * box.h[axis];
      starts.push_back(box.X_ObjectBox * l);
    }
  starts.push_back(box.X_ObjectBox.translation());
  std::vector<std::pair<double, std::size_t>> best;  // the lowest kDescentStarts, ascending
  for (std::size_t i = 0; i < starts.size(); ++i) {
    const double bar = best.size() < kDescentStarts ? kInf : best.back().first;
    const auto q = lower(mesh, starts[i], bar);
    if (!q) continue;
    best.insert(std::upper_bound(best.begin(), best.end(), std::make_pair(q->signed_distance, i)),
                {q->signed_distance, i});
    if (best.size() > kDescentStarts) best.pop_back();
  }
  double lowest = kInf;
  for (const auto& [f, i] : best) lowest = std::min(lowest, descend(mesh, box, starts[i]));
  return lowest;
}

}  // namespace

double box_signed_distance(const ObjectModel& model, const Eigen::Isometry3d& X_ObjectBox,
                           const Eigen::Vector3d& half_extent) {
  const Box box{X_ObjectBox, half_extent};
  std::vector<Eigen::Vector3d> seeds;
  double gap = edge_distance(model.distance, box, seeds);
  gap = vertex_distance(model.mesh, box, gap, seeds);
  if (gap > kTouching && !model.distance.contains(X_ObjectBox.translation())) return gap;
  return std::min(deepest(model.distance, box, std::move(seeds)), 0.0);
}

}  // namespace telegrasp::sim
