#include "curvemesh/size/curvature_size.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <fmt/format.h>

namespace cm::size {

CurvatureRule CurvatureRule::chord_deviation(double eps) {
  if (!(eps > 0) || !std::isfinite(eps))
    throw std::invalid_argument(fmt::format("curvature chord deviation must be finite and > 0 (got {})", eps));
  return {Kind::kChordDeviation, eps};
}

CurvatureRule CurvatureRule::relative_deviation(double alpha) {
  if (!(alpha > 0) || !(alpha <= 0.5))
    throw std::invalid_argument(
        fmt::format("curvature relative deviation alpha must be in (0, 0.5] (got {})", alpha));
  return {Kind::kRelativeDeviation, alpha};
}

double curvature_length(double kappa, const CurvatureRule& rule) {
  const double k = std::abs(kappa);
  if (!rule.enabled() || !(k > 0)) return std::numeric_limits<double>::infinity();
  if (!std::isfinite(k)) return 0;
  const double r = 1 / k;
  switch (rule.kind) {
    case CurvatureRule::Kind::kChordDeviation: {
      const double eps = rule.value;
      if (eps >= r) return 2 * r;
      return std::sqrt(8 * r * eps - 4 * eps * eps);
    }
    case CurvatureRule::Kind::kRelativeDeviation: {
      const double a = rule.value;
      return 8 * r * a / (1 + 4 * a * a);
    }
    case CurvatureRule::Kind::kOff: break;
  }
  return std::numeric_limits<double>::infinity();
}

double surface_curvature_length(const geom::Curvatures& c, const CurvatureRule& rule) {
  return curvature_length(std::max(std::abs(c.k1), std::abs(c.k2)), rule);
}

bool usable_curvatures(const geom::Model& model, int face, const Vec2& uv, geom::Curvatures* out) {
  return usable_curvatures(model.face_geometry(face, uv), model.tolerance({2, face}), out);
}

bool usable_curvatures(const geom::SurfaceGeometry& g, double tolerance, geom::Curvatures* out) {
  // A singular point of the parametrization: du × dv (nearly) vanishes, e.g.
  // every point of a sphere's pole row of (u, v). This bound is stricter
  // than SurfaceGeometry::regular, so the curvatures are set past it.
  const geom::SurfaceDerivatives& d = g.derivatives;
  const double area = d.du.cross(d.dv).norm(), scale = d.du.squaredNorm() + d.dv.squaredNorm();
  if (!(area > 1e-8 * scale) || !g.regular) return false;
  const geom::Curvatures& c = g.curvatures;
  const double k = std::max(std::abs(c.k1), std::abs(c.k2));
  if (!std::isfinite(k) || k * tolerance >= 1) return false;
  *out = c;
  return true;
}

int octree_level(double root_side, double length) {
  if (!(length > 0)) return std::numeric_limits<int>::max();
  if (!(length < root_side)) return 0;
  // Guard the rounding: L/2^N <= ℓ must hold exactly in floating point.
  int n = static_cast<int>(std::ceil(std::log2(root_side / length)));
  while (n > 0 && std::ldexp(root_side, -(n - 1)) <= length) --n;
  while (std::ldexp(root_side, -n) > length) ++n;
  return n;
}

Metric surface_curvature_metric(const geom::Curvatures& c, const Vec3& normal, const CurvatureRule& rule,
                                double hmin, double hmax) {
  const double l1 = std::clamp(curvature_length(c.k1, rule), hmin, hmax);
  const double l2 = std::clamp(curvature_length(c.k2, rule), hmin, hmax);
  return metric_from_sizes({c.dir1, c.dir2, normal}, Vec3(l1, l2, std::min(l1, l2)));
}

}  // namespace cm::size
