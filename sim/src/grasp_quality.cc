// Grasp quality (sim/README.md, section 5 Grasp quality): the wrenches of the contacts' friction cones, epsilon by
// the expanding polytope (wrench_epsilon.cc), and the full hull with Qhull's reentrant API (the
// volume, and the reference the tests hold the expanding polytope to).
#include "grasp_quality_internal.h"
#include "telegrasp/sim/grasp_quality.h"

#include <Eigen/Geometry>
#include <Eigen/QR>
#include <Eigen/SVD>

#include <cmath>
#include <cstdio>
#include <limits>
#include <numbers>
#include <vector>

extern "C" {
#include <libqhull_r/qhull_ra.h>
}

namespace telegrasp::sim {
namespace {

constexpr int kDim = 6;
// The wrench set spans fewer than 6 dimensions when its smallest singular value (after removing
// the centroid) falls below this fraction of its largest: the hull is flat, so it has no interior
// (epsilon 0) and no 6-D volume. Wrench coordinates are of order 1 (unit normal force, torques
// divided by the object's radius), so rounding leaves ~1e-16 where the exact value is 0.
constexpr double kFlatRatio = 1e-10;

// Where Qhull writes its messages: nowhere. Qhull takes a FILE* and falls back to stderr on null.
FILE* qhull_err_file() {
  static FILE* const file = [] {
    FILE* f = std::fopen("/dev/null", "w");
    return f ? f : std::tmpfile();
  }();
  return file;
}

// Two unit tangents completing the outward normal n to a right-handed frame (t1, t2, n). t1 is
// n x e, e the coordinate axis least aligned with n (the first such on ties), so axis-aligned
// normals get axis-aligned tangents: their 8-edge cones then contain the axes and the diagonals.
void tangents(const Eigen::Vector3d& n, Eigen::Vector3d& t1, Eigen::Vector3d& t2) {
  int axis = 0;
  const Eigen::Vector3d a = n.cwiseAbs();
  if (a.y() < a[axis]) axis = 1;
  if (a.z() < a[axis]) axis = 2;
  t1 = n.cross(Eigen::Vector3d::Unit(axis)).normalized();
  t2 = n.cross(t1);
}

}  // namespace

bool full_dimensional(const Wrenches& w) {
  if (w.cols() <= kDim) return false;  // 6 points span at most 5 dimensions
  const Eigen::Matrix<double, kDim, 1> centroid = w.rowwise().mean();
  // The singular values of the centred wrenches are those of the 6x6 R of a QR factorisation of
  // their transpose, which the SVD then takes cheaply and as accurately.
  const Eigen::MatrixXd centred = (w.colwise() - centroid).transpose();
  const Eigen::HouseholderQR<Eigen::MatrixXd> qr(centred);
  const Eigen::Matrix<double, kDim, kDim> r = qr.matrixQR().topRows<kDim>().triangularView<Eigen::Upper>();
  const Eigen::JacobiSVD<Eigen::Matrix<double, kDim, kDim>> svd(r);
  const auto& s = svd.singularValues();  // decreasing
  return s[0] > 0 && s[kDim - 1] > kFlatRatio * s[0];
}

Wrenches contact_wrenches(std::span<const QualityContact> contacts, double mu, double torque_scale, int cone_edges) {
  if (!(mu >= 0) || !std::isfinite(mu) || !(torque_scale > 0) || !std::isfinite(torque_scale) || cone_edges < 1)
    return Wrenches(kDim, 0);
  // Frictionless contacts push along their normal only: one wrench each.
  const int edges = mu > 0 ? cone_edges : 1;
  Wrenches w(kDim, static_cast<Eigen::Index>(contacts.size()) * edges);
  Eigen::Index col = 0;
  for (const QualityContact& c : contacts) {
    if (!c.p.allFinite() || !c.n.allFinite()) return Wrenches(kDim, 0);
    const double norm = c.n.norm();
    if (!(norm > 0)) return Wrenches(kDim, 0);
    const Eigen::Vector3d n = c.n / norm;
    Eigen::Vector3d t1, t2;
    tangents(n, t1, t2);
    for (int k = 0; k < edges; ++k) {
      const double angle = 2 * std::numbers::pi * k / edges;
      // Unit normal force into the object (along -n) plus the cone edge's friction.
      const Eigen::Vector3d f = -n + mu * (std::cos(angle) * t1 + std::sin(angle) * t2);
      w.col(col).head<3>() = f;
      w.col(col).tail<3>() = c.p.cross(f) / torque_scale;
      ++col;
    }
  }
  return w;
}

GraspQuality grasp_quality(std::span<const QualityContact> contacts, double mu, double torque_scale, int cone_edges,
                           QualityVolume volume) {
  return wrench_quality(contact_wrenches(contacts, mu, torque_scale, cone_edges), volume);
}

GraspQuality wrench_quality(const Wrenches& w, QualityVolume volume) {
  const EpsilonResult e = wrench_epsilon(w);
  GraspQuality out;
  out.epsilon = e.epsilon;
  out.force_closure = e.force_closure;
  out.volume = volume == QualityVolume::kCompute ? qhull_wrench_quality(w).volume : kVolumeNotComputed;
  return out;
}

GraspQuality qhull_wrench_quality(const Wrenches& w) {
  GraspQuality out;
  if (!w.allFinite() || !full_dimensional(w)) return out;

  // First without merging ('Q0': about twice as fast on these inputs); on a precision error (flat
  // or coplanar wrenches, common in symmetric grasps) again with Qhull's defaults for 6-D: exact
  // pre-merges ('Qx') and merges of facets coplanar within rounding ('C-0'), which handle them.
  // No output and no triangulation are asked for; 'FA' computes the volume.
  FILE* err = qhull_err_file();
  for (const char* options : {"qhull Q0 FA", "qhull FA"}) {
    char command[16];
    std::snprintf(command, sizeof command, "%s", options);
    qhT qh_storage;
    qhT* qh = &qh_storage;
    qh_zero(qh, err);
    // With these options (no scaling, rotation or joggle) Qhull only reads the points; ismalloc
    // False: it does not free them either.
    const int code =
        qh_new_qhull(qh, kDim, static_cast<int>(w.cols()), const_cast<coordT*>(w.data()), False, command, nullptr, err);
    if (code == qh_ERRnone) {
      double nearest = std::numeric_limits<double>::infinity();
      facetT* facet;
      FORALLfacets {
        // Unit outward normal: points x of the hull satisfy normal . x + offset <= 0, so the
        // origin lies -offset inside this facet's hyperplane (negative: outside it).
        nearest = std::min(nearest, -facet->offset);
      }
      if (qh->hasAreaVolume && std::isfinite(qh->totvol) && qh->totvol > 0) out.volume = qh->totvol;
      if (nearest > kMinEpsilon && std::isfinite(nearest) && out.volume > 0) out.epsilon = nearest;
    }
    qh_freeqhull(qh, !qh_ALL);
    int curlong = 0, totlong = 0;
    qh_memfreeshort(qh, &curlong, &totlong);
    if (code == qh_ERRnone) break;
  }
  out.force_closure = out.epsilon > 0;
  return out;
}

}  // namespace telegrasp::sim
