// The exact signed distance of a box (the palm volume) to an object's solid.
#include "palm_distance.h"

#include <algorithm>
#include <array>
#include <limits>
#include <vector>

namespace telegrasp::sim {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
// A box edge or mesh vertex this close to the other counts as touching: the box overlaps.
constexpr double kTouching = 1e-9;
// Projected descent: starts kept after the first evaluation, iterations, smallest step (m).
constexpr int kDescentStarts = 4;
constexpr int kGrid = 5;  // start points along the box's two long axes (3 across its thickness)
constexpr int kDescentIterations = 64;
constexpr double kMinStep = 1e-7;

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
    const PointQuery qy = mesh.closest_point(y);
    if (qy.signed_distance < q.signed_distance) {
      x = y;
      q = qy;
    } else {
      step *= 0.5;
    }
  }
  return q.signed_distance;
}

// The lowest signed distance over the box: descent from the best few of a 5 x 5 x 3 grid of box
// points (corners, face and edge points, centre included) and the seeds.
double deepest(const MeshDistance& mesh, const Box& box, std::vector<Eigen::Vector3d> starts) {
  const Eigen::Array3i n(kGrid, kGrid, 3);
  for (int i = 0; i < n.x(); ++i)
    for (int j = 0; j < n.y(); ++j)
      for (int k = 0; k < n.z(); ++k) {
        const Eigen::Array3d f = Eigen::Array3d(i, j, k) / (n - 1).cast<double>();
        starts.push_back(box.X_ObjectBox * Eigen::Vector3d((2 * f - 1) * box.h.array()));
      }
  std::vector<std::pair<double, std::size_t>> ranked;
  for (std::size_t i = 0; i < starts.size(); ++i) ranked.emplace_back(mesh.signed_distance(starts[i]), i);
  const std::size_t keep = std::min<std::size_t>(kDescentStarts, ranked.size());
  std::partial_sort(ranked.begin(), ranked.begin() + static_cast<std::ptrdiff_t>(keep), ranked.end());
  double lowest = kInf;
  for (std::size_t k = 0; k < keep; ++k) lowest = std::min(lowest, descend(mesh, box, starts[ranked[k].second]));
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
