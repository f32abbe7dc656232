#include "curvemesh/quality/shape_measure.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <mutex>
#include <stdexcept>

#include "curvemesh/core/error.hpp"
#include "curvemesh/mesh/high_order.hpp"
#include "curvemesh/quality/bernstein.hpp"
#include "curvemesh/quality/quadrature.hpp"

namespace cm::quality {

namespace {

// Shape function gradients of one order at the points of one rule:
// grad[i * num_nodes + n] for point i and node n.
struct GradientTable {
  std::once_flag built;
  std::vector<Vec3> grad;
};

const std::vector<Vec3>& rule_gradients(int order, int n) {
  static std::array<std::array<GradientTable, kMaxRulePoints + 1>, kMaxBezierOrder + 1> tables;
  GradientTable& table = tables[static_cast<std::size_t>(order)][static_cast<std::size_t>(n)];
  std::call_once(table.built, [&] {
    const TetRule& rule = collapsed_tet_rule(n);
    const auto num_nodes = static_cast<std::size_t>(tet_node_count(order));
    table.grad.resize(rule.points.size() * num_nodes);
    for (std::size_t i = 0; i < rule.points.size(); ++i)
      lagrange_gradients(order, rule.points[i],
                         std::span<Vec3>(table.grad.data() + i * num_nodes, num_nodes));
  });
  return table.grad;
}

// det J at the points of the collapsed rule by sum factorization. With
// xi3 = c, xi2 = b (1-c), xi1 = a (1-b)(1-c), the degree-q Bernstein
// polynomial of multi-index (a0, a1, a2, a3) is the product
//     B^{r1}_{a1}(a) B^{r2}_{a2}(b) B^{q}_{a3}(c),  r1 = a0 + a1, r2 = r1 + a2,
// of univariate ones, so the sum over the coefficients runs one direction
// at a time: about q^4 products instead of q^3 n^3 (1.2k instead of 5.4k for
// P3).
struct FactorTable {
  std::once_flag built;
  int degree = 0;
  int n = 0;  // points per direction
  // Univariate B^r_s at the rule's nodes in a, b, c: [(r(r+1)/2 + s) * n + i].
  std::array<std::vector<double>, 3> basis;
  // Coefficient ranks in the order the first stage reads them (a3, a2, a1).
  std::vector<int> ranks;
};

constexpr std::size_t tri_index(int r, int s) { return static_cast<std::size_t>(r * (r + 1) / 2 + s); }

const FactorTable& factor_table(int order) {
  static std::array<FactorTable, kMaxBezierOrder + 1> tables;
  FactorTable& table = tables[static_cast<std::size_t>(order)];
  std::call_once(table.built, [&] {
    const int q = 3 * (order - 1);
    const int n = points_for_degree(q);
    table.degree = q;
    table.n = n;
    const TetRule& rule = collapsed_tet_rule(n);
    for (int dir = 0; dir < 3; ++dir) {
      const std::vector<double>& nodes = rule.axis_nodes[static_cast<std::size_t>(dir)];
      std::vector<double>& b = table.basis[static_cast<std::size_t>(dir)];
      b.assign(tri_index(q + 1, 0) * static_cast<std::size_t>(n), 0);
      for (int r = 0; r <= q; ++r)
        for (int sdeg = 0; sdeg <= r; ++sdeg) {
          const double binomial = multinomial({r - sdeg, sdeg, 0, 0});
          for (int i = 0; i < n; ++i) {
            const double t = nodes[static_cast<std::size_t>(i)];
            b[tri_index(r, sdeg) * static_cast<std::size_t>(n) + static_cast<std::size_t>(i)] =
                binomial * std::pow(1 - t, r - sdeg) * std::pow(t, sdeg);
          }
        }
    }
    for (int a3 = 0; a3 <= q; ++a3)
      for (int a2 = 0; a2 + a3 <= q; ++a2)
        for (int a1 = 0; a1 + a2 + a3 <= q; ++a1) table.ranks.push_back(bernstein_rank({q - a1 - a2 - a3, a1, a2, a3}));
  });
  return table;
}

ShapeMeasure finish(ShapeMeasure out, double mean) {
  if (mean > 0)
    out.measure = out.min_detj / mean;
  else if (mean < 0)
    out.measure = out.min_detj / -mean;
  else
    out.measure = -std::numeric_limits<double>::infinity();
  return out;
}

}  // namespace

ShapeMeasure shape_measure_from_bezier(int order, std::span<const double> jacobian_coefs) {
  if (order < 1 || order > kMaxBezierOrder)
    throw std::invalid_argument(
        fmt::format("element order {} is not supported (1..{})", order, kMaxBezierOrder));
  const auto num_coefs = static_cast<std::size_t>(simplex_count(3 * (order - 1)));
  if (jacobian_coefs.size() != num_coefs)
    throw std::invalid_argument(fmt::format("det J of an order-{} tet has {} Bernstein coefficients, got {}", order,
                                            num_coefs, jacobian_coefs.size()));
  const FactorTable& table = factor_table(order);
  const int q = table.degree;
  const auto n = static_cast<std::size_t>(table.n);
  const auto& [ba, bb, bc] = table.basis;
  constexpr auto kN = static_cast<std::size_t>(points_for_degree(kMaxJacobianDegree));
  constexpr std::size_t kQ = kMaxJacobianDegree + 1;
  // Stage 1, along a: f1[(a3, a2)][i].
  // Only the parts this order uses are cleared: the arrays fit order 4.
  const auto num_pairs = static_cast<std::size_t>((q + 1) * (q + 2) / 2);
  std::array<double, kQ * (kQ + 1) / 2 * kN> f1;
  std::fill_n(f1.begin(), num_pairs * n, 0.0);
  const int* rank = table.ranks.data();
  std::size_t pair = 0;
  for (int a3 = 0; a3 <= q; ++a3)
    for (int a2 = 0; a2 + a3 <= q; ++a2, ++pair) {
      const int r1 = q - a3 - a2;
      double* out = &f1[pair * n];
      for (int a1 = 0; a1 <= r1; ++a1) {
        const double coef = jacobian_coefs[static_cast<std::size_t>(*rank++)];
        const double* basis = &ba[tri_index(r1, a1) * n];
        for (std::size_t i = 0; i < n; ++i) out[i] += basis[i] * coef;
      }
    }
  // Stage 2, along b: f2[a3][j][i].
  std::array<double, kQ * kN * kN> f2;
  std::fill_n(f2.begin(), static_cast<std::size_t>(q + 1) * n * n, 0.0);
  pair = 0;
  for (int a3 = 0; a3 <= q; ++a3) {
    const int r2 = q - a3;
    double* out = &f2[static_cast<std::size_t>(a3) * n * n];
    for (int a2 = 0; a2 <= r2; ++a2, ++pair) {
      const double* in = &f1[pair * n];
      const double* basis = &bb[tri_index(r2, a2) * n];
      for (std::size_t j = 0; j < n; ++j)
        for (std::size_t i = 0; i < n; ++i) out[j * n + i] += basis[j] * in[i];
    }
  }
  // Stage 3, along c: det J at point (i, j, k), stored [k][j][i].
  std::array<double, kN * kN * kN> det;
  std::fill_n(det.begin(), n * n * n, 0.0);
  for (int a3 = 0; a3 <= q; ++a3) {
    const double* in = &f2[static_cast<std::size_t>(a3) * n * n];
    const double* basis = &bc[tri_index(q, a3) * n];
    for (std::size_t k = 0; k < n; ++k)
      for (std::size_t ji = 0; ji < n * n; ++ji) det[k * n * n + ji] += basis[k] * in[ji];
  }
  const std::size_t points = n * n * n;
  ShapeMeasure out;
  out.num_points = static_cast<int>(points);
  const auto [lo, hi] = std::minmax_element(det.begin(), det.begin() + static_cast<std::ptrdiff_t>(points));
  out.min_detj = *lo;
  out.max_detj = *hi;
  // Each Bernstein polynomial of degree q integrates to the same share of
  // the volume, so the mean of det J is the mean coefficient.
  double sum = 0;
  for (double c : jacobian_coefs) sum += c;
  const double mean = sum / double(num_coefs);
  out.volume = mean / 6;
  return finish(out, mean);
}

ShapeMeasure shape_measure(int order, std::span<const Vec3> nodes, int points_per_direction) {
  if (order < 1 || order > kMaxBezierOrder)
    throw std::invalid_argument(
        fmt::format("element order {} is not supported (1..{})", order, kMaxBezierOrder));
  if (static_cast<int>(nodes.size()) != tet_node_count(order))
    throw std::invalid_argument(fmt::format("an order-{} tet has {} nodes, got {}", order,
                                            tet_node_count(order), nodes.size()));
  if (points_per_direction < 0 || points_per_direction > kMaxRulePoints)
    throw std::invalid_argument(fmt::format("{} integration points per direction (0..{})",
                                            points_per_direction, kMaxRulePoints));
  const int n =
      points_per_direction == 0 ? points_for_degree(3 * (order - 1)) : points_per_direction;
  const TetRule& rule = collapsed_tet_rule(n);
  const std::vector<Vec3>& grad = rule_gradients(order, n);
  const std::size_t num_nodes = nodes.size();

  ShapeMeasure out;
  out.num_points = static_cast<int>(rule.points.size());
  out.min_detj = std::numeric_limits<double>::infinity();
  out.max_detj = -std::numeric_limits<double>::infinity();
  // Relative to node 0: the gradients sum to zero, and differences keep the
  // rounding of large absolute coordinates out of J.
  std::array<Vec3, simplex_count(kMaxBezierOrder)> rel;
  for (std::size_t k = 1; k < num_nodes; ++k) rel[k] = nodes[k] - nodes[0];
  double weight_sum = 0;
  for (std::size_t i = 0; i < rule.points.size(); ++i) {
    const Vec3* g = grad.data() + i * num_nodes;
    Mat3 jac = Mat3::Zero();
    for (std::size_t k = 1; k < num_nodes; ++k) jac.noalias() += rel[k] * g[k].transpose();
    const double det = jac.determinant();
    out.volume += rule.weights[i] * det;
    weight_sum += rule.weights[i];
    out.min_detj = std::min(out.min_detj, det);
    out.max_detj = std::max(out.max_detj, det);
  }
  return finish(out, out.volume / weight_sum);
}

ShapeMeasure shape_measure(const mesh::TetMesh& m, TetId t, int points_per_direction) {
  const auto nodes = mesh::gather_tet_nodes(m, t);
  return shape_measure(m.high_order.order(), nodes, points_per_direction);
}

}  // namespace cm::quality
