// The assembled size field on models: the seed's formulas on the surface,
// planar faces at hmax, edge curvature, entity sizes, directional metric,
// background metric, and the octree invariants on real geometry.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>
#include <string>
#include <vector>

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

// --- sizes on regions ----------------------------------------------------------

namespace {

// Points of a unit-free sample: a deterministic cloud in a box.
std::vector<Vec3> cloud(const Vec3& lo, const Vec3& hi, int n, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0, 1);
  std::vector<Vec3> out(static_cast<std::size_t>(n));
  for (Vec3& p : out) p = lo + Vec3(u(rng), u(rng), u(rng)).cwiseProduct(hi - lo);
  return out;
}

SizeOptions region_options(int region, double h) {
  SizeOptions o;
  o.hmax = 0.5;
  o.hmin = 1e-3;
  o.hgrad = 1.3;
  o.curvature = CurvatureRule::off();
  o.entity_sizes = {{{3, region}, h}};
  return o;
}

}  // namespace

// Tolerances. Inside the region the octree's corners are at most H wherever
// an octant lies inside the region or holds a boundary sample, so the
// trilinear value is at most H there, exactly (1e-9 for rounding): that is
// every point deeper than an octant's diagonal (octants there have side
// <= 2H). An octant the boundary only clips (no corner, centre or sample
// inside) interpolates towards its outside corners, which gradation keeps
// within (hgrad − 1)·(its diagonal) of H, so up to 2 H in theory; the
// boundary samples (spacing H/2) leave few such octants and little of the
// region in them: measured at most 1.0002 H on these shapes. 1.35 H is
// asserted, far below what a region the octree missed would show (hmax is
// 6 H or more). Outside, gradation bounds growth by (hgrad − 1) per unit
// length.
TEST(SizeBuild, RegionSizeHoldsInsideAnalyticSphereAndGradesOutside) {
  const double h = 0.08;
  const auto sphere = geom::make_analytic_sphere(Vec3::Zero(), 1);
  SizeOptions o = region_options(1, h);
  o.curvature = CurvatureRule::relative_deviation(0.04);  // asks for more than h on this sphere
  const SizeFieldResult r = build_size_field(*sphere, o);
  double worst_deep = 0, worst = 0;
  for (const Vec3& x : cloud(Vec3::Constant(-1), Vec3::Constant(1), 20000, 7)) {
    if (x.norm() >= 1) continue;
    const double s = r.field->size(x);
    worst = std::max(worst, s / h);
    // Deeper than one octant's diagonal (side <= 2h).
    if (x.norm() < 1 - 2 * std::sqrt(3.0) * h) worst_deep = std::max(worst_deep, s / h);
  }
  EXPECT_LE(worst_deep, 1 + 1e-9);
  EXPECT_LE(worst, 1.35);
  // On the sphere, with its face as hint: h exactly, below the curvature size.
  std::mt19937 rng(8);
  std::normal_distribution<double> g;
  for (int i = 0; i < 100; ++i) {
    Vec3 x;
    const SizeHint hint = on_face(*sphere, 1, Vec3(g(rng), g(rng), g(rng)).normalized(), &x);
    EXPECT_DOUBLE_EQ(r.field->size(x, hint), h);
    EXPECT_DOUBLE_EQ(r.field->size(x, SizeHint{{3, 1}, Vec2::Zero()}), h);
  }
  // Outside, towards the corners of the octree's cube (the model is the
  // sphere, so that is as far as the field goes): graded by hgrad from h.
  // The octants holding the boundary samples (side <= h) have all their
  // corners at h, so h reaches up to one such octant beyond the surface
  // before growth starts: the lower bound starts 2h out.
  for (const double d : {0.1, 0.3, 0.5, 0.7}) {
    for (const Vec3& corner : std::vector<Vec3>{Vec3(1, 1, 1), Vec3(-1, 1, -1), Vec3(1, -1, -1)}) {
      const double s = r.field->size((1 + d) * corner.normalized());
      EXPECT_LE(s, h + (o.hgrad - 1) * d * 1.05 + 1e-9) << "d " << d;
      EXPECT_GE(s, h + 0.5 * (o.hgrad - 1) * std::max(0.0, d - 2 * h)) << "d " << d;
    }
  }
  expect_graded(*r.octree);
}

TEST(SizeBuild, RegionSizeAppliesOnlyInTheNamedRegionOfTwoBlocks) {
  const auto blocks = geom_occ::load_model("builtin:blocks");
  ASSERT_EQ(blocks->count(3), 2);
  const int left = blocks->center_of_mass(1).x() < 1 ? 1 : 2, right = 3 - left;
  const double h = 0.05;
  const SizeOptions o = region_options(left, h);
  const SizeFieldResult r = build_size_field(*blocks, o);
  double worst_deep = 0, worst = 0;
  for (const Vec3& x : cloud(Vec3::Zero(), Vec3(1, 1, 1), 5000, 9)) {
    const double s = r.field->size(x);
    worst = std::max(worst, s / h);
    const double depth = std::min({x.minCoeff(), (Vec3::Ones() - x).minCoeff()});
    if (depth > 2 * std::sqrt(3.0) * h) worst_deep = std::max(worst_deep, s / h);
  }
  EXPECT_LE(worst_deep, 1 + 1e-9);
  EXPECT_LE(worst, 1.35);
  // The right block grades away from the interface x = 1 and reaches hmax.
  for (const double d : {0.2, 0.5}) {
    const double s = r.field->size(Vec3(1 + d, 0.5, 0.5));
    EXPECT_GT(s, h + 0.5 * (o.hgrad - 1) * d);
    EXPECT_LE(s, h + (o.hgrad - 1) * d * 1.05 + 1e-9);
  }
  // Hints: the interface bounds both regions, so it gets h; a face of the
  // right block only does not.
  int interface = 0, far_face = 0;
  for (int f = 1; f <= blocks->count(2); ++f) {
    const auto up = blocks->upward({2, f});
    if (up.size() == 2) interface = f;
    const geom::BoundingBox b = blocks->bounding_box({2, f});
    if (up == std::vector<int>{right} && b.min.x() > 1.5) far_face = f;
  }
  ASSERT_GT(interface, 0);
  ASSERT_GT(far_face, 0);
  Vec3 x;
  SizeHint hint = on_face(*blocks, interface, Vec3(1, 0.4, 0.6), &x);
  EXPECT_DOUBLE_EQ(r.field->size(x, hint), h);
  hint = on_face(*blocks, far_face, Vec3(2, 0.4, 0.6), &x);
  EXPECT_GT(r.field->size(x, hint), 2 * h);
  EXPECT_GT(r.field->size(x, SizeHint{{3, right}, Vec2::Zero()}), 2 * h);
  // Edges and vertices of the left block's closure get h at a hint too,
  // even where the octree has graded away (the far end of the model).
  int closure_edges = 0;
  for (int e = 1; e <= blocks->count(1); ++e) {
    bool in_closure = false;
    for (const int f : blocks->upward({1, e}))
      for (const int reg : blocks->upward({2, f})) in_closure |= reg == left;
    const geom::ParamRange pr = blocks->param_range({1, e});
    const double u = 0.5 * (pr.u0 + pr.u1);
    const double s = r.field->size(Vec3(2, 0.5, 0.5), SizeHint{{1, e}, Vec2(u, 0)});
    if (in_closure) {
      EXPECT_DOUBLE_EQ(s, h) << "edge " << e;
      ++closure_edges;
    } else {
      EXPECT_GT(s, 2 * h) << "edge " << e;
    }
  }
  EXPECT_EQ(closure_edges, 12);
  for (int v = 1; v <= blocks->count(0); ++v) {
    const bool left_vertex = blocks->vertex_point(v).x() < 1.5;
    const double s = r.field->size(Vec3(2, 0.5, 0.5), SizeHint{{0, v}, Vec2::Zero()});
    if (left_vertex) {
      EXPECT_DOUBLE_EQ(s, h) << "vertex " << v;
    } else {
      EXPECT_GT(s, 2 * h) << "vertex " << v;
    }
  }
  expect_graded(*r.octree);
}

// A slab thinner than h: octant corners rarely fall inside it, so what
// holds h there is the sampling of its faces.
TEST(SizeBuild, RegionThinnerThanItsSizeIsNotMissed) {
  const auto blocks = geom_occ::load_model("builtin:blocks:dx1=0.013,dx2=1");
  const int slab = blocks->volume(1) < blocks->volume(2) ? 1 : 2;
  const double h = 0.1;
  const SizeFieldResult r = build_size_field(*blocks, region_options(slab, h));
  double worst = 0;
  for (const Vec3& x : cloud(Vec3(0, 0, 0), Vec3(0.013, 1, 1), 3000, 10)) worst = std::max(worst, r.field->size(x) / h);
  EXPECT_LE(worst, 1 + 1e-9);
}

TEST(SizeBuild, RegionSizeInsideAnInclusionAndOnItsBoundary) {
  const auto inclusion = geom_occ::load_model("builtin:inclusion:s=2,r=0.5");
  const int ball = inclusion->volume(1) < inclusion->volume(2) ? 1 : 2;
  const double h = 0.04;
  const SizeFieldResult r = build_size_field(*inclusion, region_options(ball, h));
  double worst_deep = 0, worst = 0;
  for (const Vec3& x : cloud(Vec3::Constant(-0.5), Vec3::Constant(0.5), 8000, 11)) {
    if (x.norm() >= 0.5) continue;
    const double s = r.field->size(x);
    worst = std::max(worst, s / h);
    if (x.norm() < 0.5 - 2 * std::sqrt(3.0) * h) worst_deep = std::max(worst_deep, s / h);
  }
  EXPECT_LE(worst_deep, 1 + 1e-9);
  EXPECT_LE(worst, 1.35);
  // The cube's faces are not in the ball's closure: graded from h over the
  // 0.5 between the sphere and a face centre.
  const double at_face = r.field->size(Vec3(1, 0, 0));
  EXPECT_GT(at_face, h + 0.5 * 0.3 * 0.5);
  EXPECT_LE(at_face, h + 0.3 * 0.5 * 1.05);
}

TEST(SizeBuild, RegionSizeOnAMissingRegionNamesIt) {
  const auto blocks = geom_occ::load_model("builtin:blocks");
  for (const int tag : {0, 3}) {
    try {
      build_size_field(*blocks, region_options(tag, 0.1));
      ADD_FAILURE() << "region " << tag << " accepted";
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find("size on region " + std::to_string(tag) + ": the model has no such entity"),
                std::string::npos)
          << e.what();
      EXPECT_NE(std::string(e.what()).find("region tags are 1..2"), std::string::npos) << e.what();
    }
  }
  SizeOptions four = region_options(1, 0.1);
  four.entity_sizes = {{{4, 1}, 0.1}};
  EXPECT_THROW(build_size_field(*blocks, four), std::invalid_argument);
}

// Samplers take point, derivatives and curvatures from one face_geometry
// call; on CAD faces it must give what the separate queries give.
TEST(SizeBuild, FaceGeometryMatchesTheSeparateQueries) {
  const auto part = geom_occ::load_model("builtin:part");
  int compared = 0;
  for (int f = 1; f <= part->count(2); ++f) {
    const geom::ParamRange pr = part->param_range({2, f});
    for (int i = 1; i < 8; ++i)
      for (int j = 1; j < 8; ++j) {
        const Vec2 uv(pr.u0 + (pr.u1 - pr.u0) * i / 8.0, pr.v0 + (pr.v1 - pr.v0) * j / 8.0);
        const geom::SurfaceGeometry g = part->face_geometry(f, uv);
        const geom::SurfaceDerivatives d = part->face_derivatives(f, uv);
        ASSERT_EQ(g.derivatives.point, d.point);
        ASSERT_EQ(g.derivatives.duv, d.duv);
        if (!g.regular) continue;
        const geom::Curvatures c = part->face_curvatures(f, uv);
        ASSERT_EQ(g.curvatures.k1, c.k1) << f;
        ASSERT_EQ(g.curvatures.k2, c.k2) << f;
        ASSERT_EQ(g.curvatures.dir1, c.dir1) << f;
        ++compared;
      }
  }
  EXPECT_GT(compared, 100);
}

TEST(SizeBuild, ThinClosedFacesGetThreeSegmentsAroundBelowHmin) {
  // A pin 8e-3 across and 1 long at hmax 1 (hmin 0.01): at hmin its side
  // would get fewer than three segments around. It asks for a fifth of
  // its way around instead; a pin 0.1 across asks for nothing of the kind.
  const auto thin = geom::make_analytic_cylinder(Vec3::Zero(), Vec3::UnitZ(), 0.004, 1);
  SizeOptions o;
  o.hmax = 1;
  const SizeFieldResult r = build_size_field(*thin, o);
  const double around = 2 * std::numbers::pi * 0.004;
  ASSERT_LT(around, 3 * r.hmin);
  EXPECT_TRUE(std::any_of(r.samples.begin(), r.samples.end(),
                          [](const SizeSample& s) { return s.source == SizeSource::kThinClosedFace; }));
  for (const double z : {0.02, 0.5, 0.98}) {
    const Vec3 x(0.004, 0, z);
    EXPECT_LE(r.field->size(x, on_face(*thin, 1, x)), around / 3) << "z " << z;
    EXPECT_GE(r.field->size(x, on_face(*thin, 1, x)), kCuspStripFloor * r.hmin);
  }
  const auto pin = geom::make_analytic_cylinder(Vec3::Zero(), Vec3::UnitZ(), 0.05, 1);
  const SizeFieldResult wide = build_size_field(*pin, o);
  EXPECT_TRUE(std::none_of(wide.samples.begin(), wide.samples.end(),
                           [](const SizeSample& s) { return s.source == SizeSource::kThinClosedFace; }));
}
