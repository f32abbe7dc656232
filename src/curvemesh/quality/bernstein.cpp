#include "curvemesh/quality/bernstein.hpp"

#include <fmt/format.h>

#include <stdexcept>

#include "curvemesh/core/error.hpp"
#include "curvemesh/mesh/high_order.hpp"

namespace cm::quality {

namespace {

void check_order(int order) {
  if (order < 1 || order > kMaxBezierOrder)
    throw std::invalid_argument(
        fmt::format("element order {} is not supported (1..{})", order, kMaxBezierOrder));
}

const std::vector<std::array<int, 4>>& node_indices(int order) {
  static const auto cache = [] {
    std::array<std::vector<std::array<int, 4>>, kMaxBezierOrder + 1> c;
    for (int p = 1; p <= kMaxBezierOrder; ++p) c[p] = mesh::tet_node_indices(p);
    return c;
  }();
  return cache[order];
}

double factorial(int n) {
  double f = 1;
  for (int i = 2; i <= n; ++i) f *= i;
  return f;
}

}  // namespace

std::vector<MultiIndex> bernstein_indices(int degree) {
  std::vector<MultiIndex> out(static_cast<std::size_t>(simplex_count(degree)));
  for (int a0 = 0; a0 <= degree; ++a0)
    for (int a1 = 0; a0 + a1 <= degree; ++a1)
      for (int a2 = 0; a0 + a1 + a2 <= degree; ++a2) {
        const MultiIndex a{a0, a1, a2, degree - a0 - a1 - a2};
        out[static_cast<std::size_t>(bernstein_rank(a))] = a;
      }
  return out;
}

double multinomial(const MultiIndex& a) {
  return factorial(a[0] + a[1] + a[2] + a[3]) /
         (factorial(a[0]) * factorial(a[1]) * factorial(a[2]) * factorial(a[3]));
}

double evaluate_bernstein(int degree, std::span<const double> coefs, const Bary& bary) {
  CM_ASSERT_OP(static_cast<int>(coefs.size()), ==, simplex_count(degree));
  std::array<std::array<double, kMaxJacobianDegree + 1>, 4> powers{};
  CM_ASSERT(degree >= 0 && degree <= kMaxJacobianDegree);
  for (int k = 0; k < 4; ++k) {
    powers[k][0] = 1;
    for (int i = 1; i <= degree; ++i) powers[k][i] = powers[k][i - 1] * bary[k];
  }
  double sum = 0;
  for (int a0 = 0; a0 <= degree; ++a0)
    for (int a1 = 0; a0 + a1 <= degree; ++a1)
      for (int a2 = 0; a0 + a1 + a2 <= degree; ++a2) {
        const MultiIndex a{a0, a1, a2, degree - a0 - a1 - a2};
        sum += coefs[static_cast<std::size_t>(bernstein_rank(a))] * multinomial(a) *
               powers[0][a[0]] * powers[1][a[1]] * powers[2][a[2]] * powers[3][a[3]];
      }
  return sum;
}

void lagrange_gradients(int order, const Bary& bary, std::span<Vec3> grad) {
  check_order(order);
  const auto& nodes = node_indices(order);
  CM_ASSERT_OP(grad.size(), ==, nodes.size());
  // The shape function of node a is prod_k f_{a_k}(l_k), with
  // f_m(t) = prod_{i<m} (p t - i) / (i + 1): it vanishes on the node planes
  // l_k = i/p, i < a_k, which contain every other node.
  std::array<std::array<double, kMaxBezierOrder + 1>, 4> f{};
  std::array<std::array<double, kMaxBezierOrder + 1>, 4> df{};
  for (int k = 0; k < 4; ++k) {
    f[k][0] = 1;
    df[k][0] = 0;
    const double pt = order * bary[k];
    for (int m = 1; m <= order; ++m) {
      f[k][m] = f[k][m - 1] * (pt - (m - 1)) / m;
      df[k][m] = (df[k][m - 1] * (pt - (m - 1)) + f[k][m - 1] * order) / m;
    }
  }
  for (std::size_t n = 0; n < nodes.size(); ++n) {
    const auto& a = nodes[n];
    std::array<double, 4> d_bary;
    for (int k = 0; k < 4; ++k) {
      double prod = df[k][a[k]];
      for (int l = 0; l < 4; ++l)
        if (l != k) prod *= f[l][a[l]];
      d_bary[k] = prod;
    }
    grad[n] = Vec3(d_bary[1] - d_bary[0], d_bary[2] - d_bary[0], d_bary[3] - d_bary[0]);
  }
}

Mat3 lagrange_jacobian(int order, std::span<const Vec3> nodes, const Bary& bary) {
  check_order(order);
  std::array<Vec3, simplex_count(kMaxBezierOrder)> grad;
  const std::size_t n = static_cast<std::size_t>(tet_node_count(order));
  CM_ASSERT_OP(nodes.size(), ==, n);
  lagrange_gradients(order, bary, std::span<Vec3>(grad.data(), n));
  // Relative to node 0, so that the result does not carry the rounding of
  // large absolute coordinates (the gradients sum to zero).
  Mat3 jac = Mat3::Zero();
  for (std::size_t i = 1; i < n; ++i) jac += (nodes[i] - nodes[0]) * grad[i].transpose();
  return jac;
}

double lagrange_jacobian_det(int order, std::span<const Vec3> nodes, const Bary& bary) {
  return lagrange_jacobian(order, nodes, bary).determinant();
}

Vec3 lagrange_point(int order, std::span<const Vec3> nodes, const Bary& bary) {
  check_order(order);
  const auto& idx = node_indices(order);
  CM_ASSERT_OP(nodes.size(), ==, idx.size());
  Vec3 x = Vec3::Zero();
  for (std::size_t n = 0; n < idx.size(); ++n) {
    double phi = 1;
    for (int k = 0; k < 4; ++k)
      for (int i = 0; i < idx[n][k]; ++i) phi *= (order * bary[k] - i) / (i + 1);
    x += phi * nodes[n];
  }
  return x;
}

}  // namespace cm::quality
