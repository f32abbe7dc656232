// Adaptive exact predicates: a semi-static floating-point filter, then exact
// evaluation with floating-point expansions (Priest, Shewchuk) when the filter
// cannot certify the sign.
//
// Filter. Every determinant is evaluated on the coordinate differences, and the
// same expression tree is evaluated a second time with every subtraction turned
// into an addition and every leaf into its absolute value: that is the
// permanent P. The bound c * P with c = filter_constant(m) is valid for any tree
// in which each monomial passes through at most m rounded operations; the lemma
// is proved at filter_constant, and each predicate states its own m.
//
// Exact stage. It never forms inexact differences: it evaluates the determinant
// of the lifted matrix of the raw coordinates (rows (1, x, y[, z][, |p|^2])),
// which is equal to the translated determinant in exact arithmetic, so every
// leaf is a single double and the expansions stay short. Results are exact under
// the magnitude precondition of the header: with nonzero coordinates in
// [2^-100, 2^190] every double produced is a multiple of (2^-152)^5 = 2^-760 (so
// no rounding error underflows) and stays below 2^990 (so nothing overflows,
// including the 2^27 splitter of the Dekker product).
#include "curvemesh/core/predicates.hpp"

#include <algorithm>
#include <array>
#include <cfloat>
#include <cmath>
#include <limits>

#include "curvemesh/core/error.hpp"

// The expansion arithmetic relies on every operation being rounded exactly once
// to binary64 with ties to even.
static_assert(std::numeric_limits<double>::is_iec559, "binary64 arithmetic required");
static_assert(FLT_EVAL_METHOD == 0, "excess precision (x87) breaks the error-free transforms");
#if defined(__FAST_MATH__)
#error "predicates.cpp must not be compiled with -ffast-math"
#endif
// Contracting a*b+c into an fma would break the Dekker split. GCC does not
// contract in ISO mode (-std=c++20), and clang honours this pragma.
#pragma STDC FP_CONTRACT OFF

namespace cm::predicates {

ExactStats& exact_stats() {
  thread_local ExactStats stats;
  return stats;
}

namespace {

// ---------------------------------------------------------------------------
// Filter constants (defined in predicates.hpp, shared with the inline filters).
//
// filter_constant(m) is the error bound factor for an evaluation tree whose
// monomials each pass through at most m rounded operations (a rounded
// difference used twice counts twice), with the permanent computed by the same
// tree.
//
// Lemma. Write the exact determinant as D = sum_k s_k T_k, T_k products of exact
// coordinate differences, s_k = +-1. Without underflow or overflow each
// operation returns (x op y)(1 + delta), |delta| <= u = 2^-53, so the computed
// value is D~ = sum_k s_k T_k (1 + theta_k) with |theta_k| <= gamma_m = m u /
// (1 - m u) (Higham, Lemma 3.1), hence |D~ - D| <= gamma_m sum_k |T_k|. The
// computed permanent is P~ = sum_k |T_k| (1 + theta'_k) >= (1 - gamma_m) sum |T_k|,
// and fl(c P~) >= (1 - u) c P~. So fl(c P~) >= |D~ - D| as soon as
//   c >= gamma_m / ((1 - gamma_m)(1 - u)) = m u / ((1 - 2 m u)(1 - u)),
// which is at most m u (1 + (2m + 2) u) < m u (1 + 2^-40) for m <= 64. When
// |D~| > fl(c P~) >= |D~ - D|, D is nonzero and has the sign of D~.
// No underflow: under the header's precondition every difference is a multiple
// of 2^-152 and every value of a degree-k tree a multiple of 2^(-152 k), at
// least 2^-760 when nonzero, far above the normal range limit 2^-1022.
// The constant is exact in binary64 (m (1 + 2^-40) needs 46 bits).
using detail::Bounded;
using detail::certified_sign;
using detail::filter_constant;
using detail::kInsphereBound;
using detail::kOrient3dBound;
using detail::minor2;

// orient2d: two differences, one product, one subtraction.
constexpr double kOrient2dBound = filter_constant(4);
// incircle: lift (a difference twice, square, one addition) = 4; 2x2 minor
// (two differences, product, subtraction) = 4; lift times minor 1; two additions.
constexpr double kIncircleBound = filter_constant(11);

// Small-integer stage. When every input coordinate is an integer of magnitude
// at most 2^50 and the computed permanent P~ of orient3d or insphere is below
// 2^50, the filter's floating-point value is the exact determinant, zero
// included: grids and integer inputs, where ties are the rule, then never
// reach the expansions.
//
// Lemma. The differences are integers of magnitude <= 2^51, computed exactly.
// Every node N of the value tree then has an exact value that is an integer,
// bounded by its permanent pi(N) (pi of a leaf is its magnitude, of a sum the
// sum, of a product the product). Let w(N) be the product of the permanents of
// the other factors met on the path from N to the root: pi(root) >= w(N) pi(N)
// and w(N) is 0 or >= 1 (a product of nonnegative integers). By induction from
// the leaves: (i) a node with pi(N) = 0 is computed as exactly 0 (a sum of
// zeros, or a finite value times an exact 0: every computed value stays below
// 2^(51 * 5) so none is infinite); (ii) a node with w(N) >= 1 is computed
// exactly: its operands are exact (for a product A B with pi(B) = 0, B is 0 by
// (i) and so is the computed product; otherwise w(A), w(B) >= w(N) >= 1), and
// the exact result is an integer of magnitude <= pi(N) <= pi(root) < 2^51,
// representable. The root has w = 1. Finally pi(root) <= P~ / (1 - gamma_16) <
// 2^51 by the lemma above.
constexpr double kIntegerPermanentLimit = 0x1p50;

inline bool small_integer(double x) {
  return std::abs(x) <= 0x1p50 && x == static_cast<double>(static_cast<long long>(x));
}

inline bool small_integers(const double* p) {
  return small_integer(p[0]) && small_integer(p[1]) && small_integer(p[2]);
}

inline int sign_of(double x) { return static_cast<int>(x > 0.0) - static_cast<int>(x < 0.0); }

[[maybe_unused]] inline bool all_finite(const double* p, int dim) {
  for (int i = 0; i < dim; ++i) {
    if (!std::isfinite(p[i])) return false;
  }
  return true;
}

// ---------------------------------------------------------------------------
// Error-free transformations.

// a + b = sum + err exactly, for any a, b (Knuth).
inline void two_sum(double a, double b, double& sum, double& err) {
  sum = a + b;
  const double b_part = sum - a;
  const double a_part = sum - b_part;
  err = (a - a_part) + (b - b_part);
}

// a + b = sum + err exactly, provided |a| >= |b| or a == 0 (Dekker).
inline void fast_two_sum(double a, double b, double& sum, double& err) {
  sum = a + b;
  err = b - (sum - a);
}

// a * b = product + err exactly. A factor used many times (scaling an
// expansion) is split once into a SplitFactor.
#if defined(__FMA__) || defined(__FP_FAST_FMA)
struct SplitFactor {};
inline SplitFactor split_factor(double) { return {}; }

inline void two_product(double a, double b, SplitFactor, double& product, double& err) {
  product = a * b;
  err = std::fma(a, b, -product);
}
#else
// 2^27 + 1: multiplying by it and subtracting splits a double into two halves of
// at most 26 significant bits each, whose pairwise products are exact (Dekker).
constexpr double kSplitter = 0x1p27 + 1.0;

struct SplitFactor {
  double high;
  double low;
};

inline SplitFactor split_factor(double a) {
  const double scaled = kSplitter * a;
  const double excess = scaled - a;
  const double high = scaled - excess;
  return {high, a - high};
}

inline void two_product(double a, double b, SplitFactor bs, double& product, double& err) {
  product = a * b;
  const SplitFactor as = split_factor(a);
  // Each parenthesised subtraction is exact (Dekker's theorem).
  err = as.low * bs.low - (((product - as.high * bs.high) - as.low * bs.high) - as.high * bs.low);
}
#endif

// ---------------------------------------------------------------------------
// Expansions: a value represented as the exact sum of doubles stored in
// increasing order of magnitude, strongly nonoverlapping, with no zero
// component (n == 0 means zero). The sign is the sign of the largest component.
// Capacities are compile-time worst cases, so the buffers live on the stack.

template <int N>
struct Expansion {
  std::array<double, N> c;  // only the first n are meaningful
  int n = 0;

  Expansion() = default;
  // Copies only the live components: capacities are worst cases, and copying
  // them whole made copies the dominant cost of the exact stage.
  Expansion(const Expansion& other) : n(other.n) {
    std::copy_n(other.c.begin(), other.n, c.begin());
  }
  Expansion& operator=(const Expansion& other) {
    n = other.n;
    std::copy_n(other.c.begin(), other.n, c.begin());
    return *this;
  }

  void push(double x) {
    if (x != 0.0) c[n++] = x;
  }
  int sign() const { return n == 0 ? 0 : (c[n - 1] > 0.0 ? 1 : -1); }
};

// Appends x to h unless it is zero, without a data-dependent branch (the zero
// tests are unpredictable). The slot h[n] must exist even when x is dropped.
inline void push_nonzero(double* h, int& n, double x) {
  h[n] = x;
  n += static_cast<int>(x != 0.0);
}

// h = e + f (Shewchuk's fast expansion sum with zero elimination: merge by
// magnitude, then one pass of two-sums). Needs round-to-even; h must hold
// ne + nf components and alias neither input.
int add_expansions(const double* e, int ne, const double* f, int nf, double* h) {
  if (ne == 0 || nf == 0) {
    const double* src = ne == 0 ? f : e;
    const int n = ne + nf;
    std::copy_n(src, n, h);
    return n;
  }
  int i = 0;
  int j = 0;
  // Smaller in magnitude of e[i] and f[j], both present; a select, not a branch.
  auto pop_smaller = [&]() {
    const bool from_e = std::abs(e[i]) <= std::abs(f[j]);
    const double g = from_e ? e[i] : f[j];
    i += static_cast<int>(from_e);
    j += static_cast<int>(!from_e);
    return g;
  };
  auto pop_any = [&]() {
    if (i < ne && j < nf) return pop_smaller();
    return i < ne ? e[i++] : f[j++];
  };
  // Each store below goes to a slot below the number of components consumed,
  // so it stays inside the ne + nf capacity even when the component is zero.
  int nh = 0;
  double sum = pop_smaller();
  double err = 0.0;
  fast_two_sum(pop_any(), sum, sum, err);
  push_nonzero(h, nh, err);
  while (i < ne && j < nf) {
    two_sum(sum, pop_smaller(), sum, err);
    push_nonzero(h, nh, err);
  }
  for (; i < ne; ++i) {
    two_sum(sum, e[i], sum, err);
    push_nonzero(h, nh, err);
  }
  for (; j < nf; ++j) {
    two_sum(sum, f[j], sum, err);
    push_nonzero(h, nh, err);
  }
  push_nonzero(h, nh, sum);
  return nh;
}

// h = b * e; h must hold 2 ne components.
int scale_expansion(const double* e, int ne, double b, double* h) {
  if (ne == 0 || b == 0.0) return 0;
  const SplitFactor bs = split_factor(b);
  int nh = 0;
  double carry = 0.0;
  double err = 0.0;
  two_product(e[0], b, bs, carry, err);
  push_nonzero(h, nh, err);
  for (int i = 1; i < ne; ++i) {
    double product = 0.0;
    double product_err = 0.0;
    two_product(e[i], b, bs, product, product_err);
    double partial = 0.0;
    two_sum(carry, product_err, partial, err);
    push_nonzero(h, nh, err);
    fast_two_sum(product, partial, carry, err);
    push_nonzero(h, nh, err);
  }
  push_nonzero(h, nh, carry);
  return nh;
}

// Rewrites e in place as an equal nonadjacent expansion that is usually much
// shorter (Priest/Shewchuk compression: a top-down then a bottom-up pass of
// fast two-sums). Keeps later products and sums cheap.
int compress_expansion(double* e, int n) {
  if (n <= 1) return n;
  // Top-down: outputs go to e[bottom], at an index already read.
  int bottom = n - 1;
  double carry = e[n - 1];
  for (int i = n - 2; i >= 0; --i) {
    double sum = 0.0;
    double err = 0.0;
    fast_two_sum(carry, e[i], sum, err);
    const bool keep = err != 0.0;
    e[bottom] = sum;
    bottom -= static_cast<int>(keep);
    carry = keep ? err : sum;
  }
  // Bottom-up: outputs go to e[top] with top < i, an index already read.
  int top = 0;
  for (int i = bottom + 1; i < n; ++i) {
    double sum = 0.0;
    double err = 0.0;
    fast_two_sum(e[i], carry, sum, err);
    push_nonzero(e, top, err);
    carry = sum;
  }
  push_nonzero(e, top, carry);
  return top;
}

template <int A, int B>
Expansion<A + B> add(const Expansion<A>& e, const Expansion<B>& f) {
  Expansion<A + B> h;
  h.n = add_expansions(e.c.data(), e.n, f.c.data(), f.n, h.c.data());
  return h;
}

template <int A>
Expansion<2 * A> scale(const Expansion<A>& e, double b) {
  Expansion<2 * A> h;
  h.n = scale_expansion(e.c.data(), e.n, b, h.c.data());
  return h;
}

template <int N>
void compress(Expansion<N>& e) {
  e.n = compress_expansion(e.c.data(), e.n);
}

// Running sum of expansions whose capacities add up to at most N. The budget
// check does not depend on the data, so any run that reaches an add() proves
// the capacity for every input.
template <int N>
class ExpansionSum {
 public:
  template <int M>
  void add(const Expansion<M>& term) {
    static_assert(M <= N);
    reserved_ += M;
    CM_ASSERT(reserved_ <= N);
    if (term.n == 0) return;
    Expansion<N>& next = buffers_[1 - current_];
    const Expansion<N>& now = buffers_[current_];
    next.n = add_expansions(now.c.data(), now.n, term.c.data(), term.n, next.c.data());
    current_ = 1 - current_;
  }
  const Expansion<N>& value() const { return buffers_[current_]; }

 private:
  std::array<Expansion<N>, 2> buffers_;
  int current_ = 0;
  int reserved_ = 0;
};

Expansion<2> exact_product(double a, double b) {
  double product = 0.0;
  double err = 0.0;
  two_product(a, b, split_factor(b), product, err);
  Expansion<2> r;
  r.push(err);
  r.push(product);
  return r;
}

template <int N>
Expansion<N> negated(Expansion<N> e) {
  for (int i = 0; i < e.n; ++i) e.c[i] = -e.c[i];
  return e;
}

// e * f, scaling e by each component of f (so pass the shorter one as f).
template <int A, int B, int Capacity = 2 * A* B>
Expansion<Capacity> multiply(const Expansion<A>& e, const Expansion<B>& f) {
  ExpansionSum<Capacity> sum;
  for (int j = 0; j < B; ++j) {
    // Absent components scale to nothing but still count in the budget, which
    // keeps the budget check independent of the data.
    sum.add(scale(e, j < f.n ? f.c[j] : 0.0));
  }
  Expansion<Capacity> product = sum.value();
  compress(product);
  return product;
}

// p_x q_y - q_x p_y, exactly.
Expansion<4> exact_cross(double px, double py, double qx, double qy) {
  return add(exact_product(px, qy), exact_product(-qx, py));
}

// sign * |p|^2 over the first `dim` coordinates, exactly and compressed.
template <int Dim>
Expansion<2 * Dim> exact_lift(const double* p, double sign) {
  Expansion<2 * Dim> lift;
  if constexpr (Dim == 2) {
    lift = add(exact_product(sign * p[0], p[0]), exact_product(sign * p[1], p[1]));
  } else {
    lift = add(add(exact_product(sign * p[0], p[0]), exact_product(sign * p[1], p[1])),
               exact_product(sign * p[2], p[2]));
  }
  compress(lift);
  return lift;
}

// det[[1, p], [1, q], [1, r]] = det[q - p, r - p] for 2D points, exactly:
// the cyclic sum of the 2x2 minors of the raw coordinates.
Expansion<12> exact_orient2d_det(const double* p, const double* q, const double* r) {
  Expansion<12> det =
      add(add(exact_cross(p[0], p[1], q[0], q[1]), exact_cross(q[0], q[1], r[0], r[1])),
          exact_cross(r[0], r[1], p[0], p[1]));
  compress(det);
  return det;
}

// The 3x3 minors of the (x, y, z) columns of P raw 3D rows, built from the
// 2x2 minors of (y, z), each computed once per pair of rows and shared.
template <int P>
class RawMinors {
 public:
  explicit RawMinors(const std::array<const double*, P>& rows) : rows_(rows) {
    for (int i = 0; i < P; ++i) {
      for (int j = i + 1; j < P; ++j) {
        yz_[i][j] = exact_cross(rows[i][1], rows[i][2], rows[j][1], rows[j][2]);
      }
    }
  }

  // det[row i; row j; row k] for i < j < k, exactly and compressed, expanded
  // along the x column.
  Expansion<24> det3(int i, int j, int k) const {
    Expansion<24> det = add(add(scale(yz_[j][k], rows_[i][0]), scale(yz_[i][k], -rows_[j][0])),
                            scale(yz_[i][j], rows_[k][0]));
    compress(det);
    return det;
  }

 private:
  std::array<const double*, P> rows_;
  std::array<std::array<Expansion<4>, P>, P> yz_;  // yz_[i][j] for i < j
};

// det[[1, p_i]] over four 3D rows = det[p1 - p0, p2 - p0, p3 - p0] is the
// alternating sum of the 3x3 minors of (x, y, z) left when one row is removed
// (expansion along the column of ones); `minor[i]` is the one without row i.
Expansion<96> exact_orient3d_det(const std::array<Expansion<24>, 4>& minor) {
  Expansion<96> det = add(add(minor[0], negated(minor[1])), add(minor[2], negated(minor[3])));
  compress(det);
  return det;
}

[[gnu::noinline]] int orient2d_exact(const double* a, const double* b, const double* c) {
  return exact_orient2d_det(a, b, c).sign();
}

[[gnu::noinline]] int orient3d_exact(const double* a, const double* b, const double* c,
                                     const double* d) {
  const RawMinors<4> m({a, b, c, d});
  return exact_orient3d_det({m.det3(1, 2, 3), m.det3(0, 2, 3), m.det3(0, 1, 3), m.det3(0, 1, 2)})
      .sign();
}

// incircle = -det[[1, p, |p|^2]] over the rows a, b, c, d. Expanding along the
// lifted column: sum_i (-1)^i |p_i|^2 D_i with D_i the orient2d determinant of
// the other three points in order.
[[gnu::noinline]] int incircle_exact(const double* a, const double* b, const double* c,
                                     const double* d) {
  const double* p[4] = {a, b, c, d};
  ExpansionSum<4 * 2 * 12 * 4> sum;
  for (int i = 0; i < 4; ++i) {
    const double* others[3];
    for (int k = 0, m = 0; k < 4; ++k) {
      if (k != i) others[m++] = p[k];
    }
    const double sign = i % 2 == 0 ? 1.0 : -1.0;
    sum.add(
        multiply(exact_orient2d_det(others[0], others[1], others[2]), exact_lift<2>(p[i], sign)));
  }
  return sum.value().sign();
}

// insphere = -det[[1, p, |p|^2]] over the rows a, b, c, d, e. Expanding along the
// lifted column: sum_i -(-1)^i |p_i|^2 D_i with D_i the orient3d determinant of
// the other four points in order. Each 3x3 minor of (x, y, z) is shared by two
// of the D_i, so the ten of them are computed once, indexed by the pair of rows
// they leave out. Worst case 5 * (2 * 96 * 6) components.
[[gnu::noinline]] int insphere_exact(const double* a, const double* b, const double* c,
                                     const double* d, const double* e) {
  const double* p[5] = {a, b, c, d, e};
  const RawMinors<5> raw({a, b, c, d, e});
  std::array<std::array<Expansion<24>, 5>, 5> without_pair;
  for (int m = 0; m < 5; ++m) {
    for (int n = m + 1; n < 5; ++n) {
      int rows[3];
      for (int k = 0, r = 0; k < 5; ++k) {
        if (k != m && k != n) rows[r++] = k;
      }
      without_pair[m][n] = raw.det3(rows[0], rows[1], rows[2]);
      without_pair[n][m] = without_pair[m][n];
    }
  }
  ExpansionSum<5 * 2 * 96 * 6> sum;
  for (int i = 0; i < 5; ++i) {
    std::array<Expansion<24>, 4> minor;
    for (int k = 0, r = 0; k < 5; ++k) {
      if (k != i) minor[r++] = without_pair[i][k];
    }
    const double sign = i % 2 == 0 ? -1.0 : 1.0;
    sum.add(multiply(exact_orient3d_det(minor), exact_lift<3>(p[i], sign)));
  }
  return sum.value().sign();
}

// Double-word arithmetic (a value as hi + lo, |lo| <= ulp(hi) / 2), for the
// cheap first try of insphere_adaptive. Algorithms and relative error bounds
// from Joldes, Muller and Popescu, "Tight and rigorous error bounds for basic
// building blocks of double-word arithmetic" (ACM TOMS 44(2), 2017):
// AccurateDWPlusDW errs by at most 3u^2 / (1 - 4u), DWTimesFP1 by at most
// 1.5u^2 + 4u^3 (u = 2^-53), both relative to the exact result of the
// operation on its (double-word) inputs; a two_product is exact.
struct DoubleWord {
  double hi = 0, lo = 0;
};

inline DoubleWord dw_product(double a, double b) {
  DoubleWord r;
  two_product(a, b, split_factor(b), r.hi, r.lo);
  return r;
}

inline DoubleWord dw_add(const DoubleWord& x, const DoubleWord& y) {  // AccurateDWPlusDW
  double sh, sl, th, tl, vh, vl;
  two_sum(x.hi, y.hi, sh, sl);
  two_sum(x.lo, y.lo, th, tl);
  fast_two_sum(sh, sl + th, vh, vl);
  DoubleWord z;
  fast_two_sum(vh, tl + vl, z.hi, z.lo);
  return z;
}

inline DoubleWord dw_negated(const DoubleWord& x) { return {-x.hi, -x.lo}; }

inline DoubleWord dw_times(const DoubleWord& x, double y) {  // DWTimesFP1
  double ch, cl1, th, tl1;
  two_product(x.hi, y, split_factor(y), ch, cl1);
  fast_two_sum(ch, x.lo * y, th, tl1);
  DoubleWord z;
  fast_two_sum(th, tl1 + cl1, z.hi, z.lo);
  return z;
}

// D(x) = x0^2 M0 - x1^2 M1 + x2^2 M2 - x3^2 M3 (M_i = det of the other three
// rows, in order), in double words. Every monomial of D passes through at
// most 10 operations: in M, a difference of two exact products, a product by
// a coordinate and two additions; two products by a coordinate of its row's
// lift; two additions per row (three squares) and two across the rows. With
// eps = 3.0001 u^2 per operation the standard argument bounds the error by
// gamma_10(eps) P(x) <= 30.01 u^2 P(x), P(x) the permanent of D on x.
DoubleWord insphere_double_word(const double (&x)[4][3]) {
  const auto det3 = [&](int i, int j, int k) {
    DoubleWord m;
    for (int c = 0; c < 3; ++c) {
      const int c1 = (c + 1) % 3, c2 = (c + 2) % 3;
      const DoubleWord cross = dw_add(dw_product(x[j][c1], x[k][c2]), dw_negated(dw_product(x[j][c2], x[k][c1])));
      m = c == 0 ? dw_times(cross, x[i][0]) : dw_add(m, dw_times(cross, x[i][c]));
    }
    return m;
  };
  const auto row = [&](int i, const DoubleWord& minor) {
    return dw_add(dw_add(dw_times(dw_times(minor, x[i][0]), x[i][0]), dw_times(dw_times(minor, x[i][1]), x[i][1])),
                  dw_times(dw_times(minor, x[i][2]), x[i][2]));
  };
  return dw_add(dw_add(row(0, det3(1, 2, 3)), dw_negated(row(1, det3(0, 2, 3)))),
                dw_add(row(2, det3(0, 1, 3)), dw_negated(row(3, det3(0, 1, 2)))));
}

// The sign of a + b + c when it lies outside [-bound, bound] (the sum taken
// exactly), else 2.
int sign_beyond(double a, double b, double c, double bound) {
  Expansion<1> ea, eb, ec, eu;
  ea.push(a);
  eb.push(b);
  ec.push(c);
  eu.push(bound);
  const Expansion<3> sum = add(add(ea, eb), ec);
  if (add(sum, negated(eu)).sign() > 0) return 1;
  if (add(sum, eu).sign() < 0) return -1;
  return 2;
}

// The adaptive stage of insphere, between the filter and insphere_exact:
// points rounded onto a sphere (a sphere's or a cylinder's mesh) are not
// exactly cospherical, but closer than the filter can tell, and there the
// exact stage was most of the Delaunay kernel's time.
//
// With the rows translated to e, x = fl(p - e) and t its rounding tail
// (p - e = x + t exactly, |t| <= u |x|), and D the filter's determinant
// a_lift M_a - b_lift M_b + c_lift M_c - d_lift M_d (M_a = det[b; c; d], ...):
// - D_B = D(x); it is D itself when every tail is zero.
// - dD = the first-order part of D(x + t) - D(x), in floating point: for each
//   row, 2 (x . t) times its minor plus its lift times the minor's change
//   t_p . (q x r) + t_q . (r x p) + t_r . (p x q).
// Each monomial of D is a product of five differences, so the terms of second
// order and above are at most ((1 + u)^5 - 1 - 5u) P <= 10.001 u^2 P, with P the
// permanent (the filter's, which it bounds from below by a factor 1 - gamma_16).
// dD's exact value has permanent at most 5 u P and its tree at most 16 rounded
// operations per monomial, so its computed value errs by at most gamma_16 5 u P
// <= 80.01 u^2 P. Hence |D - (D_B + dD~)| < 96 u^2 P~ = E.
// D_B is first taken in double words (insphere_double_word: within 30.01 u^2
// P(x) of it, and P(x) <= P~ / (1 - gamma_16)); the sign of D is certified
// when that plus dD~ lies outside [-(E + 64 u^2 P~), E + 64 u^2 P~] (twice the
// double-word bound, for margin). Rounded onto a sphere, D is of the order of
// u P, so this settles nearly every call in about a tenth of the time of the
// exact D_B, which comes next: certified outside [-E, E]. Returns 2 when it
// is not (D zero, or nearly).
[[gnu::noinline]] int insphere_adaptive(const double* a, const double* b, const double* c,
                                        const double* d, const double* e, double permanent) {
  const double* p[4] = {a, b, c, d};
  double x[4][3], t[4][3];
  bool exact_differences = true;
  for (int i = 0; i < 4; ++i) {
    for (int k = 0; k < 3; ++k) {
      two_sum(p[i][k], -e[k], x[i][k], t[i][k]);
      exact_differences = exact_differences && t[i][k] == 0.0;
    }
  }
  double change = 0;
  if (!exact_differences) {
    const auto cross = [&](int i, int j, double* out) {
      out[0] = x[i][1] * x[j][2] - x[i][2] * x[j][1];
      out[1] = x[i][2] * x[j][0] - x[i][0] * x[j][2];
      out[2] = x[i][0] * x[j][1] - x[i][1] * x[j][0];
    };
    const auto dot = [](const double* u, const double* v) { return (u[0] * v[0] + u[1] * v[1]) + u[2] * v[2]; };
    double first_order[4];
    for (int i = 0; i < 4; ++i) {
      int r[3];
      for (int k = 0, n = 0; k < 4; ++k) {
        if (k != i) r[n++] = k;
      }
      double qr[3], rp[3], pq[3];
      cross(r[1], r[2], qr);
      cross(r[2], r[0], rp);
      cross(r[0], r[1], pq);
      const double minor = dot(x[r[0]], qr);
      const double minor_change = (dot(t[r[0]], qr) + dot(t[r[1]], rp)) + dot(t[r[2]], pq);
      const double lift = dot(x[i], x[i]);
      const double lift_change = 2.0 * dot(x[i], t[i]);
      first_order[i] = lift_change * minor + lift * minor_change;
    }
    change = (first_order[0] - first_order[1]) + (first_order[2] - first_order[3]);
  }
  const double bound = (exact_differences ? 0.0 : 96.0) * 0x1p-106 * permanent;

  const DoubleWord quick = insphere_double_word(x);
  if (const int s = sign_beyond(quick.hi, quick.lo, change, bound + 64.0 * 0x1p-106 * permanent); s != 2) return s;

  // D_B exactly: the lifted column expanded over the four rows' 3x3 minors.
  const RawMinors<4> raw({x[0], x[1], x[2], x[3]});
  ExpansionSum<4 * 2 * 24 * 6> sum;
  sum.add(multiply(raw.det3(1, 2, 3), exact_lift<3>(x[0], 1.0)));
  sum.add(multiply(raw.det3(0, 2, 3), exact_lift<3>(x[1], -1.0)));
  sum.add(multiply(raw.det3(0, 1, 3), exact_lift<3>(x[2], 1.0)));
  sum.add(multiply(raw.det3(0, 1, 2), exact_lift<3>(x[3], -1.0)));
  const Expansion<1152>& d_b = sum.value();
  if (exact_differences) return d_b.sign();
  Expansion<1> change_e, bound_e;
  change_e.push(change);
  bound_e.push(bound);
  const Expansion<1153> estimate = add(d_b, change_e);
  if (add(estimate, negated(bound_e)).sign() > 0) return 1;
  if (add(estimate, bound_e).sign() < 0) return -1;
  return 2;
}

}  // namespace

// ---------------------------------------------------------------------------
// Public predicates: filter first, exact stage on failure.

int orient2d(const double* a, const double* b, const double* c) {
  CM_DEBUG_ASSERT(all_finite(a, 2) && all_finite(b, 2) && all_finite(c, 2));
  const Bounded det = minor2(b[0] - a[0], b[1] - a[1], c[0] - a[0], c[1] - a[1]);
  if (const int s = certified_sign(det.value, kOrient2dBound * det.permanent)) return s;
  ++exact_stats().orient2d;
  return orient2d_exact(a, b, c);
}

int orient3d(const double* a, const double* b, const double* c, const double* d) {
  CM_DEBUG_ASSERT(all_finite(a, 3) && all_finite(b, 3) && all_finite(c, 3) && all_finite(d, 3));
  const Bounded det = detail::orient3d_det(a, b, c, d);
  if (const int s = certified_sign(det.value, kOrient3dBound * det.permanent)) return s;
  ++exact_stats().orient3d;
  if (det.permanent < kIntegerPermanentLimit && small_integers(a) && small_integers(b) &&
      small_integers(c) && small_integers(d))
    return sign_of(det.value);
  return orient3d_exact(a, b, c, d);
}

int incircle(const double* a, const double* b, const double* c, const double* d) {
  CM_DEBUG_ASSERT(all_finite(a, 2) && all_finite(b, 2) && all_finite(c, 2) && all_finite(d, 2));
  const double adx = a[0] - d[0], ady = a[1] - d[1];
  const double bdx = b[0] - d[0], bdy = b[1] - d[1];
  const double cdx = c[0] - d[0], cdy = c[1] - d[1];
  const double a_lift = adx * adx + ady * ady;
  const double b_lift = bdx * bdx + bdy * bdy;
  const double c_lift = cdx * cdx + cdy * cdy;
  // det[[p - d, |p - d|^2]] expanded along the lifted column.
  const Bounded bc = minor2(bdx, bdy, cdx, cdy);
  const Bounded ca = minor2(cdx, cdy, adx, ady);
  const Bounded ab = minor2(adx, ady, bdx, bdy);
  const double det = a_lift * bc.value + b_lift * ca.value + c_lift * ab.value;
  const double permanent = a_lift * bc.permanent + b_lift * ca.permanent + c_lift * ab.permanent;
  if (const int s = certified_sign(det, kIncircleBound * permanent)) return s;
  ++exact_stats().incircle;
  return incircle_exact(a, b, c, d);
}

int insphere(const double* a, const double* b, const double* c, const double* d, const double* e) {
  CM_DEBUG_ASSERT(all_finite(a, 3) && all_finite(b, 3) && all_finite(c, 3) && all_finite(d, 3) &&
                  all_finite(e, 3));
  const Bounded det = detail::insphere_det(a, b, c, d, e);
  if (const int s = certified_sign(det.value, kInsphereBound * det.permanent)) return s;
  ++exact_stats().insphere;
  if (det.permanent < kIntegerPermanentLimit && small_integers(a) && small_integers(b) &&
      small_integers(c) && small_integers(d) && small_integers(e))
    return sign_of(det.value);
  if (const int s = insphere_adaptive(a, b, c, d, e, det.permanent); s != 2) return s;
  ++exact_stats().insphere_unsettled;
  return insphere_exact(a, b, c, d, e);
}

namespace detail {

int insphere_after_static(const double* a, const double* b, const double* c, const double* d,
                          const double* e, StaticValue v) {
  // The small-integer lemma above, with the permanent bounded through the
  // static scale: pi(root) <= 24 L* X* Y* Z* <= 24 scale / (1 - u)^6 (exact
  // differences here; a computed lift is at least (1 - u)^3 times the exact
  // one, the scale's evaluation loses (1 - u)^3), so fl(24 scale) < 2^50
  // gives pi(root) < 2^51. v.value is the same tree's value, hence exact.
  if (24.0 * v.scale < kIntegerPermanentLimit && small_integers(a) && small_integers(b) &&
      small_integers(c) && small_integers(d) && small_integers(e)) {
    ++exact_stats().insphere;
    return sign_of(v.value);
  }
  return insphere(a, b, c, d, e);
}

}  // namespace detail

double orient3d_fast(const double* a, const double* b, const double* c, const double* d) {
  const double ux = b[0] - a[0], uy = b[1] - a[1], uz = b[2] - a[2];
  const double vx = c[0] - a[0], vy = c[1] - a[1], vz = c[2] - a[2];
  const double wx = d[0] - a[0], wy = d[1] - a[1], wz = d[2] - a[2];
  return ux * (vy * wz - vz * wy) - uy * (vx * wz - vz * wx) + uz * (vx * wy - vy * wx);
}

}  // namespace cm::predicates
