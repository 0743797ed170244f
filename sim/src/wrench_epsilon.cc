// Ferrari-Canny epsilon by an expanding polytope (Y. Zheng, "An Efficient Algorithm for a Grasp
// Quality Measure", IEEE Transactions on Robotics 29(2), 2013), written for this project.
//
// epsilon(W) = max(0, min over unit u of h(u)), h(u) = max_i u . w_i the support function of the
// wrench hull. The method keeps a polytope P = conv(S), S a subset of W, as a simplicial complex
// of facets (6 vertices each) with their neighbours, built around an interior point c of a first
// simplex. Each step takes the facet f of P whose hyperplane is nearest the origin on the inner
// side (least offset n_f . x; negative while the origin is outside P), and the wrench w* farthest
// along n_f:
// - h(n_f) <= offset_f + tol: f's hyperplane supports all of W. If the origin is inside P, then
//   epsilon(P) = offset_f <= epsilon(W) <= h(n_f) <= offset_f + tol: done, exact to tol. If it is
//   not (offset_f <= 0), every wrench lies on the far side of a hyperplane that passes at or
//   beyond the origin: no force closure, and n_f is the separating direction (its certificate).
// - otherwise w* lies beyond f: add it to S (beneath-beyond: remove the facets w* sees, join the
//   horizon's ridges to w*). P grows by a wrench each step, so the loop ends after at most |W|
//   steps; in practice it builds only the facets near the origin, not the full hull's thousands.
// The first phase (origin outside P) is the exact force-closure test; the second refines epsilon.
#include "grasp_quality_internal.h"
#include "telegrasp/sim/grasp_quality.h"

#include <algorithm>
#include <array>
#include <cassert>
#include <cmath>
#include <cstdint>
#include <limits>
#include <queue>
#include <utility>
#include <vector>

namespace telegrasp::sim {
namespace {

constexpr int kDim = 6;
using Vec6 = Eigen::Matrix<double, kDim, 1>;

// Stop when the support along the nearest facet's normal exceeds its offset by at most this
// times the largest wrench norm; a wrench counts as beyond a facet (visible from it) only past
// the same margin, so wrenches coplanar with a facet (symmetric cones make many) are never added.
constexpr double kRelativeTolerance = 1e-11;
// A facet whose 6 vertices span less than this (relative) in some direction of its hyperplane is
// numerically flat: its normal is not to be trusted, and the caller falls back to the full hull.
constexpr double kFlatFacet = 1e-9;

struct Facet {
  std::array<int, kDim> v;  // wrench indices
  std::array<int, kDim> nb;  // nb[j]: the facet across the ridge opposite v[j]
  Vec6 n;  // unit normal, pointing away from the interior point
  double offset = 0;  // n . x for x on the facet: the origin's distance inside (negative: outside)
  bool alive = true;
  std::uint32_t seen = 0;  // the step whose visibility search last reached it
};

class ExpandingPolytope {
 public:
  ExpandingPolytope(const Wrenches& w, double scale) : w_(w), tol_(kRelativeTolerance * scale), scale_(scale) {}

  // Builds the first simplex from 7 affinely independent wrenches; false if there are none.
  bool start() {
    const Eigen::Index m = w_.cols();
    const Vec6 centroid = w_.rowwise().mean();
    std::array<int, kDim + 1> s{};
    Eigen::Index far = 0;
    (w_.colwise() - centroid).colwise().squaredNorm().maxCoeff(&far);
    s[0] = static_cast<int>(far);
    // Each next vertex: the wrench farthest from the affine hull of those chosen (Gram-Schmidt).
    Eigen::Matrix<double, kDim, kDim> basis;
    for (int k = 1; k <= kDim; ++k) {
      double best = -1;
      Vec6 best_r = Vec6::Zero();
      for (Eigen::Index i = 0; i < m; ++i) {
        Vec6 r = w_.col(i) - w_.col(s[0]);
        for (int b = 0; b < k - 1; ++b) r -= basis.col(b).dot(r) * basis.col(b);
        const double d = r.squaredNorm();
        if (d > best) best = d, best_r = r, s[k] = static_cast<int>(i);
      }
      if (!(std::sqrt(best) > kFlatFacet * scale_)) return false;
      basis.col(k - 1) = best_r.normalized();
    }
    interior_.setZero();
    for (int i : s) interior_ += w_.col(i);
    interior_ /= kDim + 1;
    in_s_.assign(static_cast<std::size_t>(m), 0);
    for (int i : s) in_s_[i] = 1;
    // Facet j leaves out s[j]; across its vertex s[k] lies facet k.
    for (int j = 0; j <= kDim; ++j) {
      Facet f;
      int p = 0;
      for (int k = 0; k <= kDim; ++k)
        if (k != j) f.v[p] = s[k], f.nb[p++] = k;
      if (!place(f)) return false;
      add(f);
    }
    return true;
  }

  // Runs to the end; false if the polytope became numerically inconsistent (the caller then
  // falls back to the full hull).
  bool run(EpsilonResult& out) {
    while (!heap_.empty()) {
      const auto [offset, fi] = heap_.top();
      if (!facets_[fi].alive) {
        heap_.pop();
        continue;
      }
      const Facet& f = facets_[fi];
      int best = 0;
      const double h = support(f.n, best);
      if (h <= f.offset + tol_) {
        out.epsilon = f.offset;
        out.support = h;
        out.direction = f.n;
        return true;
      }
      // A vertex of P beyond one of P's own facets: the facet's plane is off by more than tol.
      if (in_s_[best] || !expand(fi, best)) return false;
      ++out.added;
    }
    return false;
  }

  std::size_t facets_built() const { return facets_.size(); }

  // The result's certificate: no wrench lies more than tol beyond `epsilon` along `direction`,
  // and (when the origin is inside P) no live facet is nearer the origin than `epsilon`.
  bool certificate_holds(const EpsilonResult& r) const {
    if (r.epsilon > 0)
      for (const Facet& f : facets_)
        if (f.alive && f.offset < r.epsilon) return false;
    int best = 0;
    return support(r.direction, best) <= r.epsilon + tol_;
  }

 private:
  // Normal and offset of f from its vertices; false if they are (numerically) affinely flat.
  // Gram-Schmidt, each projection taken twice (exact to rounding for these 5 vectors in 6-D), then
  // the coordinate axis least in their span, less its projection, is the normal.
  bool place(Facet& f) const {
    std::array<Vec6, kDim - 1> q;
    const Vec6 origin = w_.col(f.v[0]);
    auto reject = [&](Vec6 r, int count) {
      for (int pass = 0; pass < 2; ++pass)
        for (int i = 0; i < count; ++i) r -= q[i].dot(r) * q[i];
      return r;
    };
    for (int k = 0; k < kDim - 1; ++k) {
      const Vec6 r = reject(w_.col(f.v[k + 1]) - origin, k);
      const double length = r.norm();
      if (!(length > kFlatFacet * scale_)) return false;
      q[k] = r / length;
    }
    Vec6 in_span = Vec6::Zero();
    for (const Vec6& qi : q) in_span += qi.cwiseAbs2();
    int axis = 0;
    in_span.minCoeff(&axis);
    f.n = reject(Vec6::Unit(axis), kDim - 1).normalized();
    double offset = 0;
    for (int k = 0; k < kDim; ++k) offset += f.n.dot(w_.col(f.v[k]));
    offset /= kDim;
    if (f.n.dot(interior_) > offset) f.n = -f.n, offset = -offset;
    f.offset = offset;
    return true;
  }

  int add(const Facet& f) {
    facets_.push_back(f);
    const int id = static_cast<int>(facets_.size()) - 1;
    heap_.emplace(f.offset, id);
    return id;
  }

  // The largest u . w over the wrenches, and the first wrench that has it.
  double support(const Vec6& u, int& best) const {
    double h = -std::numeric_limits<double>::infinity();
    for (Eigen::Index i = 0; i < w_.cols(); ++i) {
      const double d = u.dot(w_.col(i));
      if (d > h) h = d, best = static_cast<int>(i);
    }
    return h;
  }

  bool visible(const Facet& f, int point) const { return f.n.dot(w_.col(point)) > f.offset + tol_; }

  // Adds wrench `point`, which lies beyond facet `from`.
  bool expand(int from, int point) {
    ++step_;
    // The facets the point sees, connected to `from` (a visible region is a topological ball).
    visible_.assign(1, from);
    facets_[from].seen = step_;
    for (std::size_t q = 0; q < visible_.size(); ++q) {
      const Facet& f = facets_[visible_[q]];
      for (int nb : f.nb) {
        Facet& g = facets_[nb];
        if (g.seen == step_ || !visible(g, point)) continue;
        g.seen = step_;
        visible_.push_back(nb);
      }
    }
    for (int fi : visible_) facets_[fi].alive = false;
    // Each horizon ridge (a visible facet's side toward a hidden one) joined to the point.
    ridges_.clear();
    const std::size_t first = facets_.size();
    for (int fi : visible_) {
      for (int j = 0; j < kDim; ++j) {
        const int hidden = facets_[fi].nb[j];
        if (!facets_[hidden].alive) continue;
        Facet g;
        int p = 0;
        for (int k = 0; k < kDim; ++k)
          if (k != j) g.v[p++] = facets_[fi].v[k];
        g.v[kDim - 1] = point;
        g.nb.fill(-1);
        g.nb[kDim - 1] = hidden;
        if (!place(g)) return false;
        const int gi = add(g);
        Facet& h = facets_[hidden];
        const auto back = std::find(h.nb.begin(), h.nb.end(), fi);
        if (back == h.nb.end()) return false;
        *back = gi;
        // The new facet's other sides: the ridge less one vertex, plus the point; each is shared
        // with exactly one other new facet.
        for (int k = 0; k < kDim - 1; ++k) {
          std::array<std::uint64_t, kDim - 2> shared;
          int q = 0;
          for (int r = 0; r < kDim - 1; ++r)
            if (r != k) shared[q++] = static_cast<std::uint64_t>(g.v[r]);
          std::sort(shared.begin(), shared.end());
          const std::uint64_t key = shared[0] << 48 | shared[1] << 32 | shared[2] << 16 | shared[3];
          ridges_.push_back({key, static_cast<std::uint64_t>(gi) << 3 | static_cast<std::uint64_t>(k)});
        }
      }
    }
    if (facets_.size() == first) return false;
    std::sort(ridges_.begin(), ridges_.end());
    for (std::size_t i = 0; i < ridges_.size(); i += 2) {
      if (i + 1 >= ridges_.size() || ridges_[i].first != ridges_[i + 1].first) return false;
      if (i + 2 < ridges_.size() && ridges_[i + 2].first == ridges_[i].first) return false;
      const std::uint64_t a = ridges_[i].second, b = ridges_[i + 1].second;
      facets_[a >> 3].nb[a & 7] = static_cast<int>(b >> 3);
      facets_[b >> 3].nb[b & 7] = static_cast<int>(a >> 3);
    }
    in_s_[point] = 1;
    return true;
  }

  // A new facet's side toward another new facet: (its 4 vertices other than the point, sorted,
  // 16 bits each; the facet << 3 | the position in it of the vertex left out).
  using Side = std::pair<std::uint64_t, std::uint64_t>;
  using Entry = std::pair<double, int>;

  const Wrenches& w_;
  const double tol_;
  const double scale_;
  Vec6 interior_ = Vec6::Zero();
  std::vector<std::uint8_t> in_s_;
  std::vector<Facet> facets_;
  std::priority_queue<Entry, std::vector<Entry>, std::greater<>> heap_;
  std::vector<int> visible_;
  std::vector<Side> ridges_;
  std::uint32_t step_ = 0;
};

}  // namespace

EpsilonResult wrench_epsilon(const Wrenches& w) {
  EpsilonResult out;
  if (!w.allFinite() || !full_dimensional(w)) return out;
  const double scale = w.colwise().norm().maxCoeff();
  // Vertex indices are packed in 16 bits (the sides' keys); a grasp has at most 64 x 8 wrenches.
  if (w.cols() < 1 << 16) {
    ExpandingPolytope polytope(w, scale);
    if (polytope.start() && polytope.run(out)) {
      out.facets = static_cast<int>(polytope.facets_built());
      assert(polytope.certificate_holds(out));
      if (!(out.epsilon > kMinEpsilon)) out.epsilon = 0;
      out.force_closure = out.epsilon > 0;
      return out;
    }
  }
  // Numerically degenerate on the way (never seen on grasps; the tests count it): the full hull.
  const GraspQuality q = qhull_wrench_quality(w);
  out = EpsilonResult{};
  out.epsilon = q.epsilon;
  out.force_closure = q.force_closure;
  out.full_hull = true;
  return out;
}

}  // namespace telegrasp::sim
