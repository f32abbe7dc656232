#pragma once
// Meshing one model face in its (u, v) parameter plane (seed paper 1, §2:
// the boundary triangulation the volume mesher starts from).
//
// Method, chosen for robustness on real CAD:
// 1. The boundary loops (discretized model edges through their p-curves)
//    are triangulated by a constrained Delaunay triangulation with exact
//    predicates, in (u, v) scaled per face by the mean first fundamental
//    form, then flipped towards the Delaunay triangulation of the surface's
//    own metric (the first fundamental form), which matters where (u, v) is
//    far from isometric: at poles and in narrow wedges.
// 2. Frontal-Delaunay refinement (Rebay; Gmsh's default surface algorithm):
//    the largest triangle on the front (the boundary, or triangles whose 3D
//    circumradius is already under 1/√2 sizes) gets a point facing its front
//    edge at the height of an equilateral triangle of the local size,
//    measured in the first fundamental form; the point goes in by a
//    Bowyer–Watson cavity grown with that metric's in-circle test and checked
//    exactly, never across the boundary. What the front leaves (narrow
//    places) gets circumcentres until no edge is over √2 sizes.
// 3. Optimization judged on the 3D triangles: edge flips for the worst
//    quality, and smoothing of each vertex towards the equilateral apexes of
//    its ball's edges (built in 3D, taken back through the tangent map),
//    kept when the ball's worst triangle does not get worse and its sum
//    grows. Every accepted change keeps all triangles positive in (u, v) (no
//    parametric overlap) and their normals along the surface's; triangles
//    that fold at their centroid are flipped or split at the end. The same
//    passes are also run after flips towards interior valence 6, and that
//    more regular result is kept when its worst triangle is no worse and its
//    mean is higher.
// Points of a pole (several (u, v) points, one vertex) bound triangles that
// vanish from the surface mesh; they count as neither good nor bad.
#include <vector>

#include "curvemesh/geom/cusps.hpp"
#include "curvemesh/geom/model.hpp"
#include "curvemesh/size/size_field.hpp"

namespace cm::generate {

/// A point of a face's boundary: its (u, v) on this face and the id of the
/// mesh vertex it is (shared with the edge discretization; several (u, v)
/// points may be the same vertex: both sides of a seam, a pole).
struct BoundaryPoint {
  Vec2 uv;
  Vec3 xyz;
  std::uint32_t vertex = 0;
};

struct FaceMeshOptions {
  double max_edge = 1.4142135623730951;  ///< split edges longer than this (in units of the size)
  int optimize_passes = 4;
  std::size_t max_points = 20'000'000;   ///< guard against a runaway size field
};

struct FaceMesh {
  /// Local points: first the boundary points in the order given (loops
  /// concatenated), then the interior points.
  std::vector<Vec2> uv;
  std::vector<Vec3> xyz;
  std::size_t num_boundary = 0;
  std::vector<std::array<int, 3>> tris;  ///< counter-clockwise in (u, v)
  int refinement_insertions = 0;
  int flips = 0, smoothing_moves = 0;
};

/// Throws cm::GeometryError naming the face when its boundary cannot be
/// triangulated in (u, v) (self-intersecting p-curves, coincident points).
/// No interior point goes inside the balls of `tips` (those at the face's
/// vertices; see geom/cusps.hpp), except to unfold a triangle; nor inside
/// the balls of `keep_out`, which get none of a tip's fan (a wedge span's
/// strip).
FaceMesh mesh_face(const geom::Model& model, int face, const std::vector<std::vector<BoundaryPoint>>& loops,
                   const size::SizeField& size, const FaceMeshOptions& options,
                   const std::vector<geom::CuspTip>& tips = {}, const std::vector<geom::CuspTip>& keep_out = {});

}  // namespace cm::generate
