#pragma once
// Exact, adaptive geometric predicates.
//
// Each predicate first evaluates its determinant in floating point with a
// static/semi-static error bound (the filter); only when the result is too
// close to zero to trust does it fall back to exact arithmetic on floating-point
// expansions. The returned sign is therefore always the sign of the exact
// determinant of the (double) inputs. Inputs must be finite.
//
// Sign conventions (all return -1, 0 or +1):
// - orient2d(a,b,c)   > 0  iff a,b,c are counter-clockwise.
// - incircle(a,b,c,d) > 0  iff d is strictly inside the circle through a,b,c,
//                          given orient2d(a,b,c) > 0 (the sign flips otherwise).
// - orient3d(a,b,c,d) > 0  iff det[b-a, c-a, d-a] > 0, i.e. the tet (a,b,c,d) is
//                          positively oriented (d lies on the side of plane abc
//                          toward which (b-a)x(c-a) points).
// - insphere(a,b,c,d,e) > 0 iff e is strictly inside the sphere through a,b,c,d,
//                          given orient3d(a,b,c,d) > 0 (the sign flips otherwise).
namespace cm::predicates {

int orient2d(const double* a, const double* b, const double* c);
int incircle(const double* a, const double* b, const double* c, const double* d);
int orient3d(const double* a, const double* b, const double* c, const double* d);
int insphere(const double* a, const double* b, const double* c, const double* d,
             const double* e);

/// Plain floating-point determinants, same sign convention, no guarantee.
/// For quality measures only, never for a topological decision.
double orient3d_fast(const double* a, const double* b, const double* c, const double* d);

/// How many calls fell through the filter to the exact stage (for benchmarks
/// and tests; thread-local).
struct ExactStats {
  long long orient2d = 0, incircle = 0, orient3d = 0, insphere = 0;
};
ExactStats& exact_stats();

}  // namespace cm::predicates
