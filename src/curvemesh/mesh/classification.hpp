#pragma once
// Classification of a mesh read without a geometric model.
#include "curvemesh/mesh/tet_mesh.hpp"

namespace cm::mesh {

/// Derives a complete classification from the mesh itself (a discrete model):
/// - boundary faces are the hull faces and the faces between tets of
///   different regions; those missing from m.tris are added, tagged by the
///   pair of regions they separate (new tags above the largest existing one);
/// - mesh edges where triangles of different face tags meet (or where the
///   surface is not a 2-manifold) become model-edge edges, grouped into model
///   edges by connected chains with the same set of adjacent faces, unless
///   m.edges already classifies them;
/// - vertices are classified on the lowest-dimensional entity they lie on:
///   a model vertex where feature chains end or meet, else a model edge, a
///   model face, or the region of their tets;
/// - m.entities is rebuilt with the bounding relations.
/// Existing classification of vertices is kept where it is valid. Requires
/// adjacency (build_adjacency). Deterministic.
void derive_classification(TetMesh& m);

/// True if every vertex is classified (dim >= 0).
bool is_fully_classified(const TetMesh& m);

}  // namespace cm::mesh
