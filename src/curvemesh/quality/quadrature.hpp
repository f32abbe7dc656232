#pragma once
// Gauss-Jacobi rules and the collapsed (conical, Duffy) product rule on the
// reference tetrahedron, with positive weights and interior points.
#include <array>
#include <vector>

#include "curvemesh/quality/bernstein.hpp"

namespace cm::quality {

/// n-point Gauss rule for integral_0^1 (1-t)^alpha f(t) dt, exact for f of
/// degree <= 2n-1. Nodes ascending in (0,1), weights positive. Computed by
/// Golub-Welsch (eigen-decomposition of the Jacobi matrix). Preconditions:
/// n >= 1, alpha >= 0.
struct GaussRule {
  std::vector<double> nodes;
  std::vector<double> weights;
};
GaussRule gauss_jacobi(int n, int alpha);

/// Collapsed product rule with n points per direction (n^3 points) on the
/// reference tet: integral over the tet of f(xi) dxi ~= sum_i w_i f(point_i),
/// exact for polynomials of total degree <= 2n-1. Weights are positive and sum
/// to 1/6 (the reference volume); points are strictly interior.
struct TetRule {
  std::vector<Bary> points;
  std::vector<double> weights;
  int exact_degree = 0;  ///< 2n - 1
  /// The 1D nodes in the collapsed coordinates (a, b, c), where
  /// xi3 = c, xi2 = b (1-c), xi1 = a (1-b)(1-c); point (i, j, k) of the
  /// product is points[(i n + j) n + k].
  std::array<std::vector<double>, 3> axis_nodes;
};

inline constexpr int kMaxRulePoints = 10;  ///< largest n of collapsed_tet_rule

/// Cached (built once, thread-safe); precondition 1 <= n <= kMaxRulePoints.
const TetRule& collapsed_tet_rule(int n);

/// Smallest n whose collapsed rule integrates degree `degree` exactly.
/// Precondition: degree >= 0.
constexpr int points_for_degree(int degree) { return (degree + 2) / 2; }

}  // namespace cm::quality
