// Normals and principal curvatures against closed forms on the built-in
// primitives, and against GeomLProp on the freeform faces of t20_data.step.
#include <cmath>
#include <random>

#include <gtest/gtest.h>

#include <BRep_Tool.hxx>
#include <GeomLProp_SLProps.hxx>
#include <TopoDS.hxx>
#include <gp_Dir.hxx>
#include <gp_Vec.hxx>

#include "curvemesh/geom_occ/load.hpp"
#include "occ_reference.hpp"

namespace cm::geom_occ {
namespace {

using geom::ShapeType;

int first_face_of_type(const geom::Model& m, ShapeType type) {
  for (int f = 1; f <= m.count(2); ++f)
    if (m.type({2, f}) == type) return f;
  return 0;
}

Vec2 random_inside(const geom::Model& m, int face, std::mt19937& rng, double margin = 0.05) {
  const geom::ParamRange r = m.param_range({2, face});
  std::uniform_real_distribution<double> u(r.u0 + margin * (r.u1 - r.u0), r.u1 - margin * (r.u1 - r.u0));
  std::uniform_real_distribution<double> v(r.v0 + margin * (r.v1 - r.v0), r.v1 - margin * (r.v1 - r.v0));
  for (;;) {
    const Vec2 uv(u(rng), v(rng));
    if (m.contains_param(face, uv)) return uv;
  }
}

void expect_frame(const geom::Curvatures& k, const Vec3& n) {
  EXPECT_NEAR(k.dir1.norm(), 1, 1e-12);
  EXPECT_NEAR(k.dir2.norm(), 1, 1e-12);
  EXPECT_NEAR(k.dir1.dot(k.dir2), 0, 1e-12);
  EXPECT_NEAR(k.dir1.dot(n), 0, 1e-10);
  EXPECT_NEAR(k.dir2.dot(n), 0, 1e-10);
  EXPECT_NEAR((k.dir1.cross(k.dir2) - n).norm(), 0, 1e-10);  // right-handed about n
  EXPECT_GE(k.k1, k.k2);
}

TEST(OccCurvature, SphereIsUmbilicAtPlusOneOverRWithOutwardNormal) {
  const auto m = load_model("builtin:sphere:r=2");
  const int f = first_face_of_type(*m, ShapeType::kSphere);
  ASSERT_GT(f, 0);
  std::mt19937 rng(1);
  for (int i = 0; i < 200; ++i) {
    const Vec2 uv = random_inside(*m, f, rng);
    const Vec3 p = m->face_point(f, uv);
    const Vec3 n = m->face_normal(f, uv);
    EXPECT_NEAR((n - p.normalized()).norm(), 0, 1e-12);
    const geom::Curvatures k = m->face_curvatures(f, uv);
    EXPECT_NEAR(k.k1, 0.5, 0.5e-8);
    EXPECT_NEAR(k.k2, 0.5, 0.5e-8);
    expect_frame(k, n);
  }
  // At a pole du x dv vanishes: the normal and curvature are the limits.
  const geom::ParamRange r = m->param_range({2, f});
  const Vec2 pole(0.5 * (r.u0 + r.u1), r.v1);
  EXPECT_NEAR((m->face_normal(f, pole) - Vec3::UnitZ()).norm(), 0, 1e-6);
  EXPECT_NEAR(m->face_curvatures(f, pole).k2, 0.5, 1e-6);
  for (int e = 1; e <= m->count(1); ++e) {
    if (m->is_degenerate(e)) continue;
    const geom::ParamRange er = m->param_range({1, e});
    EXPECT_NEAR(m->edge_curvature(e, 0.3 * er.u0 + 0.7 * er.u1), 0.5, 1e-12);
  }
}

TEST(OccCurvature, CylinderHasOneOverRAroundAndZeroAlongTheAxis) {
  const double radius = 1.5;
  const auto m = load_model("builtin:cylinder:r=1.5,h=3");
  const int f = first_face_of_type(*m, ShapeType::kCylinder);
  ASSERT_GT(f, 0);
  std::mt19937 rng(2);
  for (int i = 0; i < 200; ++i) {
    const Vec2 uv = random_inside(*m, f, rng);
    const Vec3 p = m->face_point(f, uv);
    const Vec3 radial = Vec3(p.x(), p.y(), 0).normalized();
    const Vec3 n = m->face_normal(f, uv);
    EXPECT_NEAR((n - radial).norm(), 0, 1e-12);
    const geom::Curvatures k = m->face_curvatures(f, uv);
    EXPECT_NEAR(k.k1, 1 / radius, 1e-8 / radius);
    EXPECT_NEAR(k.k2, 0, 1e-8 / radius);
    EXPECT_NEAR(std::abs(k.dir2.z()), 1, 1e-8);  // the axis: the direction of zero curvature
    EXPECT_NEAR(k.dir1.z(), 0, 1e-8);
    expect_frame(k, n);
  }
  for (int p = 1; p <= m->count(2); ++p) {
    if (m->type({2, p}) != ShapeType::kPlane) continue;
    const geom::Curvatures k = m->face_curvatures(p, random_inside(*m, p, rng));
    EXPECT_EQ(k.k1, 0);
    EXPECT_EQ(k.k2, 0);
  }
}

TEST(OccCurvature, TorusMatchesTheClosedFormEverywhere) {
  const double major = 2, minor = 0.5;
  const auto m = load_model("builtin:torus:R=2,r=0.5");
  const int f = first_face_of_type(*m, ShapeType::kTorus);
  ASSERT_GT(f, 0);
  const auto check = [&](const Vec2& uv) {
    const Vec3 p = m->face_point(f, uv);
    const double rho = std::hypot(p.x(), p.y());  // distance from the axis
    const double cos_phi = (rho - major) / minor;   // +1 outer equator, -1 inner
    const double k_tube = 1 / minor, k_parallel = cos_phi / rho;
    const geom::Curvatures k = m->face_curvatures(f, uv);
    EXPECT_NEAR(k.k1, std::max(k_tube, k_parallel), 1e-8 * k_tube);
    EXPECT_NEAR(k.k2, std::min(k_tube, k_parallel), 1e-8 * k_tube);
    // Outward: away from the tube's centre circle.
    const Vec3 centre = major * Vec3(p.x(), p.y(), 0).normalized();
    EXPECT_NEAR((m->face_normal(f, uv) - (p - centre).normalized()).norm(), 0, 1e-10);
    expect_frame(k, m->face_normal(f, uv));
    return k;
  };
  std::mt19937 rng(3);
  for (int i = 0; i < 300; ++i) check(random_inside(*m, f, rng, 0));
  // Equators: OCC's torus has v = 0 on the outer one and v = pi on the inner.
  const geom::ParamRange r = m->param_range({2, f});
  const geom::Curvatures outer = check(Vec2(0.3 * r.u1, 0));
  EXPECT_NEAR(outer.k1, 1 / minor, 1e-8);
  EXPECT_NEAR(outer.k2, 1 / (major + minor), 1e-8);
  EXPECT_NEAR(std::abs(outer.dir2.z()), 0, 1e-8);  // along the parallel
  const geom::Curvatures inner = check(Vec2(0.3 * r.u1, M_PI));
  EXPECT_NEAR(inner.k1, 1 / minor, 1e-8);
  EXPECT_NEAR(inner.k2, -1 / (major - minor), 1e-8);  // saddle: bends toward the normal
}

TEST(OccCurvature, ConeHasZeroAlongItsGenerators) {
  const auto m = load_model("builtin:cone:r1=1,r2=0.5,h=2");
  const int f = first_face_of_type(*m, ShapeType::kCone);
  ASSERT_GT(f, 0);
  const double cos_alpha = 2 / std::hypot(2.0, 0.5);
  std::mt19937 rng(4);
  for (int i = 0; i < 100; ++i) {
    const Vec2 uv = random_inside(*m, f, rng);
    const Vec3 p = m->face_point(f, uv);
    const geom::Curvatures k = m->face_curvatures(f, uv);
    EXPECT_NEAR(k.k1, cos_alpha / std::hypot(p.x(), p.y()), 1e-8);
    EXPECT_NEAR(k.k2, 0, 1e-8);
  }
}

TEST(OccCurvature, FreeformFacesAgreeWithGeomLProp) {
  const std::string path = std::string(CM_SHARED_DIR) + "/models/t20_data.step";
  const auto m = load_model(path);
  const test::Reference ref = test::read_reference(path);
  ASSERT_EQ(m->units(), "mm");  // same parametrization as the reference
  std::mt19937 rng(5);
  int checked = 0;
  for (int f = 1; f <= m->count(2); ++f) {
    ASSERT_EQ(m->type({2, f}), ShapeType::kBSplineSurface);
    const Handle(Geom_Surface) s = BRep_Tool::Surface(TopoDS::Face(ref.faces(f)));
    for (int i = 0; i < 40; ++i) {
      const Vec2 uv = random_inside(*m, f, rng);
      GeomLProp_SLProps props(s, uv.x(), uv.y(), 2, 1e-9);
      if (!props.IsNormalDefined() || !props.IsCurvatureDefined()) continue;
      const gp_Dir nd = props.Normal();
      const Vec3 n_occ(nd.X(), nd.Y(), nd.Z());
      const Vec3 n = m->face_normal(f, uv);
      ASSERT_NEAR(std::abs(n.dot(n_occ)), 1, 1e-9);
      // GeomLProp signs curvature positive toward its normal; ours is
      // positive away from the outward normal.
      const double s_sign = n.dot(n_occ) > 0 ? -1 : 1;
      const double a = s_sign * props.MaxCurvature(), b = s_sign * props.MinCurvature();
      const geom::Curvatures k = m->face_curvatures(f, uv);
      const double scale = std::max({std::abs(a), std::abs(b), 1e-3});
      EXPECT_NEAR(k.k1, std::max(a, b), 1e-7 * scale) << "face " << f;
      EXPECT_NEAR(k.k2, std::min(a, b), 1e-7 * scale) << "face " << f;
      if (std::abs(a - b) > 1e-3 * scale) {
        gp_Dir d1, d2;
        props.CurvatureDirections(d1, d2);
        const Vec3 dir_max(d1.X(), d1.Y(), d1.Z()), dir_min(d2.X(), d2.Y(), d2.Z());
        // Our k1 is OCC's max curvature when the signs agree, its min otherwise.
        const Vec3& expected = s_sign > 0 ? dir_max : dir_min;
        EXPECT_NEAR(std::abs(k.dir1.dot(expected)), 1, 1e-5) << "face " << f;
      }
      ++checked;
    }
  }
  EXPECT_GT(checked, 700);
}

}  // namespace
}  // namespace cm::geom_occ
