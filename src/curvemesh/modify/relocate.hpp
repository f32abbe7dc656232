#pragma once
// Point relocation (paper 2): move one vertex inside its ball to raise the
// worst quality of the ball. The candidate is the smart Laplacian (centroid
// of the ball's other vertices), tried whole and damped; the best position
// that keeps every tet positive (exact orient3d) and improves the worst
// quality wins. Applied through the cavity kernel (the ball refilled as the
// star of the moved vertex) so the rebuild hook sees the changed tets.
//
// Vertices on the boundary move only with a model, and only on their own
// entity (model-aware overload): a vertex on a model face moves in the
// face's tangent plane and is projected back onto the face through its
// (u, v); a vertex on a model edge moves along the edge's tangent and is
// projected back through u. Model vertices never move. Without a model
// boundary vertices stay where they are.
#include "curvemesh/geom/model.hpp"
#include "curvemesh/modify/cavity.hpp"
#include "curvemesh/modify/surface.hpp"

namespace cm::modify {

struct Relocation {
  Refusal refusal = Refusal::kNone;
  Vec3 target = Vec3::Zero();
  /// The vertex's parameters on its model edge or face at `target` (NaN for
  /// a region vertex: nothing to update).
  mesh::Param param;
  /// Worst tet_quality of the ball now and with the vertex at target.
  double before = 0, after = 0;
};

/// Evaluates moving v, a region vertex (dim 3); fills the cavity with v's
/// ball. Nothing changes. Refusals: kClassification (v is not a region
/// vertex or is in no tet), kNoImprovement (no candidate raises the worst
/// quality by more than 1e-6).
Relocation plan_relocation(MeshEditor& ed, Cavity& cavity, VertId v);

/// The same for any vertex. A vertex on a model face or edge needs `model`
/// (nullptr: refused with kClassification, as are model vertices); its
/// candidates are the Laplacian moves toward the centroid of its surface
/// (or model-edge) neighbours and toward its ball's centroid, restricted to
/// the tangent plane (line) and projected onto the entity, whole and damped.
/// Besides positivity and improvement, no boundary triangle through v may
/// turn over against its old normal or against the model face where it
/// agreed with it (kFoldedSurface when that is what rejected the last
/// improving candidate). Costs about six closest-point queries, plus two per
/// boundary triangle through v for the candidates checked against the model.
Relocation plan_relocation(MeshEditor& ed, Cavity& cavity, const BoundaryIndex& boundary, VertId v,
                           const geom::Model* model);

/// Evaluates moving v to a position found by the caller: `target`, with
/// `param` its parameters on v's model edge (u) or face (u, v) — target
/// must lie on that entity (a closest point, say); ignored for a region
/// vertex. Fills the cavity with v's ball; changes nothing. The same rules
/// as plan_relocation except improvement, which is the caller's to judge
/// (before / after are the ball's worst tet_quality now and at target):
/// kClassification (a model vertex, a boundary vertex without a model, a
/// vertex in no tet), kNotStarShaped (a tet of the ball would not be
/// strictly positive, exact orient3d), kFoldedSurface (a boundary triangle
/// through v would turn over, or against the model face where it agreed
/// with it). `boundary` may be null for a region vertex.
Relocation plan_relocation_to(MeshEditor& ed, Cavity& cavity, const BoundaryIndex* boundary, VertId v,
                              const geom::Model* model, const Vec3& target, const mesh::Param& param);

/// Moves v to plan.target (and its parameters to plan.param when set), and
/// rebuilds its ball: same cavity, no other use in between. Marked faces
/// through v stay marked.
void apply(MeshEditor& ed, Cavity& cavity, VertId v, const Relocation& plan);

}  // namespace cm::modify
