#include "curvemesh/generate/plane_metric.hpp"

#include <cmath>
#include <limits>

namespace cm::generate {

Scaling face_scaling(const geom::Model& m, int face) {
  const geom::ParamRange r = m.param_range({2, face});
  double e = 0, g = 0;
  int n = 0;
  for (int i = 0; i < 5; ++i)
    for (int j = 0; j < 5; ++j) {
      const Vec2 uv(r.u0 + (r.u1 - r.u0) * (i + 0.5) / 5, r.v0 + (r.v1 - r.v0) * (j + 0.5) / 5);
      const geom::SurfaceDerivatives d = m.face_derivatives(face, uv);
      if (!d.du.allFinite() || !d.dv.allFinite()) continue;
      e += d.du.norm();
      g += d.dv.norm();
      ++n;
    }
  Scaling s;
  if (n > 0 && e > 0 && g > 0) {
    s.su = e / n;
    s.sv = g / n;
  }
  return s;
}

bool metric_circumcircle(const Vec2& p, const Vec2& q, const Vec2& r, const Metric2& m, Vec2* centre, double* r2) {
  // With y = centre - p: 2 (q - p)ᵀ M y = |q - p|², the same for r.
  const Vec2 e1 = q - p, e2 = r - p;
  const Vec2 w1 = m.apply(e1), w2 = m.apply(e2);
  const double det = w1.x() * w2.y() - w1.y() * w2.x();
  if (!(std::abs(det) > 1e-300)) return false;
  const double s1 = 0.5 * m.norm2(e1), s2 = 0.5 * m.norm2(e2);
  const Vec2 y((s1 * w2.y() - s2 * w1.y()) / det, (w1.x() * s2 - w2.x() * s1) / det);
  if (!y.allFinite()) return false;
  *centre = p + y;
  *r2 = m.norm2(y);
  return true;
}

Vec2 metric_normal(const Vec2& e, const Metric2& m) {
  const Vec2 w = m.apply(e);
  Vec2 n(-w.y(), w.x());  // ⟂ to M e, i.e. M-orthogonal to e
  if (e.x() * n.y() - e.y() * n.x() < 0) n = -n;
  return n / std::sqrt(m.norm2(n));
}

double ray_leaves_ball(const geom::Model& m, int face, const Scaling& scale, const Vec2& origin, const Vec2& ray,
                       const Vec3& centre, double radius) {
  const auto reach = [&](double s) { return (m.face_point(face, scale.to_uv(origin + s * ray)) - centre).norm(); };
  if (reach(1) >= radius) return 1;
  double lo = 1, hi = 1.25;
  for (; hi < 4 && reach(hi) < radius; hi *= 1.25) lo = hi;
  if (!(reach(hi) >= radius)) return std::numeric_limits<double>::quiet_NaN();
  for (int it = 0; it < 30; ++it) {
    const double mid = 0.5 * (lo + hi);
    (reach(mid) < radius ? lo : hi) = mid;
  }
  return hi;
}

}  // namespace cm::generate
