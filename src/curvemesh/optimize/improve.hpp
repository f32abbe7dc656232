#pragma once
// Isotropic shape improvement (paper 2, first case): the worst tets first,
// each tried, with a model, by element deletion when it stands on the
// boundary with two or three faces of one model face (modify/delete_tet.hpp),
// then with edge removal on its six edges and the 2-3 swap on its four
// faces (the best improving reconnection wins, ranked by the mean ratio
// capped by the smallest dihedral angle: measured_swap.hpp), then relocation
// of its vertices (the smart Laplacian, else a search for the position best
// for the ball's worst tet: vertex_search.hpp), else the collapse of one of
// its edges, else a new interior point replacing the shell of one of its
// interior edges (shell_insert.hpp: the fix for slivers whose vertices are
// all on the boundary); repeated over passes until nothing improves. The
// search and the collapses join in once the other operators are stuck.
// A tet is worked on when its mean ratio is below the threshold or its
// smallest dihedral angle below the angle threshold: flat caps and slivers
// can keep a fair mean ratio while one angle is tiny, and solvers suffer
// from the angle.
// Boundary triangles (m.tris) and the hull are never reconnected. Without a
// model boundary vertices do not move and no tet is deleted, so
// classification, the boundary surface and the enclosed volume are kept
// exactly; with one (its tags those of the mesh's classification) boundary
// vertices move on their model face or edge (modify/relocate.hpp), model
// vertices never, and deletions reshape the surface within the mesher's
// chord rule.
#include <cstddef>

#include "curvemesh/geom/cusps.hpp"
#include "curvemesh/geom/model.hpp"
#include "curvemesh/mesh/tet_mesh.hpp"

namespace cm::optimize {

struct ImproveOptions {
  int passes = 24;
  /// Tets with mean ratio below this are worked on (0.3 ≈ min dihedral 10°
  /// for a typical sliver).
  double threshold = 0.3;
  /// Tets with a dihedral angle below this (degrees) are worked on too, and
  /// the relocation search raises angles up to it. Well above the 10° most
  /// solvers ask for: on the shared models 18 gives minima of 15-18° and
  /// mean ratios of 0.35-0.45 where 12 gave 12° and 0.30, for about 1.5x
  /// the time.
  double dihedral_threshold = 18.0;
  bool swaps = true;
  bool relocation = true;
  /// Relocation by search when the Laplacian move does not help.
  bool search = true;
  bool insertion = true;
  /// Element deletion (with a model only), and the chord rule it keeps the
  /// new boundary to (modify::DeletionOptions: the mesher's relative
  /// deviation, --curv-alpha).
  bool deletion = true;
  double chord_alpha = 0.04;
  /// Edge collapse of a poor tet's edges (boundary vertices with a model
  /// only, along their entity).
  bool collapse = true;
  /// The CAD model of the mesh, or nullptr (boundary vertices fixed).
  const geom::Model* model = nullptr;
  /// Cusp tips the mesh was generated with (geom/cusps.hpp): no vertex is
  /// moved or inserted inside their balls, and the boundary vertices next
  /// to a tip's vertex (on its sphere) neither move nor collapse, so the
  /// needles at the tip keep their fair bases.
  std::vector<geom::CuspTip> tips;
};

struct ImproveStats {
  std::size_t edge_removals = 0, face_swaps = 0, relocations = 0, insertions = 0, deletions = 0, collapses = 0;
  /// Of the relocations, those of boundary vertices (on the model), and
  /// those the search found.
  std::size_t boundary_relocations = 0, searched_relocations = 0;
  int passes = 0;
  double min_before = 0, mean_before = 0, min_after = 0, mean_after = 0;
  /// Smallest dihedral angle over the mesh, degrees.
  double min_dihedral_before = 0, min_dihedral_after = 0;
  std::size_t below_before = 0, below_after = 0;  ///< tets under the threshold
  /// Time spent planning and applying each kind of operator (swaps:
  /// edge removal and face swap together).
  double swap_seconds = 0, relocation_seconds = 0, insertion_seconds = 0, deletion_seconds = 0, collapse_seconds = 0;
  double seconds = 0;
};

/// Improves m in place (tets renumbered, adjacency kept; insertions append
/// region vertices; a collapse, or a deletion that takes its vertex, leaves
/// a vertex unused, and unused vertices are dropped at the end, the others
/// keeping their order). Requires a
/// valid mesh with adjacency; flat tets (zero volume) are allowed and are
/// the first worked on. Never creates a tet that is not strictly
/// positive (exact orient3d), and never lowers the worst mean ratio of the
/// tets an operation replaces below the lower of its old value and 0.2
/// (measured_swap.hpp, is_progress).
ImproveStats improve_quality(mesh::TetMesh& m, const ImproveOptions& options = {});

}  // namespace cm::optimize
