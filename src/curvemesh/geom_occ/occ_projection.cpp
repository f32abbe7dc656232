// Closest point on edges and trimmed faces.
//
// Both use a bound-constrained Newton iteration on f = |S(u,v) - x|^2 / 2
// (exact Hessian, Gauss-Newton when it is not positive definite, backtracking
// so f never increases; periodic directions of a full-period entity wrap).
// With a hint, Newton starts there and its answer stands if it converges
// inside the entity. Otherwise (the global search) it starts from seed
// samples stored at load time: on an edge the two best local minima of the
// seed distances; on a face the nearest interior-grid seed and the nearest
// boundary seed, and, when a descent leaves the trimmed face for a
// trimmed-away part of the surface, a few more grid seeds from other basins
// plus the projection on the face's boundary: the best edge by 3D distance,
// refined along its p-curve image S(pc(t)), so that (u, v) lies on the
// face's boundary as the surface draws it. The best candidate inside the
// face wins. The returned point is bitwise the entity evaluated at the
// returned parameters. Remaining weakness: a local minimum in a basin no
// seed reaches can be returned instead of the global one (the grid is
// 13-41 samples per direction).
#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include <Geom2d_Curve.hxx>
#include <Standard_Failure.hxx>
#include <gp_Pnt.hxx>
#include <gp_Pnt2d.hxx>
#include <gp_Vec2d.hxx>
#include <gp_Vec.hxx>

#include "curvemesh/core/error.hpp"
#include "curvemesh/geom_occ/detail/occ_model.hpp"

namespace cm::geom_occ::detail {

namespace {

constexpr int kMaxNewtonSteps = 60;
constexpr int kMaxHalvings = 40;
// Within kNearSteps convergence lengths of the minimum, the squared distance
// of a point off the entity no longer tells a better point from a worse one
// (a tangential error e changes it by e^2, below its rounding once e is
// under about 1e-9 of the model's size), so a Newton step that does not
// lower it is taken all the same: without this, most projections ended
// with up to kMaxHalvings evaluations that could not decrease anything. A
// step under kRoundSteps convergence lengths is rounding: the point is as
// close as it gets.
constexpr double kNearSteps = 1e6;
constexpr double kRoundSteps = 1e-3;
// Further Newton starts when the first ones leave the trimmed face.
constexpr std::size_t kExtraStarts = 3;

Vec3 to_vec(const gp_XYZ& p) { return {p.X(), p.Y(), p.Z()}; }

struct SurfacePoint {
  Vec3 p, du, dv, duu, duv, dvv;
};

SurfacePoint eval(const SurfaceEvaluator& s, const Vec2& uv) {
  gp_Pnt p;
  gp_Vec du, dv, duu, dvv, duv;
  s.d2(uv.x(), uv.y(), p, du, dv, duu, dvv, duv);
  return {to_vec(p.XYZ()), to_vec(du.XYZ()), to_vec(dv.XYZ()),
          to_vec(duu.XYZ()), to_vec(duv.XYZ()), to_vec(dvv.XYZ())};
}

struct NewtonResult {
  Vec2 uv = Vec2::Zero();
  Vec3 point = Vec3::Zero();
  bool converged = false;
};

// Distance from x to an axis-aligned box (0 inside): a lower bound of the
// distance to anything in the box.
double box_distance(const geom::BoundingBox& b, const Vec3& x) {
  const Vec3 below = (b.min - x).cwiseMax(0.0);
  const Vec3 above = (x - b.max).cwiseMax(0.0);
  return (below + above).norm();
}

double wrap(double t, double lo, double period) {
  if (period <= 0) return t;
  const double k = std::floor((t - lo) / period);
  double w = t - k * period;
  if (w >= lo + period) w -= period;
  return w;
}

// Where a face's Newton iteration may go: [lo, hi] per direction, except
// directions with a period > 0, which are unbounded and wrapped into
// [origin, origin + period) to keep parameters small.
struct SearchBox {
  Vec2 lo, hi, origin, period;
};

SearchBox search_box(const FaceData& f) {
  SearchBox b{Vec2(f.box_u0, f.box_v0), Vec2(f.box_u1, f.box_v1), Vec2(f.range.u0, f.range.v0),
              Vec2::Zero()};
  if (std::isinf(f.box_u0)) b.period.x() = f.range.period_u;
  if (std::isinf(f.box_v0)) b.period.y() = f.range.period_v;
  return b;
}

Vec2 into_box(Vec2 uv, const SearchBox& b) {
  uv = uv.cwiseMax(b.lo).cwiseMin(b.hi);
  for (int k = 0; k < 2; ++k)
    if (b.period[k] > 0) uv[k] = wrap(uv[k], b.origin[k], b.period[k]);
  return uv;
}

// Newton on a face's surface, (u, v) kept in the search box.
NewtonResult newton_on_surface(const SurfaceEvaluator& s, const Vec3& x, Vec2 uv, const SearchBox& box,
                               double eps_len) {
  const Vec2& lo = box.lo;
  const Vec2& hi = box.hi;
  uv = into_box(uv, box);
  SurfacePoint sp = eval(s, uv);
  NewtonResult out;
  for (int iter = 0; iter < kMaxNewtonSteps; ++iter) {
    const Vec3 r = sp.p - x;
    const double f0 = r.squaredNorm();
    const Vec2 g(sp.du.dot(r), sp.dv.dot(r));
    // A direction at its bound with the gradient pushing outward stays fixed.
    const bool free_u = !((uv.x() <= lo.x() && g.x() > 0) || (uv.x() >= hi.x() && g.x() < 0));
    const bool free_v = !((uv.y() <= lo.y() && g.y() > 0) || (uv.y() >= hi.y() && g.y() < 0));
    if (!free_u && !free_v) {
      out.converged = true;
      break;
    }
    const double jtj_uu = sp.du.squaredNorm(), jtj_uv = sp.du.dot(sp.dv),
                 jtj_vv = sp.dv.squaredNorm();
    double huu = jtj_uu + sp.duu.dot(r), huv = jtj_uv + sp.duv.dot(r), hvv = jtj_vv + sp.dvv.dot(r);
    Vec2 step = Vec2::Zero();
    if (free_u && free_v) {
      double det = huu * hvv - huv * huv;
      if (!(huu > 0 && det > 1e-14 * huu * hvv)) {
        huu = jtj_uu;
        huv = jtj_uv;
        hvv = jtj_vv;
        // Levenberg damping keeps a pole's singular metric solvable.
        const double damping = 1e-12 * (huu + hvv) + 1e-300;
        huu += damping;
        hvv += damping;
        det = huu * hvv - huv * huv;
      }
      step = Vec2(-(hvv * g.x() - huv * g.y()) / det, -(huu * g.y() - huv * g.x()) / det);
    } else if (free_u) {
      const double h = huu > 0 ? huu : jtj_uu + 1e-300;
      step.x() = -g.x() / h;
    } else {
      const double h = hvv > 0 ? hvv : jtj_vv + 1e-300;
      step.y() = -g.y() / h;
    }
    if (!std::isfinite(step.x()) || !std::isfinite(step.y())) break;
    // Across a period the model is the same again: no longer steps.
    for (int k = 0; k < 2; ++k)
      if (box.period[k] > 0) step[k] = std::clamp(step[k], -0.5 * box.period[k], 0.5 * box.period[k]);
    // How far the step would move the point, to first order.
    const double predicted = (sp.du * step.x() + sp.dv * step.y()).norm();
    if (predicted <= kRoundSteps * eps_len) {
      out.converged = true;
      break;
    }
    bool accepted = false;
    Vec2 next = uv;
    SurfacePoint sn;
    double alpha = 1;
    for (int k = 0; k < kMaxHalvings; ++k, alpha *= 0.5) {
      next = into_box(uv + alpha * step, box);
      sn = eval(s, next);
      if ((sn.p - x).squaredNorm() <= f0) {
        accepted = true;
        break;
      }
      if (predicted <= kNearSteps * eps_len) {
        accepted = true;
        break;
      }
    }
    if (!accepted) {
      // No descent left in the Newton direction: a minimum to round-off.
      out.converged = true;
      break;
    }
    const double moved = (sn.p - sp.p).norm();
    uv = next;
    sp = sn;
    if (moved <= eps_len) {
      out.converged = true;
      break;
    }
  }
  out.uv = uv;
  out.point = sp.p;
  return out;
}

struct CurveJet {
  Vec3 point, d1, d2;
};

// Newton on t -> |C(t) - x|^2 / 2 for a curve given by `jet` (t -> C, C',
// C''), t kept in [lo, hi], or wrapped into [lo, lo + period) when period > 0
// (then lo, hi only anchor the wrap). Sets `converged` unless it ran out of
// steps.
template <class Jet>
double newton_1d(const Jet& jet, const Vec3& x, double t, double lo, double hi, double period,
                 double eps_len, bool& converged) {
  const auto keep = [&](double s) { return period > 0 ? wrap(s, lo, period) : std::clamp(s, lo, hi); };
  t = keep(t);
  CurveJet c = jet(t);
  converged = false;
  for (int iter = 0; iter < kMaxNewtonSteps; ++iter) {
    const Vec3 r = c.point - x;
    const double g = c.d1.dot(r);
    if (period <= 0 && ((t <= lo && g > 0) || (t >= hi && g < 0))) {
      converged = true;  // at an end, pushed outward
      break;
    }
    double h = c.d1.squaredNorm() + c.d2.dot(r);
    if (!(h > 0)) h = c.d1.squaredNorm();
    if (!(h > 0)) break;
    double step = -g / h;
    if (period > 0) step = std::clamp(step, -0.5 * period, 0.5 * period);
    // As on faces: a step at rounding level ends the iteration, and near the
    // minimum one the distance cannot judge is taken.
    const double predicted = std::abs(step) * c.d1.norm();
    if (predicted <= kRoundSteps * eps_len) {
      converged = true;
      break;
    }
    bool accepted = false;
    double next = t;
    CurveJet cn;
    double alpha = 1;
    for (int k = 0; k < kMaxHalvings; ++k, alpha *= 0.5) {
      next = keep(t + alpha * step);
      cn = jet(next);
      if ((cn.point - x).squaredNorm() <= r.squaredNorm()) {
        accepted = true;
        break;
      }
      if (predicted <= kNearSteps * eps_len) {
        accepted = true;
        break;
      }
    }
    if (!accepted) {
      converged = true;  // no descent left: a minimum to round-off
      break;
    }
    const double moved = (cn.point - c.point).norm();
    t = next;
    c = cn;
    if (moved <= eps_len) {
      converged = true;
      break;
    }
  }
  return t;
}

CurveJet curve_jet(const CurveEvaluator& curve, double t) {
  gp_Pnt p;
  gp_Vec d1, d2;
  curve.d2(t, p, d1, d2);
  return {to_vec(p.XYZ()), to_vec(d1.XYZ()), to_vec(d2.XYZ())};
}

// The image S(pc(t)) of a p-curve: the face's boundary as the surface sees
// it, which may stand off the 3D edge by up to the edge's tolerance.
CurveJet pcurve_jet(const SurfaceEvaluator& s, const Geom2d_Curve& pc, double t) {
  gp_Pnt2d uv;
  gp_Vec2d c1, c2;
  pc.D2(t, uv, c1, c2);
  const SurfacePoint sp = eval(s, Vec2(uv.X(), uv.Y()));
  return {sp.p, sp.du * c1.X() + sp.dv * c1.Y(),
          sp.duu * (c1.X() * c1.X()) + 2 * sp.duv * (c1.X() * c1.Y()) + sp.dvv * (c1.Y() * c1.Y()) +
              sp.du * c2.X() + sp.dv * c2.Y()};
}

}  // namespace

geom::Projection OccModel::closest_point(geom::EntityRef e, const Vec3& x,
                                         std::optional<Vec2> hint) const {
  try {
    switch (e.dim) {
      case 0: {
        const Vec3 p = vertex_at(e.tag).point;
        return {p, Vec2::Zero(), (p - x).norm()};
      }
      case 1: {
        std::optional<double> t;
        if (hint) t = hint->x();
        return project_on_edge(edge_at(e.tag), x, t);
      }
      case 2: return project_on_face(face_at(e.tag), x, hint);
      default:
        throw std::out_of_range(fmt::format("closest_point on a dimension-{} entity", e.dim));
    }
  } catch (const Standard_Failure& ex) {
    throw GeometryError(fmt::format("closest point on entity ({}, {}) failed: {}", e.dim, e.tag,
                                    ex.GetMessageString()));
  }
}

geom::Projection OccModel::project_on_edge(const EdgeData& e, const Vec3& x,
                                           std::optional<double> hint) const {
  if (e.degenerate) {
    const Vec3 p = e.sample_points.front();
    return {p, Vec2(e.first, 0), (p - x).norm()};
  }
  const double period = e.range.periodic_u ? e.range.period_u : 0;
  const double eps_len = 1e-13 * scale_;
  const auto jet = [&](double t) { return curve_jet(e.eval, t); };
  const auto newton = [&](double t, bool& converged) {
    return newton_1d(jet, x, t, e.first, e.last, period, eps_len, converged);
  };
  // Evaluated again so that the point is bitwise edge_point(param).
  const auto finish = [&](double t) {
    const Vec3 p = jet(t).point;
    return geom::Projection{p, Vec2(t, 0), (p - x).norm()};
  };
  if (hint) {
    bool converged = false;
    const double t = newton(*hint, converged);
    if (converged) return finish(t);
  }
  // Global: start from the two best local minima of the seed distances, so a
  // curve passing twice near x is not decided by one basin.
  const auto& pts = e.sample_points;
  const int n = static_cast<int>(pts.size());
  int best = -1, second = -1;
  double best_d = std::numeric_limits<double>::infinity(), second_d = best_d;
  for (int k = 0; k < n; ++k) {
    const double d = (pts[k] - x).squaredNorm();
    const bool local_min = (k == 0 || d <= (pts[k - 1] - x).squaredNorm()) &&
                           (k == n - 1 || d <= (pts[k + 1] - x).squaredNorm());
    if (!local_min) continue;
    if (d < best_d) {
      second = best;
      second_d = best_d;
      best = k;
      best_d = d;
    } else if (d < second_d) {
      second = k;
      second_d = d;
    }
  }
  bool converged = false;
  double t = newton(e.sample_params[best], converged);
  if (second >= 0) {
    const double t2 = newton(e.sample_params[second], converged);
    if ((jet(t2).point - x).squaredNorm() < (jet(t).point - x).squaredNorm()) t = t2;
  }
  return finish(t);
}

geom::Projection OccModel::project_on_face(const FaceData& f, const Vec3& x,
                                           std::optional<Vec2> hint) const {
  const SearchBox box = search_box(f);
  const double eps_len = 1e-13 * scale_;
  // Newton's point is bitwise face_point(param): the same D2 call at the
  // same parameters as face_derivatives makes.
  const auto finish_newton = [&](const NewtonResult& r) {
    return geom::Projection{r.point, r.uv, (r.point - x).norm()};
  };
  const auto inside = [&](const Vec2& uv) { return face_contains(f, uv); };
  if (hint) {
    const NewtonResult r = newton_on_surface(f.eval, x, *hint, box, eps_len);
    if (r.converged && inside(r.uv)) return finish_newton(r);
  }
  // Two starts: the nearest interior seed and the nearest boundary seed. A
  // point off a curved face can have a constrained local minimum on the
  // boundary (where the surface continues past the face) besides the
  // interior one, or the other way round.
  const auto nearest = [&](std::size_t begin, std::size_t end) {
    std::size_t best = end;
    double best_d = std::numeric_limits<double>::infinity();
    for (std::size_t k = begin; k < end; ++k) {
      const double d = (f.sample_points[k] - x).squaredNorm();
      if (d < best_d) {
        best_d = d;
        best = k;
      }
    }
    return best;
  };
  const std::size_t grid_end = f.grid_samples, all_end = f.sample_points.size();
  std::optional<geom::Projection> found;
  std::optional<Vec2> left_face;  // an answer outside the trimmed face
  const auto descend_from = [&](std::size_t seed) {
    const NewtonResult r = newton_on_surface(f.eval, x, f.sample_params[seed], box, eps_len);
    if (!inside(r.uv)) {
      left_face = r.uv;
      return;
    }
    const geom::Projection p = finish_newton(r);
    if (!found || p.distance < found->distance) found = p;
  };
  for (const std::size_t seed : {nearest(0, grid_end), nearest(grid_end, all_end)})
    if (seed < all_end) descend_from(seed);
  if (left_face) {
    // The descent left the face for a trimmed-away part of the surface:
    // other basins of the face may hold its closest point. Try the next
    // nearest grid seeds that are not neighbours of one already tried.
    std::vector<std::pair<double, std::size_t>> order;
    for (std::size_t k = 0; k < grid_end; ++k)
      order.emplace_back((f.sample_points[k] - x).squaredNorm(), k);
    const std::size_t extra = std::min<std::size_t>(order.size(), 16);
    std::partial_sort(order.begin(), order.begin() + static_cast<std::ptrdiff_t>(extra), order.end());
    std::vector<Vec2> tried;
    if (extra > 0) tried.push_back(f.sample_params[order[0].second]);
    for (std::size_t i = 1; i < extra && tried.size() <= kExtraStarts; ++i) {
      const Vec2& uv = f.sample_params[order[i].second];
      const bool near_tried = std::any_of(tried.begin(), tried.end(), [&](const Vec2& t) {
        return std::abs(t.x() - uv.x()) <= 1.5 * f.grid_step.x() &&
               std::abs(t.y() - uv.y()) <= 1.5 * f.grid_step.y();
      });
      if (near_tried) continue;
      tried.push_back(uv);
      descend_from(order[i].second);
    }
  }
  // Descent left the face: its closest point may be on the boundary.
  if (left_face) {
    const geom::Projection p = project_on_face_boundary(f, x, *left_face);
    if (!found || p.distance < found->distance) found = p;
  }
  if (!found) throw GeometryError("closest point: face without seed samples");
  return *found;
}

geom::Projection OccModel::project_on_face_boundary(const FaceData& f, const Vec3& x,
                                                    const Vec2& near_uv) const {
  geom::Projection best{Vec3::Zero(), Vec2::Zero(), std::numeric_limits<double>::infinity()};
  int best_edge = 0;
  for (const int tag : f.edges) {
    const EdgeData& e = edges_[tag - 1];
    if (e.degenerate || box_distance(e.box, x) >= best.distance) continue;
    const geom::Projection p = project_on_edge(e, x, std::nullopt);
    if (p.distance < best.distance) {
      best = p;
      best_edge = tag;
    }
  }
  if (best_edge == 0) {
    // Only degenerate edges (cannot happen on a valid face): keep the Newton answer.
    const Vec3 p = eval(f.eval, near_uv).p;
    return {p, near_uv, (p - x).norm()};
  }
  // Refine along each p-curve of that edge (a seam has two: both sides are
  // tried, the nearer kept, ties to the side nearer the unconstrained answer).
  const EdgeData& edge = edges_[best_edge - 1];
  geom::Projection result{Vec3::Zero(), near_uv, std::numeric_limits<double>::infinity()};
  double uv_gap = std::numeric_limits<double>::infinity();
  for (const PCurveUse& use : f.pcurves) {
    if (use.edge != best_edge || use.curve.IsNull()) continue;
    bool converged = false;
    const double t = newton_1d([&](double s) { return pcurve_jet(f.eval, *use.curve, s); }, x,
                               best.param.x(), edge.first, edge.last, 0, 1e-13 * scale_, converged);
    const Vec2 uv = pcurve_point(use, t);
    const Vec3 p = eval(f.eval, uv).p;
    const double d = (p - x).norm();
    const double gap = (uv - near_uv).squaredNorm();
    if (d < result.distance || (d == result.distance && gap < uv_gap)) {
      result = {p, uv, d};
      uv_gap = gap;
    }
  }
  if (std::isfinite(result.distance)) return result;
  // No p-curve stored: locate the edge point on the surface.
  const NewtonResult r = newton_on_surface(f.eval, best.point, near_uv, search_box(f),
                                           1e-13 * scale_);
  const Vec3 p = eval(f.eval, r.uv).p;
  return {p, r.uv, (p - x).norm()};
}

}  // namespace cm::geom_occ::detail
