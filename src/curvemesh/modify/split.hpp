#pragma once
// Edge split (paper 2, "point creation to suppress an edge"): a new vertex p
// on edge (a, b); every tet (a, b, c, d) of the edge's shell becomes
// (p, b, c, d) and (a, p, c, d).
//
// Where p goes and how it is classified follows the edge:
// - on a model edge (the edge is in m.edges): p is on that model edge, at
//   the mid-parameter of a and b when both are known and the pair does not
//   straddle the period of a closed edge, else at the closest point of the
//   chord's midpoint (the known parameter as hint); vert_param gets u;
// - on a model face (a triangle of m.tris holds the edge): p is the closest
//   point of the face to the chord's midpoint, hinted by the midpoint of a's
//   and b's (u, v) (or either alone); vert_param gets (u, v);
// - else the region of the shell: p is the chord's midpoint.
// Without a model, boundary edges are split at the chord's midpoint too and
// vert_param stays unknown (NaN): exact for planar faces and straight model
// edges, an approximation otherwise.
//
// Applying keeps everything an operator must keep: adjacency, vert2tet and
// orientation (through the cavity kernel, so the editor's hook sees the new
// tets), region tags, m.tris (a split triangle becomes two with the same tag
// and orientation) and m.edges (a split edge becomes two), and face marks (a
// marked face through (a, b) leaves two marked halves).
#include "curvemesh/geom/model.hpp"
#include "curvemesh/modify/surface.hpp"

namespace cm::modify {

struct SplitPlan {
  Refusal refusal = Refusal::kNone;
  VertId a = kNone, b = kNone;
  /// The new vertex: position, classification (dim 1, 2 or 3 with the
  /// entity's tag) and parameters on that entity (NaN where unknown).
  Vec3 point = Vec3::Zero();
  mesh::ModelRef classification;
  mesh::Param param;
  /// Worst tet_quality of the shell, and of the tets that replace it (-1 if
  /// one would not be positive).
  double before = 0, after = 0;
  /// The shell reaches the hull (its split changes hull faces).
  bool on_hull = false;
};

/// Plans the split of edge (a, b); `start` is a live tet holding both. Fills
/// the cavity with the edge's shell; changes nothing else. `model` may be
/// nullptr (see above). O(shell size), plus a few model queries for a
/// boundary edge.
///
/// Refusals:
/// - kClassification: the edge's classification is inconsistent (triangles
///   of different model faces through an edge that is on no model edge, a
///   hull edge with no classified triangle, a shell mixing regions without
///   a triangle between them);
/// - kNotStarShaped: a new tet would not be strictly positive (exact
///   orient3d), or the model put p farther from the edge's midpoint than
///   half the edge's length;
/// - kFoldedSurface: a half of a split boundary triangle would turn against
///   the triangle (or, with a model, against the face's normal where the
///   triangle agreed with it).
SplitPlan plan_split(MeshEditor& ed, Cavity& cavity, const BoundaryIndex& boundary, VertId a, VertId b, TetId start,
                     const geom::Model* model = nullptr);

/// Applies a plan made with this cavity (no other use of the cavity in
/// between, no other edit of the mesh). Precondition: plan.refusal == kNone.
/// Returns the new vertex. The created tets are passed to the editor's hook.
VertId apply(MeshEditor& ed, Cavity& cavity, BoundaryIndex& boundary, const SplitPlan& plan);

}  // namespace cm::modify
