#pragma once
// Self-intersections of a triangulated surface.
//
// A boundary mesh whose triangles cross each other is not a geometric
// triangulation (seed paper 1, §2): no tetrahedralization has both crossing
// triangles as faces, so boundary recovery would split them forever. Coarse
// sizes on thin features (two faces closer than the chord error of their
// triangles) produce exactly this, so the volume mesher looks for crossings
// first and refines them away on the model.
#include <array>
#include <span>
#include <vector>

#include "curvemesh/core/types.hpp"
#include "curvemesh/mesh/tet_mesh.hpp"

namespace cm::generate {

/// Pairs (i, j), i < j, of triangles of `tris` that cross: an edge of one
/// passes strictly through the other (exact orient3d). Triangles sharing an
/// edge are not compared (they can only fold, which the boundary check
/// catches); triangles sharing one vertex are compared on the edges opposite
/// to it. Touching without crossing (exact zeros) is not reported. Broad phase
/// by a uniform grid of the triangles' boxes: O(n) for a well-spread mesh.
/// Pairs of triangles of one face f with `planar[f] != 0` are not compared:
/// a planar face meshed without overlap in its parameter plane cannot cross
/// itself, and its coplanar pairs are the costly case of the exact test
/// (every orientation is an exact zero).
std::vector<std::array<std::uint32_t, 2>> crossing_triangles(std::span<const Vec3> coords,
                                                             std::span<const mesh::ClassifiedTri> tris,
                                                             std::span<const char> planar = {});

}  // namespace cm::generate
