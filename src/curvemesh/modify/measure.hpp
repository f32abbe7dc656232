#pragma once
// The quality an operator maximizes. Validity is decided exactly (orient3d);
// the measure only ranks valid configurations.
#include <array>
#include <span>

#include "curvemesh/mesh/tet_mesh.hpp"

namespace cm::modify {

/// Mean ratio of the tet with these vertices (1 = regular), or -1 when it is
/// not strictly positive by exact orient3d.
double tet_quality(const mesh::TetMesh& m, const std::array<VertId, 4>& v);

/// Smallest tet_quality over the given tets of the mesh.
double min_quality(const mesh::TetMesh& m, std::span<const TetId> tets);

/// min_quality when it is above `floor`; otherwise some value <= floor, found
/// at the first tet that shows it: for candidates that are dropped unless
/// they beat the floor.
double min_quality_above(const mesh::TetMesh& m, std::span<const TetId> tets, double floor);

}  // namespace cm::modify
