// Curvature-to-length formulas (seed eqs. 4.3–4.8) and metric algebra.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include <Eigen/Eigenvalues>

#include "curvemesh/size/curvature_size.hpp"
#include "curvemesh/size/metric.hpp"
#include "curvemesh/size/size_field.hpp"

using namespace cm;
using namespace cm::size;

TEST(CurvatureLength, ChordDeviationIsEquation43) {
  const auto rule = CurvatureRule::chord_deviation(0.1);
  for (const double r : {0.3, 1.0, 2.0, 50.0}) {
    const double expect = std::sqrt(8 * r * 0.1 - 4 * 0.01);
    EXPECT_NEAR(curvature_length(1 / r, rule), expect, 1e-14 * expect);
    EXPECT_NEAR(curvature_length(-1 / r, rule), expect, 1e-14 * expect) << "concave needs the same length";
    // The defining geometry: a chord of that length deviates by exactly ε.
    const double sagitta = r - std::sqrt(r * r - expect * expect / 4);
    EXPECT_NEAR(sagitta, 0.1, 1e-12);
  }
  EXPECT_TRUE(std::isinf(curvature_length(0, rule)));
}

TEST(CurvatureLength, DeviationAtLeastTheRadiusGivesTheDiameter) {
  // ε >= R: 4.3 would decrease again past its peak 2R at ε = R.
  EXPECT_DOUBLE_EQ(curvature_length(1 / 0.05, CurvatureRule::chord_deviation(0.1)), 0.1);
  EXPECT_DOUBLE_EQ(curvature_length(1 / 0.1, CurvatureRule::chord_deviation(0.1)), 0.2);
  EXPECT_DOUBLE_EQ(curvature_length(1 / 0.02, CurvatureRule::chord_deviation(0.1)), 0.04);
}

TEST(CurvatureLength, RelativeDeviationIsEquation45) {
  for (const double a : {0.01, 0.1, 0.5}) {
    const auto rule = CurvatureRule::relative_deviation(a);
    for (const double r : {0.5, 3.0}) {
      const double l = curvature_length(1 / r, rule);
      EXPECT_NEAR(l, 8 * r * a / (1 + 4 * a * a), 1e-14 * l);
      // ε = αℓ: the sagitta of that chord is α times its length.
      const double sagitta = r - std::sqrt(std::max(0.0, r * r - l * l / 4));
      EXPECT_NEAR(sagitta, a * l, 1e-9 * l);
    }
  }
  EXPECT_THROW(CurvatureRule::relative_deviation(0.6), std::invalid_argument);
  EXPECT_THROW(CurvatureRule::relative_deviation(0), std::invalid_argument);
  EXPECT_THROW(CurvatureRule::chord_deviation(-1), std::invalid_argument);
  EXPECT_THROW(CurvatureRule::chord_deviation(NAN), std::invalid_argument);
}

TEST(CurvatureLength, SurfaceUsesTheLargerCurvatureMagnitude) {
  const auto rule = CurvatureRule::relative_deviation(0.05);
  geom::Curvatures c;
  c.k1 = 0.25;
  c.k2 = -1.0;  // saddle: the concave direction is tighter
  EXPECT_DOUBLE_EQ(surface_curvature_length(c, rule), curvature_length(1.0, rule));
}

TEST(OctreeLevel, IsEquation46RoundedSoTheOctantFits) {
  const double big_l = 10;
  for (const double l : {9.99, 5.0, 4.99, 1.0, 0.1, 0.0123}) {
    const int n = octree_level(big_l, l);
    EXPECT_LE(std::ldexp(big_l, -n), l);
    if (n > 0) {
      EXPECT_GT(std::ldexp(big_l, -(n - 1)), l);
    }
    EXPECT_EQ(n, static_cast<int>(std::ceil(std::log2(big_l / l) - 1e-12)));
  }
  EXPECT_EQ(octree_level(10, 20), 0);
  // Eq. 4.7 and 4.8 are 4.6 with the lengths of 4.3 and 4.5.
  const double r = 0.7, eps = 0.01, a = 0.05;
  EXPECT_EQ(octree_level(big_l, curvature_length(1 / r, CurvatureRule::chord_deviation(eps))),
            static_cast<int>(std::ceil(0.5 * std::log2(big_l * big_l / (8 * r * eps - 4 * eps * eps)))));
  EXPECT_EQ(octree_level(big_l, curvature_length(1 / r, CurvatureRule::relative_deviation(a))),
            static_cast<int>(std::ceil(std::log2((1 + 4 * a * a) * big_l / (8 * r * a)))));
}

TEST(DirectionalMetric, CylinderIsFineAroundAndCoarseAlongTheAxis) {
  const auto rule = CurvatureRule::relative_deviation(0.05);
  geom::Curvatures c;
  c.k1 = 1 / 2.0;  // around a cylinder of radius 2, axis along z
  c.k2 = 0;
  c.dir1 = Vec3(0, 1, 0);
  c.dir2 = Vec3(0, 0, 1);
  const Metric m = surface_curvature_metric(c, Vec3(1, 0, 0), rule, 1e-3, 5.0);
  const double l1 = curvature_length(0.5, rule);
  EXPECT_NEAR(metric_length(m, Vec3::Zero(), Vec3(0, l1, 0)), 1, 1e-12);
  EXPECT_NEAR(metric_length(m, Vec3::Zero(), Vec3(0, 0, 5.0)), 1, 1e-12);
  EXPECT_NEAR(metric_length(m, Vec3::Zero(), Vec3(l1, 0, 0)), 1, 1e-12);
}

TEST(Metric, IntersectionKeepsTheFinerSizeInEveryDirection) {
  EXPECT_TRUE(intersect(isotropic_metric(2), isotropic_metric(0.5)).isApprox(isotropic_metric(0.5), 1e-12));
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1, 1), s(0.1, 3);
  for (int trial = 0; trial < 200; ++trial) {
    const Mat3 qa = Eigen::Quaterniond(Eigen::Vector4d(u(rng), u(rng), u(rng), u(rng)).normalized()).matrix();
    const Mat3 qb = Eigen::Quaterniond(Eigen::Vector4d(u(rng), u(rng), u(rng), u(rng)).normalized()).matrix();
    const Metric a = metric_from_sizes({qa.col(0), qa.col(1), qa.col(2)}, Vec3(s(rng), s(rng), s(rng)));
    const Metric b = metric_from_sizes({qb.col(0), qb.col(1), qb.col(2)}, Vec3(s(rng), s(rng), s(rng)));
    const Metric m = intersect(a, b);
    ASSERT_TRUE(is_metric(m));
    EXPECT_TRUE(m.isApprox(intersect(b, a), 1e-9));
    // Its unit ball lies in both: every vector is at least as long in m.
    for (int k = 0; k < 20; ++k) {
      const Vec3 e(u(rng), u(rng), u(rng));
      EXPECT_GE(e.dot(m * e), e.dot(a * e) * (1 - 1e-9));
      EXPECT_GE(e.dot(m * e), e.dot(b * e) * (1 - 1e-9));
    }
    // ... and it is the largest such ball: along the common conjugate
    // directions of a and b (generalized eigenvectors) it equals the finer.
    const Eigen::GeneralizedSelfAdjointEigenSolver<Mat3> ges(b, a);
    for (int i = 0; i < 3; ++i) {
      const Vec3 e = ges.eigenvectors().col(i);
      EXPECT_NEAR(e.dot(m * e), std::max(e.dot(a * e), e.dot(b * e)), 1e-9 * e.dot(m * e));
    }
  }
}

TEST(Metric, SizesAndLogEuclideanMean) {
  const Metric m = metric_from_sizes({Vec3(1, 1, 0), Vec3(-1, 1, 0), Vec3(0, 0, 1)}, Vec3(0.5, 2, 1));
  Mat3 dirs;
  const Vec3 sizes = metric_sizes(m, &dirs);
  EXPECT_NEAR(sizes[0], 0.5, 1e-12);
  EXPECT_NEAR(sizes[1], 1, 1e-12);
  EXPECT_NEAR(sizes[2], 2, 1e-12);
  EXPECT_NEAR(std::abs(dirs.col(0).dot(Vec3(1, 1, 0).normalized())), 1, 1e-12);
  EXPECT_NEAR(min_size(m), 0.5, 1e-12);
  const Metric a = isotropic_metric(1), b = isotropic_metric(4);
  const std::array<Metric, 2> ms{a, b};
  const std::array<double, 2> w{0.5, 0.5};
  EXPECT_NEAR(min_size(interpolate(ms, w)), 2, 1e-12);  // geometric mean of the sizes
  EXPECT_FALSE(is_metric(-isotropic_metric(1)));
  EXPECT_THROW(isotropic_metric(0), std::invalid_argument);
}

TEST(SizeFields, MinAndClampCombineSources) {
  auto min = std::make_shared<MinSizeField>();
  min->add(std::make_shared<UniformSizeField>(1.0));
  min->add(std::make_shared<AnalyticSizeField>([](const Vec3& x) { return 0.1 + x.norm(); }));
  EXPECT_DOUBLE_EQ(min->size(Vec3(0.5, 0, 0)), 0.6);
  EXPECT_DOUBLE_EQ(min->size(Vec3(5, 0, 0)), 1.0);
  const ClampedSizeField clamped(min, 0.2, 0.8);
  EXPECT_DOUBLE_EQ(clamped.size(Vec3::Zero()), 0.2);
  EXPECT_DOUBLE_EQ(clamped.size(Vec3(5, 0, 0)), 0.8);
  const AnalyticSizeField bad([](const Vec3&) { return -1.0; });
  EXPECT_THROW(bad.size(Vec3::Zero()), std::domain_error);
}
