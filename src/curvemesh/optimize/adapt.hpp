#pragma once
// Optimization with a size specification (paper 2, second and third cases):
// shapes and lengths measured in a metric field carried by the vertices
// (metric_field.hpp). An isotropic size map leaves the shape measure as it
// is (a constant I/h² does not change shape) and only asks for unit lengths;
// an anisotropic metric changes both.
//
// Each pass, as MMG does it: split the edges longer than 1.4 in the metric
// (longest first), collapse those shorter than 0.7 (shortest first, only
// when no edge of the result is longer than 1.4, so the two never undo each
// other), then improve the tets whose quality in the metric is below the
// threshold: with a model, its deletion when it stands on two or three
// faces of one model face and is worse than the tets across
// (modify/delete_tet.hpp), else the best improving reconnection of the tet
// (edge removal on its six edges, 2-3 swap on its four faces), else
// relocation of its vertices
// toward the position that is best in the metric (boundary ones only with a
// model, on it), else for an isotropic field a new point in the shell of
// one of its interior edges (shell_insert.hpp). Edge removal chooses its
// ring triangulation by the metric quality itself (measured_swap.hpp), so
// in a stretched metric it finds the reconnections the isotropic measure
// would rank low; a swap is kept only when it raises the worst metric
// quality of what it replaces. A new vertex
// gets the log-Euclidean interpolation of its edge's end metrics.
//
// The boundary. Without a model, the surface (and the volume) stays the
// same point set: a boundary edge is split at its midpoint, and by default
// boundary vertices neither move nor go. With options.flat_boundary they
// may, where the surface is exactly flat around them and, on a model edge,
// exactly straight: collapses that keep the surface
// (modify::CollapsePlan::keeps_surface) and moves within the plane or line
// (modify::FlatBoundary), as on the faces of a box. Without that,
// a boundary vertex next to a fine region keeps its short edges.
// With a model (options.model, its tags those of the mesh's
// classification), points split on boundary edges go onto the model and
// boundary vertices collapse along their model entity (modify/split.hpp,
// collapse.hpp), and poor tets on the boundary may be deleted
// (delete_tet.hpp: the surface then moves within the mesher's chord rule).
// Boundary triangles are never swapped, classification is
// kept, and no tet that is not strictly positive (exact orient3d) is ever
// created.
#include <cstddef>

#include "curvemesh/geom/model.hpp"
#include "curvemesh/mesh/tet_mesh.hpp"
#include "curvemesh/optimize/metric_field.hpp"
#include "curvemesh/size/size_field.hpp"

namespace cm::optimize {

struct AdaptOptions {
  int passes = 8;
  /// Tets whose quality in the metric is below this are worked on. In an
  /// anisotropic metric, lengths come to [0.7, 1.4] only as the shapes do
  /// (a tet with edges that far apart has a quality near 0.9 at best), so an
  /// adaptation to one wants about 0.9; `curvemesh optimize` uses that.
  double threshold = 0.3;
  bool swaps = true;
  bool relocation = true;
  /// Edge split and collapse toward unit lengths.
  bool split = true;
  bool collapse = true;
  /// Shell point insertion (shell_insert.hpp) for tets nothing else
  /// improves; isotropic fields only.
  bool insertion = true;
  /// Element deletion of poor tets on the boundary (with a model only), and
  /// the chord rule it keeps (modify::DeletionOptions).
  bool deletion = true;
  /// Without a model, lets boundary vertices collapse and move where the
  /// surface is exactly flat (straight along a model edge); see above.
  bool flat_boundary = false;
  double chord_alpha = 0.04;
  /// The CAD model the mesh is classified on, or nullptr (boundary kept).
  const geom::Model* model = nullptr;
  /// The analytic size or metric the field was sampled from, or nullptr.
  /// When given, vertices made by a split or an insertion and vertices
  /// relocated take its value at their position (its metric() when the
  /// field is anisotropic, else I/size²) instead of the log-Euclidean
  /// interpolation of their neighbours'. Must be thread-safe.
  const size::SizeField* sizes = nullptr;
};

struct AdaptStats {
  std::size_t splits = 0, collapses = 0, edge_removals = 0, face_swaps = 0, relocations = 0, insertions = 0,
              deletions = 0;
  int passes = 0;
  /// Mean ratio in the metric (MetricField::tet_quality) over all tets.
  double min_before = 0, mean_before = 0, min_after = 0, mean_after = 0;
  std::size_t below_before = 0, below_after = 0;  ///< tets under the threshold
  LengthStats lengths_before, lengths_after;
  double split_seconds = 0, collapse_seconds = 0, swap_seconds = 0, relocation_seconds = 0, insertion_seconds = 0;
  double seconds = 0;
};

/// Adapts m in place to the metric. Vertices are added (split) and removed
/// (collapse): on return the mesh is compact (tets and vertices renumbered,
/// adjacency valid) and `field` holds the metric of each of its vertices.
/// Requires a valid mesh with adjacency and field.size() == m.num_verts().
/// Throws std::invalid_argument when the sizes disagree.
AdaptStats adapt_to_metric(mesh::TetMesh& m, MetricField& field, const AdaptOptions& options = {});

/// Quality of a whole mesh, for summaries before and after.
struct MeshSummary {
  std::size_t verts = 0, tets = 0;
  double min_mean_ratio = 0, mean_mean_ratio = 0;
  double min_dihedral = 0, max_dihedral = 0;  ///< degrees
  std::size_t inverted = 0;                   ///< tets with orient3d <= 0
  /// In the metric, when one is given (else equal to the isotropic values).
  double min_metric_quality = 0, mean_metric_quality = 0;
  double volume = 0;
};
/// Measures every tet of a compact mesh, in parallel. `field` may be null.
MeshSummary summarize_mesh(const mesh::TetMesh& m, const MetricField* field = nullptr);

}  // namespace cm::optimize
