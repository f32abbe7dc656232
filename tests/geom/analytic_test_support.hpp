#pragma once
// Shared fixtures of the analytic-model tests: the three solids with their
// own implicit descriptions (inside test, on-entity residual), probes that
// hit ties, quadrature rules and parameter sampling. Expected values come
// from here, never from the model's internals.
#include <algorithm>
#include <cmath>
#include <functional>
#include <memory>
#include <numbers>
#include <string>
#include <utility>
#include <vector>

#include "curvemesh/geom/analytic_model.hpp"

namespace cm::geom::test_support {

inline constexpr double kPi = std::numbers::pi;
inline constexpr double kTwoPi = 2.0 * std::numbers::pi;

/// One analytic solid with independent descriptions of its geometry.
struct Case {
  std::string name;
  std::unique_ptr<Model> model;
  double scale = 1.0;                                         ///< size, for relative tolerances
  std::function<bool(const Vec3&)> inside;                    ///< strict interior
  std::function<double(EntityRef, const Vec3&)> residual;     ///< 0 exactly on the entity
  std::vector<Vec3> special_probes;                           ///< ties: centre, axis, core circle
};

/// Coordinates of p in the frame (origin, x, y = axis × x, axis).
inline Vec3 local(const Vec3& p, const Vec3& origin, const Vec3& axis) {
  const Vec3 x = analytic_reference_direction(axis);
  const Vec3 y = axis.cross(x);
  const Vec3 d = p - origin;
  return {d.dot(x), d.dot(y), d.dot(axis)};
}

inline double outside_interval(double t, double lo, double hi) { return std::max({0.0, lo - t, t - hi}); }

// Sphere off the origin; cylinder and torus on oblique axes so that no
// world-axis coincidence hides a frame error.
inline const Vec3 kSphereCenter(0.3, -1.2, 2.5);
inline constexpr double kSphereR = 1.7;
inline const Vec3 kCylBase(1.0, 2.0, -0.5);
inline const Vec3 kCylAxis = Vec3(1.0, 2.0, 2.0).normalized();
inline constexpr double kCylR = 0.8, kCylH = 2.5;
inline const Vec3 kTorusCenter(-0.4, 0.7, 1.1);
inline const Vec3 kTorusAxis = Vec3(0.2, -0.5, 1.0).normalized();
inline constexpr double kTorusR = 2.0, kTorusr = 0.6;

inline Case sphere_case() {
  Case c;
  c.name = "sphere";
  c.model = make_analytic_sphere(kSphereCenter, kSphereR);
  c.scale = kSphereR + kSphereCenter.norm();
  c.inside = [](const Vec3& p) { return (p - kSphereCenter).norm() < kSphereR; };
  c.residual = [](EntityRef e, const Vec3& p) {
    const Vec3 q = p - kSphereCenter;
    const Vec3 north = kSphereR * Vec3::UnitZ(), south = -north;
    if (e.dim == 0) return (q - (e.tag == 1 ? north : south)).norm();
    if (e.dim == 2) return std::abs(q.norm() - kSphereR);
    if (e.tag == 1) return (q - north).norm();
    if (e.tag == 3) return (q - south).norm();
    return std::abs(q.y()) + std::abs(q.norm() - kSphereR) + std::max(0.0, -q.x());
  };
  c.special_probes = {kSphereCenter, kSphereCenter + Vec3(0, 0, 3.0), kSphereCenter - Vec3(0, 0, 0.5),
                      kSphereCenter + Vec3(-2.0, 0, 0)};
  return c;
}

inline Case cylinder_case() {
  Case c;
  c.name = "cylinder";
  c.model = make_analytic_cylinder(kCylBase, 3.0 * kCylAxis, kCylR, kCylH);
  c.scale = kCylH + kCylBase.norm();
  c.inside = [](const Vec3& p) {
    const Vec3 l = local(p, kCylBase, kCylAxis);
    return std::hypot(l.x(), l.y()) < kCylR && l.z() > 0 && l.z() < kCylH;
  };
  c.residual = [](EntityRef e, const Vec3& p) {
    const Vec3 l = local(p, kCylBase, kCylAxis);
    const double rho = std::hypot(l.x(), l.y()), h = l.z();
    if (e.dim == 0) return std::hypot(l.x() - kCylR, l.y()) + std::abs(h - (e.tag == 1 ? kCylH : 0.0));
    if (e.dim == 2 && e.tag == 1) return std::abs(rho - kCylR) + outside_interval(h, 0, kCylH);
    if (e.dim == 2) return std::abs(h - (e.tag == 2 ? kCylH : 0.0)) + std::max(0.0, rho - kCylR);
    if (e.tag == 2) return std::hypot(l.x() - kCylR, l.y()) + outside_interval(h, 0, kCylH);
    return std::abs(h - (e.tag == 1 ? kCylH : 0.0)) + std::abs(rho - kCylR);
  };
  c.special_probes = {kCylBase, kCylBase + 1.0 * kCylAxis, kCylBase + 5.0 * kCylAxis, kCylBase - 1.0 * kCylAxis,
                      kCylBase + 0.5 * kCylH * kCylAxis};
  return c;
}

inline Case torus_case() {
  Case c;
  c.name = "torus";
  c.model = make_analytic_torus(kTorusCenter, kTorusAxis, kTorusR, kTorusr);
  c.scale = kTorusR + kTorusr + kTorusCenter.norm();
  c.inside = [](const Vec3& p) {
    const Vec3 l = local(p, kTorusCenter, kTorusAxis);
    return std::hypot(std::hypot(l.x(), l.y()) - kTorusR, l.z()) < kTorusr;
  };
  c.residual = [](EntityRef e, const Vec3& p) {
    const Vec3 l = local(p, kTorusCenter, kTorusAxis);
    const double rho = std::hypot(l.x(), l.y());
    if (e.dim == 0) return (l - Vec3(kTorusR + kTorusr, 0, 0)).norm();
    if (e.dim == 2) return std::abs(std::hypot(rho - kTorusR, l.z()) - kTorusr);
    if (e.tag == 1) return std::abs(l.z()) + std::abs(rho - (kTorusR + kTorusr));
    return std::abs(l.y()) + std::abs(std::hypot(l.x() - kTorusR, l.z()) - kTorusr) + std::max(0.0, -l.x());
  };
  const Vec3 x = analytic_reference_direction(kTorusAxis), y = kTorusAxis.cross(x);
  c.special_probes = {kTorusCenter, kTorusCenter + 0.7 * kTorusAxis, kTorusCenter + kTorusR * x,
                      kTorusCenter - kTorusR * y, kTorusCenter + kTorusR * (0.6 * x + 0.8 * y)};
  return c;
}

inline std::vector<Case> all_cases() {
  std::vector<Case> cases;
  cases.push_back(sphere_case());
  cases.push_back(cylinder_case());
  cases.push_back(torus_case());
  return cases;
}

/// Gauss-Legendre nodes and weights on [a, b] (Newton on P_n).
inline std::vector<std::pair<double, double>> gauss_legendre(int n, double a, double b) {
  std::vector<std::pair<double, double>> rule;
  for (int i = 1; i <= n; ++i) {
    double x = std::cos(kPi * (i - 0.25) / (n + 0.5));
    double dp = 0.0;
    for (int iter = 0; iter < 100; ++iter) {
      double p0 = 1.0, p1 = x;
      for (int k = 2; k <= n; ++k) {
        const double p2 = ((2.0 * k - 1.0) * x * p1 - (k - 1.0) * p0) / k;
        p0 = p1;
        p1 = p2;
      }
      dp = n * (x * p1 - p0) / (x * x - 1.0);
      const double step = p1 / dp;
      x -= step;
      if (std::abs(step) < 1e-16) break;
    }
    const double w = 2.0 / ((1.0 - x * x) * dp * dp);
    rule.emplace_back(0.5 * (a + b) + 0.5 * (b - a) * x, 0.5 * (b - a) * w);
  }
  return rule;
}

/// Quadrature of a periodic or a bounded parameter interval.
inline std::vector<std::pair<double, double>> rule_for(double lo, double hi, bool periodic, int n) {
  if (!periodic) return gauss_legendre(n, lo, hi);
  std::vector<std::pair<double, double>> rule;
  for (int i = 0; i < n; ++i) rule.emplace_back(lo + (hi - lo) * i / n, (hi - lo) / n);
  return rule;
}

/// Uniform samples of a face's parameter domain that lie on the face.
inline std::vector<Vec2> face_samples(const Model& m, int face, int n) {
  const ParamRange r = m.param_range({2, face});
  std::vector<Vec2> uv;
  for (int i = 0; i <= n; ++i)
    for (int j = 0; j <= n; ++j) {
      const Vec2 p(r.u0 + (r.u1 - r.u0) * i / n, r.v0 + (r.v1 - r.v0) * j / n);
      if (m.contains_param(face, p)) uv.push_back(p);
    }
  return uv;
}

inline std::vector<double> edge_samples(const Model& m, int edge, int n) {
  const ParamRange r = m.param_range({1, edge});
  std::vector<double> t;
  for (int i = 0; i <= n; ++i) t.push_back(r.u0 + (r.u1 - r.u0) * i / n);
  return t;
}

inline Vec3 entity_point(const Model& m, EntityRef e, const Vec2& param) {
  if (e.dim == 1) return m.edge_point(e.tag, param.x());
  return m.face_point(e.tag, param);
}

}  // namespace cm::geom::test_support
