#pragma once
// Point creation to suppress an edge (paper 2), with the point placed where
// it does most good: the shell of an interior edge (a, b) is replaced by the
// star of a new region vertex x over the shell's boundary. With x on the
// edge this is the edge split; off the edge it also removes the edge from
// flat configurations a split cannot repair: a sliver whose four vertices
// are on the boundary (so none may move) and whose edges cannot be swapped
// away is cut into tets that all reach the new interior point.
//
// Only interior edges qualify: the shell is closed, in one region, and no
// face through (a, b) is marked on the editor, so the boundary triangles,
// the hull and the volume are unchanged.
#include "curvemesh/modify/cavity.hpp"

namespace cm::optimize {

struct ShellInsertion {
  modify::Refusal refusal = modify::Refusal::kNone;
  VertId a = kNone, b = kNone;
  Vec3 point = Vec3::Zero();
  /// Worst angle_aware_quality (measured_swap.hpp) of the shell, and of the
  /// star that replaces it: the point is placed for the angles too.
  double before = 0, after = 0;
};

/// Plans the insertion for edge (a, b) of live tet `start`: candidates are
/// the edge's midpoint, the centroid of the shell's vertices and their
/// middle, each then moved a few times to the centroid of its star's
/// centroids while that improves. Fills the cavity with the shell; changes
/// nothing. Refusals: kConstrainedFace (hull edge or marked face through
/// it), kClassification (mixed regions), kNotStarShaped (no candidate sees
/// the whole shell boundary), kNoImprovement (no candidate beats the shell's
/// worst quality by 1e-6). O(shell size).
ShellInsertion plan_shell_insertion(modify::MeshEditor& ed, modify::Cavity& cavity, VertId a, VertId b, TetId start);

/// The same with the cavity made of tet t and the tets within `depth` face
/// steps of it (1 or 2) that are in its region, never crossing a marked
/// face: for a bad tet whose edges all touch the boundary, so that no edge
/// shell qualifies. a and b of the plan are kNone. Refused with
/// kConstrainedFace when a marked face would end up inside the cavity.
ShellInsertion plan_ball_insertion(modify::MeshEditor& ed, modify::Cavity& cavity, TetId t, int depth);

/// Adds the planned point as a region vertex and fills the shell with its
/// star (same cavity, nothing else in between). Returns the new vertex.
VertId apply(modify::MeshEditor& ed, modify::Cavity& cavity, const ShellInsertion& plan);

}  // namespace cm::optimize
