#pragma once
// Where the high-order nodes of boundary entities go (seed paper 1, §3): mesh
// edges and triangles classified on a curved model edge or face are curved
// to it; interior entities stay straight (no nodes stored).
//
// - An edge on a model edge: nodes at equal arc-length fractions of the
//   model edge between its two vertices' parameters (a periodic edge taken
//   the short way round). Equal parameter fractions bunch the nodes where a
//   B-spline's parametrization is uneven, and bunched nodes make det J vary.
//   A vertex without a parameter falls back to projection.
// - An edge on a model face: the straight-sided nodes projected on the face,
//   the projection hinted by the (u, v) interpolated between the vertices'
//   (brought to one side of a seam first).
// - A triangle on a model face (order 3: one interior node): the point the
//   curved edges interpolate at the centroid, projected on the face.
//
// The invariant curving keeps while it edits a mesh: m.high_order holds the
// nodes of exactly the boundary edges and triangles of the mesh (straight
// ones too, with their straight nodes), so "has nodes" tells "is on the
// boundary" and mesh::gather_tet_nodes gives any tet's nodes, existing or
// would-be.
#include <array>
#include <span>
#include <vector>

#include "curvemesh/geom/model.hpp"
#include "curvemesh/mesh/tet_mesh.hpp"

namespace cm::curved {

/// Places nodes on mesh entities of m for `model` at the order of
/// m.high_order (2 or 3). Reads vertex coordinates, classification and
/// parameters; thread-safe for concurrent calls (const queries only).
class NodePlacer {
 public:
  NodePlacer(const mesh::TetMesh& m, const geom::Model& model) : m_(m), model_(model) {}

  int order() const { return m_.high_order.order(); }

  /// The p-1 nodes of edge (a, b) listed from a, on model entity `on`
  /// (dim 1: a model edge, dim 2: a model face). Writes order() - 1 points.
  void edge_nodes(VertId a, VertId b, mesh::ModelRef on, Vec3* out) const;

  /// The interior node(s) of triangle (a, b, c) on model face `face`
  /// (order 3: one), given the nodes of its edges listed from a to b, b to
  /// c and c to a. Writes (p-1)(p-2)/2 points.
  void face_nodes(VertId a, VertId b, VertId c, int face, const Vec3* ab, const Vec3* bc, const Vec3* ca,
                  Vec3* out) const;

 private:
  // (u, v) of v on `face` as a projection hint, on the same side of a seam
  // as `near` when given.
  std::optional<Vec2> face_hint(VertId v, int face) const;
  Vec3 project_on_face(int face, const Vec3& x, std::optional<Vec2> hint) const;

  const mesh::TetMesh& m_;
  const geom::Model& model_;
};

/// Counts of what place_boundary_nodes did.
struct PlacementStats {
  std::size_t edges_on_model_edges = 0, edges_on_model_faces = 0, faces = 0;
};

/// Sets m.high_order to `order` (2 or 3; throws std::invalid_argument
/// otherwise) and places the nodes of every boundary entity: the edges of
/// m.edges on their model edges, the other edges of m.tris on their model
/// faces, and for order 3 every triangle of m.tris. Interior entities get
/// none (straight). Vertex classification and parameters must be those of a
/// mesh from curvemesh mesh or read from MSH 4.1 with its model's tags.
/// Parallel over entities; the result does not depend on the thread count.
PlacementStats place_boundary_nodes(mesh::TetMesh& m, const geom::Model& model, int order);

}  // namespace cm::curved
