#pragma once
// Meshing one model face in its (u, v) parameter plane (seed paper 1, §2:
// the boundary triangulation the volume mesher starts from).
//
// Method, chosen for robustness on real CAD:
// 1. The boundary loops (discretized model edges through their p-curves)
//    are triangulated by a constrained Delaunay triangulation with exact
//    predicates, in (u, v) scaled per face by the mean first fundamental
//    form so that the plane is close to isometric to the surface.
// 2. Refinement by Delaunay point insertion: a triangle whose longest edge,
//    measured in 3D against the size field, exceeds √2 gets a point at its
//    circumcentre (centroid when that falls outside or next to an existing
//    point); the cavity never crosses the boundary.
// 3. Optimization with local operators judged on the 3D triangles: edge
//    flips and smoothing in (u, v), each accepted only if every triangle
//    keeps a positive (u, v) orientation (no parametric overlap) and the
//    worst 3D quality improves.
// Distorted parametrizations (poles, stretched B-splines) are handled by
// judging every decision on the 3D triangle rather than in (u, v).
#include <vector>

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
FaceMesh mesh_face(const geom::Model& model, int face, const std::vector<std::vector<BoundaryPoint>>& loops,
                   const size::SizeField& size, const FaceMeshOptions& options);

}  // namespace cm::generate
