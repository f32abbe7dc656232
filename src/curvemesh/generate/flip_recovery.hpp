#pragma once
// Recovery of a missing boundary edge or triangle by flips: the assurance
// algorithm's "recovered by flips where possible" (seed paper 1, §2), tried
// before any Steiner point.
//
// No vertex is added or moved. A missing edge (a, b) is recovered by walking
// from a along the segment: the face it crosses first is swapped 2-3 when its
// two tets form a convex pair, else the edge of that face that blocks the
// swap is removed (n-to-2n-4 edge removal); a segment through an edge removes
// that edge. A missing triangle (a, b, c) whose edges are present is crossed
// by mesh edges; the one found in the shell of (a, b) is removed by edge
// removal, with a ring triangulation containing (a, b, c) when the ring holds
// all three. Each step is a valid operation of the cavity kernel (exact
// orient3d) that removes no boundary edge or triangle already present, so a
// failed attempt leaves a valid tetrahedralization; the caller then falls
// back to Steiner points. Steps per call are bounded.
//
// Flips leave a tetrahedralization that is no longer Delaunay: Steiner
// points inserted afterwards need the star-correcting insertion of
// Delaunay3d (set_non_delaunay).
#include <array>
#include <cstddef>
#include <functional>
#include <vector>

#include "curvemesh/mesh/tet_mesh.hpp"
#include "curvemesh/modify/cavity.hpp"
#include "curvemesh/modify/mesh_editor.hpp"

namespace cm::generate {

struct FlipRecoveryStats {
  std::size_t face_swaps = 0, edge_removals = 0;  ///< operations applied
  std::size_t edges_recovered = 0, triangles_recovered = 0;
};

class FlipRecovery {
 public:
  /// `is_boundary_edge(a, b)` tells the edges no flip may remove (edges of
  /// the surface mesh and model-edge segments); a face with three boundary
  /// edges is taken for a boundary triangle and never removed either.
  FlipRecovery(modify::MeshEditor& ed, std::function<bool(VertId, VertId)> is_boundary_edge);

  /// Makes (a, b) an edge of the mesh; false if flips could not (the mesh is
  /// then valid but possibly changed).
  bool recover_edge(VertId a, VertId b);
  /// Makes (a, b, c) a face of the mesh; its three edges must be edges of
  /// the mesh. False if flips could not.
  bool recover_triangle(VertId a, VertId b, VertId c);

  const FlipRecoveryStats& stats() const { return stats_; }

 private:
  bool face_swap(TetId t, int f);
  bool remove_edge(VertId p, VertId q, TetId start, const std::array<VertId, 3>& wanted);
  bool protected_face(VertId a, VertId b, VertId c) const;

  modify::MeshEditor& ed_;
  std::function<bool(VertId, VertId)> is_boundary_edge_;
  modify::Cavity cavity_;
  std::vector<TetId> ball_;
  FlipRecoveryStats stats_;
};

}  // namespace cm::generate
