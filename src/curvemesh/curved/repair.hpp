#pragma once
// The seed's incremental procedure (paper 1, §3) that makes every curved tet
// valid and acceptable by local mesh modification.
//
// For each unacceptable tet, worst first, the entities to modify are found
// from where its det J is least (the curved entity and the one it comes too
// close to), then, in order, the first kind of operation that helps is
// applied:
// 1. retriangulation, which moves and adds no vertex: edge removal of the
//    tet's interior edges (the shell's ring retriangulated by dynamic
//    programming maximizing the worst curved quality), the 2-3 swap of its
//    interior faces, and the swap of its curved face edges on their model
//    face (modify/boundary_swap.hpp). The ring triangulations best for the
//    straight tets are tried first, and taken when every tet they make is
//    acceptable curved: most of the time, at a fraction of the cost;
// 2. element deletion with reclassification of interior entities onto the
//    boundary (modify/delete_tet.hpp): a tet with two or three faces on one
//    model face — curved, its boundary edges meet tangent to the face and
//    det J vanishes there — is taken out of the domain;
// 3. remeshing: split of its curved boundary edges (the new vertex on the
//    model: the sagitta drops fourfold), collapse of its interior edges
//    that have one end on the boundary onto that end;
// 4. repositioning of its interior vertices, maximizing the worst curved
//    quality of their balls (pattern search).
// An operation is taken when every tet it creates is acceptable, else the
// best one that leaves fewer unacceptable tets (or as many, all better);
// candidates are judged on the nodes they would give before anything is
// applied (modify's plans plus the nodes the new boundary entities would
// get), and the list of unacceptable tets is updated after each step.
// Then, for what remains:
// 5. curving of interior edges of the tet (their nodes moved off the chord
//    to maximize the worst quality of their shells) — reported, since the
//    seed calls it undesirable;
// 6. and, only if a tet is still not acceptable, straightening of its
//    curved boundary entities (and of those of any tet this makes
//    unacceptable): the straight-sided mesh is kept valid throughout (every
//    operation checks the straight tets exactly), so this always ends with
//    a valid mesh, at the price of the geometric error there. Reported.
// Every operation goes through the modify kernel, so classification,
// parameters, boundary triangles and adjacency stay right; the nodes of
// the boundary entities it creates are placed on the model by the editor's
// rebuild hook.
#include <array>
#include <cstddef>
#include <span>
#include <vector>

#include "curvemesh/curved/element_check.hpp"
#include "curvemesh/geom/model.hpp"
#include "curvemesh/mesh/tet_mesh.hpp"

namespace cm::curved {

struct RepairOptions {
  Acceptance acceptance;
  /// Passes of steps 1-4 over the tets still unacceptable.
  int passes = 8;
  bool interior_curving = true;  ///< step 5
  bool straighten = true;        ///< step 6
};

/// The entities to modify in one unacceptable tet, as the repair found them.
struct ProblemEntities {
  std::array<VertId, 4> tet{};
  double score = 0;  ///< ElementCheck::score() when found
  /// The mesh entity (1 to 4 vertices) where det J is least.
  std::vector<VertId> at;
  /// The tet's curved edges.
  std::vector<std::array<VertId, 2>> curved_edges;
  /// det J least on a curved entity or at its ends (it strays too far from
  /// the straight element), rather than on an entity it comes too close to.
  bool too_far = false;
};

struct RepairStats {
  /// Problem entities found, by the seed's cases: a curved boundary entity
  /// that strays too far from its straight tet (det J least on it or at its
  /// vertices), and one that comes too close to another entity of the tet
  /// (det J least on an entity that is not curved).
  std::size_t too_far = 0, too_close = 0;
  /// The first kMaxListed of them, worst first within each pass.
  static constexpr std::size_t kMaxListed = 100;
  std::vector<ProblemEntities> problems;
  std::size_t edge_removals = 0, face_swaps = 0, boundary_swaps = 0, deletions = 0, splits = 0, collapses = 0,
              relocations = 0;
  /// Interior edges left curved at the end (step 5, less those step 6 took
  /// back).
  std::size_t interior_edges_curved = 0;
  /// Boundary edges and triangles left straight by step 6.
  std::size_t edges_straightened = 0, faces_straightened = 0;
  int passes = 0;
  double seconds = 0;
};

/// Repairs m in place, starting from `unacceptable` (the tets check_mesh
/// found not acceptable with options.acceptance; tets that become so are
/// found on the way). Preconditions: m.high_order holds the nodes of
/// exactly m's boundary edges (and for order 3 triangles), as
/// place_boundary_nodes leaves them; adjacency is valid; the straight-sided
/// mesh is valid; `model` is the mesh's model (its tags those of the
/// classification). On return the mesh is compact (tets renumbered, unused
/// vertices kept), adjacency valid, and with step 6 enabled every tet is
/// certified valid and acceptable. With `origin`, origin[t] is, for each
/// tet t on return, the id it had on entry when it is that tet with the
/// same nodes (no edit rebuilt it, none of its edges and faces has other
/// nodes), else kNone: what recheck_mesh needs to check only what changed.
RepairStats repair_curved_mesh(mesh::TetMesh& m, const geom::Model& model, std::span<const TetId> unacceptable,
                               const RepairOptions& options = {}, std::vector<TetId>* origin = nullptr);

}  // namespace cm::curved
