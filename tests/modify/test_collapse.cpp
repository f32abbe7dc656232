// Edge collapse: the classification rules refuse exactly what they should
// (model vertices, leaving a model edge or face, crossing the volume), a
// refusal changes nothing, and every vertex of a generated box mesh that may
// go is collapsed somewhere, keeping every invariant and the volume.
#include <gtest/gtest.h>

#include "curvemesh/mesh/structured.hpp"
#include "curvemesh/modify/collapse.hpp"
#include "curvemesh/modify/marks.hpp"
#include "curvemesh/modify/split.hpp"
#include "point_ops_support.hpp"

using namespace cm;
using namespace cm::modify;

namespace {

std::vector<VertId> neighbours(const mesh::TetMesh& m, VertId v) {
  std::vector<TetId> ball;
  mesh::collect_ball(m, v, ball);
  std::vector<VertId> out;
  for (TetId t : ball)
    for (VertId w : m.tet2verts[t])
      if (w != v && std::find(out.begin(), out.end(), w) == out.end()) out.push_back(w);
  return out;
}

}  // namespace

TEST(Collapse, ClassificationRulesOnABoxMesh) {
  auto m = mesh::make_box_mesh({2, 2, 2}, Vec3(0, 0, 0), Vec3(1, 1, 1), true);
  MeshEditor ed(m);
  mark_boundary_faces(ed);
  BoundaryIndex surf(m);
  Cavity cav;
  const auto before = m.tet2verts;
  const auto tris = m.tris.size();
  int refused = 0, allowed = 0;
  for (VertId a = 0; a < m.num_verts(); ++a)
    for (VertId b : neighbours(m, a)) {
      const auto plan = plan_collapse(ed, cav, surf, a, b, nullptr);
      // The rules, restated from the triangles and edges themselves.
      const auto ca = m.vert_class[a];
      bool may = ca.dim == 3;
      if (ca.dim == 1) {
        const Index e = surf.find_edge(a, b);
        may = e != kNone && m.edges[e].edge_tag == ca.tag;
      }
      if (ca.dim == 2)
        for (const auto& tri : m.tris) {
          const auto& v = tri.verts;
          may |= tri.face_tag == ca.tag && std::count(v.begin(), v.end(), a) && std::count(v.begin(), v.end(), b);
        }
      if (may) {
        EXPECT_NE(plan.refusal, Refusal::kClassification) << a << " -> " << b;
        ++allowed;
      } else {
        EXPECT_EQ(plan.refusal, Refusal::kClassification) << a << " -> " << b;
        ++refused;
      }
    }
  EXPECT_GT(refused, 100);
  EXPECT_GT(allowed, 50);
  EXPECT_EQ(m.tet2verts, before);  // plans change nothing
  EXPECT_EQ(m.tris.size(), tris);
}

TEST(Collapse, AFaceVertexGoesOnlyAlongItsFace) {
  // A face vertex made by splitting a face edge, and one made by splitting
  // an interior edge: the first may collapse onto the ends of its edge, not
  // onto the interior vertices it now sees; the second anywhere.
  auto m = mesh::make_box_mesh({2, 2, 2}, Vec3(0, 0, 0), Vec3(1, 1, 1), true);
  MeshEditor ed(m);
  mark_boundary_faces(ed);
  BoundaryIndex surf(m);
  Cavity cav;
  for (TetId t = 0; t < m.num_tets(); ++t) {
    const VertId a = m.tet2verts[t][0], b = m.tet2verts[t][1];
    const auto plan = plan_split(ed, cav, surf, a, b, t, nullptr);
    if (plan.refusal != Refusal::kNone || plan.classification.dim != 2) continue;
    const VertId p = apply(ed, cav, surf, plan);
    for (VertId w : neighbours(m, p)) {
      const auto c = plan_collapse(ed, cav, surf, p, w, nullptr);
      if (m.vert_class[w].dim == 3) {
        EXPECT_EQ(c.refusal, Refusal::kClassification);
      }
      if (w == a || w == b) {
        EXPECT_EQ(c.refusal, Refusal::kNone);
      }
    }
    return;
  }
  FAIL() << "no face edge found";
}

TEST(Collapse, AGeneratedBoxCollapsesDownToItsCorners) {
  // Collapse each vertex of a generated box that is not a model vertex onto
  // the first neighbour that accepts it, pass after pass: on a box every one
  // can go, down to the eight corners in five or six tets, keeping the
  // volume and every invariant on the way.
  for (double h : {0.3, 0.15}) {
    SCOPED_TRACE(h);
    auto r = cm::test::mesh_model("builtin:box", h);
    auto& m = r.m;
    MeshEditor ed(m);
    mark_boundary_faces(ed);
    BoundaryIndex surf(m);
    const auto ref = cm::test::make_reference(ed, true);
    Cavity cav;
    std::size_t removable = 0, removed = 0;
    for (VertId a = 0; a < m.num_verts(); ++a) removable += m.vert_class[a].dim > 0;
    for (int pass = 0; pass < 10 && removed < removable; ++pass) {
      for (VertId a = 0; a < m.num_verts(); ++a) {
        if (m.vert2tet[a] == kNone || m.vert_class[a].dim == 0) continue;
        for (VertId b : neighbours(m, a)) {
          const auto plan = plan_collapse(ed, cav, surf, a, b, r.model.get());
          if (plan.refusal != Refusal::kNone) continue;
          apply(ed, cav, surf, plan);
          ++removed;
          break;
        }
      }
      cm::test::expect_everything(ed, surf, ref, r.model.get(), r.size.field.get());
    }
    EXPECT_EQ(removed, removable);
    EXPECT_LE(ed.live_tets(), 6u);
    EXPECT_EQ(m.tris.size(), 12u);
    EXPECT_EQ(m.edges.size(), 12u);
  }
}
