#pragma once
// Certified validity of order-p Lagrange tetrahedra through the Bernstein
// (Bezier) expansion of det J (Johnen, Remacle, Geuzaine, "Geometrical
// validity of curvilinear finite elements", JCP 2013).
//
// For an order-p tet, det J(xi) (J = dx/dxi, see bernstein.hpp for the
// reference tet) is a polynomial of degree q = 3(p-1). Written in the
// Bernstein basis of degree q, its coefficients bound it: min coef <= det J
// <= max coef on the element, and the 4 corner coefficients are the exact
// values at the vertices. Subdividing the reference tet (longest-edge
// bisection in reference space, de Casteljau on the coefficients) tightens
// the bounds, and every new subdomain vertex adds an exact value.
//
// Rounding. Coefficients are computed in floating point, with an a-priori
// bound E on their error (node rounding, the Lagrange-to-Bezier map, the
// products and the subdivisions are all accounted for; E is about 1e-13 of
// max |dx/dxi|^3 for P2, 1e-12 for P3, 1e-11 for P4). Decisions use it in the
// conservative direction: a coefficient counts as positive only if it exceeds
// E, and a value at a point that does not exceed E counts as det J <= 0.
// Hence kValid certifies det J > 0 on the whole closed element, and an element
// whose det J vanishes somewhere is never kValid: it is kInvalid when the zero
// is at a vertex (a degenerate corner) or at a point the subdivision reaches,
// kUndetermined otherwise (a tangential zero strictly inside). For p = 1 the
// sign of the constant det J = 6V is decided exactly (core::predicates::
// orient3d) and E = 0.
#include <array>
#include <span>
#include <vector>

#include "curvemesh/core/types.hpp"
#include "curvemesh/mesh/tet_mesh.hpp"
#include "curvemesh/quality/bernstein.hpp"

namespace cm::quality {

enum class Validity {
  kValid,         ///< certified: det J > 0 everywhere on the closed element
  kInvalid,       ///< det J <= 0 (up to rounding, see above) at `where`
  kUndetermined,  ///< neither could be shown within the subdivision budget
};

/// A sub-entity of the reference tet: dim 0 = local vertex `index`; dim 1 =
/// edge `index` of mesh::kTetEdges; dim 2 = face `index` of mesh::kFaceVerts
/// (the face opposite vertex `index`); dim 3 = the interior (index 0).
struct SubEntity {
  int dim = 3;
  int index = 0;
  friend bool operator==(const SubEntity&, const SubEntity&) = default;
};

/// The lowest-dimensional sub-entity whose closure contains bary, treating
/// coordinates <= tol as zero: with tol = 0, the entity the point lies on
/// exactly; with tol > 0, the entity it is "near". Coordinates need not sum
/// to 1 exactly. If every coordinate is <= tol, the largest one's vertex.
SubEntity classify_bary(const Bary& bary, double tol = 0);

struct ValidityOptions {
  /// Bisections allowed along one branch (3 bisections roughly halve a
  /// subdomain's size).
  int max_depth = 36;
  /// Bisections allowed in total, a cap on time and memory per element.
  int max_splits = 4000;
  /// 0: stop as soon as validity is decided. > 0: for a valid element, keep
  /// refining until min_upper - min_lower <= bound_tolerance * max |coef|,
  /// i.e. until the certified lower bound is that close to the true minimum.
  double bound_tolerance = 0;
  /// > 0 (with bound_tolerance > 0): the tolerance applies only to an
  /// element certified valid whose scaled bound min_lower / max_upper comes
  /// out below this once validity is decided; the others stop there. The
  /// same report as deciding validity first and certifying again with the
  /// tolerance where the bound is low, in one pass.
  double refine_below = 0;
  /// After invalidity is found, further bisections (best first) spent to move
  /// `where` toward the minimum of det J; 0 reports the first point found.
  int locate_splits = 24;
};

/// Outcome of certify_jacobian. det J values are with respect to the
/// reference tet (a straight tet has det J = 6V everywhere).
struct ValidityReport {
  Validity verdict = Validity::kUndetermined;
  /// Certified lower bound of min det J (up to `rounding_bound`): the least
  /// Bezier coefficient over the final subdivision.
  double min_lower = 0;
  /// Least value of det J found at a point (at `where`): an upper bound of min det J.
  double min_upper = 0;
  /// Upper bound of max det J (the largest coefficient over the subdivision).
  double max_upper = 0;
  /// Largest value of det J found at a point: a lower bound of max det J.
  double max_lower = 0;
  /// Lower bound of min det J / max det J: min_lower / max_upper when
  /// min_lower > 0 (in (0,1], 1 for a straight tet), min_lower / max_lower
  /// when min_lower <= 0 < max_lower, -infinity when no positive value is known.
  double scaled_jacobian_lower = 0;
  /// The bound E on the rounding error of the coefficients (0 for p = 1).
  double rounding_bound = 0;
  /// Point of the reference tet where min_upper was found (for kInvalid a point
  /// with det J <= 0), and the sub-entity it lies on exactly. For p = 1 (det J
  /// constant) vertex 0.
  Bary where{1, 0, 0, 0};
  SubEntity where_entity{0, 0};
  int splits = 0;         ///< bisections performed
  int depth_reached = 0;  ///< depth of the deepest subdomain
};

/// Bernstein coefficients of det J of the order-p tet with the given nodes
/// (internal order, mesh::tet_node_indices(p)), in the rank order of
/// bernstein_indices(3(p-1)) (use bernstein_rank to look one up).
/// Preconditions: 1 <= order <= kMaxBezierOrder, nodes.size() ==
/// tet_node_count(order) (std::invalid_argument otherwise).
/// Cost: one (N x N) map of the nodes and (p(p+1)(p+2)/6)^3 triple products
/// (64 for P2, 1000 for P3); tables are built once per order.
std::vector<double> jacobian_bezier_coefficients(int order, std::span<const Vec3> nodes);

/// Bezier control points of the geometry (the Lagrange nodes mapped to the
/// Bernstein basis of degree p), in the rank order of bernstein_indices(p).
std::vector<Vec3> geometry_control_points(int order, std::span<const Vec3> nodes);

/// Certifies the sign of det J over the element (see the header comment).
/// Preconditions as for jacobian_bezier_coefficients; nodes must be finite
/// (std::invalid_argument otherwise).
/// Cost: one coefficient computation, plus O(q^4) per bisection when the
/// coefficients do not settle the question at once.
/// A non-empty `coefficients` (size simplex_count(3(order-1)), else
/// std::invalid_argument) receives the coefficients on the whole element, as
/// jacobian_bezier_coefficients gives them, at no extra cost.
ValidityReport certify_jacobian(int order, std::span<const Vec3> nodes,
                                const ValidityOptions& options = {}, std::span<double> coefficients = {});

/// Certified lower bounds of min det J / max det J and of min det J / mean
/// det J over the element, from how its derivative control points D_b
/// depart from the straight tet's J0 (orders 2 to kMaxBezierOrder): J(xi) =
/// J0 (I + A(xi)) with A a Bernstein combination of A_b = J0^-1 (D_b - J0),
/// and det(I + A) = 1 + tr A + (terms of second and third order): the
/// first-order term is bounded by the A_b's traces (its mean is theirs:
/// Bernstein polynomials of one degree have one integral), the others by
/// the A_b's largest Frobenius norm. About a sixth of a certification's cost
/// and tight for the boundary tets that curving bends a little. Rounding is
/// accounted for with a margin. Both are -1 where it cannot tell (the lower
/// bound of det J is not positive, or the straight tet is too flat to bound
/// reliably). Preconditions as for certify_jacobian.
struct NearStraightBounds {
  double ratio = -1;       ///< of min det J / max det J (the scaled Jacobian)
  double mean_ratio = -1;  ///< of min det J / mean det J (a lower bound of I, eq. 3.5)
};
NearStraightBounds near_straight_bounds(int order, std::span<const Vec3> nodes);

/// certify_jacobian on tet t of m, at the mesh's order (mesh::gather_tet_nodes).
ValidityReport certify_tet(const mesh::TetMesh& m, TetId t, const ValidityOptions& options = {});

}  // namespace cm::quality
