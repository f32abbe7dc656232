// Crossing triangles: the exact cases (crossing, shared edge, shared vertex,
// touching) and the grid broad phase against testing every pair.
#include <gtest/gtest.h>

#include <random>

#include "curvemesh/generate/surface_intersection.hpp"

using namespace cm;
using generate::crossing_triangles;

namespace {

std::size_t count(const std::vector<Vec3>& x, const std::vector<mesh::ClassifiedTri>& t) {
  return crossing_triangles(x, t).size();
}

}  // namespace

TEST(SurfaceIntersection, CrossingPairIsFound) {
  // A horizontal triangle pierced by a vertical one through its middle.
  const std::vector<Vec3> x{{0, 0, 0}, {2, 0, 0}, {0, 2, 0}, {0.5, 0.5, -1}, {0.6, 0.5, 1}, {0.5, 0.6, 1}};
  EXPECT_EQ(count(x, {{{0, 1, 2}, 1}, {{3, 4, 5}, 2}}), 1u);
  // The same vertical triangle lifted above the plane does not cross.
  auto y = x;
  for (int i = 3; i < 6; ++i) y[i].z() += 1.5;
  EXPECT_EQ(count(y, {{{0, 1, 2}, 1}, {{3, 4, 5}, 2}}), 0u);
}

TEST(SurfaceIntersection, SharedEdgeIsNeverReported) {
  // Two triangles on one edge folded onto each other.
  const std::vector<Vec3> x{{0, 0, 0}, {1, 0, 0}, {0.5, 1, 0}, {0.5, 0.8, 1e-9}};
  EXPECT_EQ(count(x, {{{0, 1, 2}, 1}, {{1, 0, 3}, 1}}), 0u);
}

TEST(SurfaceIntersection, SharedVertexCrossesOnlyThroughTheOppositeEdge) {
  // Both triangles at the origin; the second one's far edge pierces the first.
  const std::vector<Vec3> x{{0, 0, 0}, {2, 0, 0}, {0, 2, 0}, {0.5, 0.5, -1}, {0.5, 0.5, 1}};
  EXPECT_EQ(count(x, {{{0, 1, 2}, 1}, {{0, 3, 4}, 2}}), 1u);
  // Fanning out of the plane from the shared vertex: no crossing.
  const std::vector<Vec3> y{{0, 0, 0}, {2, 0, 0}, {0, 2, 0}, {0.5, 0.5, 1}, {0.4, 0.6, 2}};
  EXPECT_EQ(count(y, {{{0, 1, 2}, 1}, {{0, 3, 4}, 2}}), 0u);
}

TEST(SurfaceIntersection, TouchingIsNotCrossing) {
  // A vertex of the second triangle lies exactly on the first one.
  const std::vector<Vec3> x{{0, 0, 0}, {2, 0, 0}, {0, 2, 0}, {0.5, 0.5, 0}, {0.5, 0.5, 1}, {0.6, 0.4, 1}};
  EXPECT_EQ(count(x, {{{0, 1, 2}, 1}, {{3, 4, 5}, 2}}), 0u);
}

TEST(SurfaceIntersection, GridFindsExactlyThePairsOfTheBruteForce) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> pos(0, 10), off(-0.6, 0.6);
  std::vector<Vec3> x;
  std::vector<mesh::ClassifiedTri> tris;
  for (std::uint32_t i = 0; i < 600; ++i) {
    const Vec3 c(pos(rng), pos(rng), pos(rng));
    for (int k = 0; k < 3; ++k) x.push_back(c + Vec3(off(rng), off(rng), off(rng)));
    tris.push_back({{3 * i, 3 * i + 1, 3 * i + 2}, 1});
  }
  // A few huge triangles spanning many cells.
  for (std::uint32_t i = 0; i < 3; ++i) {
    const auto b = static_cast<VertId>(x.size());
    x.push_back({pos(rng), 0, pos(rng)});
    x.push_back({pos(rng), 10, pos(rng)});
    x.push_back({10, pos(rng), pos(rng)});
    tris.push_back({{b, b + 1, b + 2}, 2});
  }
  std::vector<std::array<std::uint32_t, 2>> brute;
  for (std::uint32_t i = 0; i < tris.size(); ++i)
    for (std::uint32_t j = i + 1; j < tris.size(); ++j)
      if (!crossing_triangles(x, std::vector<mesh::ClassifiedTri>{tris[i], tris[j]}).empty()) brute.push_back({i, j});
  ASSERT_GT(brute.size(), 10u);  // the set must exercise the broad phase
  EXPECT_EQ(crossing_triangles(x, tris), brute);
}
