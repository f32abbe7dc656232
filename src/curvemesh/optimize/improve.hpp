#pragma once
// Isotropic shape improvement (paper 2, first case): the worst tets first,
// each tried with edge removal on its six edges and the 2-3 swap on its four
// faces (the best improving reconnection wins, ranked by the mean ratio
// capped by the smallest dihedral angle: measured_swap.hpp), then relocation of its
// interior vertices, else a new interior point replacing the shell of one
// of its interior edges (shell_insert.hpp: the fix for slivers whose
// vertices are all on the boundary); repeated over a few passes until
// nothing improves.
// A tet is worked on when its mean ratio is below the threshold or its
// smallest dihedral angle below the angle threshold: flat caps and slivers
// can keep a fair mean ratio while one angle is tiny, and solvers suffer
// from the angle.
// Boundary triangles (m.tris) and the hull are never reconnected. Without a
// model boundary vertices do not move, so classification, the boundary
// surface and the enclosed volume are kept exactly; with one (its tags those
// of the mesh's classification) they move on their model face or edge
// (modify/relocate.hpp), model vertices never.
#include <cstddef>

#include "curvemesh/geom/model.hpp"
#include "curvemesh/mesh/tet_mesh.hpp"

namespace cm::optimize {

struct ImproveOptions {
  int passes = 6;
  /// Tets with mean ratio below this are worked on (0.3 ≈ min dihedral 10°
  /// for a typical sliver).
  double threshold = 0.3;
  /// Tets with a dihedral angle below this (degrees) are worked on too.
  double dihedral_threshold = 12.0;
  bool swaps = true;
  bool relocation = true;
  bool insertion = true;
  /// The CAD model of the mesh, or nullptr (boundary vertices fixed).
  const geom::Model* model = nullptr;
};

struct ImproveStats {
  std::size_t edge_removals = 0, face_swaps = 0, relocations = 0, insertions = 0;
  /// Of the relocations, those of boundary vertices (on the model).
  std::size_t boundary_relocations = 0;
  int passes = 0;
  double min_before = 0, mean_before = 0, min_after = 0, mean_after = 0;
  /// Smallest dihedral angle over the mesh, degrees.
  double min_dihedral_before = 0, min_dihedral_after = 0;
  std::size_t below_before = 0, below_after = 0;  ///< tets under the threshold
  /// Time spent planning and applying each kind of operator (swaps:
  /// edge removal and face swap together).
  double swap_seconds = 0, relocation_seconds = 0, insertion_seconds = 0;
  double seconds = 0;
};

/// Improves m in place (tets renumbered, adjacency rebuilt; insertions
/// append region vertices, existing vertices keep their ids). Requires a
/// valid mesh with adjacency; flat tets (zero volume) are allowed and are
/// the first worked on. Never creates a tet that is not strictly
/// positive (exact orient3d), and never lowers the worst mean ratio of the
/// tets an operation replaces.
ImproveStats improve_quality(mesh::TetMesh& m, const ImproveOptions& options = {});

}  // namespace cm::optimize
