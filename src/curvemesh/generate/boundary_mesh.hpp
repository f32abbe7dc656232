#pragma once
// The boundary mesh of a model: model vertices, edges discretized to the size
// field, faces meshed in their parameter planes, assembled into one surface
// mesh whose every vertex, edge and triangle is classified (seed paper 1,
// §2). Faces are meshed in parallel; the result does not depend on the
// number of threads.
#include <string>
#include <vector>

#include "curvemesh/geom/model.hpp"
#include "curvemesh/mesh/tet_mesh.hpp"
#include "curvemesh/size/size_field.hpp"
#include "curvemesh/generate/edge_mesh.hpp"
#include "curvemesh/generate/face_mesh.hpp"

namespace cm::generate {

struct BoundaryMeshOptions {
  EdgeMeshOptions edges;
  FaceMeshOptions faces;
};

struct BoundaryMeshStats {
  double edges_seconds = 0, faces_seconds = 0, assembly_seconds = 0;
  std::size_t edge_segments = 0;
  std::size_t cusp_tips = 0;  ///< vertices whose tip ball holds no other point (geom/cusps.hpp)
  int refinement_insertions = 0, flips = 0, smoothing_moves = 0;
};

/// Vertices (classified on model vertices, edges with u, faces with (u, v)),
/// `tris` (each oriented along the face's normal, i.e. out of its first
/// region) and `edges` of the result; no tets. `entities` lists every model
/// entity with its bounding entities. Throws cm::GeometryError naming the
/// face that could not be meshed.
mesh::TetMesh mesh_boundary(const geom::Model& model, const size::SizeField& size,
                            const BoundaryMeshOptions& options = {}, BoundaryMeshStats* stats = nullptr);

}  // namespace cm::generate
