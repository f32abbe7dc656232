#pragma once
// Internal to geom_occ: B-spline curves and surfaces as plain arrays, and
// their evaluation with two derivatives (no OpenCASCADE here; occ_evaluator
// fills these from OCC's geometry).
//
// Why by hand: OCC's direct evaluation (BSplSLib::D2) rebuilds the span's
// basis through generic multi-dimensional code and, for rational
// surfaces, a general derivative-of-a-quotient routine; its span caches
// pay a span lookup with tolerance handling per call and the same
// quotient routine. Evaluating the basis functions of the span (the
// standard triangular recurrence with derivatives) and the quotient rule
// for two derivatives directly is 2.4 to 3.3 times cheaper for rational
// surfaces and 1.1 to 1.3 times for polynomial ones (second derivatives
// on the shared models' B-spline faces), keeps no state (so needs no
// per-thread copies) and gives every thread the same bits for the same
// parameters.
//
// Only non-periodic splines: a periodic one is stored as its non-periodic
// form over one period, and parameters are wrapped into that period.
#include <array>
#include <vector>

#include "curvemesh/core/types.hpp"

namespace cm::geom_occ::detail {

/// Knots of one parametric direction (flat: each knot repeated by its
/// multiplicity) and how parameters are brought into the range.
struct SplineBasis {
  int degree = 0;
  std::vector<double> knots;  // poles + degree + 1 values
  double period = 0;          // > 0: parameters wrap into [first, first + period)
  double first = 0;
  /// The span index i (degree <= i < poles) whose polynomial t is evaluated
  /// with: knots[i] <= t < knots[i + 1], the first or last span beyond the
  /// ends (evaluation there extends the end polynomial). Wraps t first.
  int locate(double& t) const;
};

/// Homogeneous poles (w x, w y, w z, w); w = 1 when not rational.
struct SplineCurve {
  SplineBasis basis;
  std::vector<std::array<double, 4>> poles;
  bool rational = false;
  /// Point and first two derivatives at t.
  void d2(double t, Vec3& p, Vec3& d1, Vec3& d2) const;
  Vec3 d0(double t) const;
};

struct SplineSurface {
  SplineBasis u, v;
  int poles_v = 0;  // poles per row; pole (i, j) at i * poles_v + j
  std::vector<std::array<double, 4>> poles;
  bool rational = false;
  /// Point, first and second derivatives at (u, v).
  void d2(double pu, double pv, Vec3& p, Vec3& du, Vec3& dv, Vec3& duu, Vec3& dvv, Vec3& duv) const;
  Vec3 d0(double pu, double pv) const;
};

}  // namespace cm::geom_occ::detail
