// Tight face bounding boxes without BRepBndLib::AddOptimal, whose global
// optimizer costs ~20 ms per curved face (seconds per model).
#include <cmath>

#include <gp_Pnt.hxx>
#include <gp_Pnt2d.hxx>
#include <gp_Vec.hxx>

#include "curvemesh/geom_occ/detail/occ_model.hpp"

namespace cm::geom_occ::detail {

namespace {

constexpr int kMaxSteps = 50;

struct CoordinateJet {
  double value;
  Vec2 gradient;
  double huu, huv, hvv;
};

CoordinateJet coordinate_jet(const SurfaceEvaluator& s, const Vec2& uv, int axis, double sign) {
  gp_Pnt p;
  gp_Vec du, dv, duu, dvv, duv;
  s.d2(uv.x(), uv.y(), p, du, dv, duu, dvv, duv);
  const int k = axis + 1;  // gp coordinates are 1-based
  return {sign * p.Coord(k), sign * Vec2(du.Coord(k), dv.Coord(k)), sign * duu.Coord(k),
          sign * duv.Coord(k), sign * dvv.Coord(k)};
}

// Local maximum of sign * S(u,v)[axis] from `uv`, kept in [lo, hi]: Newton
// where the Hessian is negative definite, else a gradient step; a step is
// taken only if it increases the coordinate.
Vec2 maximize_coordinate(const SurfaceEvaluator& s, Vec2 uv, int axis, double sign, const Vec2& lo,
                         const Vec2& hi, const Vec2& scale) {
  CoordinateJet jet = coordinate_jet(s, uv, axis, sign);
  for (int iter = 0; iter < kMaxSteps; ++iter) {
    Vec2 step;
    const double det = jet.huu * jet.hvv - jet.huv * jet.huv;
    if (jet.huu < 0 && det > 0) {
      step = Vec2(-(jet.hvv * jet.gradient.x() - jet.huv * jet.gradient.y()) / det,
                  -(jet.huu * jet.gradient.y() - jet.huv * jet.gradient.x()) / det);
    } else {
      // Ascent direction scaled to a tenth of the parameter box.
      const Vec2 g = jet.gradient.cwiseProduct(scale);
      if (g.norm() == 0) break;
      step = 0.1 * (g / g.norm()).cwiseProduct(scale);
    }
    bool improved = false;
    for (double alpha = 1; alpha > 1e-12; alpha *= 0.5) {
      const Vec2 next = (uv + alpha * step).cwiseMax(lo).cwiseMin(hi);
      const CoordinateJet trial = coordinate_jet(s, next, axis, sign);
      if (trial.value > jet.value) {
        const bool tiny = (next - uv).cwiseQuotient(scale).norm() < 1e-12;
        uv = next;
        jet = trial;
        improved = !tiny;
        break;
      }
    }
    if (!improved) break;
  }
  return uv;
}

}  // namespace

void add_interior_extremes(const FaceData& face, geom::BoundingBox& box) {
  const std::size_t n = face.sample_points.size();
  if (n == 0) return;
  const geom::ParamRange& r = face.range;
  const Vec2 lo(face.box_u0, face.box_v0), hi(face.box_u1, face.box_v1);
  const Vec2 scale(std::max(r.u1 - r.u0, 1e-300), std::max(r.v1 - r.v0, 1e-300));
  for (int axis = 0; axis < 3; ++axis) {
    for (const double sign : {-1.0, 1.0}) {
      std::size_t best = 0;
      for (std::size_t k = 1; k < n; ++k)
        if (sign * face.sample_points[k][axis] > sign * face.sample_points[best][axis]) best = k;
      const Vec2 uv =
          maximize_coordinate(face.eval, face.sample_params[best], axis, sign, lo, hi, scale);
      // A maximum outside the trimmed face is bounded by the boundary edges.
      if (!face_contains(face, uv)) continue;
      const gp_Pnt p = face.eval.value(uv.x(), uv.y());
      box.add(Vec3(p.X(), p.Y(), p.Z()));
    }
  }
}

}  // namespace cm::geom_occ::detail
