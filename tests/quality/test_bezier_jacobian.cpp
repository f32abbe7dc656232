// Bernstein expansion of det J and its certified validity, checked against
// det J evaluated directly from the Lagrange shape functions.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <map>
#include <random>
#include <vector>

#include "curvemesh/mesh/high_order.hpp"
#include "curvemesh/mesh/tet_mesh.hpp"
#include "curvemesh/quality/bernstein.hpp"
#include "curvemesh/quality/bezier_jacobian.hpp"

namespace cm::quality {
namespace {

const std::array<Vec3, 4> kUnit{Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(0, 0, 1)};

// Order-p nodes of the straight tet v (internal order).
std::vector<Vec3> linear_nodes(int p, const std::array<Vec3, 4>& v) {
  std::vector<Vec3> nodes;
  for (const auto& a : mesh::tet_node_indices(p)) {
    Vec3 x = Vec3::Zero();
    for (int k = 0; k < 4; ++k) x += (static_cast<double>(a[k]) / p) * v[k];
    nodes.push_back(x);
  }
  return nodes;
}

// The nodes on the interior of edge (0,1) moved by `shift`.
std::vector<Vec3> bend_edge01(int p, const std::array<Vec3, 4>& v, const Vec3& shift) {
  auto nodes = linear_nodes(p, v);
  const auto idx = mesh::tet_node_indices(p);
  for (std::size_t n = 0; n < nodes.size(); ++n)
    if (idx[n][0] > 0 && idx[n][1] > 0 && idx[n][2] == 0 && idx[n][3] == 0) nodes[n] += shift;
  return nodes;
}

Mat3 random_rotation(std::mt19937& rng) {
  std::normal_distribution<double> n01;
  Eigen::Quaterniond q(n01(rng), n01(rng), n01(rng), n01(rng));
  q.normalize();
  return q.toRotationMatrix();
}

// x -> scale R x + t applied to every node (det J scales by scale^3).
std::vector<Vec3> similar(const std::vector<Vec3>& nodes, const Mat3& r, double scale,
                          const Vec3& t) {
  std::vector<Vec3> out;
  for (const Vec3& x : nodes) out.push_back(scale * (r * x) + t);
  return out;
}

Bary random_bary(std::mt19937& rng) {
  std::exponential_distribution<double> e(1.0);
  Bary b{e(rng), e(rng), e(rng), e(rng)};
  const double s = b[0] + b[1] + b[2] + b[3];
  for (double& x : b) x /= s;
  return b;
}

// A well-shaped random tet of size ~1 (a jittered, rotated regular tet).
std::array<Vec3, 4> random_good_tet(std::mt19937& rng) {
  std::uniform_real_distribution<double> u(-0.12, 0.12);
  const std::array<Vec3, 4> reg{Vec3(1, 1, 1), Vec3(1, -1, -1), Vec3(-1, -1, 1), Vec3(-1, 1, -1)};
  const Mat3 r = random_rotation(rng);
  std::array<Vec3, 4> v;
  for (int k = 0; k < 4; ++k) v[k] = r * (0.5 * reg[k] + Vec3(u(rng), u(rng), u(rng)));
  return v;
}

struct Samples {
  double min = std::numeric_limits<double>::infinity();
  double max = -std::numeric_limits<double>::infinity();
  Bary argmin{};
};

// Shape function gradients at the points of the barycentric grid of step
// 1/steps, computed once per (order, steps): sampling is the slowest part of
// these tests, and plain loops over a table keep it fast in Debug builds too.
struct GridTable {
  std::vector<Bary> points;
  std::vector<double> grad;  // point-major, node, then d/dxi1..3
};

const GridTable& grid_table(int p, int steps) {
  static std::map<std::pair<int, int>, GridTable> cache;
  GridTable& t = cache[{p, steps}];
  if (!t.points.empty()) return t;
  const auto n = static_cast<std::size_t>(tet_node_count(p));
  std::vector<Vec3> g(n);
  const double h = 1.0 / steps;
  for (int i = 0; i <= steps; ++i)
    for (int j = 0; i + j <= steps; ++j)
      for (int k = 0; i + j + k <= steps; ++k) {
        const Bary b{(steps - i - j - k) * h, i * h, j * h, k * h};
        t.points.push_back(b);
        lagrange_gradients(p, b, g);
        for (const Vec3& v : g) t.grad.insert(t.grad.end(), {v[0], v[1], v[2]});
      }
  return t;
}

// det J on the barycentric grid of step 1/steps plus `extra` random points,
// straight from the Lagrange shape functions.
Samples sample_detj(int p, const std::vector<Vec3>& nodes, int steps, int extra,
                    std::mt19937& rng) {
  Samples s;
  const auto note = [&](double d, const Bary& b) {
    if (d < s.min) {
      s.min = d;
      s.argmin = b;
    }
    s.max = std::max(s.max, d);
  };
  const GridTable& t = grid_table(p, steps);
  const std::size_t n = nodes.size();
  std::vector<double> rel(3 * n);
  for (std::size_t k = 0; k < n; ++k)
    for (int c = 0; c < 3; ++c) rel[3 * k + c] = nodes[k][c] - nodes[0][c];
  for (std::size_t i = 0; i < t.points.size(); ++i) {
    double j[3][3] = {};
    const double* g = t.grad.data() + 3 * n * i;
    for (std::size_t k = 1; k < n; ++k)
      for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c) j[r][c] += rel[3 * k + r] * g[3 * k + c];
    const double det = j[0][0] * (j[1][1] * j[2][2] - j[1][2] * j[2][1]) -
                       j[0][1] * (j[1][0] * j[2][2] - j[1][2] * j[2][0]) +
                       j[0][2] * (j[1][0] * j[2][1] - j[1][1] * j[2][0]);
    note(det, t.points[i]);
  }
  for (int e = 0; e < extra; ++e) {
    const Bary b = random_bary(rng);
    note(lagrange_jacobian_det(p, nodes, b), b);
  }
  return s;
}

TEST(Bernstein, RanksAndPartitionOfUnity) {
  for (int q = 0; q <= kMaxJacobianDegree; ++q) {
    const auto idx = bernstein_indices(q);
    ASSERT_EQ(static_cast<int>(idx.size()), simplex_count(q));
    for (std::size_t r = 0; r < idx.size(); ++r) {
      EXPECT_EQ(bernstein_rank(idx[r]), static_cast<int>(r));
      EXPECT_EQ(idx[r][0] + idx[r][1] + idx[r][2] + idx[r][3], q);
    }
    const std::vector<double> ones(idx.size(), 1.0);
    std::mt19937 rng(static_cast<unsigned>(q));
    for (int t = 0; t < 5; ++t)
      EXPECT_NEAR(evaluate_bernstein(q, ones, random_bary(rng)), 1.0, 1e-14);
  }
  EXPECT_EQ(multinomial({1, 1, 1, 0}), 6);
  EXPECT_EQ(multinomial({2, 0, 1, 0}), 3);
}

TEST(Bernstein, LagrangeShapeFunctions) {
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> u(-1, 1);
  for (int p = 1; p <= kMaxBezierOrder; ++p) {
    std::vector<Vec3> nodes;
    for (int n = 0; n < tet_node_count(p); ++n) nodes.emplace_back(u(rng), u(rng), u(rng));
    // Interpolation: x at the node's barycentric position is the node.
    const auto idx = mesh::tet_node_indices(p);
    for (std::size_t n = 0; n < idx.size(); ++n) {
      const Bary b{idx[n][0] / double(p), idx[n][1] / double(p), idx[n][2] / double(p),
                   idx[n][3] / double(p)};
      EXPECT_NEAR((lagrange_point(p, nodes, b) - nodes[n]).norm(), 0, 1e-13);
    }
    // The Jacobian matches central finite differences of the map.
    const Bary b = random_bary(rng);
    const Mat3 jac = lagrange_jacobian(p, nodes, b);
    const double h = 1e-6;
    for (int j = 1; j <= 3; ++j) {
      Bary plus = b, minus = b;
      plus[j] += h;
      plus[0] -= h;
      minus[j] -= h;
      minus[0] += h;
      const Vec3 fd = (lagrange_point(p, nodes, plus) - lagrange_point(p, nodes, minus)) / (2 * h);
      EXPECT_NEAR((jac.col(j - 1) - fd).norm(), 0, 1e-7) << "p " << p << " col " << j;
    }
  }
}

TEST(BezierJacobian, CoefficientsReproduceDetJ) {
  std::mt19937 rng(2);
  std::uniform_real_distribution<double> u(-0.3, 0.3);
  for (int p = 1; p <= kMaxBezierOrder; ++p)
    for (int trial = 0; trial < 5; ++trial) {
      auto nodes = linear_nodes(p, random_good_tet(rng));
      for (std::size_t n = 4; n < nodes.size(); ++n) nodes[n] += Vec3(u(rng), u(rng), u(rng));
      const auto coefs = jacobian_bezier_coefficients(p, nodes);
      ASSERT_EQ(static_cast<int>(coefs.size()), simplex_count(3 * (p - 1)));
      double scale = 0;
      for (double c : coefs) scale = std::max(scale, std::abs(c));
      for (int t = 0; t < 30; ++t) {
        const Bary b = random_bary(rng);
        EXPECT_NEAR(evaluate_bernstein(3 * (p - 1), coefs, b), lagrange_jacobian_det(p, nodes, b),
                    1e-12 * scale)
            << "p " << p;
      }
      // Corner coefficients are the values at the vertices.
      for (int k = 0; k < 4; ++k) {
        MultiIndex a{0, 0, 0, 0};
        a[k] = 3 * (p - 1);
        Bary b{0, 0, 0, 0};
        b[k] = 1;
        EXPECT_NEAR(coefs[bernstein_rank(a)], lagrange_jacobian_det(p, nodes, b), 1e-12 * scale);
      }
      // The geometry's control points reproduce the map.
      const auto control = geometry_control_points(p, nodes);
      for (int k = 0; k < 4; ++k) {
        MultiIndex vertex{0, 0, 0, 0};
        vertex[k] = p;
        EXPECT_NEAR((control[bernstein_rank(vertex)] - nodes[k]).norm(), 0, 1e-14);
      }
      const Bary b = random_bary(rng);
      for (int c = 0; c < 3; ++c) {
        std::vector<double> comp;
        for (const Vec3& x : control) comp.push_back(x[c]);
        EXPECT_NEAR(evaluate_bernstein(p, comp, b), lagrange_point(p, nodes, b)[c], 1e-13);
      }
    }
}

TEST(BezierJacobian, StraightTetsGiveConstantSixV) {
  std::mt19937 rng(3);
  // Dyadic coordinates: 6V = 8.
  const std::array<Vec3, 4> big{Vec3(0, 0, 0), Vec3(2, 0, 0), Vec3(0, 2, 0), Vec3(0, 0, 2)};
  for (int p = 1; p <= kMaxBezierOrder; ++p) {
    const auto nodes = linear_nodes(p, big);
    // Exact up to a few roundings (P4's Lagrange-to-Bezier rows have more terms).
    const double tol = p <= 3 ? 1e-14 : 1e-13;
    for (double c : jacobian_bezier_coefficients(p, nodes)) EXPECT_NEAR(c, 8.0, tol) << p;
    const ValidityReport rep = certify_jacobian(p, nodes);
    EXPECT_EQ(rep.verdict, Validity::kValid);
    EXPECT_NEAR(rep.min_lower, 8.0, tol);
    EXPECT_NEAR(rep.max_upper, 8.0, tol);
    EXPECT_NEAR(rep.scaled_jacobian_lower, 1.0, 1e-14);
    EXPECT_EQ(rep.splits, 0);
    if (p == 1) {
      EXPECT_EQ(rep.min_lower, 8.0);
    }

    // Rotated, scaled and far from the origin: still 6V everywhere.
    for (int t = 0; t < 5; ++t) {
      const auto v = random_good_tet(rng);
      const double six_v = (v[1] - v[0]).cross(v[2] - v[0]).dot(v[3] - v[0]);
      const Vec3 far(1e5, -3e4, 2e5);
      const auto moved = similar(linear_nodes(p, v), Mat3::Identity(), 1.0, far);
      const ValidityReport r = certify_jacobian(p, moved);
      EXPECT_EQ(r.verdict, Validity::kValid);
      EXPECT_NEAR(r.min_lower / six_v, 1.0, 1e-9);
      EXPECT_NEAR(r.max_upper / six_v, 1.0, 1e-9);
      EXPECT_LT(r.rounding_bound, 1e-6 * six_v);
      // Inverted (two vertices swapped): invalid at every order.
      std::array<Vec3, 4> w{v[1], v[0], v[2], v[3]};
      const ValidityReport inv = certify_jacobian(p, linear_nodes(p, w));
      EXPECT_EQ(inv.verdict, Validity::kInvalid);
      EXPECT_LT(inv.min_upper, 0);
    }
  }
}

// The core property test: certified verdicts and bounds against dense sampling.
void check_against_sampling(int p, double magnitude, int count, int steps, int& valid, int& invalid,
                            int& undetermined, std::mt19937& rng) {
  std::uniform_real_distribution<double> u(-1, 1);
  for (int e = 0; e < count; ++e) {
    auto nodes = linear_nodes(p, random_good_tet(rng));
    for (std::size_t n = 4; n < nodes.size(); ++n) {
      Vec3 d;
      do d = Vec3(u(rng), u(rng), u(rng));
      while (d.squaredNorm() > 1);
      nodes[n] += magnitude * d;
    }
    const ValidityReport rep = certify_jacobian(p, nodes);
    const Samples s = sample_detj(p, nodes, steps, 200, rng);
    const double scale = std::max(std::abs(s.min), std::abs(s.max));
    const double tol = 1e-12 * scale;
    const std::string what = ::testing::PrintToString(nodes.size()) + " nodes, magnitude " +
                             std::to_string(magnitude) + ", element " + std::to_string(e);
    if (s.min < 0) {
      EXPECT_EQ(rep.verdict, Validity::kInvalid) << what;
    }
    if (rep.verdict == Validity::kValid) {
      EXPECT_GT(s.min, 0) << what;
    }
    EXPECT_LE(rep.min_lower, s.min + tol) << what;
    EXPECT_GE(rep.max_upper, s.max - tol) << what;
    EXPECT_LE(rep.min_lower, rep.min_upper + tol) << what;
    EXPECT_LE(rep.max_lower, rep.max_upper + tol) << what;
    // min_upper is a true value of det J at `where`.
    EXPECT_NEAR(lagrange_jacobian_det(p, nodes, rep.where), rep.min_upper, tol) << what;
    if (rep.verdict == Validity::kInvalid) {
      EXPECT_LE(rep.min_upper, rep.rounding_bound) << what;
      ++invalid;
    } else if (rep.verdict == Validity::kValid) {
      EXPECT_GT(rep.min_lower, 0) << what;
      EXPECT_GT(rep.scaled_jacobian_lower, 0) << what;
      EXPECT_LE(rep.scaled_jacobian_lower, s.min / s.max + 1e-12) << what;
      ++valid;
      // Refining the bound: the gap closes as asked and the bound stays a bound.
      ValidityOptions tight;
      tight.bound_tolerance = 1e-3;
      const ValidityReport r2 = certify_jacobian(p, nodes, tight);
      EXPECT_EQ(r2.verdict, Validity::kValid) << what;
      double max_coef = 0;
      for (double c : jacobian_bezier_coefficients(p, nodes))
        max_coef = std::max(max_coef, std::abs(c));
      EXPECT_LE(r2.min_upper - r2.min_lower, 1.001e-3 * max_coef + tol) << what;
      EXPECT_LE(r2.min_lower, s.min + tol) << what;
      EXPECT_GE(r2.min_lower, rep.min_lower - tol) << what;
    } else {
      ++undetermined;
    }
  }
}

TEST(BezierJacobian, CertifiedVerdictsAgreeWithDenseSampling) {
  std::mt19937 rng(2024);
  for (int p : {2, 3}) {
    int valid = 0, invalid = 0, undetermined = 0;
    for (double magnitude : {0.03, 0.1, 0.2, 0.35})
      check_against_sampling(p, magnitude, 40, 40, valid, invalid, undetermined, rng);
    std::printf("P%d: %d valid, %d invalid, %d undetermined\n", p, valid, invalid, undetermined);
    // Both verdicts must be exercised, and the depth limit must almost never bind.
    EXPECT_GE(valid, 40);
    EXPECT_GE(invalid, 10);
    EXPECT_LE(undetermined, 1);
  }
}

// The near-straight bound never exceeds the ratio dense sampling sees (an
// upper estimate of the true min/max), is close to 1 for slightly bent
// tets, declines to answer for strongly bent ones, and is scale-free.
TEST(BezierJacobian, NearStraightRatioIsALowerBound) {
  std::mt19937 rng(77);
  std::uniform_real_distribution<double> u(-1, 1);
  for (int p : {2, 3, 4}) {
    const auto idx = mesh::tet_node_indices(p);
    int answered = 0, slight = 0;
    for (double magnitude : {0.002, 0.02, 0.06, 0.15, 0.4})
      for (int trial = 0; trial < 30; ++trial) {
        const auto v = random_good_tet(rng);
        auto nodes = linear_nodes(p, v);
        for (std::size_t n = 0; n < nodes.size(); ++n)
          if (*std::max_element(idx[n].begin(), idx[n].end()) < p)
            nodes[n] += magnitude * Vec3(u(rng), u(rng), u(rng));
        const NearStraightBounds bounds = near_straight_bounds(p, nodes);
        const double bound = bounds.ratio;
        if (bound < 0) continue;
        ++answered;
        const Samples smp = sample_detj(p, nodes, p == 4 ? 12 : 16, 200, rng);
        ASSERT_GT(smp.min, 0) << "p " << p << " magnitude " << magnitude;
        EXPECT_LE(bound, smp.min / smp.max) << "p " << p << " magnitude " << magnitude;
        // The mean of det J is the mean of its Bezier coefficients.
        const auto coefs = jacobian_bezier_coefficients(p, nodes);
        double mean = 0;
        for (double c : coefs) mean += c / static_cast<double>(coefs.size());
        EXPECT_LE(bounds.mean_ratio, smp.min / mean) << "p " << p << " magnitude " << magnitude;
        EXPECT_GE(bounds.mean_ratio, bound) << "p " << p;
        slight += magnitude <= 0.002 && bound > 0.8;
        // The same after a similarity far from the origin.
        const auto moved = similar(nodes, random_rotation(rng), 1e-3, Vec3(1e3, -2e3, 5e2));
        EXPECT_NEAR(near_straight_bounds(p, moved).ratio, bound, 1e-6) << "p " << p;
      }
    // Every node moved at random by 0.2% of the size: curving bends far more
    // smoothly, but even so orders 2 and 3 get a useful bound (order 4, which
    // curving does not use, is checked for the bound only).
    if (p <= 3) {
      EXPECT_EQ(slight, 30) << "p " << p;
    }
    EXPECT_GT(answered, 0) << "p " << p;
  }
  // Straight: the ratio is 1 up to the rounding margin; inverted: no answer.
  const auto straight = linear_nodes(3, kUnit);
  EXPECT_GT(near_straight_bounds(3, straight).ratio, 1 - 1e-9);
  const std::array<Vec3, 4> flipped{kUnit[1], kUnit[0], kUnit[2], kUnit[3]};
  EXPECT_EQ(near_straight_bounds(3, linear_nodes(3, flipped)).ratio, -1);
}

TEST(BezierJacobian, OrderFourAgainstSampling) {
  std::mt19937 rng(4);
  int valid = 0, invalid = 0, undetermined = 0;
  for (double magnitude : {0.05, 0.25})
    check_against_sampling(4, magnitude, 8, 20, valid, invalid, undetermined, rng);
  EXPECT_GT(valid, 0);
  EXPECT_EQ(undetermined, 0);
}

TEST(BezierJacobian, EdgeNodePushedThroughTheTet) {
  // Unit tet, the P2 node of edge (0,1) moved from (0.5,0,0) to (0.5,0.6,0.6),
  // beyond the face x+y+z = 1: det J = 1 - 4.8 l1, negative near vertex 1.
  std::mt19937 rng(5);
  for (int t = 0; t < 10; ++t) {
    const Mat3 r = t == 0 ? Mat3::Identity() : random_rotation(rng);
    const double scale =
        t == 0 ? 1.0 : std::exp(std::uniform_real_distribution<double>(-3, 3)(rng));
    const auto nodes = similar(bend_edge01(2, kUnit, Vec3(0, 0.6, 0.6)), r, scale, Vec3(3, 1, -2));
    const ValidityReport rep = certify_jacobian(2, nodes);
    EXPECT_EQ(rep.verdict, Validity::kInvalid);
    // Reported on the closure of edge 0 (vertex 0 or 1, or the edge itself).
    EXPECT_EQ(rep.where[2], 0);
    EXPECT_EQ(rep.where[3], 0);
    EXPECT_TRUE(rep.where_entity == (SubEntity{1, 0}) || rep.where_entity == (SubEntity{0, 1}) ||
                rep.where_entity == (SubEntity{0, 0}));
    EXPECT_LE(lagrange_jacobian_det(2, nodes, rep.where), 0);
    EXPECT_NEAR(rep.min_upper / (scale * scale * scale), -3.8, 1e-9);
  }
}

TEST(BezierJacobian, NegativeOnlyInsideAnEdge) {
  // P3, both nodes of edge (0,1) moved by (0,s,s): det J = 1 - 9 s l1 (6 l0 +
  // 3 l1 - 2), whose minimum 1 - 12 s is at l1 = 2/3 on the edge, while the
  // vertices have 1 and 1 - 9 s. With s = 0.1 every vertex is positive and the
  // edge interior is not: only subdivision can tell.
  const auto nodes = bend_edge01(3, kUnit, Vec3(0, 0.1, 0.1));
  const ValidityReport rep = certify_jacobian(3, nodes);
  EXPECT_EQ(rep.verdict, Validity::kInvalid);
  EXPECT_GT(rep.splits, 0);
  EXPECT_EQ(classify_bary(rep.where, 0.05), (SubEntity{1, 0}));
  EXPECT_NEAR(rep.where[1], 2.0 / 3.0, 0.1);
  EXPECT_LE(rep.min_upper, 0);
  EXPECT_GE(rep.min_upper, -0.2 - 1e-12);
  EXPECT_LE(rep.min_lower, -0.2 + 1e-12);
  EXPECT_LE(lagrange_jacobian_det(3, nodes, rep.where), 0);

  // s = 0.075: minimum 0.1 inside the edge, valid; the bounds bracket it.
  const auto ok = bend_edge01(3, kUnit, Vec3(0, 0.075, 0.075));
  ValidityOptions tight;
  tight.bound_tolerance = 1e-4;
  const ValidityReport good = certify_jacobian(3, ok, tight);
  EXPECT_EQ(good.verdict, Validity::kValid);
  EXPECT_LE(good.min_lower, 0.1 + 1e-12);
  EXPECT_GE(good.min_upper, 0.1 - 1e-12);
  EXPECT_GT(good.min_lower, 0.1 - 1e-3);
  // The maximum, 1 + 3 s = 1.225, is at l0 = 0, l1 = 1/3 (edge (1,2) or (1,3)).
  EXPECT_LE(good.max_lower, 1.225 + 1e-12);
  EXPECT_GT(good.max_lower, 1.15);
  EXPECT_GE(good.max_upper, 1.225 - 1e-12);

  // s = 1/12: det J = 0 exactly at l1 = 2/3 on the edge, positive elsewhere.
  // The zero is not at a dyadic point, so it cannot be hit; the element must
  // still never be called valid.
  const auto tangent = bend_edge01(3, kUnit, Vec3(0, 1.0 / 12, 1.0 / 12));
  EXPECT_NE(certify_jacobian(3, tangent).verdict, Validity::kValid);
}

// det J at vertex 0, in long double from the nodes as given: there the xi_j
// derivative is the derivative of the 1D Lagrange interpolant along edge
// (0, j) at its start.
long double corner_det_exact(int p, const std::vector<Vec3>& nodes) {
  static const std::array<std::array<long double, 4>, 4> kStart{{{0, 0, 0, 0},
                                                                {-1, 1, 0, 0},
                                                                {-3, 4, -1, 0},
                                                                {-5.5L, 9, -4.5L, 1}}};
  std::array<std::array<long double, 3>, 3> t{};
  for (int j = 1; j <= 3; ++j) {
    // The nodes of edge (0, j), from vertex 0.
    int e = 0;
    while (!((mesh::kTetEdges[static_cast<std::size_t>(e)][0] == 0 && mesh::kTetEdges[static_cast<std::size_t>(e)][1] == j) ||
             (mesh::kTetEdges[static_cast<std::size_t>(e)][0] == j && mesh::kTetEdges[static_cast<std::size_t>(e)][1] == 0)))
      ++e;
    const bool from_zero = mesh::kTetEdges[static_cast<std::size_t>(e)][0] == 0;
    std::array<Vec3, 4> along{};
    along[0] = nodes[0];
    for (int s = 1; s < p; ++s)
      along[static_cast<std::size_t>(s)] =
          nodes[static_cast<std::size_t>(4 + e * (p - 1) + (from_zero ? s - 1 : p - 1 - s))];
    along[static_cast<std::size_t>(p)] = nodes[static_cast<std::size_t>(j)];
    for (int c = 0; c < 3; ++c) {
      long double d = 0;
      for (int s = 0; s <= p; ++s)
        d += kStart[static_cast<std::size_t>(p)][static_cast<std::size_t>(s)] *
             (static_cast<long double>(along[static_cast<std::size_t>(s)][c]) - nodes[0][c]);
      t[static_cast<std::size_t>(j - 1)][static_cast<std::size_t>(c)] = d;
    }
  }
  return t[0][0] * (t[1][1] * t[2][2] - t[1][2] * t[2][1]) - t[0][1] * (t[1][0] * t[2][2] - t[1][2] * t[2][0]) +
         t[0][2] * (t[1][0] * t[2][1] - t[1][1] * t[2][0]);
}

TEST(BezierJacobian, RefiningBelowABoundInOnePassEqualsCertifyingTwice) {
  std::mt19937 rng(21);
  std::uniform_real_distribution<double> u(-1, 1);
  int refined = 0, left = 0;
  for (int p = 2; p <= 3; ++p)
    for (int trial = 0; trial < 400; ++trial) {
      auto nodes = linear_nodes(p, random_good_tet(rng));
      const double amplitude = 0.02 * (trial % 25);
      for (std::size_t n = 4; n < nodes.size(); ++n) nodes[n] += amplitude * Vec3(u(rng), u(rng), u(rng));
      ValidityOptions one;
      one.bound_tolerance = 0.01;
      one.refine_below = 0.5;
      const ValidityReport a = certify_jacobian(p, nodes, one);
      // The two calls it stands for.
      ValidityReport b = certify_jacobian(p, nodes);
      const bool refine = b.verdict == Validity::kValid && b.scaled_jacobian_lower < one.refine_below;
      if (refine) {
        ValidityOptions tight;
        tight.bound_tolerance = one.bound_tolerance;
        b = certify_jacobian(p, nodes, tight);
      }
      refined += refine;
      left += b.verdict == Validity::kValid && !refine;
      EXPECT_EQ(a.verdict, b.verdict) << p << " " << trial;
      EXPECT_EQ(a.min_lower, b.min_lower) << p << " " << trial;
      EXPECT_EQ(a.max_upper, b.max_upper) << p << " " << trial;
      EXPECT_EQ(a.min_upper, b.min_upper) << p << " " << trial;
      EXPECT_EQ(a.scaled_jacobian_lower, b.scaled_jacobian_lower) << p << " " << trial;
      EXPECT_EQ(a.splits, b.splits) << p << " " << trial;
      EXPECT_EQ(a.where_entity, b.where_entity) << p << " " << trial;
    }
  // Both branches were taken.
  EXPECT_GT(refined, 20);
  EXPECT_GT(left, 20);
}

TEST(BezierJacobian, RoundingBoundHoldsFarFromTheOrigin) {
  // Coordinates up to 1e6 on elements of size 1e-2..1: the rounding of the
  // nodes themselves, then of the coefficients, against the stated bound.
  std::mt19937 rng(12);
  std::uniform_real_distribution<double> u(-1, 1);
  for (int p = 2; p <= 3; ++p) {
    double worst = 0;
    for (int trial = 0; trial < 300; ++trial) {
      const double size = std::pow(10.0, -2 * (trial % 2)) * (1 + 0.5 * u(rng));
      const Vec3 offset = std::pow(10.0, trial % 7) * Vec3(u(rng), u(rng), u(rng));
      auto nodes = similar(linear_nodes(p, random_good_tet(rng)), random_rotation(rng), size, offset);
      for (std::size_t n = 4; n < nodes.size(); ++n) nodes[n] += 0.2 * size * Vec3(u(rng), u(rng), u(rng));
      const double coef = jacobian_bezier_coefficients(p, nodes)[0];
      const long double exact = corner_det_exact(p, nodes);
      const double bound = certify_jacobian(p, nodes).rounding_bound;
      const double error = static_cast<double>(std::abs(static_cast<long double>(coef) - exact));
      EXPECT_LE(error, bound) << p << " " << trial;
      worst = std::max(worst, error / bound);
    }
    // A priori, the bound is pessimistic (the worst error seen is about 1e-3
    // of it for P2, 2e-4 for P3); much looser, it would certify little.
    EXPECT_GT(worst, 1e-6) << p;
  }
}

TEST(BezierJacobian, ZeroAtAVertexIsInvalid) {
  // P2 node of edge (0,1) at (0.5, 1/8, 1/8): det J = 1 - l1, zero at vertex 1.
  const auto nodes = bend_edge01(2, kUnit, Vec3(0, 0.125, 0.125));
  const ValidityReport rep = certify_jacobian(2, nodes);
  EXPECT_EQ(rep.verdict, Validity::kInvalid);
  EXPECT_EQ(rep.where_entity, (SubEntity{0, 1}));
  EXPECT_EQ(rep.min_upper, 0.0);
  // Under rigid motions and scalings the computed value at vertex 1 is a
  // rounding error of either sign; the verdict must not depend on it.
  std::mt19937 rng(6);
  std::uniform_real_distribution<double> u(-1, 1);
  for (int t = 0; t < 30; ++t) {
    const double scale = std::exp(4 * u(rng));
    const auto moved =
        similar(nodes, random_rotation(rng), scale, Vec3(10 * u(rng), 10 * u(rng), 10 * u(rng)));
    const ValidityReport r = certify_jacobian(2, moved);
    EXPECT_EQ(r.verdict, Validity::kInvalid) << t;
    EXPECT_EQ(r.where_entity, (SubEntity{0, 1})) << t;
    EXPECT_LE(std::abs(r.min_upper), r.rounding_bound);
    EXPECT_LT(r.rounding_bound, 1e-10 * scale * scale * scale);
  }
  // The same corner degeneracy on a P3 element (s = 1/9 gives det J = 0 at
  // vertex 1 and negative values inside edge 0).
  EXPECT_EQ(certify_jacobian(3, bend_edge01(3, kUnit, Vec3(0, 1.0 / 9, 1.0 / 9))).verdict,
            Validity::kInvalid);
  // A P1 tet with a vertex on the opposite face: exactly flat, invalid.
  const std::vector<Vec3> flat{Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(0.3, 0.3, 0)};
  const ValidityReport f = certify_jacobian(1, flat);
  EXPECT_EQ(f.verdict, Validity::kInvalid);
  EXPECT_EQ(f.min_upper, 0.0);
}

TEST(BezierJacobian, BudgetAndDeterminism) {
  const auto nodes = bend_edge01(3, kUnit, Vec3(0, 0.1, 0.1));
  ValidityOptions none;
  none.max_splits = 0;
  EXPECT_EQ(certify_jacobian(3, nodes, none).verdict, Validity::kUndetermined);
  ValidityOptions shallow;
  shallow.max_depth = 1;
  EXPECT_EQ(
      certify_jacobian(3, bend_edge01(3, kUnit, Vec3(0, 1.0 / 12, 1.0 / 12)), shallow).verdict,
      Validity::kUndetermined);

  const ValidityReport a = certify_jacobian(3, nodes);
  const ValidityReport b = certify_jacobian(3, nodes);
  EXPECT_EQ(a.verdict, b.verdict);
  EXPECT_EQ(a.min_lower, b.min_lower);
  EXPECT_EQ(a.min_upper, b.min_upper);
  EXPECT_EQ(a.where, b.where);
  EXPECT_EQ(a.splits, b.splits);

  // Localization moves `where` toward the minimum at l1 = 2/3.
  ValidityOptions first;
  first.locate_splits = 0;
  const ValidityReport f = certify_jacobian(3, nodes, first);
  EXPECT_EQ(f.verdict, Validity::kInvalid);
  EXPECT_LE(a.min_upper, f.min_upper);
}

TEST(BezierJacobian, ClassifyBary) {
  EXPECT_EQ(classify_bary({1, 0, 0, 0}), (SubEntity{0, 0}));
  EXPECT_EQ(classify_bary({0, 0, 0, 1}), (SubEntity{0, 3}));
  EXPECT_EQ(classify_bary({0.5, 0.5, 0, 0}), (SubEntity{1, 0}));
  EXPECT_EQ(classify_bary({0, 0.5, 0.5, 0}), (SubEntity{1, 1}));
  EXPECT_EQ(classify_bary({0.5, 0, 0.5, 0}), (SubEntity{1, 2}));
  EXPECT_EQ(classify_bary({0.5, 0, 0, 0.5}), (SubEntity{1, 3}));
  EXPECT_EQ(classify_bary({0, 0.5, 0, 0.5}), (SubEntity{1, 4}));
  EXPECT_EQ(classify_bary({0, 0, 0.5, 0.5}), (SubEntity{1, 5}));
  EXPECT_EQ(classify_bary({0, 0.3, 0.3, 0.4}), (SubEntity{2, 0}));
  EXPECT_EQ(classify_bary({0.3, 0.3, 0, 0.4}), (SubEntity{2, 2}));
  EXPECT_EQ(classify_bary({0.25, 0.25, 0.25, 0.25}), (SubEntity{3, 0}));
  EXPECT_EQ(classify_bary({0.98, 0.01, 0.005, 0.005}, 0.02), (SubEntity{0, 0}));
  EXPECT_EQ(classify_bary({0.49, 0.5, 0.005, 0.005}, 0.02), (SubEntity{1, 0}));
}

TEST(BezierJacobian, OnMeshAndInputChecks) {
  mesh::TetMesh m;
  for (const Vec3& x : kUnit) m.add_vert(x);
  m.add_tet({0, 1, 2, 3}, 1);
  m.high_order.reset(3);
  const auto bent = bend_edge01(3, kUnit, Vec3(0, 0.1, 0.1));
  mesh::scatter_tet_nodes(m, 0, bent);
  const ValidityReport rep = certify_tet(m, 0);
  EXPECT_EQ(rep.verdict, Validity::kInvalid);
  EXPECT_EQ(rep.min_upper, certify_jacobian(3, bent).min_upper);

  EXPECT_THROW(certify_jacobian(2, std::span<const Vec3>(bent.data(), 9)), std::invalid_argument);
  EXPECT_THROW(certify_jacobian(kMaxBezierOrder + 1, bent), std::invalid_argument);
  auto broken = bent;
  broken[5].x() = std::nan("");
  EXPECT_THROW(certify_jacobian(3, broken), std::invalid_argument);
}

}  // namespace
}  // namespace cm::quality
