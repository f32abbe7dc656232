#pragma once
// Boundary recovery of the assurance algorithm (seed paper 1, §2): make every
// edge and triangle of the classified surface mesh an edge and a face of the
// Delaunay tetrahedralization of its points.
//
// First, triangles that cross each other (a surface mesh coarser than a thin
// feature) have their longest edges split on the model until none cross:
// nothing else could recover them.
//
// Then, before any Steiner point, a missing edge or triangle is recovered by
// flips of the tetrahedralization when they can (FlipRecovery: no vertex added, no
// boundary edge removed). Two faces closer than the mesh size — a thin
// slab, parts of an assembly nearly touching — need them: Steiner points
// alone must refine both faces to the scale of their gap, and the splits
// cascade. After a flip the mesh is no longer Delaunay, and Steiner points
// go in by star-correcting insertion (Delaunay3d::set_non_delaunay).
//
// Otherwise: conforming recovery by Steiner points on the model. A missing mesh
// edge is split at the point of its model entity closest to its midpoint — on
// the model edge (parameter kept) when it is a model-edge segment, else on the
// model face ((u, v) kept) — the triangles around it are split too, and the
// point is inserted in the Delaunay mesh. A missing edge inside one model face
// is first flipped in the surface mesh when the other diagonal of its two
// triangles is a mesh edge (the face's points can be triangulated either
// way), before the volume flips. A missing triangle whose edges are all
// present has its longest edge split. Splits shrink the local spacing
// until every surface simplex is Delaunay; since points are only added on the
// model, geometric similarity holds throughout. The loop is bounded: if it has
// not converged after max_rounds or max_steiner points it throws
// cm::GeometryError naming the model face where recovery failed.
#include <cstddef>
#include <span>

#include "curvemesh/generate/delaunay3d.hpp"
#include "curvemesh/geom/model.hpp"

namespace cm::generate {

struct RecoveryOptions {
  int max_rounds = 200;
  /// Steiner points allowed, as a multiple of the initial surface vertices.
  double max_steiner_factor = 4.0;
  /// First round in which missing simplices are flipped into the
  /// tetrahedralization (before that, only split; a large value gives
  /// conforming recovery by Steiner points alone). Flipped-in simplices keep
  /// the surface mesh as it is, which is what recovers faces closer than
  /// the mesh size, but can leave flatter tets at the boundary than splits
  /// would: on the shared models the minimum dihedral angle is the same or
  /// better with flips from round 0 on all but one.
  int flips_from_round = 0;
};

struct RecoveryStats {
  std::size_t missing_edges_initial = 0, missing_triangles_initial = 0;
  std::size_t steiner_on_edges = 0, steiner_on_faces = 0;
  std::size_t surface_flips = 0;  ///< face-interior surface edges flipped to an edge of the tetrahedralization
  std::size_t crossing_pairs_initial = 0;  ///< pairs of surface triangles crossing each other before recovery
  std::size_t crossing_splits = 0;         ///< Steiner points (counted above too) that removed crossings
  std::size_t volume_flips = 0;            ///< 2-3 swaps and edge removals made to recover simplices
  std::size_t edges_by_volume_flips = 0, triangles_by_volume_flips = 0;  ///< simplices those flips recovered
  int rounds = 0;
};

/// `dt` triangulates (among others) every vertex of its mesh's `tris` and
/// `edges`. On return every tri is a face of the tetrahedralization and every
/// classified edge an edge of it; tris, edges, coords, vert_class and
/// vert_param include the Steiner points.
RecoveryStats recover_boundary(const geom::Model& model, Delaunay3d& dt, const RecoveryOptions& options = {});

/// Whether recovery's split rounds run away, given the surface edges and
/// triangles missing at the end of each round so far: the count grew in
/// each of the last 4 rounds, to more than 8 times the first round's. A
/// converging recovery shrinks what is missing as its splits reach the local
/// scale; a runaway one (surfaces touching or crossing below the mesh size)
/// doubles it each round, splitting edges down to round-off, and would take
/// minutes to exhaust the Steiner budget before failing anyway (a KiCad
/// connector: 22 s and 30000 Steiner points; stopped here after 72 rounds,
/// 2.7 s). recover_boundary throws when this says so.
bool recovery_diverges(std::span<const std::size_t> missing_per_round);

/// True if (a, b) is an edge of the tetrahedralization (walks a's ball).
bool has_edge(const mesh::TetMesh& m, VertId a, VertId b, std::vector<TetId>& scratch);
/// True if (a, b, c) is a face of the tetrahedralization.
bool has_face(const mesh::TetMesh& m, VertId a, VertId b, VertId c, std::vector<TetId>& scratch);

}  // namespace cm::generate
