// Tests of the analytic models' shape queries: derivatives against finite
// differences, normals against the solids' implicit equations, curvatures
// against fundamental forms and closed forms, closest points against dense
// sampling, and areas, lengths, volumes and centres of mass against closed
// forms and quadrature.
#include <gtest/gtest.h>

#include <optional>
#include <random>

#include "analytic_test_support.hpp"

namespace cm::geom {
namespace {

using namespace test_support;

// --- differential geometry ---------------------------------------------------

TEST(AnalyticModel, DerivativesMatchFiniteDifferences) {
  std::mt19937_64 rng(7);
  for (const Case& c : all_cases()) {
    SCOPED_TRACE(c.name);
    const Model& m = *c.model;
    const double h = 1e-5, tol = 1e-7 * c.scale;
    for (int f = 1; f <= m.count(2); ++f) {
      const ParamRange r = m.param_range({2, f});
      std::uniform_real_distribution<double> du(r.u0, r.u1), dv(r.v0, r.v1);
      for (int k = 0; k < 200; ++k) {
        const Vec2 uv(du(rng), dv(rng));
        const SurfaceDerivatives d = m.face_derivatives(f, uv);
        const Vec2 eu(h, 0), ev(0, h);
        const auto fd = [&](const Vec2& step, auto get) {
          return Vec3((get(m.face_derivatives(f, uv + step)) - get(m.face_derivatives(f, uv - step))) / (2 * h));
        };
        const auto point = [](const SurfaceDerivatives& s) { return s.point; };
        const auto first_u = [](const SurfaceDerivatives& s) { return s.du; };
        const auto first_v = [](const SurfaceDerivatives& s) { return s.dv; };
        EXPECT_LT((fd(eu, point) - d.du).norm(), tol);
        EXPECT_LT((fd(ev, point) - d.dv).norm(), tol);
        EXPECT_LT((fd(eu, first_u) - d.duu).norm(), tol);
        EXPECT_LT((fd(ev, first_u) - d.duv).norm(), tol);
        EXPECT_LT((fd(eu, first_v) - d.duv).norm(), tol);
        EXPECT_LT((fd(ev, first_v) - d.dvv).norm(), tol);
        EXPECT_LT((m.face_point(f, uv) - d.point).norm(), 1e-15 * c.scale);
      }
    }
    for (int e = 1; e <= m.count(1); ++e) {
      for (double t : edge_samples(m, e, 50)) {
        const CurveDerivatives d = m.edge_derivatives(e, t);
        const CurveDerivatives a = m.edge_derivatives(e, t + h), b = m.edge_derivatives(e, t - h);
        EXPECT_LT(((a.point - b.point) / (2 * h) - d.d1).norm(), tol);
        EXPECT_LT(((a.d1 - b.d1) / (2 * h) - d.d2).norm(), tol);
        // Generic curvature |r' × r''| / |r'|³ against the closed form.
        const double speed = d.d1.norm();
        const double generic = speed == 0.0 ? 0.0 : d.d1.cross(d.d2).norm() / (speed * speed * speed);
        EXPECT_NEAR(m.edge_curvature(e, t), generic, 1e-12 * std::max(1.0, generic));
      }
    }
  }
}

/// Whether p is within `distance` of a non-degenerate edge (a rim, where a
/// step along the normal may graze the solid's boundary).
bool near_an_edge(const Case& c, const Vec3& p, double distance) {
  for (int e = 1; e <= c.model->count(1); ++e)
    if (!c.model->is_degenerate(e) && c.residual({1, e}, p) < distance) return true;
  return false;
}

TEST(AnalyticModel, NormalsAreUnitAlongDuCrossDvAndPointOutOfTheSolid) {
  for (const Case& c : all_cases()) {
    SCOPED_TRACE(c.name);
    const Model& m = *c.model;
    const auto shell = m.region_faces(1);
    for (const OrientedUse& use : shell) {
      const double eps = 1e-6 * c.scale;
      for (const Vec2& uv : face_samples(m, use.tag, 24)) {
        const Vec3 n = m.face_normal(use.tag, uv);
        EXPECT_NEAR(n.norm(), 1.0, 1e-14);
        const SurfaceDerivatives d = m.face_derivatives(use.tag, uv);
        const Vec3 cross = d.du.cross(d.dv);
        if (cross.norm() > 1e-8 * c.scale * c.scale) {
          EXPECT_NEAR(n.dot(cross.normalized()), use.forward ? 1.0 : -1.0, 1e-13);
        }
        // Away from the rims, a small step along n leaves the solid and a
        // step against it enters.
        if (near_an_edge(c, d.point, 1e-3 * c.scale)) continue;
        EXPECT_FALSE(c.inside(d.point + eps * n)) << "face " << use.tag;
        EXPECT_TRUE(c.inside(d.point - eps * n)) << "face " << use.tag;
      }
    }
  }
}

/// Normal curvature of the 3D tangent t from the fundamental forms, with the
/// convention k = -n · γ'' (model.hpp).
double normal_curvature(const SurfaceDerivatives& d, const Vec3& n, const Vec3& t) {
  Eigen::Matrix2d first;
  first << d.du.dot(d.du), d.du.dot(d.dv), d.du.dot(d.dv), d.dv.dot(d.dv);
  Eigen::Matrix2d second;
  second << -n.dot(d.duu), -n.dot(d.duv), -n.dot(d.duv), -n.dot(d.dvv);
  const Vec2 ab = first.ldlt().solve(Vec2(t.dot(d.du), t.dot(d.dv)));
  return ab.dot(second * ab) / ab.dot(first * ab);
}

TEST(AnalyticModel, CurvaturesMatchFundamentalFormsAndClosedForms) {
  for (const Case& c : all_cases()) {
    SCOPED_TRACE(c.name);
    const Model& m = *c.model;
    for (int f = 1; f <= m.count(2); ++f) {
      for (const Vec2& uv : face_samples(m, f, 20)) {
        const SurfaceDerivatives d = m.face_derivatives(f, uv);
        if (d.du.cross(d.dv).norm() < 1e-6 * c.scale * c.scale) continue;  // poles
        const Vec3 n = m.face_normal(f, uv);
        const Curvatures k = m.face_curvatures(f, uv);
        // Generic: k1, k2 are the roots of det(II - k I) = 0, i.e. their sum
        // is twice the mean curvature and their product the Gauss
        // curvature (compared that way because the square root of the
        // discriminant amplifies rounding at umbilics such as the sphere).
        const double E = d.du.dot(d.du), F = d.du.dot(d.dv), G = d.dv.dot(d.dv);
        const double L = -n.dot(d.duu), M = -n.dot(d.duv), N = -n.dot(d.dvv);
        const double det = E * G - F * F;
        const double mean = (E * N + G * L - 2 * F * M) / (2 * det);
        const double gauss = (L * N - M * M) / det;
        const double tol = 1e-12 * (std::abs(k.k1) + std::abs(k.k2) + 1.0 / c.scale);
        EXPECT_NEAR(k.k1 + k.k2, 2 * mean, tol);
        EXPECT_NEAR(k.k1 * k.k2, gauss, tol * (std::abs(k.k1) + std::abs(k.k2)));
        EXPECT_GE(k.k1, k.k2);
        EXPECT_NEAR(k.dir1.norm(), 1.0, 1e-14);
        EXPECT_NEAR(k.dir2.norm(), 1.0, 1e-14);
        EXPECT_NEAR(k.dir1.dot(n), 0.0, 1e-14);
        EXPECT_NEAR(k.dir1.dot(k.dir2), 0.0, 1e-14);
        EXPECT_LT((k.dir1.cross(k.dir2) - n).norm(), 1e-14);
        EXPECT_NEAR(normal_curvature(d, n, k.dir1), k.k1, tol);
        EXPECT_NEAR(normal_curvature(d, n, k.dir2), k.k2, tol);
      }
    }
  }
}

TEST(AnalyticModel, CurvatureClosedForms) {
  const auto rel = [](double got, double want) { return std::abs(got - want) <= 1e-12 * std::abs(want); };
  const auto sphere = make_analytic_sphere(kSphereCenter, kSphereR);
  for (const Vec2& uv : face_samples(*sphere, 1, 12)) {  // includes the poles
    const Curvatures k = sphere->face_curvatures(1, uv);
    EXPECT_TRUE(rel(k.k1, 1 / kSphereR) && rel(k.k2, 1 / kSphereR)) << k.k1 << " " << k.k2;
  }
  const auto cyl = make_analytic_cylinder(kCylBase, kCylAxis, kCylR, kCylH);
  for (const Vec2& uv : face_samples(*cyl, 1, 12)) {
    const Curvatures k = cyl->face_curvatures(1, uv);
    EXPECT_TRUE(rel(k.k1, 1 / kCylR));
    EXPECT_EQ(k.k2, 0.0);
    EXPECT_LT(k.dir2.cross(kCylAxis).norm(), 1e-15);
  }
  for (int cap : {2, 3}) {
    const Curvatures k = cyl->face_curvatures(cap, {0.1, -0.2});
    EXPECT_EQ(std::abs(k.k1) + std::abs(k.k2), 0.0);
  }
  const auto torus = make_analytic_torus(kTorusCenter, kTorusAxis, kTorusR, kTorusr);
  const Curvatures outer = torus->face_curvatures(1, {1.3, 0.0});
  EXPECT_TRUE(rel(outer.k1, 1 / kTorusr) && rel(outer.k2, 1 / (kTorusR + kTorusr)));
  const Curvatures inner = torus->face_curvatures(1, {4.0, kPi});
  EXPECT_TRUE(rel(inner.k1, 1 / kTorusr) && rel(inner.k2, -1 / (kTorusR - kTorusr)));
  for (const Vec2& uv : face_samples(*torus, 1, 12)) {
    const Curvatures k = torus->face_curvatures(1, uv);
    const double cv = std::cos(uv.y());
    EXPECT_TRUE(rel(k.k1, 1 / kTorusr));
    EXPECT_NEAR(k.k2, cv / (kTorusR + kTorusr * cv), 1e-12 / kTorusr);
  }
}

// --- closest point -------------------------------------------------------------

/// Worst violations found over many probes of one entity, reported once.
struct ProjectionAudit {
  double worst_residual = 0, worst_consistency = 0, worst_sample_gain = 0, worst_local_gain = 0;
  int out_of_range = 0;
  Vec3 worst_probe = Vec3::Zero();
};

void audit_projection(const Case& c, EntityRef e, const Vec3& x, const std::optional<Vec2>& hint,
                      const std::vector<Vec3>& samples, ProjectionAudit& audit) {
  const Model& m = *c.model;
  const Projection p = m.closest_point(e, x, hint);
  const double residual = c.residual(e, p.point);
  const double consistency = std::max((entity_point(m, e, p.param) - p.point).norm(),
                                      std::abs(p.distance - (x - p.point).norm()));
  double sample_gain = 0;
  for (const Vec3& s : samples) sample_gain = std::max(sample_gain, p.distance - (x - s).norm());
  // Local optimality: no nearby parameter inside the entity is closer.
  double local_gain = 0;
  const ParamRange r = m.param_range(e);
  const double du = 1e-4 * (r.u1 - r.u0), dv = 1e-4 * (r.v1 - r.v0);
  for (const Vec2& step : {Vec2(du, 0), Vec2(-du, 0), Vec2(0, dv), Vec2(0, -dv)}) {
    const Vec2 q = p.param + step;
    if (e.dim == 1 && (step.x() == 0 || q.x() < r.u0 || q.x() > r.u1)) continue;
    if (e.dim == 2 && (!m.contains_param(e.tag, q) || (!r.periodic_v && (q.y() < r.v0 || q.y() > r.v1))))
      continue;
    local_gain = std::max(local_gain, p.distance - (x - entity_point(m, e, q)).norm());
  }
  const bool in_range = e.dim == 1 ? (p.param.x() >= r.u0 && p.param.x() <= r.u1)
                                   : (m.contains_param(e.tag, p.param) && p.param.x() >= r.u0 &&
                                      p.param.x() <= r.u1 && p.param.y() >= r.v0 && p.param.y() <= r.v1);
  if (!in_range) audit.out_of_range++;
  if (residual > audit.worst_residual) audit.worst_probe = x;
  audit.worst_residual = std::max(audit.worst_residual, residual);
  audit.worst_consistency = std::max(audit.worst_consistency, consistency);
  audit.worst_sample_gain = std::max(audit.worst_sample_gain, sample_gain);
  audit.worst_local_gain = std::max(audit.worst_local_gain, local_gain);
}

TEST(AnalyticModel, ClosestPointIsOnTheEntityAndNoSampleIsCloser) {
  std::mt19937_64 rng(2024);
  for (const Case& c : all_cases()) {
    SCOPED_TRACE(c.name);
    const Model& m = *c.model;
    const BoundingBox box = m.bounding_box();
    const Vec3 mid = 0.5 * (box.min + box.max), half = 0.75 * box.size();
    std::uniform_real_distribution<double> unit(-1.0, 1.0);
    std::vector<Vec3> probes = c.special_probes;
    for (int v = 1; v <= m.count(0); ++v) probes.push_back(m.vertex_point(v));
    while (probes.size() < 10000) {
      const Vec3 r(unit(rng), unit(rng), unit(rng));
      const double far = probes.size() % 10 == 0 ? 8.0 : 1.0;
      probes.push_back(mid + far * half.cwiseProduct(r));
    }
    std::vector<EntityRef> entities;
    for (int d : {1, 2})
      for (int t = 1; t <= m.count(d); ++t) entities.push_back({d, t});
    for (const EntityRef e : entities) {
      std::vector<Vec3> samples;
      if (e.dim == 2)
        for (const Vec2& uv : face_samples(m, e.tag, 48)) samples.push_back(m.face_point(e.tag, uv));
      else
        for (double t : edge_samples(m, e.tag, 256)) samples.push_back(m.edge_point(e.tag, t));
      for (const Vec3& s : samples) ASSERT_LT(c.residual(e, s), 1e-12 * c.scale);
      ProjectionAudit audit;
      for (std::size_t i = 0; i < probes.size(); ++i) {
        std::optional<Vec2> hint;
        if (i % 3 == 0) hint = Vec2(unit(rng) * 7, unit(rng) * 7);
        audit_projection(c, e, probes[i], hint, samples, audit);
      }
      const double tol = 1e-12 * c.scale;
      EXPECT_LT(audit.worst_residual, tol) << "dim " << e.dim << " tag " << e.tag << " probe "
                                           << audit.worst_probe.transpose();
      EXPECT_LT(audit.worst_consistency, tol) << "dim " << e.dim << " tag " << e.tag;
      EXPECT_LT(audit.worst_sample_gain, tol) << "dim " << e.dim << " tag " << e.tag;
      EXPECT_LT(audit.worst_local_gain, tol) << "dim " << e.dim << " tag " << e.tag;
      EXPECT_EQ(audit.out_of_range, 0) << "dim " << e.dim << " tag " << e.tag;
    }
  }
}

TEST(AnalyticModel, ClosestPointHintPicksTheSeamSideAndBreaksTies) {
  const auto m = make_analytic_torus(kTorusCenter, kTorusAxis, kTorusR, kTorusr);
  const Vec3 on_seam = m->face_point(1, {0.0, 1.0});
  EXPECT_DOUBLE_EQ(m->closest_point({2, 1}, on_seam, Vec2(6.2, 1.0)).param.x(), kTwoPi);
  EXPECT_NEAR(m->closest_point({2, 1}, on_seam, Vec2(0.1, 1.0)).param.x(), 0.0, 1e-12);
  const Vec3 on_equator = m->edge_point(1, 0.0);
  EXPECT_DOUBLE_EQ(m->closest_point({1, 1}, on_equator, Vec2(6.0, 0)).param.x(), kTwoPi);
  // On the axis every longitude is equally close: the hint's is returned.
  const Projection tie = m->closest_point({2, 1}, kTorusCenter, Vec2(2.5, 0.3));
  EXPECT_NEAR(tie.param.x(), 2.5, 1e-15);
  EXPECT_NEAR(tie.distance, std::hypot(kTorusR, 0.0) - kTorusr, 1e-14);
  const auto s = make_analytic_sphere(kSphereCenter, kSphereR);
  const Projection centre = s->closest_point({2, 1}, kSphereCenter, Vec2(1.0, 0.5));
  EXPECT_NEAR((centre.param - Vec2(1.0, 0.5)).norm(), 0.0, 1e-15);
  EXPECT_NEAR(centre.distance, kSphereR, 1e-14);
  const Projection pole = s->closest_point({1, 1}, Vec3(9, 9, 9), Vec2(4.0, 0));
  EXPECT_DOUBLE_EQ(pole.param.x(), 4.0);
}

// --- global properties ---------------------------------------------------------

struct FaceIntegrals {
  double area = 0, flux = 0;  ///< ∫ dA and ∫ p·n dA
  Vec3 moments = Vec3::Zero(); ///< ∫ p_i² n_i dA
};

/// Integrals over a face by tensor quadrature in (u, v); a face with no
/// periodic direction is integrated over the star-shaped domain its outer
/// loop bounds, seen from the loop's centroid: uv = o + ρ (γ(t) - o).
FaceIntegrals integrate_face(const Model& m, int face, bool forward) {
  FaceIntegrals out;
  const auto add = [&](const Vec2& uv, double weight) {
    const SurfaceDerivatives d = m.face_derivatives(face, uv);
    const Vec3 n = m.face_normal(face, uv);
    const double w = weight * d.du.cross(d.dv).norm();
    out.area += w;
    out.flux += w * d.point.dot(n);
    out.moments += w * d.point.cwiseProduct(d.point).cwiseProduct(n);
  };
  const ParamRange r = m.param_range({2, face});
  if (r.periodic_u || r.periodic_v) {
    for (const auto& [u, wu] : rule_for(r.u0, r.u1, r.periodic_u, 64))
      for (const auto& [v, wv] : rule_for(r.v0, r.v1, r.periodic_v, 40)) add({u, v}, wu * wv);
    return out;
  }
  const Loop loop = m.face_loops(face).front();
  Vec2 origin = Vec2::Zero();
  int count = 0;
  for (const OrientedUse& use : loop.edges)
    for (double t : edge_samples(m, use.tag, 64)) {
      origin += m.edge_param_on_face(use.tag, face, t, use.forward);
      ++count;
    }
  origin /= count;
  const double h = 1e-5;
  for (const OrientedUse& use : loop.edges) {
    const ParamRange er = m.param_range({1, use.tag});
    for (const auto& [t, wt] : gauss_legendre(48, er.u0, er.u1)) {
      const Vec2 g = m.edge_param_on_face(use.tag, face, t, use.forward) - origin;
      const Vec2 dg = (m.edge_param_on_face(use.tag, face, t + h, use.forward) -
                       m.edge_param_on_face(use.tag, face, t - h, use.forward)) / (2 * h);
      // Signed so that a loop running the wrong way gives a negative area.
      const double turn = (g.x() * dg.y() - g.y() * dg.x()) * (use.forward ? 1.0 : -1.0) * (forward ? 1.0 : -1.0);
      for (const auto& [rho, wr] : gauss_legendre(8, 0.0, 1.0)) add(origin + rho * g, wt * wr * rho * turn);
    }
  }
  return out;
}

TEST(AnalyticModel, AreaVolumeAndCentreOfMassMatchClosedFormsAndQuadrature) {
  struct Expected {
    std::vector<double> areas, lengths;
    double volume;
    Vec3 centre;
  };
  const std::vector<Expected> expected = {
      {{4 * kPi * kSphereR * kSphereR}, {0, kPi * kSphereR, 0}, 4.0 / 3.0 * kPi * std::pow(kSphereR, 3),
       kSphereCenter},
      {{kTwoPi * kCylR * kCylH, kPi * kCylR * kCylR, kPi * kCylR * kCylR}, {kTwoPi * kCylR, kCylH, kTwoPi * kCylR},
       kPi * kCylR * kCylR * kCylH, kCylBase + 0.5 * kCylH * kCylAxis},
      {{4 * kPi * kPi * kTorusR * kTorusr}, {kTwoPi * (kTorusR + kTorusr), kTwoPi * kTorusr},
       2 * kPi * kPi * kTorusR * kTorusr * kTorusr, kTorusCenter},
  };
  const auto cases = all_cases();
  for (std::size_t i = 0; i < cases.size(); ++i) {
    SCOPED_TRACE(cases[i].name);
    const Model& m = *cases[i].model;
    const Expected& want = expected[i];
    const double rel = 1e-12;
    for (int f = 1; f <= m.count(2); ++f)
      EXPECT_NEAR(m.area(f), want.areas[static_cast<std::size_t>(f - 1)], rel * m.area(f));
    for (int e = 1; e <= m.count(1); ++e) {
      EXPECT_NEAR(m.length(e), want.lengths[static_cast<std::size_t>(e - 1)], rel * (1 + m.length(e)));
      const ParamRange r = m.param_range({1, e});
      double numeric = 0;
      for (const auto& [t, w] : gauss_legendre(40, r.u0, r.u1)) numeric += w * m.edge_derivatives(e, t).d1.norm();
      EXPECT_NEAR(numeric, m.length(e), 1e-10 * (1 + m.length(e)));
    }
    EXPECT_NEAR(m.volume(1), want.volume, rel * want.volume);
    EXPECT_LT((m.center_of_mass(1) - want.centre).norm(), rel * cases[i].scale);
    // Divergence theorem over the shell: V = ⅓ ∮ p·n, ∫ x_i dV = ½ ∮ x_i² n_i.
    double flux = 0;
    Vec3 moments = Vec3::Zero();
    for (const OrientedUse& use : m.region_faces(1)) {
      const FaceIntegrals fi = integrate_face(m, use.tag, use.forward);
      EXPECT_NEAR(fi.area, m.area(use.tag), 1e-9 * m.area(use.tag)) << "face " << use.tag;
      flux += fi.flux;
      moments += fi.moments;
    }
    const double volume = flux / 3.0;
    EXPECT_NEAR(volume, m.volume(1), 1e-9 * m.volume(1));
    EXPECT_LT((0.5 * moments / volume - m.center_of_mass(1)).norm(), 1e-9 * cases[i].scale);
  }
}

TEST(AnalyticModel, BoundingBoxesAreTightAndContainTheirEntities) {
  for (const Case& c : all_cases()) {
    SCOPED_TRACE(c.name);
    const Model& m = *c.model;
    for (int d : {1, 2}) {
      for (int t = 1; t <= m.count(d); ++t) {
        const BoundingBox box = m.bounding_box({d, t});
        BoundingBox sampled;
        if (d == 2)
          for (const Vec2& uv : face_samples(m, t, 120)) sampled.add(m.face_point(t, uv));
        else
          for (double u : edge_samples(m, t, 2000)) sampled.add(m.edge_point(t, u));
        const double slack = 1e-14 * c.scale;
        EXPECT_TRUE((sampled.min.array() >= box.min.array() - slack).all()) << d << " " << t;
        EXPECT_TRUE((sampled.max.array() <= box.max.array() + slack).all()) << d << " " << t;
        EXPECT_LT((sampled.min - box.min).cwiseAbs().maxCoeff(), 1e-3 * c.scale) << d << " " << t;
        EXPECT_LT((sampled.max - box.max).cwiseAbs().maxCoeff(), 1e-3 * c.scale) << d << " " << t;
      }
    }
    const BoundingBox all = m.bounding_box(), region = m.bounding_box({3, 1});
    EXPECT_EQ(all.min, region.min);
    EXPECT_EQ(all.max, region.max);
  }
}

}  // namespace
}  // namespace cm::geom
