#pragma once
// Exact, adaptive geometric predicates.
//
// Each predicate first evaluates its determinant in floating point together with
// a semi-static error bound proportional to the determinant's permanent (the
// filter); only when the result is too close to zero to trust does it fall back
// to exact arithmetic on floating-point expansions. The returned sign is
// therefore always the sign of the exact determinant of the (double) inputs,
// never an approximation, and a zero means an exact degeneracy.
//
// Sign conventions (all return -1, 0 or +1):
// - orient2d(a,b,c)   > 0  iff a,b,c are counter-clockwise, i.e. det[b-a, c-a] > 0.
// - incircle(a,b,c,d) > 0  iff d is strictly inside the circle through a,b,c,
//                          given orient2d(a,b,c) > 0 (the sign flips otherwise).
//                          It is the sign of det[[a-d, |a-d|^2], [b-d, ..], [c-d, ..]].
// - orient3d(a,b,c,d) > 0  iff det[b-a, c-a, d-a] > 0, i.e. the tet (a,b,c,d) is
//                          positively oriented (d lies on the side of plane abc
//                          toward which (b-a)x(c-a) points).
// - insphere(a,b,c,d,e) > 0 iff e is strictly inside the sphere through a,b,c,d,
//                          given orient3d(a,b,c,d) > 0 (the sign flips otherwise).
//                          It is minus the sign of det[[p-e, |p-e|^2]] over the
//                          rows p = a,b,c,d.
// Every predicate is antisymmetric: exchanging any two of its arguments negates
// the result (for incircle and insphere this includes the query point).
//
// Preconditions. Points are arrays of 2 (orient2d, incircle) or 3 doubles.
// Every coordinate must be finite (checked by CM_DEBUG_ASSERT in debug builds).
// The answer is guaranteed exact when every nonzero coordinate has magnitude in
// [2^-100, 2^190] (about 7.9e-31 .. 1.6e57): in that range no intermediate value
// overflows and no rounding error underflows. Outside it the result is still a
// sign, but may be wrong. The floating-point environment must be the default one
// (IEEE-754 binary64, round-to-nearest-even, no x87 excess precision, no
// -ffast-math): the expansion arithmetic depends on it.
//
// Cost. A filtered call is a few tens of flops (5 to 20 ns). A call that falls
// through to the exact stage costs from a few hundred nanoseconds (short
// expansions, e.g. integer coordinates) to several microseconds (full 53-bit
// coordinates); bench/bench_predicates measures both. insphere's exact stage
// uses about 130 KB of stack, the others under 10 KB. All functions are
// thread-safe: they keep no state other than the thread-local ExactStats.
namespace cm::predicates {

int orient2d(const double* a, const double* b, const double* c);
int incircle(const double* a, const double* b, const double* c, const double* d);
int orient3d(const double* a, const double* b, const double* c, const double* d);
int insphere(const double* a, const double* b, const double* c, const double* d, const double* e);

/// det[b-a, c-a, d-a] in plain floating point (six times the signed volume of the
/// tet), same sign convention as orient3d but with no guarantee on the sign.
/// For quality measures only, never for a topological decision.
double orient3d_fast(const double* a, const double* b, const double* c, const double* d);

/// How many calls of this thread fell through the filter to the exact stage
/// (for benchmarks and tests). Reset by assigning `exact_stats() = {}`.
struct ExactStats {
  long long orient2d = 0, incircle = 0, orient3d = 0, insphere = 0;
};
ExactStats& exact_stats();

}  // namespace cm::predicates
