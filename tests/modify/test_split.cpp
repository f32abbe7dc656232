// Edge split on a classified box mesh, one edge of each kind (inside the
// region, on a model face, on a model edge), with exact counts; the split
// undone by collapsing the new vertex gives back the same tets, triangles and
// edges. Then splits placed on a curved model.
#include <gtest/gtest.h>

#include <set>

#include "curvemesh/mesh/structured.hpp"
#include "curvemesh/modify/collapse.hpp"
#include "curvemesh/modify/marks.hpp"
#include "curvemesh/modify/measure.hpp"
#include "curvemesh/modify/split.hpp"
#include "point_ops_support.hpp"

using namespace cm;
using namespace cm::modify;

namespace {

// An edge of a live tet whose classification has this dimension: on a model
// edge (1), on a model face (2), inside (3).
struct EdgeOf {
  VertId a = kNone, b = kNone;
  TetId tet = kNone;
  std::size_t shell = 0;
};

EdgeOf find_edge_of_kind(const mesh::TetMesh& m, const BoundaryIndex& surf, int dim) {
  for (TetId t = 0; t < m.num_tets(); ++t)
    for (const auto& e : mesh::kTetEdges) {
      const VertId a = m.tet2verts[t][static_cast<std::size_t>(e[0])], b = m.tet2verts[t][static_cast<std::size_t>(e[1])];
      const auto shell = mesh::collect_shell(m, a, b, t);
      bool on_tri = false;
      for (TetId s : shell.tets)
        for (VertId r : m.tet2verts[s])
          if (r != a && r != b) on_tri |= surf.find_tri(a, b, r) != kNone;
      const int kind = surf.find_edge(a, b) != kNone ? 1 : on_tri ? 2 : 3;
      if (kind == dim) return {a, b, t, shell.tets.size()};
    }
  return {};
}

std::multiset<std::array<VertId, 4>> tet_sets(const MeshEditor& ed) {
  const auto& m = ed.mesh();
  std::multiset<std::array<VertId, 4>> s;
  for (TetId t = 0; t < m.tet2verts.size(); ++t) {
    if (ed.is_dead(t)) continue;
    auto k = m.tet2verts[t];
    std::sort(k.begin(), k.end());
    s.insert(k);
  }
  return s;
}

// Triangles with their orientation (rotated to start at the smallest id).
std::set<std::pair<std::array<VertId, 3>, int>> tri_set(const mesh::TetMesh& m) {
  std::set<std::pair<std::array<VertId, 3>, int>> s;
  for (const auto& t : m.tris) {
    auto v = t.verts;
    std::rotate(v.begin(), std::min_element(v.begin(), v.end()), v.end());
    s.insert({v, t.face_tag});
  }
  return s;
}

std::set<std::tuple<VertId, VertId, int>> edge_set(const mesh::TetMesh& m) {
  std::set<std::tuple<VertId, VertId, int>> s;
  for (const auto& e : m.edges) s.insert({std::min(e.verts[0], e.verts[1]), std::max(e.verts[0], e.verts[1]), e.edge_tag});
  return s;
}

}  // namespace

TEST(Split, EachKindOfEdgeWithExactCountsAndUndoneByACollapse) {
  for (int dim : {3, 2, 1}) {
    SCOPED_TRACE(dim);
    auto m = mesh::make_box_mesh({2, 2, 2}, Vec3(0, 0, 0), Vec3(1, 1, 1), true);
    MeshEditor ed(m);
    ASSERT_EQ(mark_boundary_faces(ed), 0u);
    BoundaryIndex surf(m);
    const auto ref = cm::test::make_reference(ed, true);
    const auto tets0 = tet_sets(ed);
    const auto tris0 = tri_set(m);
    const auto edges0 = edge_set(m);
    const std::size_t verts0 = m.num_verts();
    const EdgeOf e = find_edge_of_kind(m, surf, dim);
    ASSERT_NE(e.a, kNone);
    Cavity cav;
    const auto plan = plan_split(ed, cav, surf, e.a, e.b, e.tet, nullptr);
    ASSERT_EQ(plan.refusal, Refusal::kNone);
    EXPECT_EQ(plan.classification.dim, dim);
    EXPECT_EQ(plan.on_hull, dim < 3);
    EXPECT_EQ(cav.tets().size(), e.shell);
    EXPECT_GT(plan.after, 0);
    std::vector<TetId> hooked;
    ed.set_hook([&](const mesh::TetMesh&, std::span<const TetId> c) { hooked.assign(c.begin(), c.end()); });
    const VertId p = apply(ed, cav, surf, plan);
    EXPECT_EQ(p, verts0);
    EXPECT_EQ(m.coords[p], 0.5 * (m.coords[e.a] + m.coords[e.b]));
    EXPECT_EQ(m.vert_class[p], plan.classification);
    EXPECT_FALSE(m.vert_param[p].has_u());  // no model: unknown
    EXPECT_EQ(hooked.size(), 2 * e.shell);
    EXPECT_DOUBLE_EQ(min_quality(m, hooked), plan.after);
    EXPECT_EQ(ed.live_tets(), tets0.size() + e.shell);
    // A face edge lies on two triangles of its face, a model edge on one of
    // each of its two faces.
    EXPECT_EQ(m.tris.size(), tris0.size() + (dim < 3 ? 2 : 0));
    EXPECT_EQ(m.edges.size(), edges0.size() + (dim == 1 ? 1 : 0));
    EXPECT_EQ(cm::test::tet_with_edge(m, e.a, e.b), kNone);
    cm::test::expect_everything(ed, surf, ref, nullptr, nullptr);

    // Collapsing p into a restores everything, orientation included.
    const auto back = plan_collapse(ed, cav, surf, p, e.a, nullptr);
    ASSERT_EQ(back.refusal, Refusal::kNone);
    apply(ed, cav, surf, back);
    EXPECT_EQ(tet_sets(ed), tets0);
    EXPECT_EQ(tri_set(m), tris0);
    EXPECT_EQ(edge_set(m), edges0);
    EXPECT_EQ(m.vert2tet[p], kNone);
    cm::test::expect_everything(ed, surf, ref, nullptr, nullptr);
  }
}

TEST(Split, MarkedFacesLeaveMarkedHalvesAndUnmarkedOnesDoNot) {
  auto m = mesh::make_box_mesh({2, 2, 2}, Vec3(0, 0, 0), Vec3(1, 1, 1), true);
  MeshEditor ed(m);
  BoundaryIndex surf(m);
  // Protect one inner face through an interior edge (as generation protects
  // faces it has recovered) and nothing else.
  const EdgeOf e = find_edge_of_kind(m, surf, 3);
  ASSERT_NE(e.a, kNone);
  const auto& tv = m.tet2verts[e.tet];
  int f = 0;
  while (tv[static_cast<std::size_t>(f)] == e.a || tv[static_cast<std::size_t>(f)] == e.b) ++f;
  ed.mark_face(mesh::pack_face(e.tet, f));  // the face through (a, b) opposite local vertex f
  VertId r = kNone;
  for (VertId v : tv)
    if (v != e.a && v != e.b && v != tv[static_cast<std::size_t>(f)]) r = v;
  Cavity cav;
  const auto plan = plan_split(ed, cav, surf, e.a, e.b, e.tet, nullptr);
  ASSERT_EQ(plan.refusal, Refusal::kNone);
  const VertId p = apply(ed, cav, surf, plan);
  int marked = 0;
  for (TetId t = 0; t < m.tet2verts.size(); ++t) {
    if (ed.is_dead(t)) continue;
    for (int g = 0; g < 4; ++g) {
      if (!ed.face_marked(mesh::pack_face(t, g))) continue;
      ++marked;
      std::set<VertId> face;
      for (const int k : mesh::kFaceVerts[static_cast<std::size_t>(g)]) face.insert(m.tet2verts[t][static_cast<std::size_t>(k)]);
      EXPECT_TRUE(face == std::set<VertId>({e.a, p, r}) || face == std::set<VertId>({p, e.b, r}));
    }
  }
  EXPECT_EQ(marked, 4);  // two halves, each marked on both sides
}

TEST(Split, OnACurvedModelTheNewVertexIsOnItsEntity) {
  auto r = cm::test::mesh_model("builtin:cylinder", 0.4);
  auto& m = r.m;
  MeshEditor ed(m);
  mark_boundary_faces(ed);
  BoundaryIndex surf(m);
  const auto ref = cm::test::make_reference(ed, false);
  Cavity cav;
  int on_edge = 0, on_face = 0;
  // Every edge of every boundary triangle once (as many as stay valid).
  const std::size_t tris = m.tris.size();
  for (std::size_t i = 0; i < tris; ++i)
    for (int k = 0; k < 3; ++k) {
      const VertId a = m.tris[i].verts[static_cast<std::size_t>(k)], b = m.tris[i].verts[static_cast<std::size_t>((k + 1) % 3)];
      const TetId t = cm::test::tet_with_edge(m, a, b);
      if (t == kNone) continue;  // split already
      const auto plan = plan_split(ed, cav, surf, a, b, t, r.model.get());
      if (plan.refusal != Refusal::kNone) continue;
      const VertId p = apply(ed, cav, surf, plan);
      const auto c = m.vert_class[p];
      ASSERT_LT(c.dim, 3);
      const Vec3 on = c.dim == 1 ? r.model->edge_point(c.tag, m.vert_param[p].u)
                                 : r.model->face_point(c.tag, Vec2(m.vert_param[p].u, m.vert_param[p].v));
      EXPECT_LT((on - m.coords[p]).norm(), 1e-9);
      ++(c.dim == 1 ? on_edge : on_face);
    }
  EXPECT_GT(on_edge, 20);
  EXPECT_GT(on_face, 200);
  cm::test::expect_everything(ed, surf, ref, r.model.get(), r.size.field.get());
}
