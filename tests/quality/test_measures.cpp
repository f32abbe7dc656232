// Straight-tet measures, statistics, quadrature and the shape measure I.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <limits>
#include <numbers>
#include <random>
#include <vector>

#include "curvemesh/mesh/high_order.hpp"
#include "curvemesh/mesh/tet_mesh.hpp"
#include "curvemesh/quality/bernstein.hpp"
#include "curvemesh/quality/bezier_jacobian.hpp"
#include "curvemesh/quality/measures.hpp"
#include "curvemesh/quality/quadrature.hpp"
#include "curvemesh/quality/shape_measure.hpp"
#include "curvemesh/quality/statistics.hpp"

namespace cm::quality {
namespace {

const double kRegularDihedral = std::acos(1.0 / 3.0) * 180.0 / std::numbers::pi;  // 70.5288 deg
const double kInf = std::numeric_limits<double>::infinity();

// Regular tet with edge 2 sqrt(2), positively oriented.
const std::array<Vec3, 4> kRegular{Vec3(1, 1, 1), Vec3(1, -1, -1), Vec3(-1, -1, 1),
                                   Vec3(-1, 1, -1)};
// Right-corner tet at the origin.
const std::array<Vec3, 4> kCorner{Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(0, 0, 1)};

Mat3 random_rotation(std::mt19937& rng) {
  std::normal_distribution<double> n01;
  Eigen::Quaterniond q(n01(rng), n01(rng), n01(rng), n01(rng));
  q.normalize();
  return q.toRotationMatrix();
}

TEST(Measures, RegularTet) {
  const auto& v = kRegular;
  EXPECT_NEAR(tet_signed_volume(v[0], v[1], v[2], v[3]), 8.0 / 3.0, 1e-14);
  EXPECT_NEAR(tet_mean_ratio(v[0], v[1], v[2], v[3]), 1.0, 1e-14);
  EXPECT_NEAR(tet_radius_ratio(v[0], v[1], v[2], v[3]), 1.0, 1e-14);
  EXPECT_NEAR(tet_inverse_radius_ratio(v[0], v[1], v[2], v[3]), 1.0, 1e-14);
  for (double a : tet_dihedral_angles(v[0], v[1], v[2], v[3]))
    EXPECT_NEAR(a, kRegularDihedral, 1e-12);
  EXPECT_NEAR(kRegularDihedral, 70.528779, 1e-6);
  for (double l : tet_edge_lengths(v[0], v[1], v[2], v[3]))
    EXPECT_NEAR(l, 2 * std::sqrt(2.0), 1e-14);
}

TEST(Measures, RightCornerTet) {
  const auto& v = kCorner;
  EXPECT_DOUBLE_EQ(tet_signed_volume(v[0], v[1], v[2], v[3]), 1.0 / 6.0);
  // sum l^2 = 3 * 1 + 3 * 2 = 9, (3V)^(2/3) = (1/2)^(2/3).
  EXPECT_NEAR(tet_mean_ratio(v[0], v[1], v[2], v[3]), 12.0 * std::pow(0.5, 2.0 / 3.0) / 9.0, 1e-14);
  // rho = 3V / area = (1/2) / (3/2 + sqrt(3)/2), h_max = sqrt(2).
  EXPECT_NEAR(tet_radius_ratio(v[0], v[1], v[2], v[3]), (1.0 + std::sqrt(3.0)) / 2.0, 1e-14);
  const auto angles = tet_dihedral_angles(v[0], v[1], v[2], v[3]);
  const double face_angle = std::acos(1.0 / std::sqrt(3.0)) * 180.0 / std::numbers::pi;
  // kTetEdges: (0,1) (1,2) (2,0) (0,3) (1,3) (2,3); the three edges at the corner are right angles.
  const std::array<double, 6> expected{90, face_angle, 90, 90, face_angle, face_angle};
  for (int e = 0; e < 6; ++e) EXPECT_NEAR(angles[e], expected[e], 1e-12) << "edge " << e;
  const auto range = tet_dihedral_range(v[0], v[1], v[2], v[3]);
  EXPECT_NEAR(range.min, 54.7356103, 1e-6);
  EXPECT_NEAR(range.max, 90, 1e-12);
  const auto lengths = tet_edge_lengths(v[0], v[1], v[2], v[3]);
  EXPECT_DOUBLE_EQ(lengths[0], 1);
  EXPECT_DOUBLE_EQ(lengths[1], std::sqrt(2.0));
}

TEST(Measures, InvertedAndFlatTets) {
  const auto& v = kCorner;
  const double eta = tet_mean_ratio(v[0], v[1], v[2], v[3]);
  // Swapping two vertices inverts the tet: negative volume and mean ratio.
  EXPECT_DOUBLE_EQ(tet_signed_volume(v[1], v[0], v[2], v[3]), -1.0 / 6.0);
  EXPECT_NEAR(tet_mean_ratio(v[1], v[0], v[2], v[3]), -eta, 1e-15);
  EXPECT_EQ(tet_radius_ratio(v[1], v[0], v[2], v[3]), kInf);
  EXPECT_EQ(tet_inverse_radius_ratio(v[1], v[0], v[2], v[3]), 0.0);
  const auto a = tet_dihedral_angles(v[0], v[1], v[2], v[3]);
  const auto b = tet_dihedral_angles(v[1], v[0], v[2], v[3]);
  // Same edge set, listed differently: the multisets of angles agree.
  auto sa = a;
  auto sb = b;
  std::sort(sa.begin(), sa.end());
  std::sort(sb.begin(), sb.end());
  for (int e = 0; e < 6; ++e) EXPECT_NEAR(sa[e], sb[e], 1e-12);

  // Four coplanar points (a square): zero volume, dihedral angles 0 and 180.
  const Vec3 p0(0, 0, 0), p1(1, 0, 0), p2(1, 1, 0), p3(0, 1, 0);
  EXPECT_EQ(tet_signed_volume(p0, p1, p2, p3), 0.0);
  EXPECT_EQ(tet_mean_ratio(p0, p1, p2, p3), 0.0);
  EXPECT_EQ(tet_radius_ratio(p0, p1, p2, p3), kInf);
  const auto flat = tet_dihedral_range(p0, p1, p2, p3);
  EXPECT_NEAR(flat.min, 0, 1e-12);
  EXPECT_NEAR(flat.max, 180, 1e-12);
  // Coincident points: no NaN.
  EXPECT_EQ(tet_mean_ratio(p0, p0, p0, p0), 0.0);
  for (double ang : tet_dihedral_angles(p0, p0, p1, p2)) EXPECT_FALSE(std::isnan(ang));

  // A sliver: four nearly coplanar points with good edges.
  const Vec3 s3(0.5, 0.5, 1e-3);
  const double sliver = tet_mean_ratio(Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0), s3);
  EXPECT_GT(sliver, 0);
  EXPECT_LT(sliver, 0.05);
}

TEST(Measures, InvariantUnderSimilarity) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1, 1);
  std::array<Vec3, 4> v{Vec3(0.1, 0.2, 0), Vec3(1.3, 0.1, 0.2), Vec3(0.4, 1.1, -0.1),
                        Vec3(0.5, 0.3, 0.9)};
  const double eta = tet_mean_ratio(v[0], v[1], v[2], v[3]);
  const double q = tet_radius_ratio(v[0], v[1], v[2], v[3]);
  const auto range = tet_dihedral_range(v[0], v[1], v[2], v[3]);
  ASSERT_GT(eta, 0.3);
  for (int trial = 0; trial < 20; ++trial) {
    const Mat3 r = random_rotation(rng);
    const double s = std::exp(3 * u(rng));
    const Vec3 t(100 * u(rng), 100 * u(rng), 100 * u(rng));
    std::array<Vec3, 4> w;
    for (int k = 0; k < 4; ++k) w[k] = s * (r * v[k]) + t;
    EXPECT_NEAR(tet_mean_ratio(w[0], w[1], w[2], w[3]), eta, 1e-10);
    EXPECT_NEAR(tet_radius_ratio(w[0], w[1], w[2], w[3]), q, 1e-9);
    EXPECT_NEAR(tet_dihedral_range(w[0], w[1], w[2], w[3]).min, range.min, 1e-8);
    EXPECT_NEAR(tet_dihedral_range(w[0], w[1], w[2], w[3]).max, range.max, 1e-8);
  }
}

// The optimizer's cheaper minimum agrees with the range's on random tets,
// slivers, needles, inverted and flat ones.
TEST(Measures, MinDihedralIsTheRangesMinimum) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-1, 1);
  for (int trial = 0; trial < 20000; ++trial) {
    std::array<Vec3, 4> v;
    for (auto& x : v) x = Vec3(u(rng), u(rng), u(rng));
    if (trial % 4 == 1) v[3] = (v[0] + v[1] + v[2]) / 3 + 1e-4 * Vec3(u(rng), u(rng), u(rng));  // sliver or cap
    if (trial % 4 == 2) v[1] = v[0] + 1e-3 * Vec3(u(rng), u(rng), u(rng));                         // needle
    const double range_min = tet_dihedral_range(v[0], v[1], v[2], v[3]).min;
    EXPECT_NEAR(tet_min_dihedral(v[0], v[1], v[2], v[3]), range_min, 1e-9) << "trial " << trial;
  }
  const Vec3 p0(0, 0, 0), p1(1, 0, 0), p2(1, 1, 0), p3(0, 1, 0);
  EXPECT_NEAR(tet_min_dihedral(p0, p1, p2, p3), 0, 1e-12);
  EXPECT_EQ(tet_min_dihedral(p0, p0, p1, p2), 0);
}

// The optimizer's cheap bounds never claim more than the measures return,
// on random tets, slivers, needles, caps near the threshold and inverted
// ones; and they do settle most tets clearly above the threshold (else they
// would save nothing).
TEST(Measures, CheapBoundsAreOneSided) {
  std::mt19937 rng(23);
  std::uniform_real_distribution<double> u(-1, 1), unit(0, 1);
  int clear = 0, settled = 0;
  for (int trial = 0; trial < 40000; ++trial) {
    std::array<Vec3, 4> v;
    for (auto& x : v) x = Vec3(u(rng), u(rng), u(rng));
    if (trial % 4 == 1) v[3] = (v[0] + v[1] + v[2]) / 3 + 1e-4 * Vec3(u(rng), u(rng), u(rng));
    if (trial % 4 == 2) v[1] = v[0] + 1e-3 * Vec3(u(rng), u(rng), u(rng));
    const double eta = tet_mean_ratio(v[0], v[1], v[2], v[3]);
    const double angle = tet_min_dihedral(v[0], v[1], v[2], v[3]);
    // Thresholds at, just under and just over the value, and random ones.
    for (const double f : {1.0, 1 - 1e-12, 1 + 1e-12, 1 - 1e-6, unit(rng), 0.5}) {
      const double r = eta * f, deg = angle * f;
      if (tet_mean_ratio_at_least(v[0], v[1], v[2], v[3], r)) {
        EXPECT_GE(eta, r) << "trial " << trial;
      }
      if (tet_min_dihedral_at_least(v[0], v[1], v[2], v[3], deg)) {
        EXPECT_GE(angle, deg) << "trial " << trial;
      }
    }
    if (eta > 0.05 && angle > 1) {
      ++clear;
      settled += tet_mean_ratio_at_least(v[0], v[1], v[2], v[3], 0.5 * eta) &&
                 tet_min_dihedral_at_least(v[0], v[1], v[2], v[3], 0.5 * angle);
    }
  }
  EXPECT_GT(clear, 1000);
  EXPECT_EQ(settled, clear);  // half the value is always within the bounds' slack
  const Vec3 p0(0, 0, 0), p1(1, 0, 0), p2(0, 1, 0), p3(0, 0, 1);
  EXPECT_FALSE(tet_mean_ratio_at_least(p0, p2, p1, p3, -1));  // inverted: never settled
  EXPECT_FALSE(tet_min_dihedral_at_least(p0, p0, p1, p2, 0));  // degenerate face
}

// The mean ratio's cube root is a fast one: against a long double
// reference over a wide range of tet sizes and shapes.
TEST(Measures, MeanRatioIsAccurateAtEveryScale) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-1, 1), e(-60, 60);
  for (int trial = 0; trial < 20000; ++trial) {
    const double s = std::exp2(e(rng));
    std::array<Vec3, 4> v;
    for (auto& x : v) x = s * Vec3(u(rng), u(rng), u(rng));
    using L = long double;
    const L vol = L((v[1] - v[0]).cross(v[2] - v[0]).dot(v[3] - v[0])) / 6;
    L sum = 0;
    for (const auto& ed : cm::mesh::kTetEdges) sum += L((v[ed[1]] - v[ed[0]]).squaredNorm());
    const L ref = 12 * std::cbrt(9 * vol * vol) / sum * (vol > 0 ? 1 : -1);
    EXPECT_NEAR(tet_mean_ratio(v[0], v[1], v[2], v[3]), double(ref), 1e-13) << "trial " << trial;
  }
  const Vec3 a(1, 1, 1), b(1, -1, -1), c(-1, -1, 1), d(-1, 1, -1);
  EXPECT_NEAR(tet_mean_ratio(a, b, c, d), 1.0, 4e-16);
}

TEST(Measures, MetricVersions) {
  const Mat3 m = Vec3(4, 1, 9).asDiagonal();
  EXPECT_DOUBLE_EQ(metric_length(Vec3(1, 0, 0), m), 2);
  EXPECT_DOUBLE_EQ(metric_length(Vec3(0, 0, 1), m), 3);
  EXPECT_DOUBLE_EQ(metric_length(Vec3(1, 1, 0), m), std::sqrt(5.0));

  const auto& r = kRegular;
  const auto& c = kCorner;
  EXPECT_NEAR(tet_metric_mean_ratio(c[0], c[1], c[2], c[3], Mat3::Identity()),
              tet_mean_ratio(c[0], c[1], c[2], c[3]), 1e-15);
  // An isotropic metric only scales lengths: eta is unchanged.
  EXPECT_NEAR(tet_metric_mean_ratio(c[0], c[1], c[2], c[3], 7.0 * Mat3::Identity()),
              tet_mean_ratio(c[0], c[1], c[2], c[3]), 1e-14);
  // A regular tet squashed by A = diag(1,1,1/4) is regular again in the metric
  // M = A^-T A^-1 = diag(1,1,16), and poor in the Euclidean one.
  const Mat3 a = Vec3(1, 1, 0.25).asDiagonal();
  const Mat3 metric = Vec3(1, 1, 16).asDiagonal();
  std::array<Vec3, 4> p;
  for (int k = 0; k < 4; ++k) p[k] = a * r[k];
  EXPECT_NEAR(tet_metric_mean_ratio(p[0], p[1], p[2], p[3], metric), 1.0, 1e-14);
  EXPECT_LT(tet_mean_ratio(p[0], p[1], p[2], p[3]), 0.6);
  EXPECT_LT(tet_metric_mean_ratio(p[1], p[0], p[2], p[3], metric), 0);

  // Log-Euclidean mean: geometric mean of commuting metrics, and idempotent.
  const std::vector<Mat3> pair{Vec3(1, 4, 9).asDiagonal(), Vec3(4, 1, 1).asDiagonal()};
  const Mat3 mean = metric_log_mean(pair);
  EXPECT_NEAR((mean - Mat3(Vec3(2, 2, 3).asDiagonal())).norm(), 0, 1e-13);
  std::mt19937 rng(3);
  const Mat3 rot = random_rotation(rng);
  const Mat3 spd = rot * Vec3(0.5, 2, 30).asDiagonal() * rot.transpose();
  const std::vector<Mat3> same{spd, spd, spd};
  EXPECT_NEAR((metric_log_mean(same) - spd).norm(), 0, 1e-12);
}

TEST(Measures, TriangleMeanRatio) {
  EXPECT_NEAR(triangle_mean_ratio(Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0.5, std::sqrt(3.0) / 2, 0)),
              1.0, 1e-15);
  EXPECT_NEAR(triangle_mean_ratio(Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0)), std::sqrt(3.0) / 2,
              1e-15);
  EXPECT_EQ(triangle_mean_ratio(Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(2, 0, 0)), 0.0);
  EXPECT_EQ(triangle_mean_ratio(Vec3(1, 1, 1), Vec3(1, 1, 1), Vec3(1, 1, 1)), 0.0);
  // Unsigned: the reversed triangle has the same ratio.
  EXPECT_EQ(triangle_mean_ratio(Vec3(0, 0, 0), Vec3(0, 1, 0), Vec3(1, 0, 0)),
            triangle_mean_ratio(Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0)));
}

TEST(Measures, EvaluateTetOnMesh) {
  mesh::TetMesh m;
  for (const Vec3& x : kCorner) m.add_vert(x);
  m.add_vert(Vec3(1, 1, 1));
  m.add_tet({0, 1, 2, 3}, 1);
  m.add_tet({2, 1, 3, 4}, 1);  // negative: det[x1-x2, x3-x2, x4-x2] = -2
  const TetQuality q = evaluate_tet(m, 0);
  EXPECT_DOUBLE_EQ(q.volume, 1.0 / 6.0);
  EXPECT_NEAR(q.mean_ratio, tet_mean_ratio(kCorner[0], kCorner[1], kCorner[2], kCorner[3]), 1e-15);
  EXPECT_NEAR(q.radius_ratio, (1.0 + std::sqrt(3.0)) / 2.0, 1e-14);
  EXPECT_NEAR(q.min_dihedral, 54.7356103, 1e-6);
  EXPECT_NEAR(q.max_dihedral, 90, 1e-12);
  const TetQuality bad = evaluate_tet(m, 1);
  EXPECT_LT(bad.volume, 0);
  EXPECT_LT(bad.mean_ratio, 0);
  EXPECT_EQ(bad.radius_ratio, kInf);
}

TEST(Statistics, ExactValues) {
  std::vector<double> v;
  for (int i = 100; i >= 1; --i) v.push_back(i);
  const Statistics s = compute_statistics(v);
  EXPECT_EQ(s.count, 100u);
  EXPECT_EQ(s.nan_count, 0u);
  EXPECT_EQ(s.min, 1);
  EXPECT_EQ(s.max, 100);
  EXPECT_DOUBLE_EQ(s.mean, 50.5);
  // Position q/100 * 99 in the sorted values 1..100.
  EXPECT_NEAR(s.p1, 1.99, 1e-12);
  EXPECT_NEAR(s.p5, 5.95, 1e-12);
  EXPECT_NEAR(s.p50, 50.5, 1e-12);
  EXPECT_NEAR(s.p95, 95.05, 1e-12);
  EXPECT_NEAR(s.p99, 99.01, 1e-12);

  const std::vector<double> one{0.25};
  const Statistics s1 = compute_statistics(one);
  EXPECT_EQ(s1.count, 1u);
  EXPECT_EQ(s1.p1, 0.25);
  EXPECT_EQ(s1.p99, 0.25);

  const double nan = std::numeric_limits<double>::quiet_NaN();
  const std::vector<double> with_nan{3, nan, 1, 2, nan};
  const Statistics sn = compute_statistics(with_nan);
  EXPECT_EQ(sn.count, 3u);
  EXPECT_EQ(sn.nan_count, 2u);
  EXPECT_EQ(sn.min, 1);
  EXPECT_EQ(sn.max, 3);
  EXPECT_EQ(sn.p50, 2);

  const Statistics empty = compute_statistics(std::vector<double>{});
  EXPECT_EQ(empty.count, 0u);
  EXPECT_TRUE(std::isnan(empty.min));
  EXPECT_TRUE(std::isnan(empty.p50));

  // Infinite radius ratios (inverted tets) must not poison the percentiles.
  const std::vector<double> inf{1, 2, kInf, kInf};
  const Statistics si = compute_statistics(inf);
  EXPECT_EQ(si.max, kInf);
  EXPECT_NEAR(si.p1, 1.03, 1e-15);
  EXPECT_EQ(si.p99, kInf);
}

TEST(Statistics, Histogram) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const std::vector<double> v{0, 0.05, 0.1, 0.95, 1.0, 1.2, -0.1, nan};
  const Histogram h = make_quality_histogram(v);
  ASSERT_EQ(h.counts.size(), 10u);
  EXPECT_EQ(h.counts[0], 2u);
  EXPECT_EQ(h.counts[1], 1u);
  EXPECT_EQ(h.counts[9], 2u);
  EXPECT_EQ(h.below, 1u);
  EXPECT_EQ(h.above, 1u);
  EXPECT_EQ(h.nan_count, 1u);
  EXPECT_EQ(h.total(), 7u);
  // Every decimal bound k/10 falls in the bin that starts there.
  for (int k = 0; k <= 10; ++k) {
    const std::vector<double> one{k / 10.0};
    const Histogram hk = make_quality_histogram(one);
    EXPECT_EQ(hk.counts[static_cast<std::size_t>(std::min(k, 9))], 1u) << k / 10.0;
  }
  // Angles: 18 bins of 10 degrees, 180 in the last one.
  const std::vector<double> angles{0, 9.99, 10, 70.53, 179, 180};
  const Histogram ha = make_angle_histogram(angles);
  ASSERT_EQ(ha.counts.size(), 18u);
  EXPECT_EQ(ha.counts[0], 2u);
  EXPECT_EQ(ha.counts[1], 1u);
  EXPECT_EQ(ha.counts[7], 1u);
  EXPECT_EQ(ha.counts[17], 2u);
  EXPECT_DOUBLE_EQ(ha.bin_lower(7), 70);
  EXPECT_DOUBLE_EQ(ha.bin_upper(7), 80);
  EXPECT_THROW(make_histogram(v, 1, 0, 10), std::invalid_argument);
  EXPECT_THROW(make_histogram(v, 0, 1, 0), std::invalid_argument);
}

TEST(Statistics, RenderHistogram) {
  std::vector<double> v;
  for (int i = 0; i < 30; ++i) v.push_back(0.95);
  for (int i = 0; i < 15; ++i) v.push_back(0.55);
  v.push_back(0.01);
  const std::string text = render_histogram(make_quality_histogram(v), 30, 2);
  std::vector<std::string> lines;
  std::size_t start = 0;
  while (start < text.size()) {
    const std::size_t end = text.find('\n', start);
    lines.push_back(text.substr(start, end - start));
    start = end + 1;
  }
  ASSERT_EQ(lines.size(), 10u) << text;  // no below/above/NaN lines
  EXPECT_EQ(lines[9], "[0.90, 1.00] 30 " + std::string(30, '#'));
  EXPECT_EQ(lines[5], "[0.50, 0.60) 15 " + std::string(15, '#'));
  EXPECT_EQ(lines[0], "[0.00, 0.10)  1 #");  // small counts still show
  EXPECT_EQ(lines[1], "[0.10, 0.20)  0");
  v.push_back(-1);
  const std::string with_below = render_histogram(make_quality_histogram(v), 30, 2);
  EXPECT_EQ(with_below.substr(0, 7), "< 0.00 ");
}

TEST(Quadrature, GaussJacobiExactness) {
  for (int alpha = 0; alpha <= 2; ++alpha)
    for (int n = 1; n <= 6; ++n) {
      const GaussRule r = gauss_jacobi(n, alpha);
      ASSERT_EQ(r.nodes.size(), static_cast<std::size_t>(n));
      for (int k = 0; k <= 2 * n; ++k) {
        // integral_0^1 (1-t)^alpha t^k dt = k! alpha! / (k + alpha + 1)!
        double exact =
            std::tgamma(k + 1.0) * std::tgamma(alpha + 1.0) / std::tgamma(k + alpha + 2.0);
        double sum = 0;
        for (int i = 0; i < n; ++i) {
          EXPECT_GT(r.weights[i], 0);
          EXPECT_GT(r.nodes[i], 0);
          EXPECT_LT(r.nodes[i], 1);
          sum += r.weights[i] * std::pow(r.nodes[i], k);
        }
        if (k <= 2 * n - 1)
          EXPECT_NEAR(sum, exact, 1e-14) << "n " << n << " alpha " << alpha << " k " << k;
        else
          EXPECT_GT(std::abs(sum - exact), 1e-10) << "degree 2n must not be exact";
      }
    }
}

TEST(Quadrature, CollapsedTetRule) {
  for (int n = 1; n <= 6; ++n) {
    const TetRule& rule = collapsed_tet_rule(n);
    ASSERT_EQ(rule.points.size(), static_cast<std::size_t>(n * n * n));
    EXPECT_EQ(rule.exact_degree, 2 * n - 1);
    double wsum = 0;
    for (std::size_t i = 0; i < rule.points.size(); ++i) {
      EXPECT_GT(rule.weights[i], 0);
      const Bary& b = rule.points[i];
      for (double l : b) EXPECT_GT(l, 0);
      EXPECT_NEAR(b[0] + b[1] + b[2] + b[3], 1, 1e-15);
      wsum += rule.weights[i];
    }
    EXPECT_NEAR(wsum, 1.0 / 6.0, 1e-15);
    // integral over the tet of xi1^a xi2^b xi3^c = a! b! c! / (a+b+c+3)!
    for (int a = 0; a <= 2 * n - 1; ++a)
      for (int b = 0; a + b <= 2 * n - 1; ++b)
        for (int c = 0; a + b + c <= 2 * n - 1; ++c) {
          double sum = 0;
          for (std::size_t i = 0; i < rule.points.size(); ++i) {
            const Bary& p = rule.points[i];
            sum += rule.weights[i] * std::pow(p[1], a) * std::pow(p[2], b) * std::pow(p[3], c);
          }
          const double exact = std::tgamma(a + 1.0) * std::tgamma(b + 1.0) * std::tgamma(c + 1.0) /
                               std::tgamma(a + b + c + 4.0);
          EXPECT_NEAR(sum, exact, 1e-15) << n << ": " << a << b << c;
        }
  }
  EXPECT_EQ(points_for_degree(0), 1);
  EXPECT_EQ(points_for_degree(3), 2);
  EXPECT_EQ(points_for_degree(6), 4);
  EXPECT_THROW(collapsed_tet_rule(0), std::invalid_argument);
}

// Order-p nodes of the straight tet v, plus `bend` times the displacement
// `shift` on the edge nodes of edge (0,1) (edge 0 of kTetEdges).
std::vector<Vec3> p_nodes(int p, const std::array<Vec3, 4>& v, const Vec3& shift = Vec3::Zero()) {
  std::vector<Vec3> nodes;
  for (const auto& a : mesh::tet_node_indices(p)) {
    Vec3 x = Vec3::Zero();
    for (int k = 0; k < 4; ++k) x += (static_cast<double>(a[k]) / p) * v[k];
    if (a[0] > 0 && a[1] > 0 && a[2] == 0 && a[3] == 0) x += shift;
    nodes.push_back(x);
  }
  return nodes;
}

TEST(ShapeMeasure, StraightTetsGiveOne) {
  std::mt19937 rng(11);
  for (int p = 1; p <= kMaxBezierOrder; ++p) {
    const auto nodes = p_nodes(p, kRegular);
    const ShapeMeasure s = shape_measure(p, nodes);
    EXPECT_NEAR(s.measure, 1.0, 1e-13) << p;
    EXPECT_NEAR(s.volume, 8.0 / 3.0, 1e-13) << p;
    const int n = points_for_degree(3 * (p - 1));
    EXPECT_EQ(s.num_points, n * n * n);
    // An arbitrary (non-regular, rotated) straight tet: still exactly 1.
    const Mat3 r = random_rotation(rng);
    std::array<Vec3, 4> w;
    for (int k = 0; k < 4; ++k) w[k] = r * kCorner[k] * 3.0 + Vec3(5, -2, 1);
    const ShapeMeasure t = shape_measure(p, p_nodes(p, w), 3);
    EXPECT_NEAR(t.measure, 1.0, 1e-12);
    EXPECT_NEAR(t.volume, 27.0 / 6.0, 1e-12);
  }
  // Inverted straight tet: I = -1 (min / |mean|).
  const std::array<Vec3, 4> inv{kCorner[1], kCorner[0], kCorner[2], kCorner[3]};
  EXPECT_NEAR(shape_measure(2, p_nodes(2, inv)).measure, -1.0, 1e-13);
}

TEST(ShapeMeasure, DecreasesWithCurvatureAndVolumeIsExact) {
  // Unit tet with the edge (0,1) nodes moved by (0,s,s): for P2, det J =
  // 1 - 8 s l1 and the volume is 1/6 - s/3; for P3, det J =
  // 1 - 9 s l1 (6 l0 + 3 l1 - 2) and the volume 1/6 - 0.15 s.
  for (int p : {2, 3}) {
    double previous = 1.0 + 1e-15;
    for (double s : {0.0, 0.01, 0.03, 0.06, 0.1, 0.2}) {
      const auto nodes = p_nodes(p, kCorner, Vec3(0, s, s));
      const ShapeMeasure m = shape_measure(p, nodes);
      const double exact_volume = p == 2 ? 1.0 / 6.0 - s / 3.0 : 1.0 / 6.0 - 0.15 * s;
      EXPECT_NEAR(m.volume, exact_volume, 1e-15) << p << " " << s;
      EXPECT_LT(m.measure, previous) << p << " " << s;
      if (s > 0) {
        EXPECT_LT(m.measure, 1.0 - 1e-3);
      }
      previous = m.measure;
      // The analytic det J at an interior point, through the Lagrange basis.
      const Bary at{0.1, 0.4, 0.3, 0.2};
      const double det =
          p == 2 ? 1 - 8 * s * at[1] : 1 - 9 * s * at[1] * (6 * at[0] + 3 * at[1] - 2);
      EXPECT_NEAR(lagrange_jacobian_det(p, nodes, at), det, 1e-14);
    }
  }
}

TEST(ShapeMeasure, VolumeAgreesAcrossRulesAndBezier) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-1, 1);
  for (int p = 2; p <= kMaxBezierOrder; ++p)
    for (int trial = 0; trial < 10; ++trial) {
      auto nodes = p_nodes(p, kRegular);
      for (std::size_t n = 4; n < nodes.size(); ++n) nodes[n] += 0.3 * Vec3(u(rng), u(rng), u(rng));
      const double minimal = shape_measure(p, nodes).volume;
      const double fine = shape_measure(p, nodes, 8).volume;
      // integral of B^q_a over the reference tet is (1/6) / simplex_count(q).
      const auto coefs = jacobian_bezier_coefficients(p, nodes);
      double sum = 0;
      for (double c : coefs) sum += c;
      const double bezier = sum / static_cast<double>(coefs.size()) / 6.0;
      EXPECT_NEAR(minimal, fine, 1e-13 * std::abs(fine));
      EXPECT_NEAR(minimal, bezier, 1e-13 * std::abs(fine));
      // A rule one degree short is visibly different for a generic element.
      if (p == 3) {
        const double coarse = shape_measure(p, nodes, 3).volume;
        EXPECT_GT(std::abs(coarse - fine), 1e-12);
      }
    }
}

TEST(ShapeMeasure, FromBezierCoefficientsMatchesTheNodalRule) {
  std::mt19937 rng(17);
  std::uniform_real_distribution<double> u(-1, 1);
  int inverted = 0;
  for (int p = 1; p <= kMaxBezierOrder; ++p)
    for (int trial = 0; trial < 40; ++trial) {
      auto nodes = p_nodes(p, kRegular);
      // Up to strongly folded elements (I < 0), where the least value and
      // the mean disagree in sign.
      const double amplitude = 0.05 * (trial % 20);
      for (std::size_t n = 4; n < nodes.size(); ++n) nodes[n] += amplitude * Vec3(u(rng), u(rng), u(rng));
      if (p == 1 && trial % 2) std::swap(nodes[0], nodes[1]);
      const ShapeMeasure direct = shape_measure(p, nodes);
      const ShapeMeasure bezier = shape_measure_from_bezier(p, jacobian_bezier_coefficients(p, nodes));
      const double scale = std::max(std::abs(direct.max_detj), std::abs(direct.min_detj));
      EXPECT_EQ(bezier.num_points, direct.num_points);
      EXPECT_NEAR(bezier.min_detj, direct.min_detj, 1e-12 * scale) << p << " " << trial;
      EXPECT_NEAR(bezier.max_detj, direct.max_detj, 1e-12 * scale) << p << " " << trial;
      EXPECT_NEAR(bezier.volume, direct.volume, 1e-13 * scale) << p << " " << trial;
      // I = min / |mean|: its error is the inputs' relative to the mean.
      const double mean = std::abs(6 * direct.volume);
      EXPECT_NEAR(bezier.measure, direct.measure, 1e-11 * scale / mean * (1 + std::abs(direct.measure)))
          << p << " " << trial;
      inverted += direct.measure < 0;
    }
  EXPECT_GT(inverted, 5);  // the comparison covered folded elements too
  EXPECT_THROW(shape_measure_from_bezier(3, std::vector<double>(20, 1.0)), std::invalid_argument);
  EXPECT_THROW(shape_measure_from_bezier(0, std::vector<double>(1, 1.0)), std::invalid_argument);
}

TEST(ShapeMeasure, OnMeshAndInputChecks) {
  mesh::TetMesh m;
  for (const Vec3& x : kCorner) m.add_vert(x);
  m.add_tet({0, 1, 2, 3}, 1);
  m.high_order.reset(2);
  const Vec3 mid(0.5, 0.1, 0.1);
  m.high_order.set_edge(0, 1, std::span<const Vec3>(&mid, 1));
  const ShapeMeasure s = shape_measure(m, 0);
  EXPECT_NEAR(s.volume, 1.0 / 6.0 - 0.1 / 3.0, 1e-15);
  EXPECT_LT(s.measure, 1);
  const auto nodes = p_nodes(2, kCorner);
  EXPECT_THROW(shape_measure(2, std::span<const Vec3>(nodes.data(), 4)), std::invalid_argument);
  EXPECT_THROW(shape_measure(5, nodes), std::invalid_argument);
  EXPECT_THROW(shape_measure(2, nodes, kMaxRulePoints + 1), std::invalid_argument);
}

TEST(Measures, DihedralRangeIsTheExtremesOfTheAngles) {
  // The range ranks angles by a pseudo-angle; it must pick the same extremes
  // as the full computation, also for slivers, needles and caps.
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-1, 1);
  for (int i = 0; i < 20000; ++i) {
    std::array<Vec3, 4> v;
    for (auto& x : v) x = Vec3(u(rng), u(rng), u(rng));
    if (i % 3 == 1) v[3] = (v[0] + v[1] + v[2]) / 3 + 1e-7 * Vec3(u(rng), u(rng), u(rng));  // cap / sliver
    if (i % 3 == 2) v[1] = v[0] + 1e-6 * Vec3(u(rng), u(rng), u(rng));                      // needle
    const auto all = tet_dihedral_angles(v[0], v[1], v[2], v[3]);
    const auto range = tet_dihedral_range(v[0], v[1], v[2], v[3]);
    ASSERT_DOUBLE_EQ(range.min, *std::min_element(all.begin(), all.end())) << i;
    ASSERT_DOUBLE_EQ(range.max, *std::max_element(all.begin(), all.end())) << i;
  }
}

}  // namespace
}  // namespace cm::quality
