#include "curvemesh/quality/quadrature.hpp"

#include <fmt/format.h>

#include <Eigen/Eigenvalues>
#include <cmath>
#include <stdexcept>

namespace cm::quality {

GaussRule gauss_jacobi(int n, int alpha) {
  if (n < 1 || alpha < 0)
    throw std::invalid_argument(
        fmt::format("gauss_jacobi needs n >= 1, alpha >= 0 (got {}, {})", n, alpha));
  // Golub-Welsch on [-1,1] with weight (1-x)^alpha (beta = 0): the nodes are
  // the eigenvalues of the symmetric tridiagonal Jacobi matrix of the monic
  // recurrence, the weights mu0 times the squared first eigenvector entries.
  const double a = alpha;
  Eigen::MatrixXd jacobi = Eigen::MatrixXd::Zero(n, n);
  for (int k = 0; k < n; ++k) {
    const double s = 2.0 * k + a;
    jacobi(k, k) = k == 0 ? -a / (a + 2.0) : -a * a / (s * (s + 2.0));
    if (k + 1 < n) {
      const double m = k + 1.0;
      const double t = 2.0 * m + a;
      const double b = 4.0 * m * (m + a) * m * (m + a) / (t * t * (t + 1.0) * (t - 1.0));
      jacobi(k, k + 1) = jacobi(k + 1, k) = std::sqrt(b);
    }
  }
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(jacobi);
  const double mu0 = std::pow(2.0, a + 1.0) / (a + 1.0);
  GaussRule rule;
  rule.nodes.resize(static_cast<std::size_t>(n));
  rule.weights.resize(static_cast<std::size_t>(n));
  // t = (1+x)/2 maps the rule to [0,1]; (1-x)^alpha dx = 2^(alpha+1) (1-t)^alpha dt.
  const double scale = std::pow(2.0, -(a + 1.0));
  for (int i = 0; i < n; ++i) {
    const double v0 = eig.eigenvectors()(0, i);
    rule.nodes[static_cast<std::size_t>(i)] = 0.5 * (1.0 + eig.eigenvalues()(i));
    rule.weights[static_cast<std::size_t>(i)] = mu0 * v0 * v0 * scale;
  }
  return rule;
}

namespace {

TetRule build_tet_rule(int n) {
  // xi3 = c, xi2 = b (1-c), xi1 = a (1-b)(1-c) maps the unit cube onto the
  // tet with Jacobian (1-b)(1-c)^2, absorbed by the Jacobi weights in b and c.
  const GaussRule ra = gauss_jacobi(n, 0);
  const GaussRule rb = gauss_jacobi(n, 1);
  const GaussRule rc = gauss_jacobi(n, 2);
  TetRule rule;
  rule.exact_degree = 2 * n - 1;
  rule.axis_nodes = {ra.nodes, rb.nodes, rc.nodes};
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j)
      for (int k = 0; k < n; ++k) {
        const double a = ra.nodes[static_cast<std::size_t>(i)];
        const double b = rb.nodes[static_cast<std::size_t>(j)];
        const double c = rc.nodes[static_cast<std::size_t>(k)];
        const double xi3 = c;
        const double xi2 = b * (1 - c);
        const double xi1 = a * (1 - b) * (1 - c);
        // l0 = 1 - xi1 - xi2 - xi3 factorizes; the product avoids cancellation.
        const double l0 = (1 - a) * (1 - b) * (1 - c);
        rule.points.push_back({l0, xi1, xi2, xi3});
        rule.weights.push_back(ra.weights[static_cast<std::size_t>(i)] *
                               rb.weights[static_cast<std::size_t>(j)] *
                               rc.weights[static_cast<std::size_t>(k)]);
      }
  return rule;
}

}  // namespace

const TetRule& collapsed_tet_rule(int n) {
  if (n < 1 || n > kMaxRulePoints)
    throw std::invalid_argument(
        fmt::format("collapsed_tet_rule: {} points per direction (1..{})", n, kMaxRulePoints));
  static const auto rules = [] {
    std::array<TetRule, kMaxRulePoints + 1> r;
    for (int m = 1; m <= kMaxRulePoints; ++m) r[m] = build_tet_rule(m);
    return r;
  }();
  return rules[n];
}

}  // namespace cm::quality
