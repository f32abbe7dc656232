#pragma once
// Isotropic shape improvement (paper 2, first case): the worst tets first,
// each tried with edge removal on its six edges and the 2-3 swap on its four
// faces (the best improving reconnection wins), then relocation of its
// interior vertices; repeated over a few passes until nothing improves.
// Boundary triangles (m.tris) and the hull are never changed and boundary
// vertices do not move, so classification and the model fit are kept.
#include <cstddef>

#include "curvemesh/mesh/tet_mesh.hpp"

namespace cm::optimize {

struct ImproveOptions {
  int passes = 6;
  /// Tets with mean ratio below this are worked on (0.3 ≈ min dihedral 10°
  /// for a typical sliver).
  double threshold = 0.3;
  bool swaps = true;
  bool relocation = true;
};

struct ImproveStats {
  std::size_t edge_removals = 0, face_swaps = 0, relocations = 0;
  int passes = 0;
  double min_before = 0, mean_before = 0, min_after = 0, mean_after = 0;
  std::size_t below_before = 0, below_after = 0;  ///< tets under the threshold
  double seconds = 0;
};

/// Improves m in place (tets renumbered, adjacency rebuilt). Requires a
/// valid mesh with adjacency.
ImproveStats improve_quality(mesh::TetMesh& m, const ImproveOptions& options = {});

}  // namespace cm::optimize
