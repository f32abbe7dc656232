#pragma once
// A size or metric field given at the vertices of a tet mesh: what a user
// passes as `--background mesh.msh --background-sol sizes.sol` (MMG-style
// background mesh plus solution), and the MMG-style gradation of such
// vertex values along the mesh edges.
//
// Interpolation. Inside a tet the value is the barycentric interpolation of
// its four vertex values: linear in h for sizes, log-Euclidean for metrics
// (the result of size::interpolate on the four vertex metrics, so the field
// is SPD everywhere and does not inflate between vertices). Outside the mesh
// a point gets the value at the closest point of the mesh (SizeField
// contract), i.e. the barycentric value at the closest point of the nearest
// tet.
//
// Point location. A bounding-volume hierarchy over the tet bounding boxes,
// built once in O(T log T). A BVH rather than a uniform grid because
// background meshes are graded by design (that is what they encode): a grid
// sized for the average tet puts thousands of small tets in one cell where the
// mesh is fine. Queries are O(log T) expected, const and thread-safe.
#include <array>
#include <cstddef>
#include <vector>

#include "curvemesh/core/types.hpp"
#include "curvemesh/mesh/tet_mesh.hpp"
#include "curvemesh/size/metric.hpp"
#include "curvemesh/size/size_field.hpp"

namespace cm::size {

class BackgroundField final : public SizeField {
 public:
  /// Scalar sizes, one per vertex of `mesh` (sizes[v] at mesh.coords[v]),
  /// each finite and > 0. Only coords and tet2verts of the mesh are used
  /// (adjacency and classification need not be built). Tets may have either
  /// orientation; flat tets are only used for the outside projection.
  /// Throws std::invalid_argument when the mesh has no tet or a tet refers to
  /// a missing vertex, when the count differs from the vertex count, or on the
  /// first invalid size, naming its vertex 1-based (as in .msh/.sol files).
  BackgroundField(mesh::TetMesh mesh, std::vector<double> sizes);

  /// Metrics, one per vertex, each symmetric positive definite (is_metric).
  /// Same checks and errors as the scalar constructor.
  BackgroundField(mesh::TetMesh mesh, std::vector<Metric> metrics);

  /// Interpolated size; for metric input the finest size of the
  /// interpolated metric (min_size). Throws std::domain_error for a
  /// non-finite x.
  double size(const Vec3& x, const SizeHint& hint = {}) const override;
  /// Interpolated metric (I/h² for scalar input).
  Metric metric(const Vec3& x, const SizeHint& hint = {}) const override;
  bool anisotropic() const override { return !log_metrics_.empty(); }

  std::size_t num_tets() const { return tets_.size(); }
  std::size_t num_verts() const { return coords_.size(); }

  /// Where a query point falls.
  struct Location {
    TetId tet = kNone;           ///< tet of the background mesh (input numbering)
    std::array<double, 4> bary{};  ///< weights of tet2verts[tet][0..3]: >= 0, sum 1
    double distance = 0;         ///< from x to Σ bary·vertices; 0 for x in the mesh
  };

  /// The tet containing x (up to a relative tolerance of 1e-10 in the
  /// barycentrics, clamped to the tet), or else the nearest tet and the
  /// barycentrics of the closest point of it. Throws std::domain_error for a
  /// non-finite x.
  Location locate(const Vec3& x) const;

 private:
  // Boxes in float, rounded outwards: 32-byte nodes, two per cache line;
  // traversal is bound by memory, and a slightly larger box costs nothing
  // but an occasional extra barycentric test.
  struct Node {
    std::array<float, 3> lo, hi;
    Index first;  ///< leaf: first tet slot; inner: index of the right child (left = this + 1)
    Index count;  ///< leaf: number of tets (> 0); inner: 0
  };

  void build_bvh();
  // These work on internal tet numbers (slots in BVH leaf order).
  Location locate_slot(const Vec3& x) const;
  bool find_containing(const Vec3& x, Location& loc) const;
  Location find_nearest(const Vec3& x) const;

  // Tets are stored in BVH leaf order and vertices renumbered by first use
  // in that order (build_bvh); corner order within a tet is the input's.
  std::vector<Vec3> coords_;
  std::vector<std::array<VertId, 4>> tets_;
  std::vector<double> sizes_;        ///< scalar input, else empty
  std::vector<Metric> log_metrics_;  ///< log(M) per vertex for metric input, else empty
  std::vector<Node> nodes_;
  std::vector<TetId> order_;  ///< input tet id of each slot
};

/// MMG-style size gradation along the edges of `mesh` (the edges of its
/// tets): returns the largest sizes h' <= h with
///   h'(q) <= h'(p) + (hgrad - 1)·|pq|   for every mesh edge pq,
/// i.e. h'(q) = min over p of h(p) + (hgrad - 1)·(edge-path distance p→q).
/// Exact on the edge graph (multi-source Dijkstra, O(E log V)); the bound
/// holds exactly in floating point. hgrad = 1 makes h constant on each
/// connected part (its minimum). Sizes are only lowered. Throws
/// std::invalid_argument unless hgrad >= 1 and finite, and for the size
/// errors of BackgroundField (count, non-finite or non-positive values, bad
/// tets). Grade before constructing the field:
///   BackgroundField f(mesh, grade_sizes(mesh, h, 1.3));
std::vector<double> grade_sizes(const mesh::TetMesh& mesh, std::vector<double> h, double hgrad);

/// Metric gradation (MMG's anisotropic rule): for every mesh edge pq, with
/// l_p = metric_length(M_p, p, q) and η = 1 + (hgrad - 1)·l_p,
///   M_q := intersect(M_q, M_p / η²)
/// (M_p with its sizes grown by the factor η, which for M_p = I/h_p² is the
/// scalar rule h_p + (hgrad - 1)|pq|). Relaxed with a work queue, finest
/// vertex first, until no edge asks for a change of more than 1e-9 relative
/// (largest generalized eigenvalue of (M_p/η², M_q) <= 1 + 1e-9). Metrics
/// only grow (sizes are only lowered). Intersection is not associative, so an
/// anisotropic relaxation may revisit vertices; it stops after 100·#V vertex
/// visits in any case (never reached on the meshes we tested; when it is, the
/// result is still a lowering of the input but some edges may exceed the
/// bound). Same errors as grade_sizes, with the metric checks of
/// BackgroundField.
std::vector<Metric> grade_metrics(const mesh::TetMesh& mesh, std::vector<Metric> m, double hgrad);

}  // namespace cm::size
