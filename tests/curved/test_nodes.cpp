// Node placement (curved/nodes.hpp) on meshes of curved built-in shapes:
// every node of a boundary entity on its model entity, edge nodes at equal
// arc length, no nodes on interior entities, and the high-order storage's
// erase / remap operations the repair relies on.
#include <cmath>
#include <numbers>
#include <set>

#include <gtest/gtest.h>

#include "curved_support.hpp"
#include "curvemesh/mesh/topology.hpp"

namespace cm::test {
namespace {

class NodesOnShapes : public ::testing::TestWithParam<std::tuple<std::string, int>> {};

TEST_P(NodesOnShapes, EveryBoundaryNodeIsOnItsEntityAndInteriorEntitiesHaveNone) {
  const auto& [spec, order] = GetParam();
  Meshed r = mesh_for_curving(spec, 0.3);
  const curved::PlacementStats st = curved::place_boundary_nodes(r.m, *r.model, order);
  const auto& m = r.m;
  const auto boundary = boundary_edges(m);
  EXPECT_EQ(m.high_order.num_edges(), boundary.size());
  EXPECT_EQ(st.edges_on_model_edges + st.edges_on_model_faces, boundary.size());
  EXPECT_EQ(st.edges_on_model_edges, m.edges.size());
  EXPECT_EQ(m.high_order.num_faces(), order == 3 ? m.tris.size() : 0u);
  const double scale = r.model->bounding_box().diagonal();
  std::set<std::pair<VertId, VertId>> on_model_edge;
  for (const auto& e : m.edges) {
    on_model_edge.insert({std::min(e.verts[0], e.verts[1]), std::max(e.verts[0], e.verts[1])});
    std::array<Vec3, 2> nodes;
    ASSERT_TRUE(m.high_order.get_edge(e.verts[0], e.verts[1], nodes.data()));
    for (int s = 0; s < order - 1; ++s)
      EXPECT_LT(r.model->closest_point({1, e.edge_tag}, nodes[s]).distance, 1e-9 * scale);
  }
  for (const auto& t : m.tris) {
    for (const auto& e : mesh::kTriEdges) {
      const VertId a = t.verts[e[0]], b = t.verts[e[1]];
      if (on_model_edge.count({std::min(a, b), std::max(a, b)})) continue;
      std::array<Vec3, 2> nodes;
      ASSERT_TRUE(m.high_order.get_edge(a, b, nodes.data()));
      for (int s = 0; s < order - 1; ++s)
        EXPECT_LT(r.model->closest_point({2, t.face_tag}, nodes[s]).distance, 1e-9 * scale);
    }
    if (order == 3) {
      Vec3 centre;
      ASSERT_TRUE(m.high_order.get_face(t.verts[0], t.verts[1], t.verts[2], &centre));
      EXPECT_LT(r.model->closest_point({2, t.face_tag}, centre).distance, 1e-9 * scale);
    }
  }
  // No tet edge off the boundary has nodes.
  for (const auto& tv : m.tet2verts)
    for (const auto& e : mesh::kTetEdges) {
      const VertId a = tv[e[0]], b = tv[e[1]];
      EXPECT_EQ(m.high_order.has_edge(a, b), boundary.count({std::min(a, b), std::max(a, b)}) == 1);
    }
}

INSTANTIATE_TEST_SUITE_P(Shapes, NodesOnShapes,
                         ::testing::Combine(::testing::Values("builtin:sphere", "builtin:cylinder", "builtin:torus",
                                                              "builtin:part"),
                                            ::testing::Values(2, 3)),
                         [](const auto& param_info) {
                           std::string s = std::get<0>(param_info.param).substr(8);
                           return s + "_P" + std::to_string(std::get<1>(param_info.param));
                         });

// On the cylinder's circular edges (radius 1 about the z axis) the nodes
// split each mesh edge's arc into equal angles.
TEST(Nodes, EdgeNodesSplitTheArcEvenly) {
  Meshed r = mesh_for_curving("builtin:cylinder", 0.5);
  curved::place_boundary_nodes(r.m, *r.model, 3);
  const auto& m = r.m;
  int checked = 0;
  for (const auto& e : m.edges) {
    if (r.model->type({1, e.edge_tag}) != geom::ShapeType::kCircle) continue;
    const Vec3 a = m.coords[e.verts[0]], b = m.coords[e.verts[1]];
    std::array<Vec3, 2> n;
    ASSERT_TRUE(m.high_order.get_edge(e.verts[0], e.verts[1], n.data()));
    auto angle = [](const Vec3& x, const Vec3& y) {
      return std::atan2(x.x() * y.y() - x.y() * y.x(), x.x() * y.x() + x.y() * y.y());
    };
    const double a0 = angle(a, n[0]), a1 = angle(n[0], n[1]), a2 = angle(n[1], b);
    EXPECT_NEAR(a0, a1, 1e-3 * std::abs(a0));
    EXPECT_NEAR(a1, a2, 1e-3 * std::abs(a0));
    ++checked;
  }
  EXPECT_GT(checked, 10);
}

TEST(HighOrderNodes, EraseAndRemapKeepTheOtherEntries) {
  mesh::HighOrderNodes h;
  h.reset(3);
  const std::array<Vec3, 2> e01{Vec3(1, 0, 0), Vec3(2, 0, 0)}, e23{Vec3(0, 1, 0), Vec3(0, 2, 0)};
  h.set_edge(0, 1, e01);
  h.set_edge(3, 2, e23);  // listed from 3
  const Vec3 f{5, 5, 5};
  h.set_face(4, 2, 0, std::span<const Vec3>(&f, 1));
  h.erase_edge(1, 0);
  EXPECT_FALSE(h.has_edge(0, 1));
  EXPECT_TRUE(h.has_edge(2, 3));
  EXPECT_EQ(h.num_edges(), 1u);
  // A slot freed by the erase is reused.
  h.set_edge(5, 6, e01);
  EXPECT_EQ(h.num_edges(), 2u);
  // 0 goes, the rest shift down by one and keep their order.
  const std::vector<VertId> old2new{kNone, 0, 1, 2, 3, 4, 5};
  h.remap_vertices(old2new);
  std::array<Vec3, 2> got;
  ASSERT_TRUE(h.get_edge(2, 1, got.data()));
  EXPECT_EQ(got[0], e23[0]);
  EXPECT_EQ(got[1], e23[1]);
  ASSERT_TRUE(h.get_edge(4, 5, got.data()));
  EXPECT_EQ(got[0], e01[0]);
  EXPECT_EQ(h.num_faces(), 0u);  // the face on vertex 0 is dropped
}

}  // namespace
}  // namespace cm::test
