#pragma once
// Internal to geom_occ (includes OpenCASCADE): point evaluation of a model's
// surfaces and 3D curves, the innermost call of projections and meshing.
//
// B-spline surfaces and curves are evaluated by detail/bspline.hpp from a
// plain copy of their poles and knots, faster than OCC's evaluation
// (bspline.hpp says why and by how much), with no state; other kinds of
// geometry through the Geom handle, which is read-only (detail/
// occ_model.hpp, thread safety). Values agree with OCC's to round-off, not
// bit for bit.
#include <memory>

#include <Geom_Curve.hxx>
#include <Geom_Surface.hxx>
#include <gp_Pnt.hxx>
#include <gp_Vec.hxx>

#include "curvemesh/geom_occ/detail/bspline.hpp"

namespace cm::geom_occ::detail {

class SurfaceEvaluator {
 public:
  SurfaceEvaluator() = default;
  /// `surface` without trimming wrappers; kept alive by the evaluator.
  explicit SurfaceEvaluator(const Handle(Geom_Surface)& surface);

  void d2(double u, double v, gp_Pnt& p, gp_Vec& du, gp_Vec& dv, gp_Vec& duu, gp_Vec& dvv, gp_Vec& duv) const;
  gp_Pnt value(double u, double v) const;

 private:
  Handle(Geom_Surface) surface_;
  std::unique_ptr<const SplineSurface> spline_;  // null unless a B-spline
};

class CurveEvaluator {
 public:
  CurveEvaluator() = default;
  /// `curve` without trimming wrappers; kept alive by the evaluator.
  explicit CurveEvaluator(const Handle(Geom_Curve)& curve);

  void d2(double t, gp_Pnt& p, gp_Vec& d1, gp_Vec& d2) const;
  gp_Pnt value(double t) const;

 private:
  Handle(Geom_Curve) curve_;
  std::unique_ptr<const SplineCurve> spline_;  // null unless a B-spline
};

}  // namespace cm::geom_occ::detail
