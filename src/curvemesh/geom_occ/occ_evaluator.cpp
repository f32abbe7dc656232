#include "curvemesh/geom_occ/detail/occ_evaluator.hpp"

#include <Geom_BSplineCurve.hxx>
#include <Geom_BSplineSurface.hxx>
#include <TColStd_Array1OfReal.hxx>

namespace cm::geom_occ::detail {

namespace {

// One direction's knots; a periodic direction (already made non-periodic
// over one period) wraps parameters into that period.
SplineBasis basis_of(int degree, const TColStd_Array1OfReal& flat, bool periodic) {
  SplineBasis b;
  b.degree = degree;
  b.knots.assign(flat.begin(), flat.end());
  if (periodic) {
    const std::size_t poles = b.knots.size() - static_cast<std::size_t>(degree) - 1;
    b.first = b.knots[static_cast<std::size_t>(degree)];
    b.period = b.knots[poles] - b.first;
  }
  return b;
}

std::array<double, 4> homogeneous(const gp_Pnt& p, double w) { return {w * p.X(), w * p.Y(), w * p.Z(), w}; }

gp_Pnt to_pnt(const Vec3& p) { return {p.x(), p.y(), p.z()}; }
gp_Vec to_gp_vec(const Vec3& p) { return {p.x(), p.y(), p.z()}; }

}  // namespace

SurfaceEvaluator::SurfaceEvaluator(const Handle(Geom_Surface)& surface) : surface_(surface) {
  Handle(Geom_BSplineSurface) b = Handle(Geom_BSplineSurface)::DownCast(surface);
  if (b.IsNull()) return;
  const bool periodic_u = b->IsUPeriodic(), periodic_v = b->IsVPeriodic();
  if (periodic_u || periodic_v) {
    b = Handle(Geom_BSplineSurface)::DownCast(b->Copy());
    if (periodic_u) b->SetUNotPeriodic();
    if (periodic_v) b->SetVNotPeriodic();
  }
  auto s = std::make_unique<SplineSurface>();
  s->u = basis_of(b->UDegree(), b->UKnotSequence(), periodic_u);
  s->v = basis_of(b->VDegree(), b->VKnotSequence(), periodic_v);
  s->rational = b->IsURational() || b->IsVRational();
  s->poles_v = b->NbVPoles();
  s->poles.reserve(static_cast<std::size_t>(b->NbUPoles() * b->NbVPoles()));
  for (int i = 1; i <= b->NbUPoles(); ++i)
    for (int j = 1; j <= b->NbVPoles(); ++j) s->poles.push_back(homogeneous(b->Pole(i, j), s->rational ? b->Weight(i, j) : 1));
  spline_ = std::move(s);
}

void SurfaceEvaluator::d2(double u, double v, gp_Pnt& p, gp_Vec& du, gp_Vec& dv, gp_Vec& duu, gp_Vec& dvv,
                          gp_Vec& duv) const {
  if (!spline_) {
    surface_->D2(u, v, p, du, dv, duu, dvv, duv);
    return;
  }
  Vec3 x, xu, xv, xuu, xvv, xuv;
  spline_->d2(u, v, x, xu, xv, xuu, xvv, xuv);
  p = to_pnt(x);
  du = to_gp_vec(xu);
  dv = to_gp_vec(xv);
  duu = to_gp_vec(xuu);
  dvv = to_gp_vec(xvv);
  duv = to_gp_vec(xuv);
}

gp_Pnt SurfaceEvaluator::value(double u, double v) const {
  return spline_ ? to_pnt(spline_->d0(u, v)) : surface_->Value(u, v);
}

CurveEvaluator::CurveEvaluator(const Handle(Geom_Curve)& curve) : curve_(curve) {
  Handle(Geom_BSplineCurve) b = Handle(Geom_BSplineCurve)::DownCast(curve);
  if (b.IsNull()) return;
  const bool periodic = b->IsPeriodic();
  if (periodic) {
    b = Handle(Geom_BSplineCurve)::DownCast(b->Copy());
    b->SetNotPeriodic();
  }
  auto c = std::make_unique<SplineCurve>();
  c->basis = basis_of(b->Degree(), b->KnotSequence(), periodic);
  c->rational = b->IsRational();
  c->poles.reserve(static_cast<std::size_t>(b->NbPoles()));
  for (int i = 1; i <= b->NbPoles(); ++i) c->poles.push_back(homogeneous(b->Pole(i), c->rational ? b->Weight(i) : 1));
  spline_ = std::move(c);
}

void CurveEvaluator::d2(double t, gp_Pnt& p, gp_Vec& d1, gp_Vec& d2) const {
  if (!spline_) {
    curve_->D2(t, p, d1, d2);
    return;
  }
  Vec3 x, x1, x2;
  spline_->d2(t, x, x1, x2);
  p = to_pnt(x);
  d1 = to_gp_vec(x1);
  d2 = to_gp_vec(x2);
}

gp_Pnt CurveEvaluator::value(double t) const {
  return spline_ ? to_pnt(spline_->d0(t)) : curve_->Value(t);
}

}  // namespace cm::geom_occ::detail
