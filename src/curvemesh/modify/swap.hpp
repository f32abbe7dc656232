#pragma once
// Swaps (paper 2, "edge removal" and its inverse): change the connectivity
// of a shell or of a face's two tets without moving or adding vertices.
//
// - Edge removal: the shell of an interior edge (a, b) — n tets around it,
//   their ring of n vertices — is replaced by 2(n-2) tets: a triangulation of
//   the ring polygon joined to a and to b. The triangulation that maximizes
//   the worst quality is found by dynamic programming over the ring
//   (Klincsek), which covers the 3-2, 4-4, 5-6, 6-8 ... swaps at once.
// - Face swap (2-3): the two tets on an interior face (a, b, c) with apexes
//   d, e are replaced by the three tets around the new edge (d, e).
// Plans are evaluated first; nothing changes until apply(). Faces marked on
// the editor (boundary triangles) are never removed, and cavities never mix
// regions.
#include <vector>

#include "curvemesh/modify/cavity.hpp"
#include "curvemesh/modify/ring_triangulation.hpp"

namespace cm::modify {

/// An evaluated local reconnection: the cavity (held by the Cavity object
/// passed to the planner), the fill, and the worst quality before and after.
struct Plan {
  Refusal refusal = Refusal::kNone;
  double before = 0, after = 0;
  std::vector<NewTet> fill;
  bool improves(double margin = 1e-6) const { return refusal == Refusal::kNone && after > before + margin; }
};

/// Largest shell edge removal considers (the DP is cubic in it).
inline constexpr int kMaxShell = kMaxRing;

/// Plans the removal of edge (a, b); `start` is a live tet containing it.
Plan plan_edge_removal(MeshEditor& ed, Cavity& cavity, VertId a, VertId b, TetId start);
/// Plans the 2-3 swap of face f of tet t.
Plan plan_face_swap(MeshEditor& ed, Cavity& cavity, TetId t, int f);
/// Applies a plan made with this cavity (no other cavity use in between).
std::span<const TetId> apply(MeshEditor& ed, Cavity& cavity, const Plan& plan);

}  // namespace cm::modify
