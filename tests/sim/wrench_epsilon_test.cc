// Ferrari-Canny epsilon by the expanding polytope (sim/grasp_quality.h, wrench_epsilon) against
// Qhull's full hull on random grasps, polytopes whose epsilon is known in closed form,
// invariances, degenerate inputs and its certificate.
//
// TELEGRASP_EPSILON_LONG=1 runs the long comparison instead of the unit test's: 10,000 grasps of
// 3-20 contacts, mu 0.2-1, 4 and 8 cone edges, with a summary on stdout.
#include "telegrasp/sim/grasp_quality.h"

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <numeric>
#include <random>
#include <vector>

namespace telegrasp::sim {
namespace {

using Vec6 = Eigen::Matrix<double, 6, 1>;
using Contacts = std::vector<QualityContact>;

double tolerance(double epsilon) { return 1e-9 * std::max(1.0, epsilon); }

// Wrenches from a list of columns.
Wrenches columns(const std::vector<Vec6>& points) {
  Wrenches w(6, static_cast<Eigen::Index>(points.size()));
  for (std::size_t i = 0; i < points.size(); ++i) w.col(static_cast<Eigen::Index>(i)) = points[i];
  return w;
}

// Every vertex of the hypercube {-1, 1}^6.
Wrenches hypercube() {
  std::vector<Vec6> p;
  for (int bits = 0; bits < 64; ++bits) {
    Vec6 x;
    for (int k = 0; k < 6; ++k) x[k] = (bits >> k & 1) ? 1.0 : -1.0;
    p.push_back(x);
  }
  return columns(p);
}

// The cross-polytope {+-e_k}.
Wrenches cross_polytope() {
  std::vector<Vec6> p;
  for (int k = 0; k < 6; ++k)
    for (double s : {1.0, -1.0}) p.push_back(s * Vec6::Unit(k));
  return columns(p);
}

// A regular 6-simplex of circumradius r centred on the origin: the 7 standard basis vectors of
// R^7 less their centroid, in an orthonormal basis of the hyperplane they span, scaled to r.
Wrenches regular_simplex(double r) {
  Eigen::Matrix<double, 7, 7> v = Eigen::Matrix<double, 7, 7>::Identity();
  v.colwise() -= v.rowwise().mean();
  // Orthonormal basis of the hyperplane sum x = 0: the first 6 columns of Q of its vectors.
  const Eigen::HouseholderQR<Eigen::Matrix<double, 7, 7>> qr(v);
  const Eigen::Matrix<double, 7, 6> basis = Eigen::Matrix<double, 7, 7>(qr.householderQ()).leftCols<6>();
  Wrenches w = basis.transpose() * v;
  for (Eigen::Index i = 0; i < w.cols(); ++i) w.col(i) *= r / w.col(i).norm();
  return w;
}

// A random grasp: n contacts on an ellipsoid about the centre of mass (semi-axes up to the torque
// scale 1), normals the surface's tilted at random, so that some grasps are in closure and some
// are not.
Contacts random_grasp(std::mt19937& rng, int n) {
  std::normal_distribution<double> gauss;
  std::uniform_real_distribution<double> uniform(0.3, 1.0);
  const Eigen::Vector3d axes(uniform(rng), uniform(rng), uniform(rng));
  const double tilt = std::uniform_real_distribution<double>(0.0, 0.8)(rng);
  Contacts c;
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector3d d = Eigen::Vector3d(gauss(rng), gauss(rng), gauss(rng)).normalized();
    const Eigen::Vector3d p = axes.cwiseProduct(d);
    const Eigen::Vector3d normal = d.cwiseQuotient(axes).normalized();
    const Eigen::Vector3d noise(gauss(rng), gauss(rng), gauss(rng));
    c.push_back({p, (normal + tilt * noise).normalized()});
  }
  return c;
}

struct Comparison {
  int grasps = 0, closure = 0, verdicts_differ = 0, beyond_tolerance = 0, full_hull = 0;
  double worst_relative = 0;
};

// Compares wrench_epsilon with Qhull on `count` random grasps of min_contacts..max_contacts.
Comparison compare_with_qhull(int count, int min_contacts, int max_contacts, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_int_distribution<int> contacts(min_contacts, max_contacts);
  std::uniform_real_distribution<double> mu(0.2, 1.0);
  Comparison out;
  for (int g = 0; g < count; ++g) {
    const Wrenches w = contact_wrenches(random_grasp(rng, contacts(rng)), mu(rng), 1.0, g % 2 ? 4 : 8);
    const GraspQuality reference = qhull_wrench_quality(w);
    const EpsilonResult e = wrench_epsilon(w);
    ++out.grasps;
    out.closure += reference.force_closure;
    out.full_hull += e.full_hull;
    out.verdicts_differ += e.force_closure != reference.force_closure;
    const double error = std::abs(e.epsilon - reference.epsilon);
    out.beyond_tolerance += error > tolerance(reference.epsilon);
    out.worst_relative = std::max(out.worst_relative, error / std::max(1.0, reference.epsilon));
  }
  return out;
}

TEST(WrenchEpsilon, AgreesWithQhullOnRandomGrasps) {
  const bool long_mode = std::getenv("TELEGRASP_EPSILON_LONG") != nullptr;
  const Comparison c = long_mode ? compare_with_qhull(10000, 3, 20, 2) : compare_with_qhull(1000, 3, 12, 1);
  std::printf(
      "wrench_epsilon vs Qhull: %d grasps (%d in closure), %d verdicts differ, %d beyond 1e-9, worst "
      "|delta epsilon| / max(1, epsilon) %.3g, %d fell back to the full hull\n",
      c.grasps, c.closure, c.verdicts_differ, c.beyond_tolerance, c.worst_relative, c.full_hull);
  EXPECT_EQ(c.verdicts_differ, 0);
  EXPECT_EQ(c.beyond_tolerance, 0);
  EXPECT_EQ(c.full_hull, 0);
  // The sample is worth something only if it has both verdicts in number.
  EXPECT_GT(c.closure, c.grasps / 10);
  EXPECT_LT(c.closure, c.grasps * 9 / 10);
}

TEST(WrenchEpsilon, CrossPolytopeHasInradiusOneOverRootSix) {
  EXPECT_NEAR(wrench_epsilon(cross_polytope()).epsilon, 1 / std::sqrt(6.0), 1e-12);
}

TEST(WrenchEpsilon, HypercubeHasInradiusOne) {
  const EpsilonResult e = wrench_epsilon(hypercube());
  EXPECT_NEAR(e.epsilon, 1.0, 1e-12);
  EXPECT_TRUE(e.force_closure);
}

TEST(WrenchEpsilon, RegularSimplexHasInradiusASixthOfItsCircumradius) {
  for (double r : {0.5, 1.0, 3.0}) EXPECT_NEAR(wrench_epsilon(regular_simplex(r)).epsilon, r / 6, 1e-12 * r) << r;
}

TEST(WrenchEpsilon, OriginOnAFacetGivesZero) {
  Wrenches w = hypercube();
  w.row(0).array() += 1.0;  // the facet x0 = -1 moves to x0 = 0, through the origin
  const EpsilonResult e = wrench_epsilon(w);
  EXPECT_EQ(e.epsilon, 0.0);
  EXPECT_FALSE(e.force_closure);
  // Beyond it: the origin outside, and the result separates: every wrench at x0 >= 0.5.
  w.row(0).array() += 0.5;
  const EpsilonResult outside = wrench_epsilon(w);
  EXPECT_EQ(outside.epsilon, 0.0);
  EXPECT_FALSE(outside.force_closure);
  EXPECT_LE((outside.direction.transpose() * w).maxCoeff(), 1e-12);
}

TEST(WrenchEpsilon, ShiftedPolytopesHaveTheShiftedValue) {
  Vec6 delta;
  delta << 0.1, -0.3, 0.2, 0.0, 0.05, -0.1;
  // Hypercube: the facets x_k = +-1 move by delta_k, the nearest is 1 - max |delta_k|.
  EXPECT_NEAR(wrench_epsilon(hypercube().colwise() + delta).epsilon, 0.7, 1e-12);
  // Cross-polytope: the facets s . x = 1 (s in {+-1}^6) lie (1 + s . delta) / sqrt(6) from the
  // origin; the nearest has s = -sign(delta): (1 - sum |delta_k|) / sqrt(6).
  EXPECT_NEAR(wrench_epsilon(cross_polytope().colwise() + delta).epsilon, (1 - delta.lpNorm<1>()) / std::sqrt(6.0),
              1e-12);
  // Regular simplex of circumradius 1 (vertices v_j, v_i . v_j = -1/6): the facet opposite v_j
  // has the normal -v_j and lies 1/6 from the centre. Shifted by t v_0, the facet opposite v_0
  // comes nearer by t, the others move away by t / 6: epsilon = 1/6 - t.
  const Wrenches s = regular_simplex(1.0);
  const double t = 0.1;
  EXPECT_NEAR(wrench_epsilon(s.colwise() + t * Vec6(s.col(0))).epsilon, 1.0 / 6 - t, 1e-12);
}

TEST(WrenchEpsilon, RotatingTheWrenchesChangesNothing) {
  std::mt19937 rng(5);
  for (int g = 0; g < 50; ++g) {
    const Wrenches w = contact_wrenches(random_grasp(rng, 4 + g % 6), 0.6, 1.0);
    const Eigen::Matrix3d r = Eigen::Quaterniond::UnitRandom().toRotationMatrix();
    Eigen::Matrix<double, 6, 6> rr = Eigen::Matrix<double, 6, 6>::Zero();
    rr.topLeftCorner<3, 3>() = r;
    rr.bottomRightCorner<3, 3>() = r;
    const EpsilonResult a = wrench_epsilon(w), b = wrench_epsilon(rr * w);
    EXPECT_EQ(a.force_closure, b.force_closure) << g;
    EXPECT_NEAR(a.epsilon, b.epsilon, tolerance(a.epsilon)) << g;
  }
}

TEST(WrenchEpsilon, PermutingAndDuplicatingContactsChangeNothing) {
  std::mt19937 rng(6);
  for (int g = 0; g < 50; ++g) {
    Contacts c = random_grasp(rng, 4 + g % 6);
    const EpsilonResult a = wrench_epsilon(contact_wrenches(c, 0.5, 1.0));
    std::shuffle(c.begin(), c.end(), rng);
    const EpsilonResult permuted = wrench_epsilon(contact_wrenches(c, 0.5, 1.0));
    c.push_back(c[g % c.size()]);
    c.push_back(c.front());
    const EpsilonResult duplicated = wrench_epsilon(contact_wrenches(c, 0.5, 1.0));
    EXPECT_EQ(a.force_closure, permuted.force_closure) << g;
    EXPECT_EQ(a.force_closure, duplicated.force_closure) << g;
    EXPECT_NEAR(a.epsilon, permuted.epsilon, tolerance(a.epsilon)) << g;
    EXPECT_NEAR(a.epsilon, duplicated.epsilon, tolerance(a.epsilon)) << g;
  }
}

TEST(WrenchEpsilon, AddingAContactNeverLowersEpsilon) {
  std::mt19937 rng(7);
  int rose = 0;
  for (int g = 0; g < 100; ++g) {
    Contacts c = random_grasp(rng, 3 + g % 8);
    const double before = wrench_epsilon(contact_wrenches(c, 0.5, 1.0)).epsilon;
    c.push_back(random_grasp(rng, 1).front());
    const double after = wrench_epsilon(contact_wrenches(c, 0.5, 1.0)).epsilon;
    EXPECT_GE(after, before - 1e-11) << g;
    rose += after > before + 1e-9;
  }
  EXPECT_GT(rose, 10);  // the extra contacts do change things
}

TEST(WrenchEpsilon, DegenerateInputsGiveZero) {
  std::mt19937 rng(8);
  for (int n = 0; n <= 2; ++n) {
    const EpsilonResult e = wrench_epsilon(contact_wrenches(random_grasp(rng, n), 0.5, 1.0));
    EXPECT_EQ(e.epsilon, 0.0) << n;
    EXPECT_FALSE(e.force_closure) << n;
  }
  // Rank 5: every wrench has no torque about z.
  Wrenches flat = hypercube();
  flat.row(5).setZero();
  EXPECT_EQ(wrench_epsilon(flat).epsilon, 0.0);
  // Affinely flat: all on the hyperplane x5 = 1 (linear rank 6, affine rank 5).
  flat.row(5).setOnes();
  EXPECT_EQ(wrench_epsilon(flat).epsilon, 0.0);
  // Fewer than 7 points, non-finite values.
  EXPECT_EQ(wrench_epsilon(cross_polytope().leftCols(6)).epsilon, 0.0);
  Wrenches bad = hypercube();
  bad(2, 7) = std::nan("");
  EXPECT_EQ(wrench_epsilon(bad).epsilon, 0.0);
  bad(2, 7) = INFINITY;
  EXPECT_EQ(wrench_epsilon(bad).epsilon, 0.0);
  EXPECT_EQ(wrench_epsilon(Wrenches(6, 0)).epsilon, 0.0);
}

TEST(WrenchEpsilon, CertificateHoldsOnRandomGrasps) {
  std::mt19937 rng(9);
  int closure = 0, open = 0;
  for (int g = 0; g < 200; ++g) {
    const Wrenches w = contact_wrenches(random_grasp(rng, 3 + g % 10), 0.7, 1.0);
    const EpsilonResult e = wrench_epsilon(w);
    if (e.direction.isZero()) continue;  // flat: no certificate to give
    EXPECT_NEAR(e.direction.norm(), 1.0, 1e-12);
    const double tol = 1e-11 * w.colwise().norm().maxCoeff();
    const double reach = (e.direction.transpose() * w).maxCoeff();
    if (e.force_closure) {
      ++closure;
      // Every wrench within epsilon + tol along the nearest facet's normal: epsilon is at most that.
      EXPECT_LE(reach, e.epsilon + tol) << g;
      EXPECT_GE(reach, e.epsilon - tol) << g;
    } else {
      ++open;
      // A separating direction: no wrench beyond the origin's hyperplane (plus tol).
      EXPECT_LE(reach, tol) << g;
    }
    // Far fewer facets than the full hull's.
    EXPECT_LT(e.facets, 5000) << g;
  }
  EXPECT_GT(closure, 20);
  EXPECT_GT(open, 20);
}

TEST(WrenchEpsilon, GraspQualityUsesItAndSkipsTheVolumeUnlessAsked) {
  std::mt19937 rng(10);
  const Contacts c = random_grasp(rng, 6);
  const GraspQuality fast = grasp_quality(c, 0.5, 1.0);
  const GraspQuality full = grasp_quality(c, 0.5, 1.0, 8, QualityVolume::kCompute);
  const GraspQuality reference = qhull_wrench_quality(contact_wrenches(c, 0.5, 1.0));
  EXPECT_EQ(fast.volume, kVolumeNotComputed);
  EXPECT_EQ(fast.epsilon, full.epsilon);
  EXPECT_EQ(full.volume, reference.volume);
  EXPECT_GT(full.volume, 0.0);
  EXPECT_NEAR(fast.epsilon, reference.epsilon, tolerance(reference.epsilon));
}

}  // namespace
}  // namespace telegrasp::sim
