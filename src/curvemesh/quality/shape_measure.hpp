#pragma once
// The shape distortion measure I of the seed paper, eq. (3.5): det J sampled
// at the points of a quadrature rule that integrates the element volume
// exactly, compared with the volume.
//
// Eq. (3.5) reads I = N_int min_i(det J_i w_i) / V for a rule with N_int
// points. Its rules have equal weights; the collapsed Gauss-Jacobi rules used
// here (quadrature.hpp) do not, and min_i(det J_i w_i) would then rate a
// straight tet below 1 only because its weights differ. So curvemesh defines
//
//     I = min_i det J_i / (sum_i w_i det J_i / sum_i w_i),
//
// the least det J at an integration point over its weighted mean. It equals
// (3.5) (normalized so that a straight element has I = 1) whenever the weights
// are equal, is 1 for every straight tet, and is < 1 as soon as det J varies.
// I <= 0 flags a non-positive det J at an integration point. This samples the
// element; it certifies nothing (certify_jacobian does).
#include <span>

#include "curvemesh/core/types.hpp"
#include "curvemesh/mesh/tet_mesh.hpp"

namespace cm::quality {

struct ShapeMeasure {
  double measure = 0;   ///< I as defined above
  double volume = 0;    ///< sum_i w_i det J_i: the element volume, exact for the rule's degree
  double min_detj = 0;  ///< least det J over the integration points
  double max_detj = 0;  ///< largest det J over the integration points
  int num_points = 0;   ///< N_int
};

/// I of the order-p tet with the given nodes (internal order). The rule has
/// `points_per_direction` = n points per direction (n^3 points, exact for
/// degree 2n-1); 0 picks the smallest n exact for det J (degree 3(p-1)):
/// 1 point for p = 1, 8 for p = 2, 64 for p = 3.
/// If the weighted mean of det J is <= 0, measure = min / |mean| (<= -1), or
/// -infinity when the mean is 0.
/// Preconditions: 1 <= order <= kMaxBezierOrder, nodes.size() ==
/// tet_node_count(order), 0 <= n <= kMaxRulePoints (std::invalid_argument).
/// Cost: n^3 Jacobians of N nodes each; shape function gradients are cached
/// per (order, n).
ShapeMeasure shape_measure(int order, std::span<const Vec3> nodes, int points_per_direction = 0);

/// The same I from the Bernstein coefficients of det J
/// (jacobian_bezier_coefficients, rank order of degree 3(p-1)), at the
/// points of the same default rule: equal to shape_measure(order, nodes) up to
/// rounding. The volume is then exactly the mean coefficient over 6. What the
/// checks of curved meshes use, since the certification computed the
/// coefficients already: one (points x coefficients) product, about half the
/// work of assembling the Jacobian at every point.
/// Precondition: 1 <= order <= kMaxBezierOrder, coefs.size() ==
/// simplex_count(3(order-1)) (std::invalid_argument otherwise).
ShapeMeasure shape_measure_from_bezier(int order, std::span<const double> jacobian_coefs);

/// shape_measure of tet t of m at the mesh's order.
ShapeMeasure shape_measure(const mesh::TetMesh& m, TetId t, int points_per_direction = 0);

}  // namespace cm::quality
