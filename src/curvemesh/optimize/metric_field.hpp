#pragma once
// A size specification carried by the mesh being optimized (paper 2, second
// and third cases): one metric tensor per vertex. An isotropic size h is the
// metric I/h²; a tensor comes from a .sol in MMG conventions. Between
// vertices the metric is interpolated log-Euclidean (size::interpolate), so
// it stays SPD and does not swell.
//
// Measures in the metric:
// - edge length: the integral of the metric length along the edge, with the
//   size in the edge's direction, h(t) = |e| / sqrt(eᵀM(t)e), taken linear
//   between the endpoints (the convention of MMG, Gmsh and BAMG). With
//   l_a = sqrt(eᵀM_a e) and l_b = sqrt(eᵀM_b e) this is
//   L = l_a l_b ln(l_a/l_b) / (l_a − l_b), and l_a when both are equal.
//   A unit mesh has every L in [1/√2, √2] ≈ [0.7, 1.4].
// - tet quality: the mean ratio of the tet in its mean metric, the
//   log-Euclidean mean of its four vertex metrics (quality::
//   tet_metric_mean_ratio). For an isotropic field this is the plain mean
//   ratio (a constant I/h² does not change shape), which is what is used.
#include <array>
#include <cstddef>
#include <span>
#include <vector>

#include "curvemesh/mesh/tet_mesh.hpp"
#include "curvemesh/size/metric.hpp"
#include "curvemesh/size/size_field.hpp"

namespace cm::optimize {

class MetricField {
 public:
  MetricField() = default;
  /// M_v = I / h_v², one size per vertex. Throws std::invalid_argument on the
  /// first size that is not finite and > 0, naming its vertex 1-based (as
  /// .sol files count).
  static MetricField from_sizes(std::span<const double> sizes);
  /// One SPD tensor per vertex; `anisotropic()` is then true. Throws
  /// std::invalid_argument on the first tensor that is not symmetric positive
  /// definite, naming its vertex 1-based.
  static MetricField from_tensors(std::vector<size::Metric> metrics);

  std::size_t size() const { return metrics_.size(); }
  bool empty() const { return metrics_.empty(); }
  bool anisotropic() const { return anisotropic_; }

  const size::Metric& metric(VertId v) const { return metrics_[v]; }
  const size::Metric& log_metric(VertId v) const { return logs_[v]; }
  /// Isotropic size of v (for an anisotropic field, its finest size).
  double size_at(VertId v) const;

  /// Replaces v's metric (must be SPD; not checked here).
  void set(VertId v, const size::Metric& m);
  /// Gives vertex v (which may be new: the arrays grow) the log-Euclidean
  /// interpolation (1 − t)·M_a + t·M_b, as for a point inserted on edge ab.
  void set_interpolated(VertId v, VertId a, VertId b, double t);

  /// log-Euclidean mean of the four vertex metrics: one eigen-solve.
  size::Metric tet_metric(const std::array<VertId, 4>& v) const;
  /// Length of edge ab in the metric (see the header comment).
  double edge_length(const mesh::TetMesh& m, VertId a, VertId b) const;
  /// Mean ratio in the tet's mean metric when the tet is strictly positive
  /// by exact orient3d (in (0, 1]), else −1. Same scale as modify::tet_quality.
  double tet_quality(const mesh::TetMesh& m, const std::array<VertId, 4>& v) const;
  /// The same for corners that need not be mesh vertices yet (a planned
  /// point), given with their log-metrics (log_metric(), or the
  /// interpolated one for a new point).
  double tet_quality_at(const std::array<Vec3, 4>& x, const std::array<const size::Metric*, 4>& logs) const;

 private:
  std::vector<size::Metric> metrics_, logs_;
  bool anisotropic_ = false;
};

/// Length of the segment pq for the metrics mp at p and mq at q (see the
/// header comment). Symmetric in (p, mp) ↔ (q, mq); equals
/// size::metric_length when mp == mq.
double edge_metric_length(const Vec3& p, const Vec3& q, const size::Metric& mp, const size::Metric& mq);

/// Reads a field given as values per vertex: 1 component (sizes) or 6 (MMG
/// order m11 m12 m22 m13 m23 m33). Throws std::invalid_argument when the
/// count is not components · num_verts ("N values for M vertices") or a value
/// is unusable.
MetricField metric_field_from_values(std::span<const double> values, int components, std::size_t num_verts);
/// Its inverse: per vertex the size (isotropic field) or the tensor's six
/// entries in MMG's order (m11, m12, m22, m13, m23, m33), as a .sol holds them.
std::vector<double> metric_field_values(const MetricField& field);

/// The mesh's own sizes: at each vertex, the mean length of its edges. What
/// --hmin/--hmax clamp when no other size is given (as MMG does). Vertices
/// in no tet get the mean over the mesh. O(T).
MetricField metric_field_from_mesh_sizes(const mesh::TetMesh& m);

/// The mesh's own anisotropy: at each vertex the metric in which its edges
/// are closest to unit length (least squares on eᵀMe = 1 over its edges),
/// or I/h² with h its mean edge length when the fit is not SPD or not
/// determined. Makes a stretched mesh keep its stretching while optimized.
MetricField metric_field_from_mesh_shape(const mesh::TetMesh& m);

/// The field's metric (or size) at every vertex of m. The field must be
/// thread-safe (SizeField contract); queried in parallel.
MetricField metric_field_from_size_field(const mesh::TetMesh& m, const size::SizeField& field);

/// Clamps every size to [hmin, hmax] (eigenvalues of M to [1/hmax², 1/hmin²]);
/// a bound <= 0 is not applied. Throws std::invalid_argument if hmin > hmax > 0.
void clamp_sizes(MetricField& field, double hmin, double hmax);

/// MMG's gradation along the mesh edges (size::grade_sizes for an isotropic
/// field, size::grade_metrics for an anisotropic one): sizes only decrease,
/// until h(q) <= h(p) + (hgrad − 1)|pq| (or its metric form) on every edge.
/// hgrad <= 0 means no gradation. Requires field.size() == m.num_verts().
void grade(MetricField& field, const mesh::TetMesh& m, double hgrad);

/// Edge lengths in the metric over the unique edges of the live tets of m
/// (tets whose first vertex is kNone are skipped).
struct LengthStats {
  std::size_t edges = 0;
  double min = 0, max = 0, mean = 0;
  std::size_t in_range = 0;  ///< edges with length in [0.7, 1.4]
  std::size_t too_short = 0, too_long = 0;
  /// Counts in [0, 0.25), [0.25, 0.5), ... [2.75, 3), then >= 3.
  std::array<std::size_t, 13> histogram{};
  double percent_in_range() const { return edges ? 100.0 * static_cast<double>(in_range) / static_cast<double>(edges) : 0; }
};
LengthStats measure_lengths(const mesh::TetMesh& m, const MetricField& field);

inline constexpr double kShortEdge = 0.7;
inline constexpr double kLongEdge = 1.4;

}  // namespace cm::optimize
