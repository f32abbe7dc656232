// TriangleClassifier (the fast tiers of OccModel::classify_point) on a unit
// cube of 12 triangles: parity, rays through vertices, bands, nearest
// triangle and the "only this face nearby" test.
#include <array>
#include <vector>

#include <gtest/gtest.h>

#include "curvemesh/geom_occ/detail/triangle_classifier.hpp"

namespace cm::geom_occ::detail {
namespace {

using Triangle = TriangleClassifier::Triangle;

// Faces 1..6: x = 0, x = 1, y = 0, y = 1, z = 0, z = 1, two triangles each.
std::vector<Triangle> cube(double band) {
  std::vector<Triangle> out;
  for (int axis = 0; axis < 3; ++axis)
    for (int side = 0; side < 2; ++side) {
      const int u = (axis + 1) % 3, v = (axis + 2) % 3;
      std::array<Vec3, 4> q;
      for (int k = 0; k < 4; ++k) {
        q[k][axis] = side;
        q[k][u] = (k == 1 || k == 2) ? 1 : 0;
        q[k][v] = (k >= 2) ? 1 : 0;
      }
      const int face = 1 + 2 * axis + side;
      out.push_back({{q[0], q[1], q[2]}, band, face});
      out.push_back({{q[0], q[2], q[3]}, band, face});
    }
  return out;
}

TEST(TriangleClassifier, ParityTellsInsideFromOutside) {
  const TriangleClassifier c(cube(0.01));
  EXPECT_EQ(c.size(), 12u);
  EXPECT_EQ(c.inside(Vec3(0.5, 0.5, 0.5)), std::optional<bool>(true));
  EXPECT_EQ(c.inside(Vec3(0.1, 0.9, 0.2)), std::optional<bool>(true));
  EXPECT_EQ(c.inside(Vec3(1.5, 0.5, 0.5)), std::optional<bool>(false));
  EXPECT_EQ(c.inside(Vec3(-3, -3, -3)), std::optional<bool>(false));
  EXPECT_EQ(c.inside(Vec3(0.5, 0.5, 7)), std::optional<bool>(false));
  // Below the cube, some rays cross it twice, others miss it.
  EXPECT_EQ(c.inside(Vec3(0.5, 0.5, -0.5)), std::optional<bool>(false));
}

// A ray aimed exactly at a vertex (or along a diagonal edge shared by two
// triangles) is unreliable; the others still decide.
TEST(TriangleClassifier, RaysThroughVerticesAndDiagonalsAreOutvoted) {
  const TriangleClassifier c(cube(0.01));
  const Vec3 first_ray = Vec3(0.8234, 0.4471, 0.3497).normalized();
  for (const Vec3& target : {Vec3(1, 1, 1), Vec3(1, 0.5, 0.5), Vec3(0.5, 0.5, 1)}) {
    EXPECT_EQ(c.inside(target - 0.3 * first_ray), std::optional<bool>(true)) << target.transpose();
    EXPECT_EQ(c.inside(target - 3.0 * first_ray), std::optional<bool>(false)) << target.transpose();
  }
}

TEST(TriangleClassifier, BandNearestAndNeighbouringFaces) {
  const TriangleClassifier c(cube(0.1));
  EXPECT_TRUE(c.in_band(Vec3(0.5, 0.5, 1.05)));
  EXPECT_TRUE(c.in_band(Vec3(0.5, 0.5, 0.95)));
  EXPECT_FALSE(c.in_band(Vec3(0.5, 0.5, 1.2)));
  EXPECT_FALSE(c.in_band(Vec3(0.5, 0.5, 0.5)));
  EXPECT_TRUE(c.in_band(Vec3(1.05, 1.05, 0.5)));  // near an edge: two faces' bands

  const auto n = c.nearest(Vec3(0.3, 0.6, 1.4));
  ASSERT_TRUE(n);
  EXPECT_EQ(n->triangle->face, 6);
  EXPECT_NEAR(n->distance, 0.4, 1e-15);
  const Vec3 foot = n->barycentric[0] * n->triangle->corners[0] + n->barycentric[1] * n->triangle->corners[1] +
                    n->barycentric[2] * n->triangle->corners[2];
  EXPECT_NEAR((foot - Vec3(0.3, 0.6, 1)).norm(), 0, 1e-15);
  EXPECT_NEAR(n->barycentric.sum(), 1, 1e-15);
  // Outside a corner: the corner is nearest.
  EXPECT_NEAR(c.nearest(Vec3(2, 2, 2))->distance, std::sqrt(3.0), 1e-15);

  // Near the middle of the top face only it is within reach; near its edge
  // with x = 1 that face reaches too (its band widens the ball).
  const auto faces_near = [&](const Vec3& x, double radius) {
    std::vector<int> faces;
    for (const auto& f : c.faces_within(x, radius, 6)) faces.push_back(f.triangle->face);
    return faces;
  };
  EXPECT_EQ(faces_near(Vec3(0.5, 0.5, 1.05), 0.05), std::vector<int>{6});
  EXPECT_EQ(faces_near(Vec3(0.85, 0.5, 1.05), 0.1), (std::vector<int>{2, 6}));
  EXPECT_EQ(faces_near(Vec3(0.7, 0.5, 1.05), 0.1), std::vector<int>{6});
  EXPECT_EQ(faces_near(Vec3(0.95, 0.95, 0.95), 0.1), (std::vector<int>{2, 4, 6}));
  EXPECT_EQ(c.faces_within(Vec3(0.5, 0.5, 0.5), 1, 3).size(), 4u);  // stops after more than 3
  // Each face's nearest triangle and the foot on it.
  for (const auto& f : c.faces_within(Vec3(0.85, 0.5, 1.05), 0.1, 6)) {
    const Vec3 on = f.barycentric[0] * f.triangle->corners[0] + f.barycentric[1] * f.triangle->corners[1] +
                    f.barycentric[2] * f.triangle->corners[2];
    EXPECT_NEAR((Vec3(0.85, 0.5, 1.05) - on).norm(), f.distance, 1e-15);
    EXPECT_NEAR(f.distance, f.triangle->face == 6 ? 0.05 : std::hypot(0.15, 0.05), 1e-15);
  }
}

TEST(TriangleClassifier, EmptySurfaceAnswersNothing) {
  const TriangleClassifier c({});
  EXPECT_TRUE(c.empty());
  EXPECT_FALSE(c.in_band(Vec3::Zero()));
  EXPECT_FALSE(c.nearest(Vec3::Zero()));
  EXPECT_FALSE(c.inside(Vec3::Zero()));
}

// A larger surface: a finely split cube exercises the hierarchy's inner
// nodes; answers match the unsplit one.
TEST(TriangleClassifier, HierarchyGivesTheSameAnswersAsFewTriangles) {
  std::vector<Triangle> fine;
  constexpr int kSplit = 16;
  for (const Triangle& t : cube(0.01)) {
    // Each triangle into kSplit² smaller ones (midpoint-free barycentric grid).
    for (int i = 0; i < kSplit; ++i)
      for (int j = 0; i + j < kSplit; ++j) {
        const auto at = [&](double a, double b) {
          return t.corners[0] + a / kSplit * (t.corners[1] - t.corners[0]) + b / kSplit * (t.corners[2] - t.corners[0]);
        };
        fine.push_back({{at(i, j), at(i + 1, j), at(i, j + 1)}, t.band, t.face});
        if (i + j + 1 < kSplit) fine.push_back({{at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)}, t.band, t.face});
      }
  }
  const TriangleClassifier coarse(cube(0.01)), split(std::move(fine));
  EXPECT_EQ(split.size(), 12u * kSplit * kSplit);
  for (int i = 0; i < 400; ++i) {
    const Vec3 x(-0.5 + 2.0 * ((i * 37) % 101) / 101.0, -0.5 + 2.0 * ((i * 53) % 103) / 103.0,
                 -0.5 + 2.0 * ((i * 71) % 107) / 107.0);
    EXPECT_EQ(split.in_band(x), coarse.in_band(x)) << x.transpose();
    EXPECT_NEAR(split.nearest(x)->distance, coarse.nearest(x)->distance, 1e-12) << x.transpose();
    if (coarse.in_band(x)) continue;
    const std::optional<bool> a = coarse.inside(x), b = split.inside(x);
    ASSERT_TRUE(a && b) << x.transpose();
    EXPECT_EQ(*a, *b) << x.transpose();
  }
}

}  // namespace
}  // namespace cm::geom_occ::detail
