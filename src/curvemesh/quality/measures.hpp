#pragma once
// Shape measures of straight tetrahedra and triangles, isotropic and in a
// constant metric. Plain floating point: these measure quality, they never
// decide orientation (use core::predicates for that).
//
// Vertex order and sign follow mesh/topology.hpp: tet (a,b,c,d) is positive iff
// det[b-a, c-a, d-a] > 0. Edge arrays follow mesh::kTetEdges:
// (a,b), (b,c), (c,a), (a,d), (b,d), (c,d).
#include <array>
#include <span>

#include "curvemesh/core/types.hpp"
#include "curvemesh/mesh/tet_mesh.hpp"

namespace cm::quality {

/// Signed volume det[b-a, c-a, d-a] / 6; positive for a positively oriented tet.
double tet_signed_volume(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d);

/// The 6 edge lengths in kTetEdges order.
std::array<double, 6> tet_edge_lengths(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d);

/// Mean ratio eta = 12 (3|V|)^(2/3) / sum of squared edge lengths, multiplied by
/// the sign of V: 1 for the regular tet, in (0,1) for other positive tets, 0 for
/// a flat (or point-like) tet and in [-1,0) for an inverted one.
double tet_mean_ratio(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d);

/// Normalized radius ratio Q = alpha h_max / rho, with h_max the longest edge,
/// rho the inradius (3V / total face area) and alpha = sqrt(6)/12 so that the
/// regular tet gives 1. Q >= 1, larger is worse; +infinity when V <= 0.
double tet_radius_ratio(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d);

/// 1/Q in (0,1] (1 for the regular tet), 0 when V <= 0. Convenient where
/// "larger is better" is expected, e.g. in a histogram next to the mean ratio.
double tet_inverse_radius_ratio(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d);

/// Interior dihedral angles in degrees, at the 6 edges in kTetEdges order, in
/// [0,180]. An inverted tet gets the angles of its mirror image (orientation
/// does not enter); an angle at an edge with a zero-area adjacent face is 0.
std::array<double, 6> tet_dihedral_angles(const Vec3& a, const Vec3& b, const Vec3& c,
                                          const Vec3& d);

struct AngleRange {
  double min = 0;  ///< degrees
  double max = 0;  ///< degrees
};
/// Min and max of tet_dihedral_angles.
AngleRange tet_dihedral_range(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d);
/// tet_dihedral_range(a, b, c, d).min at about half the cost (one atan2,
/// the edge found from unit normals): what the optimizer's measures ask
/// for millions of times.
double tet_min_dihedral(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d);

/// Cheap one-sided tests for searches that only need a tet's measure when it
/// is below a running minimum: true only when tet_mean_ratio(a, b, c, d) >= r
/// (no cube root), resp. tet_min_dihedral(a, b, c, d) >= degrees (no square
/// root, division or atan2), holds for the values those functions return,
/// round-off included. False means "maybe not": compute the measure.
bool tet_mean_ratio_at_least(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d, double r);
bool tet_min_dihedral_at_least(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d, double degrees);

/// Length sqrt(e^T M e) of the vector e in the metric M (3x3 symmetric positive
/// definite; not checked).
double metric_length(const Vec3& e, const Mat3& metric);

/// Mean ratio measured in a metric M constant over the tet: squared edge
/// lengths e^T M e and volume sqrt(det M) V. Same sign convention and range as
/// tet_mean_ratio; with M = I it equals tet_mean_ratio. M must be symmetric
/// positive definite; the caller picks it (e.g. metric_log_mean of the vertex
/// metrics).
double tet_metric_mean_ratio(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d,
                             const Mat3& metric);

/// Log-Euclidean mean exp(mean(log M_i)) of SPD matrices: the usual way to
/// obtain one constant metric from the metrics at an element's vertices (it
/// keeps the determinant's geometric mean, unlike the arithmetic mean, which
/// swells). Precondition: a non-empty list of SPD matrices.
Mat3 metric_log_mean(std::span<const Mat3> metrics);

/// Triangle mean ratio 4 sqrt(3) A / sum of squared edge lengths in [0,1]
/// (1 for the equilateral triangle, 0 for a flat one). Unsigned: a surface
/// triangle in 3D has no orientation of its own.
double triangle_mean_ratio(const Vec3& a, const Vec3& b, const Vec3& c);

/// Straight-sided measures of one tet.
struct TetQuality {
  double volume = 0;        ///< signed, see tet_signed_volume
  double mean_ratio = 0;    ///< signed, see tet_mean_ratio
  double radius_ratio = 0;  ///< Q >= 1 (+infinity when volume <= 0)
  double min_dihedral = 0;  ///< degrees
  double max_dihedral = 0;  ///< degrees
};

/// Measures of tet t from its 4 vertices only: high-order nodes are ignored
/// (use certify_jacobian / shape_measure for curved elements).
TetQuality evaluate_tet(const mesh::TetMesh& m, TetId t);

}  // namespace cm::quality
