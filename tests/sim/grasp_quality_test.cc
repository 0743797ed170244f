// Ferrari-Canny epsilon and wrench-space volume (sim/grasp_quality.h) against values derived by
// hand, an independent brute-force facet enumeration, and degenerate inputs.
#include "telegrasp/sim/grasp_quality.h"

#include <Eigen/Geometry>
#include <Eigen/SVD>
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <numbers>
#include <random>
#include <vector>

namespace telegrasp::sim {
namespace {

using Contacts = std::vector<QualityContact>;
constexpr double kPi = std::numbers::pi;

void expect_zero(const GraspQuality& q) {
  EXPECT_EQ(q.epsilon, 0.0);
  EXPECT_EQ(q.volume, 0.0);
  EXPECT_FALSE(q.force_closure);
}

// Runs grasp_quality (with the volume) and checks that it printed nothing.
GraspQuality quiet_quality(const Contacts& c, double mu, double torque_scale) {
  testing::internal::CaptureStderr();
  testing::internal::CaptureStdout();
  const GraspQuality q = grasp_quality(c, mu, torque_scale, 8, QualityVolume::kCompute);
  EXPECT_EQ(testing::internal::GetCapturedStdout(), "");
  EXPECT_EQ(testing::internal::GetCapturedStderr(), "");
  return q;
}

// Two contacts per face of the cube [-1, 1]^3, offset by +-d along one tangent axis, so that
// their normal forces (frictionless) give torques +-d about a third axis:
//   faces +-x offset along y: wrenches (+-e_x force, +-d e_z torque), every sign combination;
//   faces +-y offset along z: (+-e_y, +-d e_x); faces +-z offset along x: (+-e_z, +-d e_y).
Contacts twelve_on_cube(double d) {
  Contacts c;
  for (double s : {1.0, -1.0})
    for (double o : {d, -d}) {
      c.push_back({{s, o, 0}, {s, 0, 0}});
      c.push_back({{0, s, o}, {0, s, 0}});
      c.push_back({{o, 0, s}, {0, 0, s}});
    }
  return c;
}

// Three contacts 120 degrees apart on the equator of the unit sphere, normals radial.
Contacts three_on_equator() {
  Contacts c;
  for (int k = 0; k < 3; ++k) {
    const Eigen::Vector3d p(std::cos(2 * kPi * k / 3), std::sin(2 * kPi * k / 3), 0);
    c.push_back({p, p});
  }
  return c;
}

// Independent of grasp_quality: the wrenches of `c` with cone edges in the tangent basis
// (t1(n), t2(n)) given, then epsilon as the smallest distance from the origin to a hyperplane
// through 6 affinely independent wrenches that has every wrench on its origin's side (each facet
// of the hull lies in such a hyperplane, and every such hyperplane supports the hull).
double brute_force_epsilon(const Contacts& c, double mu, double torque_scale,
                           const std::vector<std::pair<Eigen::Vector3d, Eigen::Vector3d>>& bases) {
  using W = Eigen::Matrix<double, 6, 1>;
  std::vector<W> w;
  for (std::size_t i = 0; i < c.size(); ++i)
    for (int j = 0; j < 8; ++j) {
      const double a = 2 * kPi * j / 8;
      const Eigen::Vector3d f = -c[i].n + mu * (std::cos(a) * bases[i].first + std::sin(a) * bases[i].second);
      W x;
      x << f, c[i].p.cross(f) / torque_scale;
      w.push_back(x);
    }
  const int n = static_cast<int>(w.size());
  double best = std::numeric_limits<double>::infinity();
  int i[6];
  for (i[0] = 0; i[0] < n; ++i[0])
    for (i[1] = i[0] + 1; i[1] < n; ++i[1])
      for (i[2] = i[1] + 1; i[2] < n; ++i[2])
        for (i[3] = i[2] + 1; i[3] < n; ++i[3])
          for (i[4] = i[3] + 1; i[4] < n; ++i[4])
            for (i[5] = i[4] + 1; i[5] < n; ++i[5]) {
              Eigen::MatrixXd d(5, 6);
              for (int r = 0; r < 5; ++r) d.row(r) = (w[i[r + 1]] - w[i[0]]).transpose();
              const Eigen::JacobiSVD<Eigen::MatrixXd> svd(d, Eigen::ComputeFullV);
              if (svd.singularValues()[4] < 1e-9) continue;
              W normal = svd.matrixV().col(5);
              double offset = normal.dot(w[i[0]]);
              if (offset < 0) {
                normal = -normal;
                offset = -offset;
              }
              bool supporting = true;
              for (const W& x : w)
                if (normal.dot(x) > offset + 1e-9) {
                  supporting = false;
                  break;
                }
              if (supporting) best = std::min(best, offset);
            }
  return best;
}

TEST(GraspQuality, TwoFrictionlessAntipodalContactsHaveNoClosure) {
  // Wrenches (-e_x, 0) and (e_x, 0): a segment through the origin, no 6-D interior.
  const Contacts c{{{0.05, 0, 0}, {1, 0, 0}}, {{-0.05, 0, 0}, {-1, 0, 0}}};
  expect_zero(quiet_quality(c, 0.0, 0.05));
}

TEST(GraspQuality, TwoAntipodalContactsWithFrictionCannotResistTwistAboutTheirAxis) {
  // Both contacts lie on the x axis, so every force f they apply gives a torque p x f with no x
  // component: all 16 wrenches lie in the hyperplane torque_x = 0 (the wrench space is 5-D), a
  // twist about the axis joining them is unresisted, and epsilon and the 6-D volume are 0.
  const Contacts c{{{0.05, 0, 0}, {1, 0, 0}}, {{-0.05, 0, 0}, {-1, 0, 0}}};
  expect_zero(quiet_quality(c, 0.5, 0.05));
  expect_zero(quiet_quality(c, 2.0, 0.05));
}

TEST(GraspQuality, ThreeContactsOnTheEquator) {
  // Frictionless: three normal forces in the equator's plane and no torque (normals through the
  // centre): a 2-D wrench set.
  expect_zero(quiet_quality(three_on_equator(), 0.0, 1.0));
  // With friction the tangential forces give torques about every axis: force closure. The normals
  // are in the x-y plane, so any tangent basis made of the equator's tangent and e_z (up to
  // order and sign) gives the same 8 cone edges; the brute force uses that one.
  std::vector<std::pair<Eigen::Vector3d, Eigen::Vector3d>> bases;
  for (const QualityContact& k : three_on_equator())
    bases.push_back({Eigen::Vector3d(-k.n.y(), k.n.x(), 0), Eigen::Vector3d::UnitZ()});
  for (double mu : {0.5, 1.0}) {
    const GraspQuality q = quiet_quality(three_on_equator(), mu, 1.0);
    EXPECT_TRUE(q.force_closure);
    EXPECT_GT(q.volume, 0.0);
    EXPECT_NEAR(q.epsilon, brute_force_epsilon(three_on_equator(), mu, 1.0, bases), 1e-9) << "mu " << mu;
    // Upper bound by hand: against the twist u = (force 0, torque e_z) every edge's wrench gives
    // u . w = p x f . e_z = the edge's tangential force along the equator, at most mu.
    EXPECT_LE(q.epsilon, mu + 1e-12);
  }
}

// One contact at each face centre of the unit cube, its normal pointing in.
Contacts cube_face_centre_contacts() {
  Contacts c;
  for (double s : {1.0, -1.0})
    for (int axis = 0; axis < 3; ++axis) {
      Eigen::Vector3d n = Eigen::Vector3d::Zero();
      n[axis] = s;
      c.push_back({0.5 * n, n});
    }
  return c;
}

TEST(GraspQuality, SixFrictionlessContactsAtCubeFaceCentresResistNoTorque) {
  // A normal force at a face centre points through the centre: no contact gives any torque.
  const Contacts c = cube_face_centre_contacts();
  expect_zero(quiet_quality(c, 0.0, std::sqrt(3.0) / 2));
}

TEST(GraspQuality, SixContactsWithFrictionAtCubeFaceCentres) {
  // Unit cube (face centres at 0.5 from the centre, torque scale = its corner radius sqrt(3)/2).
  // A contact at face centre p = s n gives w = (-n + mu t, k mu n x t), k = s / torque_scale, t
  // one of 8 unit tangents 45 degrees apart, here axis-aligned (normals are axes). Against the
  // pure twist u = (0, b), u . w = k mu t . (b x n). For b = (1, 1, 1)/sqrt(3), b x n has length
  // sqrt(2/3) on every face and points along a diagonal cone edge, so the hull has a supporting
  // hyperplane at distance k mu sqrt(2/3) = mu sqrt(2) / 3; over pure twists no b does better
  // (max over faces of the octagon norm of b x n is smallest at the diagonal). Qhull's nearest
  // facet is that one.
  const Contacts c = cube_face_centre_contacts();
  const double mu = 0.5;
  const GraspQuality q = quiet_quality(c, mu, std::sqrt(3.0) / 2);
  EXPECT_NEAR(q.epsilon, mu * std::sqrt(2.0) / 3, 1e-9);
  EXPECT_TRUE(q.force_closure);
  EXPECT_GT(q.volume, 0.0);
}

TEST(GraspQuality, TwelveFrictionlessContactsOnACubeHaveClosedFormEpsilonAndVolume) {
  // The wrench set is the union of three squares [-1, 1] x [-delta, delta] (delta = d / torque
  // scale) in the orthogonal planes (f_x, tau_z), (f_y, tau_x), (f_z, tau_y); its hull is their
  // free sum. A facet takes one edge of each square: with distances h1, h2, h3 of those edges from
  // the origin its distance is 1 / sqrt(1/h1^2 + 1/h2^2 + 1/h3^2), smallest with every h =
  // min(1, delta): epsilon = min(1, delta) / sqrt(3). Volume of a free sum of polytopes of
  // dimensions p, q: p! q! / (p+q)! vol vol, so 2! 2! 2! / 6! (4 delta)^3 = 32 delta^3 / 45.
  const Contacts c = twelve_on_cube(0.5);
  GraspQuality q = quiet_quality(c, 0.0, 1.0);  // delta = 0.5
  EXPECT_NEAR(q.epsilon, 0.5 / std::sqrt(3.0), 1e-9);
  EXPECT_NEAR(q.volume, 32 * 0.125 / 45, 1e-9);
  EXPECT_TRUE(q.force_closure);
}

TEST(GraspQuality, TorqueScaleDividesTorques) {
  // Same grasp, torque scale 0.25: delta = 0.5 / 0.25 = 2, so the force edges (distance 1) are
  // now the nearest: epsilon = 1 / sqrt(3); the volume grows with delta^3.
  const Contacts c = twelve_on_cube(0.5);
  GraspQuality q = quiet_quality(c, 0.0, 0.25);
  EXPECT_NEAR(q.epsilon, 1 / std::sqrt(3.0), 1e-9);
  EXPECT_NEAR(q.volume, 32 * 8.0 / 45, 1e-9);
  // Scaling the object and its torque scale together changes nothing.
  Contacts big = c;
  for (QualityContact& k : big) k.p *= 3.0;
  q = quiet_quality(big, 0.0, 3.0);
  EXPECT_NEAR(q.epsilon, 0.5 / std::sqrt(3.0), 1e-9);
  EXPECT_NEAR(q.volume, 32 * 0.125 / 45, 1e-9);
}

TEST(GraspQuality, RotatingTheGraspChangesNothing) {
  std::mt19937 rng(7);
  std::normal_distribution<double> gauss;
  const GraspQuality frictionless = grasp_quality(twelve_on_cube(0.5), 0.0, 1.0);
  const Contacts cube_friction = [] {
    Contacts c = twelve_on_cube(0.3);
    c.resize(9);  // not symmetric any more, still in closure with friction
    return c;
  }();
  const double mu = 0.5;
  const GraspQuality with_friction = grasp_quality(cube_friction, mu, 1.0);
  ASSERT_TRUE(with_friction.force_closure);
  // The linearised cones of a rotated grasp are the original octagons turned about their normals;
  // each lies between the octagon of friction mu cos(pi/8) and that of mu / cos(pi/8), so epsilon
  // does too.
  const double lo = grasp_quality(cube_friction, mu * std::cos(kPi / 8), 1.0).epsilon;
  const double hi = grasp_quality(cube_friction, mu / std::cos(kPi / 8), 1.0).epsilon;
  for (int trial = 0; trial < 10; ++trial) {
    const Eigen::Quaterniond r = Eigen::Quaterniond(gauss(rng), gauss(rng), gauss(rng), gauss(rng)).normalized();
    auto rotated = [&](Contacts c) {
      for (QualityContact& k : c) {
        k.p = r * k.p;
        k.n = r * k.n;
      }
      return c;
    };
    const GraspQuality q = grasp_quality(rotated(twelve_on_cube(0.5)), 0.0, 1.0);
    EXPECT_NEAR(q.epsilon, frictionless.epsilon, 1e-9);
    EXPECT_NEAR(q.volume, frictionless.volume, 1e-9);
    const GraspQuality f = grasp_quality(rotated(cube_friction), mu, 1.0);
    EXPECT_GE(f.epsilon, lo - 1e-12);
    EXPECT_LE(f.epsilon, hi + 1e-12);
  }
  // A quarter turn maps the axis-aligned cone edges onto themselves: exactly the same.
  const Eigen::AngleAxisd quarter(kPi / 2, Eigen::Vector3d::UnitZ());
  Contacts turned = cube_friction;
  for (QualityContact& k : turned) {
    k.p = quarter * k.p;
    k.n = quarter * k.n;
  }
  const GraspQuality t = grasp_quality(turned, mu, 1.0);
  EXPECT_NEAR(t.epsilon, with_friction.epsilon, 1e-9);
  EXPECT_NEAR(t.volume, with_friction.volume, 1e-9);
}

TEST(GraspQuality, DegenerateInputsGiveZeroQuietly) {
  expect_zero(quiet_quality({}, 0.5, 0.1));
  expect_zero(quiet_quality({{{0.1, 0, 0}, {1, 0, 0}}}, 0.5, 0.1));
  expect_zero(quiet_quality({{{0.1, 0, 0}, {1, 0, 0}}, {{0, 0.1, 0}, {0, 1, 0}}}, 0.5, 0.1));
  // Coplanar: frictionless contacts on the rim of a disc with in-plane normals only push in the
  // plane and twist about its normal: a 3-D wrench set however many contacts.
  Contacts rim;
  for (int k = 0; k < 7; ++k) {
    const double a = 2 * kPi * k / 7 + 0.1 * k * k;
    rim.push_back({{std::cos(a), std::sin(a), 0}, Eigen::Vector3d(std::cos(a + 0.3), std::sin(a + 0.3), 0)});
  }
  expect_zero(quiet_quality(rim, 0.0, 1.0));
  // One contact repeated: 8 distinct wrenches on a 2-D ellipse.
  expect_zero(quiet_quality(Contacts(20, {{0.1, 0.02, 0}, {1, 0, 0}}), 0.5, 0.1));
  // Not a number, or a zero normal, or bad parameters.
  Contacts bad = twelve_on_cube(0.5);
  bad[3].p.x() = std::numeric_limits<double>::quiet_NaN();
  expect_zero(quiet_quality(bad, 0.0, 1.0));
  bad = twelve_on_cube(0.5);
  bad[5].n.setZero();
  expect_zero(quiet_quality(bad, 0.0, 1.0));
  expect_zero(quiet_quality(twelve_on_cube(0.5), -0.1, 1.0));
  expect_zero(quiet_quality(twelve_on_cube(0.5), 0.0, 0.0));
  expect_zero(quiet_quality(twelve_on_cube(0.5), std::numeric_limits<double>::infinity(), 1.0));
}

// n contacts on a sphere of radius r about the centre of mass, normals radial (seeded).
Contacts on_sphere(int n, double r, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> gauss;
  Contacts c;
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector3d d = Eigen::Vector3d(gauss(rng), gauss(rng), gauss(rng)).normalized();
    c.push_back({r * d, d});
  }
  return c;
}

// contact_wrenches: one column per cone edge (one per contact without friction), each a unit push
// along -n plus a friction force of size mu across n, its torque p x f over the torque scale;
// grasp_quality is the hull's quality of exactly these, bit for bit.
TEST(GraspQuality, IsTheQualityOfTheContactWrenches) {
  const Contacts c = on_sphere(6, 0.04, 5);
  for (double mu : {0.0, 0.5}) {
    const Wrenches w = contact_wrenches(c, mu, 0.04);
    const int edges = mu > 0 ? 8 : 1;
    ASSERT_EQ(w.cols(), 6 * edges);
    for (Eigen::Index col = 0; col < w.cols(); ++col) {
      const QualityContact& k = c[col / edges];
      const Eigen::Vector3d f = w.col(col).head<3>();
      EXPECT_NEAR(f.dot(k.n), -1.0, 1e-12);
      EXPECT_NEAR((f + k.n).norm(), mu, 1e-12);
      EXPECT_NEAR((w.col(col).tail<3>() - k.p.cross(f) / 0.04).norm(), 0.0, 1e-12);
    }
    const GraspQuality direct = grasp_quality(c, mu, 0.04, 8, QualityVolume::kCompute),
                       hull = wrench_quality(w, QualityVolume::kCompute);
    EXPECT_EQ(direct.epsilon, hull.epsilon);
    EXPECT_EQ(direct.volume, hull.volume);
    EXPECT_EQ(direct.force_closure, hull.force_closure);
  }
  EXPECT_GT(wrench_quality(contact_wrenches(c, 0.5, 0.04), QualityVolume::kCompute).volume, 0.0);
  // Degenerate inputs have no wrenches, and no wrenches no quality.
  EXPECT_EQ(contact_wrenches({}, 0.5, 0.1).cols(), 0);
  Contacts bad = c;
  bad[2].n.setZero();
  EXPECT_EQ(contact_wrenches(bad, 0.5, 0.1).cols(), 0);
  EXPECT_EQ(contact_wrenches(c, -0.5, 0.1).cols(), 0);
  EXPECT_EQ(contact_wrenches(c, 0.5, 0.0).cols(), 0);
  expect_zero(wrench_quality(Wrenches(6, 0), QualityVolume::kCompute));
}

// The bound under which HandController reuses a hull's quality (hand_controller.h,
// quality_hulls()): moving no wrench by more than d moves epsilon by at most d (plus the 1e-12
// closure threshold) and the volume by at most kappa6 ((R + d)^6 - R^6), R the largest wrench norm.
TEST(GraspQuality, MovingTheWrenchesByDMovesTheQualityWithinTheBound) {
  const double kappa6 = kPi * kPi * kPi / 6;  // volume of the unit 6-ball
  constexpr double kRounding = 1e-12;  // Qhull's, on wrenches of norm ~1
  std::mt19937 rng(7);
  std::normal_distribution<double> gauss;
  int closures = 0, moved_epsilons = 0;
  for (int trial = 0; trial < 12; ++trial) {
    const Wrenches w = contact_wrenches(on_sphere(5 + trial % 4, 0.04, 100 + trial), 0.5, 0.04);
    const GraspQuality q = wrench_quality(w, QualityVolume::kCompute);
    closures += q.force_closure;
    for (double d : {1e-11, 1e-6, 1e-3}) {
      Wrenches moved = w;
      for (Eigen::Index j = 0; j < moved.cols(); ++j) {
        Eigen::Matrix<double, 6, 1> dir;
        for (int r = 0; r < 6; ++r) dir[r] = gauss(rng);
        moved.col(j) += d * dir.normalized();
      }
      const GraspQuality m = wrench_quality(moved, QualityVolume::kCompute);
      const double R = std::max(w.colwise().norm().maxCoeff(), moved.colwise().norm().maxCoeff());
      EXPECT_LE(std::abs(m.epsilon - q.epsilon), d + 1e-12 + kRounding) << trial << " " << d;
      EXPECT_LE(std::abs(m.volume - q.volume), kappa6 * (std::pow(R + d, 6) - std::pow(R, 6)) + kRounding)
          << trial << " " << d;
      moved_epsilons += d == 1e-3 && m.epsilon != q.epsilon;
    }
  }
  EXPECT_GE(closures, 6);  // the bound is exercised on grasps with closure
  EXPECT_GE(moved_epsilons, 6);  // and the moves do move epsilon
}

TEST(GraspQuality, DuplicateContactsChangeNothing) {
  // Each contact three times over: the same hull, so the same epsilon and volume.
  Contacts c;
  for (const QualityContact& k : twelve_on_cube(0.5)) c.insert(c.end(), 3, k);
  const GraspQuality q = quiet_quality(c, 0.0, 1.0);
  EXPECT_NEAR(q.epsilon, 0.5 / std::sqrt(3.0), 1e-9);
  EXPECT_NEAR(q.volume, 32 * 0.125 / 45, 1e-9);
}

}  // namespace
}  // namespace telegrasp::sim
