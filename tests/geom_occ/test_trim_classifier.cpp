// TrimClassifier (the fast path of OccModel::contains_param): parity on a
// square with a hole, the band, points on the ray through polygon vertices,
// and random star-shaped loops against a brute-force crossing count.
#include <cmath>
#include <numbers>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "curvemesh/geom_occ/detail/trim_classifier.hpp"

namespace cm::geom_occ::detail {
namespace {

std::vector<Vec2> square(double lo, double hi) { return {{lo, lo}, {hi, lo}, {hi, hi}, {lo, hi}}; }

// Even-odd parity over every segment, with no grid.
bool brute_inside(const std::vector<std::vector<Vec2>>& loops, const Vec2& p) {
  bool in = false;
  for (const auto& l : loops)
    for (std::size_t k = 0; k < l.size(); ++k) {
      const Vec2 a = l[k], b = l[(k + 1) % l.size()];
      if ((a.y() > p.y()) == (b.y() > p.y())) continue;
      if (a.x() + (p.y() - a.y()) * (b.x() - a.x()) / (b.y() - a.y()) > p.x()) in = !in;
    }
  return in;
}

double distance_to_loops(const std::vector<std::vector<Vec2>>& loops, const Vec2& p) {
  double d = INFINITY;
  for (const auto& l : loops)
    for (std::size_t k = 0; k < l.size(); ++k) {
      const Vec2 a = l[k], ab = l[(k + 1) % l.size()] - a;
      const double t = std::clamp((p - a).dot(ab) / ab.squaredNorm(), 0.0, 1.0);
      d = std::min(d, (p - (a + t * ab)).norm());
    }
  return d;
}

TEST(TrimClassifier, SquareWithAHole) {
  const TrimClassifier c({square(0, 4), square(1, 2)}, 0.01);
  EXPECT_EQ(c.segments(), 8u);
  EXPECT_EQ(c.inside({0.5, 0.5}), true);
  EXPECT_EQ(c.inside({3, 3}), true);
  EXPECT_EQ(c.inside({1.5, 1.5}), false);  // in the hole
  EXPECT_EQ(c.inside({5, 1.5}), false);    // right of everything
  EXPECT_EQ(c.inside({-1, 1.5}), false);   // left: the ray crosses four edges
  EXPECT_EQ(c.inside({100, -100}), false);  // outside the box
  // Within the band of an edge or a corner: undecided.
  EXPECT_EQ(c.inside({4.005, 2}), std::nullopt);
  EXPECT_EQ(c.inside({1, 1.005}), std::nullopt);
  EXPECT_EQ(c.inside({2.007, 2.007}), std::nullopt);
  EXPECT_EQ(c.inside({2.02, 2.02}), true);
}

TEST(TrimClassifier, RayThroughPolygonVerticesCountsEachCrossingOnce) {
  // A diamond: the ray from (-1, 0) passes exactly through vertices (0, 0)
  // and (2, 0), from (1, 0) through (2, 0) only.
  const TrimClassifier c({{{0, 0}, {1, -1}, {2, 0}, {1, 1}}}, 1e-9);
  EXPECT_EQ(c.inside({-1, 0}), false);
  EXPECT_EQ(c.inside({1, 0}), true);
  EXPECT_EQ(c.inside({3, 0}), false);
  // A loop touching the ray's line at a vertex from one side.
  const TrimClassifier w({{{0, 0}, {2, 0}, {2, 2}, {1, 1}, {0, 2}}}, 1e-9);
  EXPECT_EQ(w.inside({0.5, 1}), true);
  EXPECT_EQ(w.inside({-1, 1}), false);
  EXPECT_EQ(w.inside({1, 1.5}), false);
}

TEST(TrimClassifier, RandomStarLoopsAgreeWithBruteForceOutsideTheBand) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> unit(0, 1);
  int decided = 0, undecided = 0;
  for (int trial = 0; trial < 20; ++trial) {
    std::vector<std::vector<Vec2>> loops;
    // An outer star and two small star holes, each of many vertices.
    for (int l = 0; l < 3; ++l) {
      const Vec2 centre = l == 0 ? Vec2(0, 0) : Vec2(l == 1 ? -0.4 : 0.4, 0.1);
      const double radius = l == 0 ? 1.0 : 0.2;
      const int n = 20 + static_cast<int>(unit(rng) * 300);
      std::vector<Vec2> loop;
      for (int k = 0; k < n; ++k) {
        const double a = 2 * std::numbers::pi * k / n;
        const double r = radius * (0.6 + 0.4 * unit(rng));
        loop.push_back(centre + r * Vec2(std::cos(a), std::sin(a)));
      }
      loops.push_back(loop);
    }
    const double band = 1e-3;
    const TrimClassifier c(loops, band);
    for (int i = 0; i < 2000; ++i) {
      const Vec2 p(-1.2 + 2.4 * unit(rng), -1.2 + 2.4 * unit(rng));
      const auto got = c.inside(p);
      const double d = distance_to_loops(loops, p);
      if (!got) {
        ++undecided;
        EXPECT_LE(d, band * (1 + 1e-12));
        continue;
      }
      ++decided;
      EXPECT_GT(d, band);
      ASSERT_EQ(*got, brute_inside(loops, p)) << "trial " << trial << " at (" << p.x() << ", " << p.y() << ")";
    }
  }
  EXPECT_GT(decided, 39000);
  EXPECT_GT(undecided, 0);
}

TEST(TrimClassifier, NoLoopsDecideNothing) {
  const TrimClassifier c({}, 0.1);
  EXPECT_TRUE(c.empty());
  EXPECT_EQ(c.inside({0, 0}), std::nullopt);
}

}  // namespace
}  // namespace cm::geom_occ::detail
