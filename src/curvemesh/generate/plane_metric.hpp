#pragma once
// The plane a face is meshed in: (u, v) scaled to the surface's mean
// lengths, and the 2×2 metrics of the surface's first fundamental form in it.
// Internal to the face mesher.

#include <cmath>

#include "curvemesh/geom/model.hpp"

namespace cm::generate {

// The face seen through (u, v) scaled by the mean first fundamental form:
// lengths in the scaled plane approximate lengths on the surface, so that a
// Euclidean Delaunay triangulation there is close to the surface's own.
struct Scaling {
  double su = 1, sv = 1;
  Vec2 to_plane(const Vec2& uv) const { return {su * uv.x(), sv * uv.y()}; }
  Vec2 to_uv(const Vec2& p) const { return {p.x() / su, p.y() / sv}; }
};

/// The scaling of a face's (u, v) by its first fundamental form's mean
/// diagonal, sampled on a 5 × 5 grid of its parameter box (identity where
/// the derivatives vanish or are not finite).
Scaling face_scaling(const geom::Model& m, int face);

// A 2×2 symmetric metric [a b; b c] of the scaled plane: |e|² = eᵀ M e.
struct Metric2 {
  double a = 1, b = 0, c = 1;
  double norm2(const Vec2& e) const { return a * e.x() * e.x() + 2 * b * e.x() * e.y() + c * e.y() * e.y(); }
  double dot(const Vec2& e, const Vec2& f) const {
    return a * e.x() * f.x() + b * (e.x() * f.y() + e.y() * f.x()) + c * e.y() * f.y();
  }
  Vec2 apply(const Vec2& e) const { return {a * e.x() + b * e.y(), b * e.x() + c * e.y()}; }
  Metric2 scaled(double s) const { return {a * s, b * s, c * s}; }
  bool positive() const { return a > 0 && c > 0 && a * c - b * b > 1e-14 * a * c && std::isfinite(a + b + c); }
};

/// Circumcentre and squared circumradius of (p, q, r) in the metric m;
/// false where they are degenerate in it.
bool metric_circumcircle(const Vec2& p, const Vec2& q, const Vec2& r, const Metric2& m, Vec2* centre, double* r2);

/// The unit normal, in metric m, of the plane vector e, on its left.
Vec2 metric_normal(const Vec2& e, const Metric2& m);

/// Along the scaled plane's ray origin + s·ray, s >= 1: where the face's
/// point first lies `radius` or more from `centre` (1 if it does at s = 1,
/// else bracketed up to s = 4 and bisected to the last bit). NaN when it
/// does not within s = 4.
double ray_leaves_ball(const geom::Model& m, int face, const Scaling& scale, const Vec2& origin, const Vec2& ray,
                       const Vec3& centre, double radius);

}  // namespace cm::generate
