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
#include <array>
#include <functional>
#include <span>
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
/// Rates ring triangle (ring[i], ring[k], ring[j]), i < k < j, of an edge
/// removal by the two tets (a-side, b-side) it would make; higher is better,
/// <= 0 forbids the triangle. `ring` is the shell's ring in order.
using RingTriangleValue = std::function<double(std::span<const VertId> ring, const std::array<int, 3>& ikj,
                                               const std::array<std::array<VertId, 4>, 2>& tets)>;
/// Edge removal for a purpose other than quality (as boundary recovery
/// wanting a given face): the ring triangulation maximizing the worst value.
/// Refused (kNotStarShaped) when every triangulation has a value <= 0; never
/// refused for not improving, and plan.before is then meaningless. The
/// value must refuse inverted tets itself (tet_quality does).
Plan plan_edge_removal(MeshEditor& ed, Cavity& cavity, VertId a, VertId b, TetId start, const RingTriangleValue& value);
/// Plans the 2-3 swap of face f of tet t.
Plan plan_face_swap(MeshEditor& ed, Cavity& cavity, TetId t, int f);
/// Applies a plan made with this cavity (no other cavity use in between).
std::span<const TetId> apply(MeshEditor& ed, Cavity& cavity, const Plan& plan);

}  // namespace cm::modify
