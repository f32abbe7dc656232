// classify_point of the analytic solids against their own implicit
// descriptions (analytic_test_support.hpp): random points, the tolerance band
// around every face, the volume seen by Monte Carlo, errors and concurrency.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>
#include <stdexcept>
#include <thread>

#include "analytic_test_support.hpp"

namespace cm::geom {
namespace {

using namespace test_support;

BoundingBox padded_box(const Model& m) {
  BoundingBox b = m.bounding_box();
  const Vec3 pad = 0.2 * b.size();
  b.min -= pad;
  b.max += pad;
  return b;
}

// Distance of p to the nearest face, as the support's residuals measure it.
double boundary_residual(const Case& c, const Vec3& p) {
  double r = std::numeric_limits<double>::infinity();
  for (int f = 1; f <= c.model->count(2); ++f) r = std::min(r, c.residual({2, f}, p));
  return r;
}

TEST(AnalyticClassify, RandomPointsAgreeWithTheImplicitSolid) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> unit(0, 1);
  for (const Case& c : all_cases()) {
    SCOPED_TRACE(c.name);
    const BoundingBox b = padded_box(*c.model);
    int inside = 0;
    for (int i = 0; i < 20000; ++i) {
      const Vec3 p = b.min + Vec3(unit(rng), unit(rng), unit(rng)).cwiseProduct(b.size());
      const Containment got = c.model->classify_point(1, p);
      if (got == Containment::kOn) {
        EXPECT_LE(boundary_residual(c, p), 2 * c.model->tolerance({3, 1})) << p.transpose();
        continue;
      }
      EXPECT_EQ(got == Containment::kInside, c.inside(p)) << p.transpose();
      inside += got == Containment::kInside;
    }
    EXPECT_GT(inside, 100);  // the box is not mostly empty
    for (const Vec3& p : c.special_probes) {
      const Containment got = c.model->classify_point(1, p);
      if (got != Containment::kOn) {
        EXPECT_EQ(got == Containment::kInside, c.inside(p)) << p.transpose();
      }
    }
  }
}

// Every face, away from its edges: the point itself and points within the
// tolerance along the normal are on; a few tolerances out or in are not.
TEST(AnalyticClassify, TheToleranceBandAroundEveryFaceIsOn) {
  for (const Case& c : all_cases()) {
    SCOPED_TRACE(c.name);
    const double tol = c.model->tolerance({3, 1});
    const double step = 1e-6 * c.scale;
    int checked = 0;
    for (int f = 1; f <= c.model->count(2); ++f) {
      for (const Vec2& uv : face_samples(*c.model, f, 12)) {
        const Vec3 p = c.model->face_point(f, uv);
        // Near an edge, a step along one face's normal may slide along the
        // neighbouring face (a cylinder's rim) and stay on the boundary.
        double to_edge = std::numeric_limits<double>::infinity();
        for (int e = 1; e <= c.model->count(1); ++e)
          to_edge = std::min(to_edge, c.model->closest_point({1, e}, p).distance);
        if (to_edge < 100 * step) continue;
        // Poles and seams have a normal too: face_normal extends it.
        const Vec3 n = c.model->face_normal(f, uv);
        EXPECT_EQ(c.model->classify_point(1, p), Containment::kOn);
        EXPECT_EQ(c.model->classify_point(1, p + 0.5 * tol * n), Containment::kOn);
        EXPECT_EQ(c.model->classify_point(1, p - 0.5 * tol * n), Containment::kOn);
        EXPECT_EQ(c.model->classify_point(1, p + 3 * tol * n), Containment::kOutside);
        EXPECT_EQ(c.model->classify_point(1, p - 3 * tol * n), Containment::kInside);
        EXPECT_EQ(c.model->classify_point(1, p + step * n), Containment::kOutside);
        EXPECT_EQ(c.model->classify_point(1, p - step * n), Containment::kInside);
        ++checked;
      }
    }
    EXPECT_GT(checked, 50);
  }
}

TEST(AnalyticClassify, EdgesAndVerticesAreOn) {
  for (const Case& c : all_cases()) {
    SCOPED_TRACE(c.name);
    for (int v = 1; v <= c.model->count(0); ++v)
      EXPECT_EQ(c.model->classify_point(1, c.model->vertex_point(v)), Containment::kOn);
    for (int e = 1; e <= c.model->count(1); ++e)
      for (const double t : edge_samples(*c.model, e, 16))
        EXPECT_EQ(c.model->classify_point(1, c.model->edge_point(e, t)), Containment::kOn);
  }
}

// Monte Carlo volume: the inside fraction of uniform points in the box times
// its volume estimates the solid's volume with standard deviation
// V_box·sqrt(p(1−p)/N); the closed-form volume must be within 4 of them.
TEST(AnalyticClassify, InsideFractionGivesTheVolume) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> unit(0, 1);
  constexpr int kSamples = 200000;
  for (const Case& c : all_cases()) {
    SCOPED_TRACE(c.name);
    const BoundingBox b = c.model->bounding_box();
    const double box_volume = b.size().prod();
    int inside = 0;
    for (int i = 0; i < kSamples; ++i) {
      const Vec3 p = b.min + Vec3(unit(rng), unit(rng), unit(rng)).cwiseProduct(b.size());
      inside += c.model->classify_point(1, p) != Containment::kOutside;
    }
    const double fraction = double(inside) / kSamples;
    const double sigma = box_volume * std::sqrt(fraction * (1 - fraction) / kSamples);
    EXPECT_NEAR(fraction * box_volume, c.model->volume(1), 4 * sigma);
  }
}

TEST(AnalyticClassify, BadRegionsAndPointsThrow) {
  for (const Case& c : all_cases()) {
    SCOPED_TRACE(c.name);
    EXPECT_THROW(c.model->classify_point(0, Vec3::Zero()), std::out_of_range);
    EXPECT_THROW(c.model->classify_point(2, Vec3::Zero()), std::out_of_range);
    EXPECT_THROW(c.model->classify_point(1, Vec3(std::nan(""), 0, 0)), std::invalid_argument);
    EXPECT_THROW(c.model->classify_point(1, Vec3(0, std::numeric_limits<double>::infinity(), 0)),
                 std::invalid_argument);
  }
}

TEST(AnalyticClassify, ConcurrentCallsGiveTheSerialAnswers) {
  for (const Case& c : all_cases()) {
    SCOPED_TRACE(c.name);
    const BoundingBox b = padded_box(*c.model);
    std::vector<Vec3> probes;
    std::mt19937 rng(9);
    std::uniform_real_distribution<double> unit(0, 1);
    for (int i = 0; i < 4000; ++i) probes.push_back(b.min + Vec3(unit(rng), unit(rng), unit(rng)).cwiseProduct(b.size()));
    const auto run = [&] {
      std::vector<Containment> out;
      for (const Vec3& p : probes) out.push_back(c.model->classify_point(1, p));
      return out;
    };
    const std::vector<Containment> serial = run();
    std::vector<std::vector<Containment>> results(4);
    std::vector<std::thread> threads;
    for (auto& r : results) threads.emplace_back([&] { r = run(); });
    for (std::thread& t : threads) t.join();
    for (const auto& r : results) EXPECT_TRUE(r == serial);
  }
}

}  // namespace
}  // namespace cm::geom
