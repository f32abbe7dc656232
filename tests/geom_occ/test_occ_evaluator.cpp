// The cached evaluation of B-spline surfaces and curves (detail/
// occ_evaluator.hpp) against OCC's direct evaluation, on every B-spline of
// the shared models: the same point and derivatives to round-off, inside
// the parameter range, at the knots and beyond the ends; and the very same
// bits whatever the thread evaluated before (the spans visited in another
// order, knots approached from either side).
#include <algorithm>
#include <array>
#include <cmath>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include <BRep_Tool.hxx>
#include <Geom_BSplineCurve.hxx>
#include <Geom_BSplineSurface.hxx>
#include <GeomConvert.hxx>
#include <Geom_Circle.hxx>
#include <Geom_SphericalSurface.hxx>
#include <gp_Ax3.hxx>
#include <Geom_RectangularTrimmedSurface.hxx>
#include <Geom_TrimmedCurve.hxx>
#include <TopExp_Explorer.hxx>
#include <TopoDS.hxx>

#include "curvemesh/geom_occ/detail/occ_evaluator.hpp"
#include "occ_reference.hpp"

namespace cm::geom_occ {
namespace {

using detail::CurveEvaluator;
using detail::SurfaceEvaluator;

double max_abs(const gp_XYZ& p) { return std::max({std::abs(p.X()), std::abs(p.Y()), std::abs(p.Z())}); }

// Parameters to probe in [lo, hi]: every knot, one ulp either side of it,
// random ones, and points a little beyond both ends.
std::vector<double> probes(const TColStd_Array1OfReal& knots, double lo, double hi, std::mt19937& rng) {
  std::vector<double> t;
  for (int i = knots.Lower(); i <= knots.Upper(); ++i) {
    const double k = knots(i);
    if (k < lo || k > hi) continue;
    t.insert(t.end(), {k, std::nextafter(k, -INFINITY), std::nextafter(k, INFINITY)});
  }
  std::uniform_real_distribution<double> u(lo, hi);
  for (int i = 0; i < 40; ++i) t.push_back(u(rng));
  t.push_back(lo - 0.01 * (hi - lo));
  t.push_back(hi + 0.01 * (hi - lo));
  return t;
}

struct SurfaceSample {
  gp_Pnt p;
  gp_Vec d[5];
  bool operator==(const SurfaceSample& o) const {
    if (!p.IsEqual(o.p, 0)) return false;
    for (int k = 0; k < 5; ++k)
      if (d[k].X() != o.d[k].X() || d[k].Y() != o.d[k].Y() || d[k].Z() != o.d[k].Z()) return false;
    return true;
  }
};

// Checks one B-spline surface: agreement with OCC, then history independence.
void check_surface(const Handle(Geom_BSplineSurface)& b, std::mt19937& rng) {
  const SurfaceEvaluator eval(b);
  double u0, u1, v0, v1;
  b->Bounds(u0, u1, v0, v1);
  const std::vector<double> us = probes(b->UKnotSequence(), u0, u1, rng);
  const std::vector<double> vs = probes(b->VKnotSequence(), v0, v1, rng);
  std::vector<std::pair<double, double>> at;
  for (std::size_t i = 0; i < 300; ++i) at.emplace_back(us[i % us.size()], vs[(i * 7 + i / vs.size()) % vs.size()]);
  const double scale = max_abs(b->Pole(1, 1).XYZ()) + b->Pole(1, 1).Distance(b->Pole(b->NbUPoles(), b->NbVPoles()));
  // Beyond the ends both extrapolate the end span's polynomial, which
  // amplifies round-off differently in the two bases.
  auto tolerance = [&](double u, double v) { return (u >= u0 && u <= u1 && v >= v0 && v <= v1 ? 1e-9 : 1e-7) * scale; };
  for (const auto& [u, v] : at) {
    SurfaceSample c, o;
    eval.d2(u, v, c.p, c.d[0], c.d[1], c.d[2], c.d[3], c.d[4]);
    b->D2(u, v, o.p, o.d[0], o.d[1], o.d[2], o.d[3], o.d[4]);
    ASSERT_LE(c.p.Distance(o.p), tolerance(u, v)) << "surface point at " << u << ", " << v;
    for (int k = 0; k < 2; ++k)
      ASSERT_LE((c.d[k] - o.d[k]).Magnitude(), 1e-7 * (1 + o.d[k].Magnitude()))
          << "derivative " << k << " at " << u << ", " << v;
    ASSERT_LE(eval.value(u, v).Distance(b->Value(u, v)), tolerance(u, v)) << "surface value at " << u << ", " << v;
  }
  std::shuffle(at.begin(), at.end(), rng);  // the same points after other spans
  for (const auto& [u, v] : at) {
    SurfaceSample c, again;
    eval.d2(u, v, c.p, c.d[0], c.d[1], c.d[2], c.d[3], c.d[4]);
    const SurfaceEvaluator fresh(b);
    fresh.d2(u, v, again.p, again.d[0], again.d[1], again.d[2], again.d[3], again.d[4]);
    ASSERT_TRUE(c == again) << "history changed the value at " << u << ", " << v;
  }
}

// The same for one B-spline curve; knots are approached from both sides.
void check_curve(const Handle(Geom_BSplineCurve)& b, std::mt19937& rng) {
  const CurveEvaluator eval(b);
  std::vector<double> ts = probes(b->KnotSequence(), b->FirstParameter(), b->LastParameter(), rng);
  const double scale = max_abs(b->Pole(1).XYZ()) + b->Pole(1).Distance(b->Pole(b->NbPoles()));
  auto tolerance = [&](double t) {
    return (t >= b->FirstParameter() && t <= b->LastParameter() ? 1e-9 : 1e-7) * scale;
  };
  std::vector<std::array<gp_XYZ, 3>> first;
  for (const double t : ts) {
    gp_Pnt p, q;
    gp_Vec d1, d2, e1, e2;
    eval.d2(t, p, d1, d2);
    b->D2(t, q, e1, e2);
    ASSERT_LE(p.Distance(q), tolerance(t)) << "curve point at " << t;
    ASSERT_LE((d1 - e1).Magnitude(), 1e-7 * (1 + e1.Magnitude())) << "tangent at " << t;
    ASSERT_LE(eval.value(t).Distance(b->Value(t)), tolerance(t)) << "curve value at " << t;
    first.push_back({p.XYZ(), d1.XYZ(), d2.XYZ()});
  }
  std::reverse(ts.begin(), ts.end());
  for (std::size_t i = 0; i < ts.size(); ++i) {
    gp_Pnt p;
    gp_Vec d1, d2;
    eval.d2(ts[i], p, d1, d2);
    const auto& was = first[ts.size() - 1 - i];
    ASSERT_TRUE(p.XYZ().IsEqual(was[0], 0) && d1.XYZ().IsEqual(was[1], 0) && d2.XYZ().IsEqual(was[2], 0))
        << "history changed the value at " << ts[i];
  }
}

// Rational and periodic: a sphere and a circle made B-splines.
TEST(Evaluators, PeriodicRationalSplines) {
  std::mt19937 rng(3);
  const gp_Ax3 frame(gp_Pnt(1, 2, 3), gp_Dir(0.2, 0.3, 1));
  const auto sphere = GeomConvert::SurfaceToBSplineSurface(new Geom_SphericalSurface(frame, 2.5));
  ASSERT_FALSE(sphere.IsNull());
  ASSERT_TRUE(sphere->IsUPeriodic() && sphere->IsURational());
  check_surface(sphere, rng);
  const auto circle = GeomConvert::CurveToBSplineCurve(new Geom_Circle(frame.Ax2(), 4));
  ASSERT_FALSE(circle.IsNull());
  ASSERT_TRUE(circle->IsPeriodic() && circle->IsRational());
  check_curve(circle, rng);
}

class Evaluators : public ::testing::TestWithParam<std::string> {};

TEST_P(Evaluators, AgreeWithOccAndDoNotDependOnWhatCameBefore) {
  const test::Reference ref = test::read_reference(GetParam());
  std::mt19937 rng(7);
  int surfaces = 0, curves = 0;
  for (TopExp_Explorer ex(ref.solids, TopAbs_FACE); ex.More() && surfaces < 60; ex.Next()) {
    Handle(Geom_Surface) s = BRep_Tool::Surface(TopoDS::Face(ex.Current()));
    while (auto t = Handle(Geom_RectangularTrimmedSurface)::DownCast(s)) s = t->BasisSurface();
    if (const auto b = Handle(Geom_BSplineSurface)::DownCast(s); !b.IsNull()) {
      ++surfaces;
      check_surface(b, rng);
    }
  }
  for (TopExp_Explorer ex(ref.solids, TopAbs_EDGE); ex.More() && curves < 200; ex.Next()) {
    double f = 0, l = 0;
    Handle(Geom_Curve) c = BRep_Tool::Curve(TopoDS::Edge(ex.Current()), f, l);
    while (auto t = Handle(Geom_TrimmedCurve)::DownCast(c)) c = t->BasisCurve();
    if (const auto b = Handle(Geom_BSplineCurve)::DownCast(c); !b.IsNull()) {
      ++curves;
      check_curve(b, rng);
    }
  }
  RecordProperty("bspline_surfaces", surfaces);
  RecordProperty("bspline_curves", curves);
}

std::string test_name(const ::testing::TestParamInfo<std::string>& info) {
  std::string name = test::base_name(info.param);
  for (char& c : name)
    if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
  return name;
}

INSTANTIATE_TEST_SUITE_P(Models, Evaluators, ::testing::ValuesIn(test::model_files()), test_name);

}  // namespace
}  // namespace cm::geom_occ
