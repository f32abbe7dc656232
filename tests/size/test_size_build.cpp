// The assembled size field on models: the seed's formulas on the surface,
// planar faces at hmax, edge curvature, entity sizes, directional metric,
// background metric, and the octree invariants on real geometry.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>

#include "curvemesh/geom/analytic_model.hpp"
#include "curvemesh/geom_occ/load.hpp"
#include "curvemesh/mesh/structured.hpp"
#include "curvemesh/size/background_field.hpp"
#include "curvemesh/size/build.hpp"

using namespace cm;
using namespace cm::size;

namespace {

SizeHint on_face(const geom::Model& m, int face, const Vec3& x, Vec3* foot = nullptr) {
  const geom::Projection p = m.closest_point({2, face}, x);
  if (foot) *foot = p.point;
  return {{2, face}, p.param};
}

void expect_graded(const SizeOctree& tree) {
  const auto leaves = tree.leaves();
  const double rate = tree.options().hgrad - 1;
  for (const auto& [a, b] : tree.face_neighbours()) {
    const Vec3 ca = leaves[a].lo + Vec3::Constant(0.5 * leaves[a].side);
    const Vec3 cb = leaves[b].lo + Vec3::Constant(0.5 * leaves[b].side);
    ASSERT_LE(std::abs(tree.size(ca) - tree.size(cb)), rate * (ca - cb).norm() * (1 + 1e-9));
    ASSERT_LE(std::abs(leaves[a].level - leaves[b].level), 1);
  }
}

}  // namespace

TEST(SizeBuild, SphereSurfaceSizeIsEquation43AndEquation45) {
  const double radius = 2;
  const auto sphere = geom::make_analytic_sphere(Vec3::Zero(), radius);
  std::mt19937 rng(1);
  std::normal_distribution<double> g;
  for (const bool relative : {false, true}) {
    SizeOptions o;
    o.hmax = 1;
    o.hmin = 1e-3;
    o.curvature = relative ? CurvatureRule::relative_deviation(0.05) : CurvatureRule::chord_deviation(0.01);
    const double expect = relative ? 8 * radius * 0.05 / (1 + 4 * 0.05 * 0.05)
                                   : std::sqrt(8 * radius * 0.01 - 4 * 0.01 * 0.01);
    const SizeFieldResult r = build_size_field(*sphere, o);
    for (int i = 0; i < 300; ++i) {
      const Vec3 dir = Vec3(g(rng), g(rng), g(rng)).normalized();
      Vec3 x;
      const SizeHint hint = on_face(*sphere, 1, radius * dir, &x);
      EXPECT_NEAR(r.field->size(x, hint), expect, 1e-6 * expect);
      // Without a hint the octree answers: never below the formula (the
      // sphere asks for nothing smaller), at most one gradation step above.
      const double h = r.field->size(x);
      EXPECT_GE(h, expect * (1 - 1e-9));
      EXPECT_LE(h, expect * 1.35);
    }
    for (const auto& s : r.samples) EXPECT_LE(r.octree->size(s.point), s.size * (1 + 1e-9));
    // Far outside the sphere, gradation has brought sizes back to hmax.
    EXPECT_NEAR(r.field->size(Vec3(1e3, 0, 0)), r.octree->size(Vec3(1e3, 0, 0)), 1e-12);
    expect_graded(*r.octree);
  }
}

TEST(SizeBuild, TorusInnerEquatorIsFinerByTheFormulasRatio) {
  // R = 3, r = 2: on the inner equator |κ|max = 1/(R − r) = 1, on the outer
  // 1/r = 1/2, so the radii entering eqs. 4.3/4.5 are 1 and 2.
  const auto torus = geom::make_analytic_torus(Vec3::Zero(), Vec3::UnitZ(), 3, 2);
  for (const bool relative : {false, true}) {
    SizeOptions o;
    o.hmax = 2;
    o.hmin = 1e-3;
    o.curvature = relative ? CurvatureRule::relative_deviation(0.05) : CurvatureRule::chord_deviation(0.02);
    const SizeFieldResult r = build_size_field(*torus, o);
    const double ratio = relative ? 0.5 : std::sqrt((8 * 1 * 0.02 - 4 * 0.02 * 0.02) / (8 * 2 * 0.02 - 4 * 0.02 * 0.02));
    for (const double angle : {0.0, 1.0, 2.5, 4.0}) {
      const Vec3 radial(std::cos(angle), std::sin(angle), 0);
      Vec3 inner, outer;
      const SizeHint hi = on_face(*torus, 1, 1.0 * radial, &inner);
      const SizeHint ho = on_face(*torus, 1, 5.0 * radial, &outer);
      EXPECT_NEAR(r.field->size(inner, hi) / r.field->size(outer, ho), ratio, 1e-9);
      EXPECT_LT(r.field->size(inner), r.field->size(outer));
    }
    expect_graded(*r.octree);
  }
}

TEST(SizeBuild, PlanarFacesGetHmax) {
  const auto box = geom_occ::load_model("builtin:box:dx=2,dy=1,dz=1");
  SizeOptions o;
  o.hmax = 0.3;
  o.hmin = 0.01;
  const SizeFieldResult r = build_size_field(*box, o);
  EXPECT_TRUE(r.samples.empty());
  std::mt19937 rng(2);
  std::uniform_real_distribution<double> u(0, 1);
  for (int i = 0; i < 500; ++i) {
    const Vec3 x(2 * u(rng), u(rng), u(rng));
    EXPECT_DOUBLE_EQ(r.field->size(x), 0.3);
    const int face = 1 + i % 6;
    Vec3 foot;
    const SizeHint hint = on_face(*box, face, x, &foot);
    EXPECT_DOUBLE_EQ(r.field->size(foot, hint), 0.3);
  }
}

TEST(SizeBuild, FlatCapsAreRefinedAlongTheirCurvedEdgesOnly) {
  const double radius = 2;
  const auto cyl = geom::make_analytic_cylinder(Vec3::Zero(), Vec3::UnitZ(), radius, 3);
  SizeOptions o;
  o.hmax = 1.5;
  o.hmin = 1e-3;
  o.hgrad = 1.2;
  o.curvature = CurvatureRule::relative_deviation(0.01);
  const SizeFieldResult r = build_size_field(*cyl, o);
  const double rim = 8 * radius * 0.01 / (1 + 4 * 0.01 * 0.01);
  // Near the rim of the bottom cap: the edge's curvature; at its centre the
  // rim size grown by gradation over the radius (at most), below hmax.
  EXPECT_LE(r.field->size(Vec3(radius * 0.999, 0, 0)), rim * 1.1);
  const double centre = r.field->size(Vec3(0, 0, 0));
  EXPECT_GT(centre, 2 * rim);
  EXPECT_LE(centre, rim + 0.2 * radius * 1.01);
  expect_graded(*r.octree);
}

TEST(SizeBuild, EntitySizeAppliesOnItsFaceAndSpreadsByGradation) {
  const auto cyl = geom::make_analytic_cylinder(Vec3::Zero(), Vec3::UnitZ(), 1, 2);
  SizeOptions o;
  o.hmax = 0.5;
  o.hmin = 1e-3;
  o.curvature = CurvatureRule::off();
  int cap = 0;
  for (int f = 1; f <= cyl->count(2); ++f)
    if (cyl->type({2, f}) == geom::ShapeType::kPlane) cap = f;
  ASSERT_GT(cap, 0);
  o.entity_sizes = {{{2, cap}, 0.05}};
  const SizeFieldResult r = build_size_field(*cyl, o);
  const geom::BoundingBox cb = cyl->bounding_box({2, cap});
  const Vec3 on_cap = 0.5 * (cb.min + cb.max) + Vec3(0.3, 0.2, 0);
  EXPECT_LE(r.field->size(on_cap), 0.05 * (1 + 1e-9));
  const Vec3 far = on_cap + Vec3(0, 0, cb.min.z() < 1 ? 1.0 : -1.0);
  EXPECT_GT(r.field->size(far), 0.05);
  EXPECT_LE(r.field->size(far), 0.05 + 0.3 * 1.0 + 1e-9);
  SizeOptions bad = o;
  bad.entity_sizes = {{{2, 99}, 0.05}};
  EXPECT_THROW(build_size_field(*cyl, bad), std::invalid_argument);
}

TEST(SizeBuild, DirectionalMetricIsFineAroundACylinderAndCoarseAlongIt) {
  const double radius = 1;
  const auto cyl = geom::make_analytic_cylinder(Vec3::Zero(), Vec3::UnitZ(), radius, 4);
  SizeOptions o;
  o.hmax = 0.8;
  o.hmin = 1e-3;
  o.curvature = CurvatureRule::relative_deviation(0.02);
  o.directional = true;
  const SizeFieldResult r = build_size_field(*cyl, o);
  ASSERT_TRUE(r.field->anisotropic());
  int lateral = 0;
  for (int f = 1; f <= cyl->count(2); ++f)
    if (cyl->type({2, f}) == geom::ShapeType::kCylinder) lateral = f;
  Vec3 x;
  const SizeHint hint = on_face(*cyl, lateral, Vec3(1, 0, 2), &x);
  const Metric m = r.field->metric(x, hint);
  const double around = 8 * radius * 0.02 / (1 + 4 * 0.02 * 0.02);
  // Unit length in the metric = the requested size in that direction.
  EXPECT_NEAR(1 / std::sqrt(Vec3::UnitY().dot(m * Vec3::UnitY())), around, 1e-6 * around);
  const double along = 1 / std::sqrt(Vec3::UnitZ().dot(m * Vec3::UnitZ()));
  EXPECT_GT(along, 3 * around);  // the rims' isotropic sizes, graded over 2 units
  EXPECT_LE(along, 0.8 + 1e-12);
}

TEST(SizeBuild, BackgroundMetricIsIntersectedAndAnalyticFieldsAreGraded) {
  const auto sphere = geom::make_analytic_sphere(Vec3::Zero(), 1);
  mesh::TetMesh bg = mesh::make_box_mesh({4, 4, 4}, Vec3::Constant(-2), Vec3::Constant(2), false);
  // Stretched metric: 0.05 along x, 1 across.
  const Metric aniso = metric_from_sizes({Vec3::UnitX(), Vec3::UnitY(), Vec3::UnitZ()}, Vec3(0.05, 1, 1));
  SizeOptions o;
  o.hmax = 0.4;
  o.hmin = 1e-3;
  o.curvature = CurvatureRule::off();
  o.metric = std::make_shared<BackgroundField>(bg, std::vector<Metric>(bg.num_verts(), aniso));
  o.fields = {std::make_shared<AnalyticSizeField>([](const Vec3& x) { return 0.02 + (x - Vec3(0.5, 0, 0)).norm(); })};
  o.hgrad = 1.5;
  const SizeFieldResult r = build_size_field(*sphere, o);
  const Metric m = r.field->metric(Vec3(-0.5, 0.1, 0));
  EXPECT_NEAR(1 / std::sqrt(Vec3::UnitX().dot(m * Vec3::UnitX())), 0.05, 1e-9);
  const double across = 1 / std::sqrt(Vec3::UnitY().dot(m * Vec3::UnitY()));
  EXPECT_LE(across, 0.4 + 1e-9);  // hmax and the graded analytic field
  EXPECT_GT(across, 0.2);
  // The field's minimum, as resolved by the octree's corners and centres
  // around it: within one octant's gradation of the field.
  EXPECT_NEAR(r.field->size(Vec3(0.5, 0, 0)), 0.02, 0.02);
  expect_graded(*r.octree);
}

TEST(SizeBuild, FreeformPartBuildsAndStaysGraded) {
  const auto part = geom_occ::load_model("builtin:part");
  SizeOptions o;
  const SizeFieldResult r = build_size_field(*part, o);
  EXPECT_GT(r.samples.size(), 100u);
  EXPECT_GT(r.stats.evaluations, r.samples.size());
  EXPECT_NEAR(r.hmax, part->bounding_box().diagonal() / 20, 1e-12);
  for (const auto& s : r.samples) ASSERT_LE(r.octree->size(s.point), s.size * (1 + 1e-9));
  expect_graded(*r.octree);
}
