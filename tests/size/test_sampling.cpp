// Curvature sampling of faces and edges (seed §4, Fig. 4.1).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "bump_model.hpp"
#include "curvemesh/geom/analytic_model.hpp"
#include "curvemesh/size/sampling.hpp"

using namespace cm;
using namespace cm::size;

namespace {

double largest_curvature(const std::vector<SizeSample>& samples) {
  double k = 0;
  for (const auto& s : samples) k = std::max({k, std::abs(s.k1), std::abs(s.k2)});
  return k;
}

SamplingOptions fixed_grid(int cells, bool centroids) {
  SamplingOptions o;
  o.rule = CurvatureRule::relative_deviation(0.05);
  o.hmin = 1e-6;
  o.hmax = 1e9;  // keep every sample
  o.grid_cells = cells;
  o.centroids = centroids;
  o.adaptive = false;
  return o;
}

}  // namespace

TEST(CurvatureSampling, CentroidsFindANarrowPeakThatCornersAloneMissAtTheSameCount) {
  // Peak at the centre of the face: for an odd number of cells it is a cell
  // centroid, never a corner of any grid with an odd cell count.
  const test::BumpModel bump(0.01, 0.005, Vec2(0.5, 0.5));
  const double peak = bump.peak_curvature();

  SamplingStats with_centroids, corners_only;
  const auto a = sample_face_curvature(bump, 1, fixed_grid(9, true), &with_centroids);
  const auto b = sample_face_curvature(bump, 1, fixed_grid(13, false), &corners_only);
  // The corner-only grid even gets more samples: 14² = 196 >= 10² + 9² = 181.
  EXPECT_EQ(with_centroids.evaluations, 181u);
  EXPECT_EQ(corners_only.evaluations, 196u);
  EXPECT_NEAR(largest_curvature(a), peak, 1e-6 * peak);
  EXPECT_LT(largest_curvature(b), 1e-3 * peak) << "the corner grid should not see the peak";
}

TEST(CurvatureSampling, SubdivisionResolvesAPeakItsGridOnlyGlimpses) {
  const test::BumpModel bump(0.02, 0.03, Vec2(0.4137, 0.6071));
  const double peak = bump.peak_curvature();
  SamplingOptions o = fixed_grid(8, true);
  o.hmax = 0.2;
  o.hmin = 1e-4;
  o.adaptive = true;
  SamplingStats st;
  const auto samples = sample_face_curvature(bump, 1, o, &st);
  EXPECT_GT(st.subdivided, 0u);
  EXPECT_GT(largest_curvature(samples), 0.9 * peak);
  o.adaptive = false;
  EXPECT_LT(largest_curvature(sample_face_curvature(bump, 1, o)), 0.9 * peak);
}

TEST(CurvatureSampling, SphereSamplesAskForEquation43Everywhere) {
  const double radius = 2, eps = 0.01;
  const auto sphere = geom::make_analytic_sphere(Vec3(1, 2, 3), radius);
  SamplingOptions o;
  o.rule = CurvatureRule::chord_deviation(eps);
  o.hmax = 1.0;
  o.hmin = 1e-3;
  SamplingStats st;
  const auto samples = sample_model_curvature(*sphere, o, &st);
  ASSERT_FALSE(samples.empty());
  const double expect = std::sqrt(8 * radius * eps - 4 * eps * eps);
  std::size_t on_face = 0;
  for (const auto& s : samples) {
    EXPECT_NEAR((s.point - Vec3(1, 2, 3)).norm(), radius, 1e-9);
    if (s.source != SizeSource::kFaceCurvature) continue;
    ++on_face;
    EXPECT_NEAR(s.size, expect, 1e-9 * expect);
  }
  EXPECT_GT(on_face, 100u);
  // The grid is refined until cells are no larger than the size asked.
  EXPECT_GT(st.subdivided, 0u);
  EXPECT_GT(st.revisited, 0u) << "shared corners are evaluated once";
}

TEST(CurvatureSampling, CylinderCapEdgesAreRefinedByTheirOwnCurvature) {
  const auto cyl = geom::make_analytic_cylinder(Vec3::Zero(), Vec3::UnitZ(), 1.5, 4);
  SamplingOptions o;
  o.rule = CurvatureRule::relative_deviation(0.05);
  o.hmax = 10;
  o.hmin = 1e-3;
  const auto samples = sample_model_curvature(*cyl, o);
  const double expect = 8 * 1.5 * 0.05 / (1 + 4 * 0.05 * 0.05);
  std::size_t on_edges = 0;
  for (const auto& s : samples) {
    if (s.source == SizeSource::kEdgeCurvature && cyl->type({1, s.entity.tag}) == geom::ShapeType::kCircle) {
      ++on_edges;
      EXPECT_NEAR(s.size, expect, 1e-9);
    }
    // Planar caps ask for nothing: no face sample comes from them.
    if (s.source == SizeSource::kFaceCurvature) {
      EXPECT_EQ(cyl->type({2, s.entity.tag}), geom::ShapeType::kCylinder);
    }
  }
  EXPECT_GT(on_edges, 8u);
}

TEST(CurvatureSampling, EntitySizeCoversTheEntity) {
  const auto cyl = geom::make_analytic_cylinder(Vec3::Zero(), Vec3::UnitZ(), 1, 2);
  const auto samples = sample_entity_size(*cyl, {2, 1}, 0.2);
  ASSERT_FALSE(samples.empty());
  for (const auto& s : samples) EXPECT_EQ(s.size, 0.2);
  // Every point of the face is within h/2 of a sample (probe a fine grid).
  const auto pr = cyl->param_range({2, 1});
  for (int i = 0; i <= 40; ++i)
    for (int j = 0; j <= 40; ++j) {
      const Vec3 x = cyl->face_point(1, Vec2(pr.u0 + (pr.u1 - pr.u0) * i / 40, pr.v0 + (pr.v1 - pr.v0) * j / 40));
      double d = 1e9;
      for (const auto& s : samples) d = std::min(d, (s.point - x).norm());
      EXPECT_LE(d, 0.1 + 1e-9);
    }
  EXPECT_THROW(sample_entity_size(*cyl, {4, 1}, 0.2), std::invalid_argument);
}

TEST(CurvatureSampling, RegionSizeCoversEveryBoundingFaceOnce) {
  const auto cyl = geom::make_analytic_cylinder(Vec3::Zero(), Vec3::UnitZ(), 1, 2);
  const auto samples = sample_entity_size(*cyl, {3, 1}, 0.2);
  // The boundary only (the interior is the size field's business), each
  // sample on the face or edge it names.
  for (const auto& s : samples) {
    EXPECT_EQ(s.size, 0.2);
    EXPECT_EQ(s.source, SizeSource::kEntitySize);
    ASSERT_TRUE(s.entity.dim == 1 || s.entity.dim == 2);
    EXPECT_LT(cyl->closest_point(s.entity, s.point).distance, 1e-9);
  }
  for (int face = 1; face <= 3; ++face) {
    const auto pr = cyl->param_range({2, face});
    for (int i = 0; i <= 20; ++i)
      for (int j = 0; j <= 20; ++j) {
        const Vec2 uv(pr.u0 + (pr.u1 - pr.u0) * i / 20, pr.v0 + (pr.v1 - pr.v0) * j / 20);
        if (!cyl->contains_param(face, uv)) continue;
        const Vec3 x = cyl->face_point(face, uv);
        double d = 1e9;
        for (const auto& s : samples) d = std::min(d, (s.point - x).norm());
        EXPECT_LE(d, 0.1 + 1e-9) << "face " << face;
      }
  }
  // Each face and edge sampled once: no two samples coincide except where
  // a face's grid meets its own boundary or a closed edge meets itself.
  std::size_t on_faces = 0;
  for (int face = 1; face <= 3; ++face) on_faces += sample_entity_size(*cyl, {2, face}, 0.2).size();
  EXPECT_LT(samples.size(), on_faces);
  EXPECT_THROW(sample_entity_size(*cyl, {3, 2}, 0.2), std::out_of_range);
}

TEST(CurvatureSampling, PlanesAndLinesAreNotEvaluated) {
  const auto cyl = geom::make_analytic_cylinder(Vec3::Zero(), Vec3::UnitZ(), 1, 2);
  SamplingOptions o;
  o.rule = CurvatureRule::relative_deviation(0.05);
  o.hmin = 1e-3;
  o.hmax = 0.5;
  int planes = 0;
  for (int f = 1; f <= cyl->count(2); ++f) {
    SamplingStats st;
    const auto samples = sample_face_curvature(*cyl, f, o, &st);
    if (cyl->type({2, f}) == geom::ShapeType::kPlane) {
      ++planes;
      EXPECT_TRUE(samples.empty());
      EXPECT_EQ(st.evaluations + st.outside, 0u);
    } else {
      EXPECT_FALSE(samples.empty());
    }
  }
  EXPECT_EQ(planes, 2);
  for (int e = 1; e <= cyl->count(1); ++e) {
    SamplingStats st;
    const auto samples = sample_edge_curvature(*cyl, e, o, &st);
    if (cyl->type({1, e}) == geom::ShapeType::kLine) {
      EXPECT_EQ(st.evaluations, 0u);
    } else if (cyl->type({1, e}) == geom::ShapeType::kCircle) {
      EXPECT_FALSE(samples.empty());
    }
  }
}
