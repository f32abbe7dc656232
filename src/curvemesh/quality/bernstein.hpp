#pragma once
// Polynomials on the reference tetrahedron: Bernstein polynomials indexed by
// barycentric multi-indices, and the Lagrange shape functions of order-p tets
// in curvemesh's internal node order (mesh::tet_node_indices).
//
// Reference coordinates: a point of the reference tet is given by barycentric
// coordinates bary = (l0, l1, l2, l3), l_k = weight of local vertex k, sum 1.
// The reference tet is {xi in R^3 : xi >= 0, xi1+xi2+xi3 <= 1} with
// xi_j = l_j (j = 1..3); the Jacobian of an element map x(xi) is
// J = [dx/dxi1, dx/dxi2, dx/dxi3], so a straight tet has det J = 6 V.
#include <array>
#include <span>
#include <vector>

#include "curvemesh/core/types.hpp"

namespace cm::quality {

using Bary = std::array<double, 4>;
using MultiIndex = std::array<int, 4>;

/// Highest geometric order handled by the Bezier machinery (mesh::kMaxOrder
/// is 3; one more is supported and tested so that raising it is not blocked).
inline constexpr int kMaxBezierOrder = 4;
/// Degree 3(p-1) of det J for the highest order.
inline constexpr int kMaxJacobianDegree = 3 * (kMaxBezierOrder - 1);

/// Number of multi-indices of degree q in 4 variables, (q+1)(q+2)(q+3)/6.
constexpr int simplex_count(int q) { return (q + 1) * (q + 2) * (q + 3) / 6; }

/// Position of a multi-index in the rank order of its degree. The order sorts
/// by (a1+a2+a3, a2+a3, a3), so it does not depend on the degree: rank 0 is
/// vertex 0, and the indices of degree q are exactly the ranks
/// [0, simplex_count(q)).
constexpr int bernstein_rank(const MultiIndex& a) {
  const int r = a[1] + a[2] + a[3];
  const int s = a[2] + a[3];
  return r * (r + 1) * (r + 2) / 6 + s * (s + 1) / 2 + a[3];
}

/// The multi-indices of degree q, in rank order. O(q^3).
std::vector<MultiIndex> bernstein_indices(int degree);

/// Multinomial q! / (a0! a1! a2! a3!) with q = a0+a1+a2+a3 (exact for q <= 20).
double multinomial(const MultiIndex& a);

/// Value at bary of sum_a coefs[rank(a)] B^q_a, B^q_a = multinomial(a) prod l_k^a_k.
/// Precondition: coefs.size() == simplex_count(degree).
double evaluate_bernstein(int degree, std::span<const double> coefs, const Bary& bary);

/// Gradients with respect to (xi1, xi2, xi3) of the order-p Lagrange shape
/// functions at bary, one per node in the order of mesh::tet_node_indices(p).
/// Preconditions: 1 <= order <= kMaxBezierOrder, grad.size() == number of nodes.
void lagrange_gradients(int order, const Bary& bary, std::span<Vec3> grad);

/// Jacobian matrix dx/dxi of the order-p Lagrange tet with the given nodes
/// (internal order) at bary, computed directly from the shape functions.
Mat3 lagrange_jacobian(int order, std::span<const Vec3> nodes, const Bary& bary);
double lagrange_jacobian_det(int order, std::span<const Vec3> nodes, const Bary& bary);

/// Position x(bary) of the order-p Lagrange tet.
Vec3 lagrange_point(int order, std::span<const Vec3> nodes, const Bary& bary);

/// Number of nodes of an order-p tet, (p+1)(p+2)(p+3)/6.
constexpr int tet_node_count(int order) { return simplex_count(order); }

}  // namespace cm::quality
