#include "curvemesh/geom_occ/detail/bspline.hpp"

#include <algorithm>
#include <array>
#include <cmath>

namespace cm::geom_occ::detail {

namespace {

// OCC's largest B-spline degree (Geom_BSplineSurface::MaxDegree()).
constexpr int kMaxDegree = 25;
constexpr int kMaxOrder = kMaxDegree + 1;

using Basis = std::array<std::array<double, kMaxOrder>, 3>;

// The degree + 1 basis functions that are nonzero on span i, and their
// first `wanted` (<= 2) derivatives, at t: n[k][j] is the k-th derivative of
// N_{i - degree + j}. The triangular recurrence (Cox-de Boor) gives the
// nonzero functions of every degree up to `degree`; a derivative of degree
// p is p times the difference of two degree p - 1 functions (or
// derivatives) over their knot spans. Each knot difference is inverted
// once. t outside the span gives the span's polynomials extended. Every
// knot difference used spans the span itself, so none is zero for a span
// of positive length.
void basis_derivatives(const std::vector<double>& knots, int i, double t, int degree, int wanted, Basis& n) {
  const int p = degree;
  // ndu[r][j] (r <= j): N_{i - j + r, j}(t), the degree j functions;
  // inv[j][r] (r < j): one over u_{i + r + 1} - u_{i + r + 1 - j}, the knot
  // span of N_{i - j + r + 1, j - 1} and of N_{i - j + r, j}'s right half.
  std::array<std::array<double, kMaxOrder>, kMaxOrder> ndu, inv;
  std::array<double, kMaxOrder> left, right;
  ndu[0][0] = 1;
  for (int j = 1; j <= p; ++j) {
    left[j] = t - knots[i + 1 - j];
    right[j] = knots[i + j] - t;
    double saved = 0;
    for (int r = 0; r < j; ++r) {
      inv[j][r] = 1 / (right[r + 1] + left[j - r]);
      const double q = ndu[r][j - 1] * inv[j][r];
      ndu[r][j] = saved + right[r + 1] * q;
      saved = left[j - r] * q;
    }
    ndu[j][j] = saved;
  }
  for (int r = 0; r <= p; ++r) n[0][r] = ndu[r][p];
  if (wanted == 0) return;
  if (p < 1) {
    for (int k = 1; k <= wanted; ++k) n[k].fill(0);
    return;
  }
  // First derivatives: N'_{r} = p (a[r - 1] - a[r]), a[s] = N_{s, p-1} / span.
  std::array<double, kMaxOrder + 1> a;
  for (int s = 0; s < p; ++s) a[s] = ndu[s][p - 1] * inv[p][s];
  for (int r = 0; r <= p; ++r) n[1][r] = p * ((r > 0 ? a[r - 1] : 0) - (r < p ? a[r] : 0));
  if (wanted == 1) return;
  if (p < 2) {
    n[2].fill(0);
    return;
  }
  // Second: the same step on the degree p - 1 derivatives d.
  std::array<double, kMaxOrder> b, d;
  for (int s = 0; s < p - 1; ++s) b[s] = ndu[s][p - 2] * inv[p - 1][s];
  for (int s = 0; s < p; ++s) d[s] = (p - 1) * ((s > 0 ? b[s - 1] : 0) - (s < p - 1 ? b[s] : 0));
  for (int s = 0; s < p; ++s) a[s] = d[s] * inv[p][s];
  for (int r = 0; r <= p; ++r) n[2][r] = p * ((r > 0 ? a[r - 1] : 0) - (r < p ? a[r] : 0));
}

Vec3 xyz(const std::array<double, 4>& h) { return {h[0], h[1], h[2]}; }

}  // namespace

int SplineBasis::locate(double& t) const {
  // The period's end stays (the last span's end, as OCC evaluates it: at
  // a seam of reduced continuity the derivatives there are one-sided).
  if (period > 0 && (t < first || t > first + period)) t -= period * std::floor((t - first) / period);
  const int poles = static_cast<int>(knots.size()) - degree - 1;
  // The last knot <= t among knots[degree + 1 .. poles - 1] starts the span.
  const auto from = knots.begin() + degree + 1, to = knots.begin() + poles;
  return static_cast<int>(std::upper_bound(from, to, t) - knots.begin()) - 1;
}

void SplineCurve::d2(double t, Vec3& p, Vec3& d1, Vec3& d2) const {
  const int deg = basis.degree;
  const int i = basis.locate(t);
  Basis n;
  basis_derivatives(basis.knots, i, t, deg, 2, n);
  std::array<std::array<double, 4>, 3> a{};
  for (int j = 0; j <= deg; ++j) {
    const auto& pole = poles[static_cast<std::size_t>(i - deg + j)];
    for (int k = 0; k < 3; ++k)
      for (int c = 0; c < 4; ++c) a[k][c] += n[k][j] * pole[c];
  }
  if (!rational) {
    p = xyz(a[0]);
    d1 = xyz(a[1]);
    d2 = xyz(a[2]);
    return;
  }
  // The quotient rule on (A, w) = (sum N w P, sum N w).
  const double w = a[0][3], w1 = a[1][3], w2 = a[2][3];
  p = xyz(a[0]) / w;
  d1 = (xyz(a[1]) - w1 * p) / w;
  d2 = (xyz(a[2]) - 2 * w1 * d1 - w2 * p) / w;
}

Vec3 SplineCurve::d0(double t) const {
  const int deg = basis.degree;
  const int i = basis.locate(t);
  Basis n;
  basis_derivatives(basis.knots, i, t, deg, 0, n);
  std::array<double, 4> a{};
  for (int j = 0; j <= deg; ++j) {
    const auto& pole = poles[static_cast<std::size_t>(i - deg + j)];
    for (int c = 0; c < 4; ++c) a[c] += n[0][j] * pole[c];
  }
  return rational ? Vec3(xyz(a) / a[3]) : xyz(a);
}

Vec3 SplineSurface::d0(double pu, double pv) const {
  const int du_deg = u.degree, dv_deg = v.degree;
  const int iu = u.locate(pu), iv = v.locate(pv);
  Basis nu, nv;
  basis_derivatives(u.knots, iu, pu, du_deg, 0, nu);
  basis_derivatives(v.knots, iv, pv, dv_deg, 0, nv);
  std::array<double, 4> s{};
  for (int b = 0; b <= dv_deg; ++b) {
    std::array<double, 4> t{};
    for (int a = 0; a <= du_deg; ++a) {
      const auto& pole = poles[static_cast<std::size_t>((iu - du_deg + a) * poles_v + (iv - dv_deg + b))];
      for (int c = 0; c < 4; ++c) t[c] += nu[0][a] * pole[c];
    }
    for (int c = 0; c < 4; ++c) s[c] += nv[0][b] * t[c];
  }
  return rational ? Vec3(xyz(s) / s[3]) : xyz(s);
}

namespace {

// s[k][l]: the k-th u- and l-th v-derivative (k + l <= 2) of the first C
// homogeneous coordinates, row by row (a row's poles are contiguous).
template <int C>
void surface_sums(const SplineSurface& f, int iu, int iv, const Basis& nu, const Basis& nv,
                  std::array<std::array<std::array<double, 4>, 3>, 3>& s) {
  const int pu = f.u.degree, pv = f.v.degree;
  for (int a = 0; a <= pu; ++a) {
    const std::array<double, 4>* row = &f.poles[static_cast<std::size_t>((iu - pu + a) * f.poles_v + (iv - pv))];
    std::array<std::array<double, C>, 3> r{};
    for (int b = 0; b <= pv; ++b)
      for (int l = 0; l < 3; ++l)
        for (int c = 0; c < C; ++c) r[l][c] += nv[l][b] * row[b][c];
    for (int k = 0; k < 3; ++k)
      for (int l = 0; l + k < 3; ++l)
        for (int c = 0; c < C; ++c) s[k][l][c] += nu[k][a] * r[l][c];
  }
}

}  // namespace

void SplineSurface::d2(double pu, double pv, Vec3& p, Vec3& du, Vec3& dv, Vec3& duu, Vec3& dvv, Vec3& duv) const {
  const int iu = u.locate(pu), iv = v.locate(pv);
  Basis nu, nv;
  basis_derivatives(u.knots, iu, pu, u.degree, 2, nu);
  basis_derivatives(v.knots, iv, pv, v.degree, 2, nv);
  std::array<std::array<std::array<double, 4>, 3>, 3> s{};
  if (!rational) {
    surface_sums<3>(*this, iu, iv, nu, nv, s);
    p = xyz(s[0][0]);
    du = xyz(s[1][0]);
    dv = xyz(s[0][1]);
    duu = xyz(s[2][0]);
    dvv = xyz(s[0][2]);
    duv = xyz(s[1][1]);
    return;
  }
  surface_sums<4>(*this, iu, iv, nu, nv, s);
  // The quotient rule on (A, w) = (sum N w P, sum N w).
  const double w = s[0][0][3];
  p = xyz(s[0][0]) / w;
  du = (xyz(s[1][0]) - s[1][0][3] * p) / w;
  dv = (xyz(s[0][1]) - s[0][1][3] * p) / w;
  duu = (xyz(s[2][0]) - 2 * s[1][0][3] * du - s[2][0][3] * p) / w;
  dvv = (xyz(s[0][2]) - 2 * s[0][1][3] * dv - s[0][2][3] * p) / w;
  duv = (xyz(s[1][1]) - s[1][0][3] * dv - s[0][1][3] * du - s[1][1][3] * p) / w;
}

}  // namespace cm::geom_occ::detail
