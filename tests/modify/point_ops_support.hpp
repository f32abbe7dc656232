#pragma once
// Shared by the point-operator tests (split, collapse, model-aware
// relocation): meshes of real models from the project's own volume mesher,
// and a check of every invariant the operators promise, recomputed from
// scratch.
#include <gtest/gtest.h>

#include <map>
#include <memory>
#include <set>
#include <string>

#include "curvemesh/generate/boundary_check.hpp"
#include "curvemesh/generate/volume_mesh.hpp"
#include "curvemesh/geom_occ/load.hpp"
#include "curvemesh/mesh/adjacency.hpp"
#include "curvemesh/mesh/validate.hpp"
#include "curvemesh/modify/surface.hpp"
#include "curvemesh/size/build.hpp"
#include "invariants.hpp"

namespace cm::test {

struct MeshedModel {
  std::unique_ptr<geom::Model> model;
  size::SizeFieldResult size;
  mesh::TetMesh m;
};

/// `refine` false: the tets of the boundary points alone (many against the
/// hull with two or three faces there).
inline MeshedModel mesh_model(const std::string& spec, double hmax, bool refine = true) {
  MeshedModel r;
  r.model = geom_occ::load_model(spec);
  size::SizeOptions so;
  so.hmax = hmax;
  r.size = size::build_size_field(*r.model, so);
  generate::VolumeMeshOptions vo;
  vo.refine = refine;
  r.m = generate::mesh_volume(*r.model, *r.size.field, vo);
  return r;
}

/// Volume of the live tets, by region tag.
inline std::map<std::int32_t, double> region_volumes(const modify::MeshEditor& ed) {
  const auto& m = ed.mesh();
  std::map<std::int32_t, double> v;
  for (TetId t = 0; t < m.tet2verts.size(); ++t)
    if (!ed.is_dead(t)) v[m.tet_region[t]] += mesh::tet_volume(m, t);
  return v;
}

inline std::array<VertId, 3> sorted3(std::array<VertId, 3> k) {
  std::sort(k.begin(), k.end());
  return k;
}

/// A live tet holding both a and b, or kNone.
inline TetId tet_with_edge(const mesh::TetMesh& m, VertId a, VertId b) {
  if (m.vert2tet[a] == kNone) return kNone;
  std::vector<TetId> ball;
  mesh::collect_ball(m, a, ball);
  for (TetId t : ball)
    if (mesh::local_index(m, t, b) >= 0) return t;
  return kNone;
}

/// A live tet with face (a, b, c), or kNone.
inline TetId tet_with_face(const mesh::TetMesh& m, const std::array<VertId, 3>& f) {
  if (m.vert2tet[f[0]] == kNone) return kNone;
  std::vector<TetId> ball;
  mesh::collect_ball(m, f[0], ball);
  for (TetId t : ball)
    if (mesh::local_index(m, t, f[1]) >= 0 && mesh::local_index(m, t, f[2]) >= 0) return t;
  return kNone;
}

/// Same cyclic order (same orientation) of two triangles on the same vertices.
inline bool same_orientation(const std::array<VertId, 3>& x, const std::array<VertId, 3>& y) {
  for (int k = 0; k < 3; ++k)
    if (x[0] == y[k] && x[1] == y[(k + 1) % 3] && x[2] == y[(k + 2) % 3]) return true;
  return false;
}

/// What the mesh looked like before the operators ran, to compare with.
struct Reference {
  /// Per face tag, the region whose tets its triangles point out of.
  std::map<std::int32_t, std::int32_t> outward_region;
  /// Per region volume; compared only when `planar` (else the surface moves
  /// onto the model and volumes legitimately change).
  std::map<std::int32_t, double> volumes;
  bool planar = false;
};

struct BoundaryFaceSides {
  // Per sorted triangle: (tet, local face) of each tet holding it.
  std::map<std::array<VertId, 3>, std::vector<std::pair<TetId, int>>> sides;
};

inline BoundaryFaceSides tet_sides_of_tris(const modify::MeshEditor& ed) {
  const auto& m = ed.mesh();
  std::set<std::array<VertId, 3>> keys;
  for (const auto& tri : m.tris) keys.insert(sorted3(tri.verts));
  BoundaryFaceSides s;
  for (TetId t = 0; t < m.tet2verts.size(); ++t) {
    if (ed.is_dead(t)) continue;
    const auto& tv = m.tet2verts[t];
    for (int f = 0; f < 4; ++f) {
      const auto& fv = mesh::kFaceVerts[static_cast<std::size_t>(f)];
      const auto k = sorted3({tv[fv[0]], tv[fv[1]], tv[fv[2]]});
      if (keys.count(k)) s.sides[k].push_back({t, f});
    }
  }
  return s;
}

// The region a triangle points out of: the tet whose face has its order.
inline std::int32_t outward_region_of(const mesh::TetMesh& m, const mesh::ClassifiedTri& tri,
                                      const std::vector<std::pair<TetId, int>>& sides) {
  for (const auto& [t, f] : sides) {
    const auto& tv = m.tet2verts[t];
    const auto& fv = mesh::kFaceVerts[static_cast<std::size_t>(f)];
    if (same_orientation(tri.verts, {tv[fv[0]], tv[fv[1]], tv[fv[2]]})) return m.tet_region[t];
  }
  return -1;
}

inline Reference make_reference(const modify::MeshEditor& ed, bool planar) {
  const auto& m = ed.mesh();
  Reference r;
  r.planar = planar;
  r.volumes = region_volumes(ed);
  const auto sides = tet_sides_of_tris(ed);
  for (const auto& tri : m.tris) r.outward_region[tri.face_tag] = outward_region_of(m, tri, sides.sides.at(sorted3(tri.verts)));
  return r;
}

/// Every invariant, from scratch: positive tets, adjacency, vert2tet; the
/// mesh valid for mesh::validate(kFull) once compacted; each region's
/// boundary a closed oriented 2-manifold of classified triangles that point
/// out of the region they did; face marks exactly on triangles and hull
/// faces; m.tris and m.edges without duplicates and `index` right about
/// them; classification consistent (vertices on model edges have two edges
/// of it, vertices on faces only triangles of their face, region vertices
/// none); with a model, every boundary vertex on its entity at its own
/// parameters and no triangle folded against its face (check_boundary);
/// region volumes unchanged for planar models.
inline void expect_everything(const modify::MeshEditor& ed, const modify::BoundaryIndex& index, const Reference& ref,
                              const geom::Model* model, const size::SizeField* size) {
  const auto& m = ed.mesh();
  // Tets, adjacency, vert2tet.
  const auto volumes = region_volumes(ed);
  double total = 0;
  for (const auto& [reg, v] : volumes) total += v;
  expect_invariants(ed, total);
  std::vector<char> used(m.num_verts(), 0);
  for (TetId t = 0; t < m.tet2verts.size(); ++t)
    if (!ed.is_dead(t))
      for (VertId v : m.tet2verts[t]) used[v] = 1;
  for (VertId v = 0; v < m.num_verts(); ++v) {
    if (used[v]) {
      ASSERT_NE(m.vert2tet[v], kNone) << "vertex " << v << " is in tets but has no seed";
    } else {
      ASSERT_EQ(m.vert2tet[v], kNone) << "vertex " << v << " is in no tet but has a seed";
    }
  }
  // Regions and volumes.
  for (const auto& [reg, v] : volumes) {
    ASSERT_TRUE(ref.volumes.count(reg)) << "unknown region tag " << reg;
    if (ref.planar) {
      EXPECT_NEAR(v, ref.volumes.at(reg), 1e-9 * ref.volumes.at(reg)) << "region " << reg;
    }
  }
  EXPECT_EQ(volumes.size(), ref.volumes.size());

  // The classified triangles and edges, and the index over them.
  EXPECT_EQ(index.tri_count(), m.tris.size());
  EXPECT_EQ(index.edge_count(), m.edges.size());
  for (Index i = 0; i < m.tris.size(); ++i) {
    const auto& v = m.tris[i].verts;
    ASSERT_EQ(index.find_tri(v[0], v[1], v[2]), i) << "index wrong about triangle " << i;
  }
  for (Index i = 0; i < m.edges.size(); ++i) {
    const auto& v = m.edges[i].verts;
    ASSERT_EQ(index.find_edge(v[0], v[1]), i) << "index wrong about edge " << i;
    ASSERT_NE(tet_with_edge(m, v[0], v[1]), kNone) << "classified edge " << i << " is no mesh edge";
  }
  {
    auto copy = m;
    EXPECT_NO_THROW(modify::BoundaryIndex fresh(copy));  // no duplicates
  }

  // Each triangle on one tet (hull) or two; the region it points out of, as
  // before; each region's boundary closed and oriented.
  const auto sides = tet_sides_of_tris(ed);
  std::map<std::int32_t, std::map<std::pair<VertId, VertId>, int>> directed;  // region -> edge -> uses
  for (const auto& tri : m.tris) {
    const auto k = sorted3(tri.verts);
    ASSERT_TRUE(sides.sides.count(k)) << "triangle of face " << tri.face_tag << " is no tet face";
    const auto& s = sides.sides.at(k);
    ASSERT_LE(s.size(), 2u);
    EXPECT_EQ(outward_region_of(m, tri, s), ref.outward_region.at(tri.face_tag)) << "face " << tri.face_tag;
    for (const auto& [t, f] : s) {
      const auto& tv = m.tet2verts[t];
      const auto& fv = mesh::kFaceVerts[static_cast<std::size_t>(f)];
      const std::array<VertId, 3> out{tv[fv[0]], tv[fv[1]], tv[fv[2]]};
      for (int e = 0; e < 3; ++e) ++directed[m.tet_region[t]][{out[e], out[(e + 1) % 3]}];
    }
  }
  for (const auto& [reg, uses] : directed)
    for (const auto& [e, n] : uses) {
      ASSERT_EQ(n, 1) << "region " << reg << ": edge (" << e.first << ", " << e.second << ") used " << n << " times";
      ASSERT_TRUE(uses.count({e.second, e.first})) << "region " << reg << ": boundary not closed";
    }

  // Marks: exactly the triangles and the hull.
  for (TetId t = 0; t < m.tet2verts.size(); ++t) {
    if (ed.is_dead(t)) continue;
    const auto& tv = m.tet2verts[t];
    for (int f = 0; f < 4; ++f) {
      const auto& fv = mesh::kFaceVerts[static_cast<std::size_t>(f)];
      const bool boundary = m.tet2adj[mesh::pack_face(t, f)] == kNone ||
                            sides.sides.count(sorted3({tv[fv[0]], tv[fv[1]], tv[fv[2]]}));
      ASSERT_EQ(ed.face_marked(mesh::pack_face(t, f)), boundary) << "mark of tet " << t << " face " << f;
    }
  }

  // Classification of the vertices in use.
  std::vector<int> edge_uses(m.num_verts(), 0), tri_uses(m.num_verts(), 0);
  for (const auto& e : m.edges)
    for (VertId v : e.verts) {
      ++edge_uses[v];
      if (m.vert_class[v].dim == 1) {
        ASSERT_EQ(m.vert_class[v].tag, e.edge_tag) << "vertex " << v;
      }
      ASSERT_LE(m.vert_class[v].dim, 1) << "vertex " << v << " on a classified edge";
    }
  for (const auto& tri : m.tris)
    for (VertId v : tri.verts) {
      ++tri_uses[v];
      if (m.vert_class[v].dim == 2) {
        ASSERT_EQ(m.vert_class[v].tag, tri.face_tag) << "vertex " << v;
      }
      ASSERT_LE(m.vert_class[v].dim, 2) << "region vertex " << v << " on a triangle";
    }
  for (VertId v = 0; v < m.num_verts(); ++v) {
    if (!used[v]) continue;
    const auto c = m.vert_class[v];
    if (c.dim == 1) {
      EXPECT_EQ(edge_uses[v], 2) << "vertex " << v << " inside model edge " << c.tag;
    }
    if (c.dim == 2) {
      EXPECT_GE(tri_uses[v], 3) << "vertex " << v << " inside model face " << c.tag;
    }
    if (c.dim == 1 || c.dim == 2) {
      EXPECT_TRUE(m.vert_param[v].has_u() || !model) << "vertex " << v << " has no parameters";
    }
  }

  // The whole mesh through the project's validator and boundary check.
  auto copy = m;
  modify::MeshEditor compactor(copy);
  compactor.compact();
  const auto rep = mesh::validate(copy, mesh::Level::kFull);
  ASSERT_TRUE(rep.valid()) << rep.num_issues << " issues, first: " << (rep.issues.empty() ? "" : rep.issues.front().message);
  if (model && size) {
    const auto b = generate::check_boundary(*model, copy, *size);
    EXPECT_EQ(b.vertices_off_entity, 0u) << (b.problems.empty() ? "" : b.problems.front());
    EXPECT_EQ(b.folded_triangles, 0u) << (b.problems.empty() ? "" : b.problems.front());
    EXPECT_EQ(b.open_region_edges, 0u) << (b.problems.empty() ? "" : b.problems.front());
    EXPECT_EQ(b.unmeshed_faces, 0u);
  }
}

}  // namespace cm::test
