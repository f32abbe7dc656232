#pragma once
// The tetrahedral mesh: compact arrays, classification, high-order nodes.
#include <array>
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include "curvemesh/core/types.hpp"
#include "curvemesh/mesh/high_order.hpp"
#include "curvemesh/mesh/topology.hpp"

namespace cm::mesh {

/// Reference to a model entity: dimension 0..3 and its integer tag.
/// dim == -1 means "not classified".
struct ModelRef {
  std::int32_t dim = -1;
  std::int32_t tag = 0;
  bool valid() const { return dim >= 0; }
  friend bool operator==(const ModelRef&, const ModelRef&) = default;
  friend auto operator<=>(const ModelRef&, const ModelRef&) = default;
};

/// Parametric coordinates of a vertex on its classification entity: u on a
/// model edge, (u, v) on a model face. NaN when unknown (e.g. read from a file
/// that has none).
struct Param {
  double u = std::nan("");
  double v = std::nan("");
  bool has_u() const { return !std::isnan(u); }
};

/// A mesh triangle classified on a model face. Oriented: for a face on the
/// outer boundary the normal points out of the tet that owns it.
struct ClassifiedTri {
  std::array<VertId, 3> verts;
  std::int32_t face_tag;
};

/// A mesh edge classified on a model edge (verts in any order).
struct ClassifiedEdge {
  std::array<VertId, 2> verts;
  std::int32_t edge_tag;
};

/// A model entity as known to the mesh (for $Entities in MSH 4.1 and for the
/// discrete model): its bounding entities of dimension dim-1 (signed tags for
/// orientation, as MSH 4.1 writes them) and physical groups.
struct EntityInfo {
  std::int32_t dim = 0;
  std::int32_t tag = 0;
  std::vector<std::int32_t> bounding;
  std::vector<std::int32_t> physicals;
  std::string name;
};

/// A tetrahedral mesh in structure-of-arrays form.
///
/// Contract:
/// - `coords`: #V points. `tet2verts`: #T tets, each positively oriented
///   (see topology.hpp). `tet_region`: #T model region tags.
/// - `tet2adj`: 4*#T entries; entry 4*t+f is the packed opposite face 4*t'+f'
///   of the tet across face f of t, or kNone on the hull. Built by
///   build_adjacency(); stale after any edit of `tet2verts` until rebuilt.
/// - `vert2tet`: one incident tet per vertex (kNone for a vertex in no tet).
/// - `vert_class`/`vert_param`: #V entries (classification and parameters).
/// - `tris`/`edges`: boundary (and interface) triangles classified on model
///   faces, and edges classified on model edges. Interior edges and faces are
///   implicitly classified on the region of their tets.
/// - `high_order`: nodes of order p >= 2, keyed by edge / face vertex sets.
struct TetMesh {
  std::vector<Vec3> coords;
  std::vector<std::array<VertId, 4>> tet2verts;
  std::vector<std::int32_t> tet_region;
  std::vector<Index> tet2adj;
  std::vector<TetId> vert2tet;

  std::vector<ModelRef> vert_class;
  std::vector<Param> vert_param;
  std::vector<ClassifiedTri> tris;
  std::vector<ClassifiedEdge> edges;
  std::vector<EntityInfo> entities;

  HighOrderNodes high_order;

  std::size_t num_verts() const { return coords.size(); }
  std::size_t num_tets() const { return tet2verts.size(); }

  /// Append a vertex (unclassified, no param); returns its id.
  VertId add_vert(const Vec3& x);
  /// Append a tet with region tag; does not touch adjacency.
  TetId add_tet(const std::array<VertId, 4>& v, std::int32_t region);

  /// Resize the per-vertex arrays to #V (new entries unclassified).
  void resize_vertex_arrays();
  /// Bytes held by the arrays (capacity), for benchmarks.
  std::size_t memory_bytes() const;
};

/// Removes the vertices no tet uses (those collapses and element deletions
/// leave), renumbering the rest in order: tets, boundary triangles and
/// edges, the per-vertex arrays (vert2tet included, kept valid) and the
/// high-order nodes follow. Precondition: no dead tets (an editor's
/// compact() first). Returns old id -> new id (kNone for a removed vertex),
/// empty when none was removed. O(V + T).
std::vector<VertId> drop_unused_vertices(TetMesh& m);

/// Packed face handle helpers for tet2adj.
inline Index pack_face(TetId t, int f) { return 4 * t + static_cast<Index>(f); }
inline TetId face_tet(Index packed) { return packed >> 2; }
inline int face_index(Index packed) { return static_cast<int>(packed & 3u); }

/// Signed volume of tet t (straight-sided), plain floating point.
double tet_volume(const TetMesh& m, TetId t);

}  // namespace cm::mesh
