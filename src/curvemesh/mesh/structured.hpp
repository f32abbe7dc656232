#pragma once
// Structured tet meshes of a box, for tests, benchmarks and examples.
#include "curvemesh/mesh/tet_mesh.hpp"

namespace cm::mesh {

/// n[0] x n[1] x n[2] cells over [lo, hi], each cut into 6 tets around its
/// main diagonal (Kuhn subdivision, conforming across cells). All tets
/// positive, region tag 1. With `classify`, the six box sides become model
/// faces 1..6 (-x, +x, -y, +y, -z, +z), the 12 box edges and 8 corners model
/// edges and vertices, and adjacency is built; otherwise only coords, tets
/// and regions are filled. 6·n0·n1·n2 tets.
TetMesh make_box_mesh(const std::array<int, 3>& n, const Vec3& lo, const Vec3& hi, bool classify);

}  // namespace cm::mesh
