#pragma once
// Edge collapse (paper 2, "point removal"): vertex `from` (a) is merged into
// vertex `to` (b) along the mesh edge (a, b). The tets of a's ball that hold
// b disappear; every other tet of the ball has a replaced by b.
//
// Admissibility, as small named rules checked in this order:
// - classification: a's model entity must contain b's in its closure and the
//   edge must run on a's entity: a model vertex never goes; a vertex on a
//   model edge only along a mesh edge of that model edge (m.edges); a vertex
//   on a model face only along a mesh edge that lies on that face (an edge
//   of one of its triangles, not on a model edge); a region vertex along any
//   edge (kClassification);
// - link condition: a vertex or edge adjacent to both a and b must be so
//   through the edge (a, b) itself, in the volume and on the boundary
//   surface; no triangle or classified edge may be created twice
//   (kNonManifold);
// - validity: every surviving tet stays strictly positive, exact orient3d
//   (kNotStarShaped);
// - surface: no boundary triangle through a turns over (its normal against
//   the old one) nor, with a model, against its model face where it agreed
//   with it before (kFoldedSurface).
// b does not move, so the model is optional: without it boundary vertices
// still collapse along their own entity when the rules allow (the surface is
// then checked combinatorially and by normals only). The plan also tells
// whether the surface stays the same point set (keeps_surface), which is
// what a driver without a model needs to let a boundary vertex go.
//
// Applying keeps adjacency, vert2tet, orientation, region tags, m.tris
// (triangles through (a, b) removed, the others through a moved to b with
// their orientation), m.edges likewise, and face marks (a marked face
// through a stays marked as it moves to b). Vertex a stays in the vertex
// arrays with its classification but in no tet (vert2tet[a] == kNone): ids
// never shift under a driver; drop unused vertices once at the end.
#include "curvemesh/geom/model.hpp"
#include "curvemesh/modify/surface.hpp"

namespace cm::modify {

struct CollapsePlan {
  Refusal refusal = Refusal::kNone;
  VertId from = kNone, to = kNone;
  /// Worst tet_quality of from's ball, and of the tets that replace it
  /// (1 if none survives).
  double before = 0, after = 0;
  /// from is on the hull (the collapse changes hull faces).
  bool on_hull = false;
  /// The boundary surface is the same point set after the collapse: every
  /// classified triangle through from lies, exactly (orient3d), in one
  /// plane with the others of its model face, and a from on a model edge
  /// lies exactly on the straight line through its neighbours along it. A
  /// region vertex keeps it trivially. Only meaningful without a refusal.
  bool keeps_surface = true;
};

/// Plans collapsing `from` into `to`. Precondition: both are vertices of the
/// mesh joined by an edge (asserted). Fills the cavity with from's ball;
/// changes nothing else. O(|ball(from)| + |ball(to)|) plus, with a model,
/// two closest-point queries per boundary triangle through from.
CollapsePlan plan_collapse(MeshEditor& ed, Cavity& cavity, const BoundaryIndex& boundary, VertId from, VertId to,
                           const geom::Model* model = nullptr);

/// Applies a plan made with this cavity (no other use of the cavity or edit
/// of the mesh in between). Precondition: plan.refusal == kNone. Returns the
/// created tets (valid until the cavity or the kernel is used again); they
/// were passed to the editor's hook.
std::span<const TetId> apply(MeshEditor& ed, Cavity& cavity, BoundaryIndex& boundary, const CollapsePlan& plan);

}  // namespace cm::modify
