#include "curvemesh/quality/shape_measure.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <mutex>
#include <stdexcept>

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

}  // namespace

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
  const double mean = out.volume / weight_sum;
  if (mean > 0)
    out.measure = out.min_detj / mean;
  else if (mean < 0)
    out.measure = out.min_detj / -mean;
  else
    out.measure = -std::numeric_limits<double>::infinity();
  return out;
}

ShapeMeasure shape_measure(const mesh::TetMesh& m, TetId t, int points_per_direction) {
  const auto nodes = mesh::gather_tet_nodes(m, t);
  return shape_measure(m.high_order.order(), nodes, points_per_direction);
}

}  // namespace cm::quality
