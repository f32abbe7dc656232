// Point-wise shape queries of OccModel: derivatives, normals, curvatures,
// p-curves and the trimmed-face test. Everything here reads the tables built
// at load time and evaluates Geom handles directly (thread-safety argument in
// detail/occ_model.hpp).
#include <cmath>
#include <cstdint>
#include <stdexcept>

#include <Standard_Failure.hxx>
#include <gp_Pnt.hxx>
#include <gp_Pnt2d.hxx>
#include <gp_Vec.hxx>

#include "curvemesh/core/error.hpp"
#include "curvemesh/geom_occ/detail/occ_model.hpp"

namespace cm::geom_occ::detail {

namespace {

Vec3 to_vec(const gp_XYZ& p) { return {p.X(), p.Y(), p.Z()}; }

geom::SurfaceDerivatives eval_surface(const FaceData& f, int tag, const Vec2& uv) {
  gp_Pnt p;
  gp_Vec du, dv, duu, dvv, duv;
  try {
    f.eval.d2(uv.x(), uv.y(), p, du, dv, duu, dvv, duv);
  } catch (const Standard_Failure& e) {
    throw GeometryError(fmt::format("face {}: cannot evaluate at ({}, {}): {}", tag, uv.x(),
                                    uv.y(), e.GetMessageString()));
  }
  return {to_vec(p.XYZ()), to_vec(du.XYZ()), to_vec(dv.XYZ()),
          to_vec(duu.XYZ()), to_vec(duv.XYZ()), to_vec(dvv.XYZ())};
}

// The cross product du x dv vanishes at poles and apexes; the normal there is
// its limit, approached from inside the UV box. Returns false when even the
// nudged points are singular.
bool regular_derivatives(const FaceData& f, int tag, const Vec2& uv,
                         geom::SurfaceDerivatives& d, Vec3& normal) {
  const geom::ParamRange& r = f.range;
  const Vec2 center(0.5 * (r.u0 + r.u1), 0.5 * (r.v0 + r.v1));
  for (const double t : {0.0, 1e-9, 1e-7, 1e-5, 1e-3}) {
    const Vec2 at = uv + t * (center - uv);
    d = eval_surface(f, tag, at);
    const Vec3 n = d.du.cross(d.dv);
    const double scale = d.du.norm() * d.dv.norm();
    if (scale > 0 && n.norm() > 1e-12 * scale) {
      normal = (f.flip_normal ? -n : n).normalized();
      return true;
    }
  }
  return false;
}

// Edge meshing asks for an edge's derivatives at u and then, through the
// size field, for its curvature at the same u (a second D2 evaluation, a
// third of the edge meshing): the last evaluation of each thread serves
// both. Keyed by the model's serial number, not its address, which a later
// model may take.
struct LastEdgeEvaluation {
  std::uint64_t model = 0;
  int edge = 0;
  double u = 0;
  geom::CurveDerivatives d;
};
thread_local LastEdgeEvaluation t_last_edge;

}  // namespace

geom::CurveDerivatives OccModel::edge_derivatives(int edge, double u) const {
  const EdgeData& e = edge_at(edge);
  if (e.degenerate) {
    const Vec3 p = e.vertices[0] > 0 ? vertices_[e.vertices[0] - 1].point : e.box.min;
    return {p, Vec3::Zero(), Vec3::Zero()};
  }
  gp_Pnt p;
  gp_Vec d1, d2;
  try {
    e.eval.d2(u, p, d1, d2);
  } catch (const Standard_Failure& ex) {
    throw GeometryError(
        fmt::format("edge {}: cannot evaluate at {}: {}", edge, u, ex.GetMessageString()));
  }
  const geom::CurveDerivatives d{to_vec(p.XYZ()), to_vec(d1.XYZ()), to_vec(d2.XYZ())};
  t_last_edge = {serial_, edge, u, d};
  return d;
}

geom::SurfaceDerivatives OccModel::face_derivatives(int face, const Vec2& uv) const {
  return eval_surface(face_at(face), face, uv);
}

Vec3 OccModel::face_normal(int face, const Vec2& uv) const {
  const FaceData& f = face_at(face);
  geom::SurfaceDerivatives d;
  Vec3 n;
  if (!regular_derivatives(f, face, uv, d, n))
    throw GeometryError(
        fmt::format("face {}: no normal at ({}, {}): singular parametrization", face, uv.x(), uv.y()));
  return n;
}

namespace {

// n: the unit normal of d, out of the material.
geom::Curvatures curvatures_of(const geom::SurfaceDerivatives& d, const Vec3& n) {
  // Second fundamental form in an orthonormal tangent frame (e1, e2), where
  // it is a symmetric 2x2 matrix whose eigenpairs are the principal
  // curvatures and directions. A tangent t = a du + b dv has (a, b) = I^-1
  // (du.t, dv.t).
  const double E = d.du.dot(d.du), F = d.du.dot(d.dv), G = d.dv.dot(d.dv);
  const double L = d.duu.dot(n), M = d.duv.dot(n), N = d.dvv.dot(n);
  const double det = E * G - F * F;
  const Vec3 e1 = d.du.norm() > 0 ? Vec3(d.du.normalized()) : Vec3(d.dv.cross(n).normalized());
  const Vec3 e2 = n.cross(e1);
  const auto coords = [&](const Vec3& t) {
    const double pu = d.du.dot(t), pv = d.dv.dot(t);
    return Vec2((G * pu - F * pv) / det, (E * pv - F * pu) / det);
  };
  const auto second_form = [&](const Vec2& s, const Vec2& t) {
    return s.x() * L * t.x() + (s.x() * t.y() + s.y() * t.x()) * M + s.y() * N * t.y();
  };
  const Vec2 c1 = coords(e1), c2 = coords(e2);
  // Sign: positive where the surface bends away from the outward normal (a
  // convex solid), i.e. minus the second form taken with the outward normal.
  const double a = -second_form(c1, c1), b = -second_form(c1, c2), c = -second_form(c2, c2);
  const double mean = 0.5 * (a + c);
  const double half_gap = std::hypot(0.5 * (a - c), b);
  geom::Curvatures k;
  k.k1 = mean + half_gap;
  k.k2 = mean - half_gap;
  // Eigenvector of k1: the larger of two equivalent expressions, for stability.
  Vec2 w1(b, k.k1 - a), w2(k.k1 - c, b);
  Vec2 w = w1.squaredNorm() >= w2.squaredNorm() ? w1 : w2;
  if (w.squaredNorm() <= 1e-300) w = Vec2(1, 0);  // umbilic: every direction is principal
  k.dir1 = (w.x() * e1 + w.y() * e2).normalized();
  k.dir2 = n.cross(k.dir1);
  return k;
}

}  // namespace

geom::Curvatures OccModel::face_curvatures(int face, const Vec2& uv) const {
  const FaceData& f = face_at(face);
  geom::SurfaceDerivatives d;
  Vec3 n;
  if (!regular_derivatives(f, face, uv, d, n))
    throw GeometryError(fmt::format("face {}: no curvature at ({}, {}): singular parametrization",
                                    face, uv.x(), uv.y()));
  return curvatures_of(d, n);
}

// One D2 evaluation where face_point, face_derivatives and face_curvatures
// would make three; at a regular point regular_derivatives takes exactly
// this evaluation, so the curvatures are face_curvatures' own.
geom::SurfaceGeometry OccModel::face_geometry(int face, const Vec2& uv) const {
  const FaceData& f = face_at(face);
  geom::SurfaceGeometry g;
  g.derivatives = eval_surface(f, face, uv);
  const geom::SurfaceDerivatives& d = g.derivatives;
  const Vec3 cross = d.du.cross(d.dv);
  const double scale = d.du.norm() * d.dv.norm();
  g.regular = scale > 0 && cross.norm() > 1e-12 * scale;
  if (g.regular) g.curvatures = curvatures_of(d, (f.flip_normal ? -cross : cross).normalized());
  return g;
}

double OccModel::edge_curvature(int edge, double u) const {
  const LastEdgeEvaluation& last = t_last_edge;
  const geom::CurveDerivatives d =
      last.model == serial_ && last.edge == edge && last.u == u ? last.d : edge_derivatives(edge, u);
  const double speed = d.d1.norm();
  if (speed <= 0) return 0;
  return d.d1.cross(d.d2).norm() / (speed * speed * speed);
}

Vec2 OccModel::pcurve_point(const PCurveUse& use, double u) {
  const gp_Pnt2d p = use.curve->Value(u);
  return {p.X(), p.Y()};
}

Vec2 OccModel::edge_param_on_face(int edge, int face, double u, bool forward) const {
  const FaceData& f = face_at(face);
  edge_at(edge);
  const PCurveUse* found = nullptr;
  for (const PCurveUse& use : f.pcurves) {
    if (use.edge != edge) continue;
    // Only a seam has two different p-curves; any use serves another edge.
    if (use.forward == forward) {
      found = &use;
      break;
    }
    if (!found) found = &use;
  }
  if (!found)
    throw std::invalid_argument(fmt::format("edge {} does not bound face {}", edge, face));
  if (!found->curve.IsNull()) return pcurve_point(*found, u);
  // No stored p-curve: locate the edge point on the surface instead.
  const Vec3 p = edge_derivatives(edge, u).point;
  return project_on_face(f, p, std::nullopt).param;
}

bool OccModel::contains_param(int face, const Vec2& uv) const {
  return face_contains(face_at(face), uv);
}


}  // namespace cm::geom_occ::detail
