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
#include <algorithm>
#include <cmath>
#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace cm::predicates {

int orient2d(const double* a, const double* b, const double* c);
int incircle(const double* a, const double* b, const double* c, const double* d);
int orient3d(const double* a, const double* b, const double* c, const double* d);
int insphere(const double* a, const double* b, const double* c, const double* d, const double* e);

/// det[b-a, c-a, d-a] in plain floating point (six times the signed volume of the
/// tet), same sign convention as orient3d but with no guarantee on the sign.
/// For quality measures only, never for a topological decision.
double orient3d_fast(const double* a, const double* b, const double* c, const double* d);

/// orient3d and insphere with their first filter inline, for hot loops (point
/// location, Delaunay cavities): the same exact answers, the later stages out
/// of line. insphere_inline's filter bounds the error by the largest
/// coordinate differences and lift instead of the permanent: fewer flops, a
/// little more often undecided; after it, grids and other small-integer
/// inputs are settled without recomputing anything.
inline int orient3d_inline(const double* a, const double* b, const double* c, const double* d);
inline int insphere_inline(const double* a, const double* b, const double* c, const double* d,
                           const double* e);

/// How many calls of this thread fell through the filter to the exact stage
/// (for benchmarks and tests). Reset by assigning `exact_stats() = {}`.
/// insphere_unsettled counts, among the insphere ones, those its adaptive
/// stage (first-order error terms, for near-cospherical points) left to the
/// full expansion.
struct ExactStats {
  long long orient2d = 0, incircle = 0, orient3d = 0, insphere = 0;
  long long insphere_unsettled = 0;
};
ExactStats& exact_stats();

// ---------------------------------------------------------------------------
// The floating-point filters, shared by the inline entries above and the full
// predicates in predicates.cpp (which holds the proof of the error bounds).
namespace detail {

constexpr double kUnitRoundoff = 0x1p-53;

// Error bound factor for an evaluation tree whose monomials each pass through
// at most `roundings` rounded operations, the permanent computed by the same
// tree: |computed - exact| <= fl(filter_constant(m) * computed permanent).
// Proved in predicates.cpp.
constexpr double filter_constant(int roundings) {
  return roundings * kUnitRoundoff * (1.0 + 0x1p-40);
}

// Roundings per monomial, counted on the evaluation trees below.
// orient3d: three differences, the 2x2 product and subtraction, the product by
// the third row, two additions.
inline constexpr double kOrient3dBound = filter_constant(8);
// insphere: lift (a difference twice, square, two additions) = 5; 3x3 minor
// (three differences, product, subtraction, product, two additions) = 8; lift
// times minor 1; two additions.
inline constexpr double kInsphereBound = filter_constant(16);
// The same tree bounded by X Y Z L (largest |difference| per coordinate,
// largest lift; all as computed) instead of its permanent:
// |computed - exact| <= fl(kInsphereStaticBound * ((L X) * (Y Z))).
// Proof: by the lemma of predicates.cpp the error is at most gamma_16 sum_k
// |T_k|, the monomials T_k taken on the exact differences; that sum is
// sum_i lift_i perm3_i <= 4 L* 6 X* Y* Z* (each 3x3 minor has six monomials
// |z x y|). An exact difference is at most the computed one over (1 - u), a
// computed lift (three rounded operations on positive terms) at least (1 -
// u)^3 times the sum of squares of the computed differences, so L* X* Y* Z*
// <= L X Y Z / (1 - u)^8; evaluating the bound loses at most (1 - u)^3. All
// together the factor needed is 24 * 16 u / ((1 - 16 u) (1 - u)^11) < 384 u
// (1 + 2^-40). Under the header's precondition nothing underflows; a zero
// bound (all differences of one coordinate zero) only means "undecided".
inline constexpr double kInsphereStaticBound = 24 * filter_constant(16);

// A value and the permanent of the same expression.
struct Bounded {
  double value;
  double permanent;
};

// p_x q_y - q_x p_y.
inline Bounded minor2(double px, double py, double qx, double qy) {
  const double left = px * qy;
  const double right = qx * py;
  return {left - right, std::abs(left) + std::abs(right)};
}

// p_z M(q,r) - q_z M(p,r) + r_z M(p,q): a 3x3 determinant expanded along one
// column. The evaluation order ((first - second) + third) is the one counted in
// the filter constants.
inline Bounded minor3(double pz, double qz, double rz, const Bounded& qr, const Bounded& pr,
                      const Bounded& pq) {
  return {pz * qr.value - qz * pr.value + rz * pq.value,
          std::abs(pz) * qr.permanent + std::abs(qz) * pr.permanent + std::abs(rz) * pq.permanent};
}

// +1 or -1 when |value| is certainly above the error bound, 0 when undecided.
inline int certified_sign(double value, double bound) {
  return static_cast<int>(value > bound) - static_cast<int>(value < -bound);
}

// det[b-a, c-a, d-a] and its permanent.
inline Bounded orient3d_det(const double* a, const double* b, const double* c, const double* d) {
  const double ux = b[0] - a[0], uy = b[1] - a[1], uz = b[2] - a[2];
  const double vx = c[0] - a[0], vy = c[1] - a[1], vz = c[2] - a[2];
  const double wx = d[0] - a[0], wy = d[1] - a[1], wz = d[2] - a[2];
  // det[u; v; w] expanded along its first row.
  return minor3(ux, uy, uz, minor2(vy, vz, wy, wz), minor2(vx, vz, wx, wz), minor2(vx, vy, wx, wy));
}

// Minus det[[p - e, |p - e|^2]] over the rows p = a, b, c, d, and its permanent.
inline Bounded insphere_det(const double* a, const double* b, const double* c, const double* d,
                            const double* e) {
  const double aex = a[0] - e[0], aey = a[1] - e[1], aez = a[2] - e[2];
  const double bex = b[0] - e[0], bey = b[1] - e[1], bez = b[2] - e[2];
  const double cex = c[0] - e[0], cey = c[1] - e[1], cez = c[2] - e[2];
  const double dex = d[0] - e[0], dey = d[1] - e[1], dez = d[2] - e[2];
  const double a_lift = aex * aex + aey * aey + aez * aez;
  const double b_lift = bex * bex + bey * bey + bez * bez;
  const double c_lift = cex * cex + cey * cey + cez * cez;
  const double d_lift = dex * dex + dey * dey + dez * dez;
  // 2x2 minors of the (x, y) columns, then 3x3 minors along the z column.
  const Bounded ab = minor2(aex, aey, bex, bey);
  const Bounded ac = minor2(aex, aey, cex, cey);
  const Bounded ad = minor2(aex, aey, dex, dey);
  const Bounded bc = minor2(bex, bey, cex, cey);
  const Bounded bd = minor2(bex, bey, dex, dey);
  const Bounded cd = minor2(cex, cey, dex, dey);
  const Bounded bcd = minor3(bez, cez, dez, cd, bd, bc);
  const Bounded acd = minor3(aez, cez, dez, cd, ad, ac);
  const Bounded abd = minor3(aez, bez, dez, bd, ad, ab);
  const Bounded abc = minor3(aez, bez, cez, bc, ac, ab);
  // Expanded along the lifted column.
  return {(a_lift * bcd.value - b_lift * acd.value) + (c_lift * abd.value - d_lift * abc.value),
          (a_lift * bcd.permanent + b_lift * acd.permanent) +
              (c_lift * abd.permanent + d_lift * abc.permanent)};
}

}  // namespace detail

namespace detail {

// The value tree of insphere_det, and the scale L X Y Z of its static error
// bound (largest lift and |differences|, see kInsphereStaticBound).
struct StaticValue {
  double value;
  double scale;
};
inline StaticValue insphere_static(const double* a, const double* b, const double* c,
                                   const double* d, const double* e) {
#if defined(__SSE2__)
  // Two rows at a time: the very same operations (each lane rounds as the
  // scalar code below does), in half the instructions.
  const __m128d exy = _mm_loadu_pd(e);
  const __m128d ez = _mm_set1_pd(e[2]);
  const __m128d axy = _mm_sub_pd(_mm_loadu_pd(a), exy);  // [aex, aey]
  const __m128d bxy = _mm_sub_pd(_mm_loadu_pd(b), exy);
  const __m128d cxy = _mm_sub_pd(_mm_loadu_pd(c), exy);
  const __m128d dxy = _mm_sub_pd(_mm_loadu_pd(d), exy);
  const __m128d z_ab = _mm_sub_pd(_mm_set_pd(b[2], a[2]), ez);  // [aez, bez]
  const __m128d z_cd = _mm_sub_pd(_mm_set_pd(d[2], c[2]), ez);  // [cez, dez]
  const __m128d x_ab = _mm_unpacklo_pd(axy, bxy), y_ab = _mm_unpackhi_pd(axy, bxy);
  const __m128d x_cd = _mm_unpacklo_pd(cxy, dxy), y_cd = _mm_unpackhi_pd(cxy, dxy);
  const __m128d lift_ab = _mm_add_pd(_mm_add_pd(_mm_mul_pd(x_ab, x_ab), _mm_mul_pd(y_ab, y_ab)),
                                     _mm_mul_pd(z_ab, z_ab));
  const __m128d lift_cd = _mm_add_pd(_mm_add_pd(_mm_mul_pd(x_cd, x_cd), _mm_mul_pd(y_cd, y_cd)),
                                     _mm_mul_pd(z_cd, z_cd));
  // 2x2 minors, in pairs [ac, bd], [ad, bc], [ab, cd].
  const __m128d ac_bd = _mm_sub_pd(_mm_mul_pd(x_ab, y_cd), _mm_mul_pd(x_cd, y_ab));
  const __m128d ad_bc = _mm_sub_pd(_mm_mul_pd(x_ab, _mm_shuffle_pd(y_cd, y_cd, 1)),
                                   _mm_mul_pd(_mm_shuffle_pd(x_cd, x_cd, 1), y_ab));
  const __m128d ab_cd =
      _mm_sub_pd(_mm_mul_pd(_mm_unpacklo_pd(axy, cxy), _mm_unpackhi_pd(bxy, dxy)),
                 _mm_mul_pd(_mm_unpacklo_pd(bxy, dxy), _mm_unpackhi_pd(axy, cxy)));
  // 3x3 minors [bcd, acd] and [abd, abc].
  const __m128d bcd_acd = _mm_add_pd(
      _mm_sub_pd(_mm_mul_pd(_mm_shuffle_pd(z_ab, z_ab, 1), _mm_unpackhi_pd(ab_cd, ab_cd)),
                 _mm_mul_pd(_mm_unpacklo_pd(z_cd, z_cd), _mm_shuffle_pd(ac_bd, ad_bc, 1))),
      _mm_mul_pd(_mm_unpackhi_pd(z_cd, z_cd), _mm_shuffle_pd(ad_bc, ac_bd, 1)));
  const __m128d abd_abc =
      _mm_add_pd(_mm_sub_pd(_mm_mul_pd(_mm_unpacklo_pd(z_ab, z_ab), _mm_unpackhi_pd(ac_bd, ad_bc)),
                            _mm_mul_pd(_mm_unpackhi_pd(z_ab, z_ab), _mm_unpacklo_pd(ad_bc, ac_bd))),
                 _mm_mul_pd(_mm_shuffle_pd(z_cd, z_cd, 1), _mm_unpacklo_pd(ab_cd, ab_cd)));
  // [a_lift bcd - b_lift acd, c_lift abd - d_lift abc], then their sum.
  const __m128d halves =
      _mm_sub_pd(_mm_mul_pd(_mm_unpacklo_pd(lift_ab, lift_cd), _mm_unpacklo_pd(bcd_acd, abd_abc)),
                 _mm_mul_pd(_mm_unpackhi_pd(lift_ab, lift_cd), _mm_unpackhi_pd(bcd_acd, abd_abc)));
  const double det = _mm_cvtsd_f64(halves) + _mm_cvtsd_f64(_mm_unpackhi_pd(halves, halves));
  const __m128d abs_mask = _mm_castsi128_pd(_mm_set1_epi64x(0x7FFFFFFFFFFFFFFF));
  const __m128d max_x = _mm_max_pd(_mm_and_pd(x_ab, abs_mask), _mm_and_pd(x_cd, abs_mask));
  const __m128d max_y = _mm_max_pd(_mm_and_pd(y_ab, abs_mask), _mm_and_pd(y_cd, abs_mask));
  const __m128d max_z = _mm_max_pd(_mm_and_pd(z_ab, abs_mask), _mm_and_pd(z_cd, abs_mask));
  const __m128d max_lift = _mm_max_pd(lift_ab, lift_cd);
  const __m128d lift_y =
      _mm_max_pd(_mm_unpacklo_pd(max_lift, max_y), _mm_unpackhi_pd(max_lift, max_y));
  const __m128d x_z = _mm_max_pd(_mm_unpacklo_pd(max_x, max_z), _mm_unpackhi_pd(max_x, max_z));
  const __m128d products = _mm_mul_pd(lift_y, x_z);  // [L X, Y Z]
  return {det, _mm_cvtsd_f64(products) * _mm_cvtsd_f64(_mm_unpackhi_pd(products, products))};
#else
  const double aex = a[0] - e[0], aey = a[1] - e[1], aez = a[2] - e[2];
  const double bex = b[0] - e[0], bey = b[1] - e[1], bez = b[2] - e[2];
  const double cex = c[0] - e[0], cey = c[1] - e[1], cez = c[2] - e[2];
  const double dex = d[0] - e[0], dey = d[1] - e[1], dez = d[2] - e[2];
  const double a_lift = aex * aex + aey * aey + aez * aez;
  const double b_lift = bex * bex + bey * bey + bez * bez;
  const double c_lift = cex * cex + cey * cey + cez * cez;
  const double d_lift = dex * dex + dey * dey + dez * dez;
  const double ab = aex * bey - bex * aey;
  const double ac = aex * cey - cex * aey;
  const double ad = aex * dey - dex * aey;
  const double bc = bex * cey - cex * bey;
  const double bd = bex * dey - dex * bey;
  const double cd = cex * dey - dex * cey;
  const double bcd = bez * cd - cez * bd + dez * bc;
  const double acd = aez * cd - cez * ad + dez * ac;
  const double abd = aez * bd - bez * ad + dez * ab;
  const double abc = aez * bc - bez * ac + cez * ab;
  const double det = (a_lift * bcd - b_lift * acd) + (c_lift * abd - d_lift * abc);
  auto max4 = [](double p, double q, double r, double s) {
    return std::max(std::max(p, q), std::max(r, s));
  };
  const double max_x = max4(std::abs(aex), std::abs(bex), std::abs(cex), std::abs(dex));
  const double max_y = max4(std::abs(aey), std::abs(bey), std::abs(cey), std::abs(dey));
  const double max_z = max4(std::abs(aez), std::abs(bez), std::abs(cez), std::abs(dez));
  const double max_lift = max4(a_lift, b_lift, c_lift, d_lift);
  return {det, (max_lift * max_x) * (max_y * max_z)};
#endif
}

// The stages of insphere after insphere_static's filter failed: small
// integers settle it from `v` itself, anything else goes to insphere().
int insphere_after_static(const double* a, const double* b, const double* c, const double* d,
                          const double* e, StaticValue v);

}  // namespace detail

inline int orient3d_inline(const double* a, const double* b, const double* c, const double* d) {
  // (A static bound as insphere_inline's takes as many instructions here and
  // fails more often.)
  const detail::Bounded det = detail::orient3d_det(a, b, c, d);
  if (const int s = detail::certified_sign(det.value, detail::kOrient3dBound * det.permanent))
    return s;
  return orient3d(a, b, c, d);
}

inline int insphere_inline(const double* a, const double* b, const double* c, const double* d,
                           const double* e) {
  const detail::StaticValue v = detail::insphere_static(a, b, c, d, e);
  if (const int s = detail::certified_sign(v.value, detail::kInsphereStaticBound * v.scale))
    return s;
  return detail::insphere_after_static(a, b, c, d, e, v);
}

}  // namespace cm::predicates
