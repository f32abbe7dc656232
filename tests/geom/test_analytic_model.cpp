// Tests of the analytic models' topology: entity counts and tags as
// OpenCASCADE numbers them, adjacency, loops closing in parameter space with
// the face on the left, p-curves, trims, errors and concurrent queries.
#include <gtest/gtest.h>

#include <random>
#include <thread>

#include "analytic_test_support.hpp"
#include "curvemesh/core/error.hpp"

namespace cm::geom {
namespace {

using namespace test_support;

// --- topology ----------------------------------------------------------------

TEST(AnalyticModel, SphereTopologyMatchesOpenCascade) {
  const auto m = make_analytic_sphere(kSphereCenter, kSphereR);
  EXPECT_EQ(m->count(0), 2);
  EXPECT_EQ(m->count(1), 3);
  EXPECT_EQ(m->count(2), 1);
  EXPECT_EQ(m->count(3), 1);
  EXPECT_EQ(m->count(4), 0);
  EXPECT_EQ(m->type({2, 1}), ShapeType::kSphere);
  EXPECT_EQ(m->type({1, 2}), ShapeType::kCircle);
  EXPECT_EQ(m->type({3, 1}), ShapeType::kSolid);
  EXPECT_TRUE(m->is_degenerate(1));
  EXPECT_FALSE(m->is_degenerate(2));
  EXPECT_TRUE(m->is_degenerate(3));
  EXPECT_EQ(m->edge_vertices(2), (std::array<int, 2>{2, 1}));
  EXPECT_EQ(m->edge_vertices(1), (std::array<int, 2>{1, 1}));
  EXPECT_NEAR((m->vertex_point(1) - (kSphereCenter + kSphereR * Vec3::UnitZ())).norm(), 0, 1e-15);
  EXPECT_EQ(m->upward({0, 1}), (std::vector<int>{1, 2}));
  EXPECT_EQ(m->upward({1, 2}), (std::vector<int>{1}));
  const ParamRange r = m->param_range({2, 1});
  EXPECT_TRUE(r.periodic_u);
  EXPECT_FALSE(r.periodic_v);
  EXPECT_DOUBLE_EQ(r.u1, kTwoPi);
  EXPECT_DOUBLE_EQ(r.v0, -0.5 * kPi);
  EXPECT_EQ(m->units(), "");
  EXPECT_DOUBLE_EQ(m->tolerance({2, 1}), 1e-9 * m->bounding_box().diagonal());
  // The seam's two sides: forward at u = 2π, reversed at u = 0.
  EXPECT_DOUBLE_EQ(m->edge_param_on_face(2, 1, 0.3, true).x(), kTwoPi);
  EXPECT_DOUBLE_EQ(m->edge_param_on_face(2, 1, 0.3, false).x(), 0.0);
}

TEST(AnalyticModel, CylinderTopologyAndReversedBottomCap) {
  const auto m = make_analytic_cylinder(kCylBase, kCylAxis, kCylR, kCylH);
  EXPECT_EQ(m->count(0), 2);
  EXPECT_EQ(m->count(1), 3);
  EXPECT_EQ(m->count(2), 3);
  EXPECT_EQ(m->type({2, 1}), ShapeType::kCylinder);
  EXPECT_EQ(m->type({2, 2}), ShapeType::kPlane);
  EXPECT_EQ(m->type({2, 3}), ShapeType::kPlane);
  EXPECT_EQ(m->type({1, 1}), ShapeType::kCircle);
  EXPECT_EQ(m->type({1, 2}), ShapeType::kLine);
  EXPECT_EQ(m->edge_vertices(2), (std::array<int, 2>{2, 1}));
  EXPECT_EQ(m->edge_vertices(3), (std::array<int, 2>{2, 2}));
  const auto shell = m->region_faces(1);
  ASSERT_EQ(shell.size(), 3u);
  EXPECT_TRUE(shell[0].forward);
  EXPECT_TRUE(shell[1].forward);
  EXPECT_FALSE(shell[2].forward);
  EXPECT_NEAR((m->face_normal(3, {0.1, 0.2}) + kCylAxis).norm(), 0, 1e-15);
  EXPECT_NEAR((m->face_normal(2, {0.1, 0.2}) - kCylAxis).norm(), 0, 1e-15);
  const SurfaceDerivatives d = m->face_derivatives(3, {0.1, 0.2});
  EXPECT_GT(d.du.cross(d.dv).dot(kCylAxis), 0.0);  // the plane keeps OCC's +axis normal
  EXPECT_EQ(m->upward({1, 1}), (std::vector<int>{1, 2}));
  EXPECT_EQ(m->upward({1, 3}), (std::vector<int>{1, 3}));
  EXPECT_EQ(m->upward({2, 3}), (std::vector<int>{1}));
  EXPECT_DOUBLE_EQ(m->edge_curvature(2, 0.4), 0.0);
  EXPECT_DOUBLE_EQ(m->edge_curvature(1, 0.4), 1.0 / kCylR);
}

TEST(AnalyticModel, TorusTopology) {
  const auto m = make_analytic_torus(kTorusCenter, kTorusAxis, kTorusR, kTorusr);
  EXPECT_EQ(m->count(0), 1);
  EXPECT_EQ(m->count(1), 2);
  EXPECT_EQ(m->count(2), 1);
  EXPECT_EQ(m->type({2, 1}), ShapeType::kTorus);
  EXPECT_EQ(m->edge_vertices(1), (std::array<int, 2>{1, 1}));
  EXPECT_EQ(m->edge_vertices(2), (std::array<int, 2>{1, 1}));
  const ParamRange r = m->param_range({2, 1});
  EXPECT_TRUE(r.periodic_u && r.periodic_v);
  EXPECT_TRUE(m->param_range({1, 1}).periodic_u);
  EXPECT_DOUBLE_EQ(m->edge_param_on_face(1, 1, 0.5, true).y(), 0.0);
  EXPECT_DOUBLE_EQ(m->edge_param_on_face(1, 1, 0.5, false).y(), kTwoPi);
  EXPECT_DOUBLE_EQ(m->edge_curvature(1, 0.1), 1.0 / (kTorusR + kTorusr));
  EXPECT_DOUBLE_EQ(m->edge_curvature(2, 0.1), 1.0 / kTorusr);
  EXPECT_DOUBLE_EQ(m->length(2), kTwoPi * kTorusr);
}

TEST(AnalyticModel, UpwardAdjacencyInvertsDownward) {
  for (const Case& c : all_cases()) {
    SCOPED_TRACE(c.name);
    const Model& m = *c.model;
    for (int v = 1; v <= m.count(0); ++v) {
      std::vector<int> expected;
      for (int e = 1; e <= m.count(1); ++e) {
        const auto ev = m.edge_vertices(e);
        if (ev[0] == v || ev[1] == v) expected.push_back(e);
      }
      EXPECT_EQ(m.upward({0, v}), expected);
    }
    for (int e = 1; e <= m.count(1); ++e) {
      std::vector<int> expected;
      for (int f = 1; f <= m.count(2); ++f)
        for (const Loop& loop : m.face_loops(f))
          for (const OrientedUse& use : loop.edges)
            if (use.tag == e && (expected.empty() || expected.back() != f)) expected.push_back(f);
      EXPECT_EQ(m.upward({1, e}), expected);
    }
    for (int f = 1; f <= m.count(2); ++f) EXPECT_EQ(m.upward({2, f}), std::vector<int>{1});
    EXPECT_TRUE(m.upward({3, 1}).empty());
  }
}

/// Start and end (u, v) of an edge use, following its orientation.
std::pair<Vec2, Vec2> use_ends(const Model& m, int face, const OrientedUse& use) {
  const ParamRange r = m.param_range({1, use.tag});
  const Vec2 a = m.edge_param_on_face(use.tag, face, r.u0, use.forward);
  const Vec2 b = m.edge_param_on_face(use.tag, face, r.u1, use.forward);
  return use.forward ? std::pair{a, b} : std::pair{b, a};
}

TEST(AnalyticModel, LoopsCloseInParameterSpaceWithTheFaceOnTheLeft) {
  for (const Case& c : all_cases()) {
    SCOPED_TRACE(c.name);
    const Model& m = *c.model;
    const auto shell = m.region_faces(1);
    std::vector<int> forward_uses(static_cast<std::size_t>(m.count(1) + 1), 0);
    std::vector<int> reversed_uses(forward_uses.size(), 0);
    for (const OrientedUse& face_use : shell) {
      const int f = face_use.tag;
      const auto loops = m.face_loops(f);
      ASSERT_EQ(loops.size(), 1u);
      const auto& uses = loops[0].edges;
      double signed_area = 0.0;
      for (std::size_t i = 0; i < uses.size(); ++i) {
        (uses[i].forward ? forward_uses : reversed_uses)[static_cast<std::size_t>(uses[i].tag)]++;
        const Vec2 end = use_ends(m, f, uses[i]).second;
        const Vec2 next_start = use_ends(m, f, uses[(i + 1) % uses.size()]).first;
        EXPECT_LT((end - next_start).norm(), 1e-12) << "face " << f << " use " << i;
        // Shoelace over a fine sampling of the use, in its direction.
        const auto ts = edge_samples(m, uses[i].tag, 64);
        for (std::size_t k = 0; k + 1 < ts.size(); ++k) {
          const double t0 = uses[i].forward ? ts[k] : ts[ts.size() - 1 - k];
          const double t1 = uses[i].forward ? ts[k + 1] : ts[ts.size() - 2 - k];
          const Vec2 a = m.edge_param_on_face(uses[i].tag, f, t0, uses[i].forward);
          const Vec2 b = m.edge_param_on_face(uses[i].tag, f, t1, uses[i].forward);
          signed_area += 0.5 * (a.x() * b.y() - a.y() * b.x());
        }
      }
      // Counter-clockwise about the outward normal: positive area in (u, v)
      // for a forward face, negative for a reversed one.
      EXPECT_GT(face_use.forward ? signed_area : -signed_area, 0.0) << "face " << f;
    }
    // A closed shell uses every real edge once in each direction.
    for (int e = 1; e <= m.count(1); ++e) {
      if (m.is_degenerate(e)) continue;
      EXPECT_EQ(forward_uses[static_cast<std::size_t>(e)], 1) << "edge " << e;
      EXPECT_EQ(reversed_uses[static_cast<std::size_t>(e)], 1) << "edge " << e;
    }
  }
}

TEST(AnalyticModel, PCurvesAndVerticesLieOnTheirEdges) {
  for (const Case& c : all_cases()) {
    SCOPED_TRACE(c.name);
    const Model& m = *c.model;
    for (int e = 1; e <= m.count(1); ++e) {
      const ParamRange r = m.param_range({1, e});
      const auto ev = m.edge_vertices(e);
      EXPECT_LT((m.edge_point(e, r.u0) - m.vertex_point(ev[0])).norm(), 1e-14 * c.scale);
      EXPECT_LT((m.edge_point(e, r.u1) - m.vertex_point(ev[1])).norm(), 1e-14 * c.scale);
      for (double t : edge_samples(m, e, 16)) {
        EXPECT_LT(c.residual({1, e}, m.edge_point(e, t)), 1e-12 * c.scale);
        for (int f : m.upward({1, e}))
          for (bool fwd : {true, false}) {
            const Vec2 uv = m.edge_param_on_face(e, f, t, fwd);
            EXPECT_TRUE(m.contains_param(f, uv));
            EXPECT_LT((m.face_point(f, uv) - m.edge_point(e, t)).norm(), 1e-14 * c.scale);
          }
      }
    }
    for (int v = 1; v <= m.count(0); ++v) EXPECT_LT(c.residual({0, v}, m.vertex_point(v)), 1e-14 * c.scale);
  }
}

TEST(AnalyticModel, ContainsParamFollowsTheTrim) {
  const auto s = make_analytic_sphere(kSphereCenter, kSphereR);
  EXPECT_TRUE(s->contains_param(1, {1.0, 0.5 * kPi}));
  EXPECT_TRUE(s->contains_param(1, {-20.0, 0.0}));  // periodic u
  EXPECT_FALSE(s->contains_param(1, {1.0, 0.5 * kPi + 1e-6}));
  EXPECT_FALSE(s->contains_param(1, {std::nan(""), 0.0}));
  const auto cyl = make_analytic_cylinder(kCylBase, kCylAxis, kCylR, kCylH);
  EXPECT_TRUE(cyl->contains_param(1, {3.0, kCylH}));
  EXPECT_FALSE(cyl->contains_param(1, {3.0, -1e-6}));
  EXPECT_TRUE(cyl->contains_param(3, {0.0, kCylR}));
  EXPECT_FALSE(cyl->contains_param(3, {0.7 * kCylR, 0.72 * kCylR}));
  EXPECT_FALSE(cyl->contains_param(2, {std::nan(""), 0.0}));
  const auto t = make_analytic_torus(kTorusCenter, kTorusAxis, kTorusR, kTorusr);
  EXPECT_TRUE(t->contains_param(1, {-3.0, 40.0}));
}

TEST(AnalyticModel, BadTagsAndBadShapesThrow) {
  const auto m = make_analytic_cylinder(kCylBase, kCylAxis, kCylR, kCylH);
  EXPECT_THROW(m->type({2, 4}), std::out_of_range);
  EXPECT_THROW(m->type({5, 1}), std::out_of_range);
  EXPECT_THROW(m->vertex_point(0), std::out_of_range);
  EXPECT_THROW(m->face_normal(9, {0, 0}), std::out_of_range);
  EXPECT_THROW(m->edge_derivatives(-1, 0.0), std::out_of_range);
  EXPECT_THROW(m->edge_param_on_face(1, 3, 0.0), std::invalid_argument);  // top circle, bottom cap
  EXPECT_THROW(m->closest_point({3, 1}, Vec3::Zero()), std::invalid_argument);
  EXPECT_THROW(make_analytic_sphere(Vec3::Zero(), 0.0), GeometryError);
  EXPECT_THROW(make_analytic_sphere(Vec3(0, std::nan(""), 0), 1.0), GeometryError);
  EXPECT_THROW(make_analytic_cylinder(Vec3::Zero(), Vec3::Zero(), 1.0, 1.0), GeometryError);
  EXPECT_THROW(make_analytic_cylinder(Vec3::Zero(), Vec3::UnitZ(), 1.0, -2.0), GeometryError);
  EXPECT_THROW(make_analytic_torus(Vec3::Zero(), Vec3::UnitZ(), 1.0, 1.0), GeometryError);
  EXPECT_THROW(make_analytic_torus(Vec3::Zero(), Vec3::UnitZ(), 2.0, -1.0), GeometryError);
}

TEST(AnalyticModel, ReferenceDirectionIsPerpendicularAndMatchesOccForZ) {
  EXPECT_EQ(analytic_reference_direction(Vec3::UnitZ()), Vec3::UnitX());
  for (const Vec3& a : {kCylAxis, kTorusAxis, Vec3(-1, 0, 0), Vec3(0, 3, 0)}) {
    const Vec3 x = analytic_reference_direction(a);
    EXPECT_NEAR(x.norm(), 1.0, 1e-15);
    EXPECT_NEAR(x.dot(a.normalized()), 0.0, 1e-15);
  }
}

// --- concurrency ---------------------------------------------------------------

/// Every query kind over a fixed probe set, flattened to numbers.
std::vector<double> run_queries(const Model& m, int seed) {
  std::mt19937_64 rng(static_cast<std::uint64_t>(seed));
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  const BoundingBox box = m.bounding_box();
  std::vector<double> out;
  for (int i = 0; i < 1500; ++i) {
    const Vec3 x = 0.5 * (box.min + box.max) + box.size().cwiseProduct(Vec3(unit(rng), unit(rng), unit(rng)));
    for (int f = 1; f <= m.count(2); ++f) {
      const Projection p = m.closest_point({2, f}, x);
      const Curvatures k = m.face_curvatures(f, p.param);
      const SurfaceDerivatives d = m.face_derivatives(f, p.param);
      out.insert(out.end(), {p.distance, p.param.x(), p.param.y(), k.k1, k.k2, d.duv.x(), d.dvv.z(),
                             m.face_normal(f, p.param).y(), m.contains_param(f, p.param) ? 1.0 : 0.0});
    }
    for (int e = 1; e <= m.count(1); ++e) {
      const Projection p = m.closest_point({1, e}, x);
      out.insert(out.end(), {p.distance, p.param.x(), m.edge_curvature(e, p.param.x())});
    }
  }
  return out;
}

TEST(AnalyticModel, ConcurrentQueriesGiveTheSerialResults) {
  for (const Case& c : all_cases()) {
    SCOPED_TRACE(c.name);
    const std::vector<double> serial = run_queries(*c.model, 5);
    constexpr int kThreads = 4;
    std::vector<std::vector<double>> results(kThreads);
    std::vector<std::thread> threads;
    for (int i = 0; i < kThreads; ++i)
      threads.emplace_back([&, i] { results[static_cast<std::size_t>(i)] = run_queries(*c.model, 5); });
    for (std::thread& t : threads) t.join();
    for (const auto& r : results) EXPECT_TRUE(r == serial);
  }
}

}  // namespace
}  // namespace cm::geom
