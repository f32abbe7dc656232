#pragma once
// Point relocation (paper 2): move one vertex inside its ball to raise the
// worst quality of the ball. The candidate is the smart Laplacian (centroid
// of the ball's other vertices), tried whole and damped; the best position
// that keeps every tet positive (exact orient3d) and improves the worst
// quality wins. Applied through the cavity kernel (the ball refilled as the
// star of the moved vertex) so the rebuild hook sees the changed tets.
//
// Only vertices classified on a region (dim 3) move here; vertices on model
// faces, edges and vertices stay put (moving them along the model is the job
// of a model-aware relocation).
#include "curvemesh/modify/cavity.hpp"

namespace cm::modify {

struct Relocation {
  Refusal refusal = Refusal::kNone;
  Vec3 target = Vec3::Zero();
  double before = 0, after = 0;
};

/// Evaluates moving v; fills the cavity with v's ball. Nothing changes.
Relocation plan_relocation(MeshEditor& ed, Cavity& cavity, VertId v);
/// Moves v to plan.target and rebuilds its ball (same cavity, no reuse between).
void apply(MeshEditor& ed, Cavity& cavity, VertId v, const Relocation& plan);

}  // namespace cm::modify
