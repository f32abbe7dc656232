#pragma once
// Protecting a mesh's classified triangles from the operators.
#include "curvemesh/modify/mesh_editor.hpp"

namespace cm::modify {

/// Marks every tet face that is one of the mesh's classified triangles
/// (m.tris) or lies on the hull, so no operator removes it. Returns the
/// number of triangles not found as tet faces (0 for a valid mesh). O(T).
std::size_t mark_boundary_faces(MeshEditor& ed);

}  // namespace cm::modify
