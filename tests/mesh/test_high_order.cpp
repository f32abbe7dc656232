#include <gtest/gtest.h>

#include <random>

#include "curvemesh/mesh/adjacency.hpp"
#include "curvemesh/mesh/high_order.hpp"
#include "curvemesh/mesh/structured.hpp"

using namespace cm;
using namespace cm::mesh;

TEST(HighOrder, NodeCountsAndOrder) {
  EXPECT_EQ(tet_node_indices(1).size(), 4u);
  EXPECT_EQ(tet_node_indices(2).size(), 10u);
  EXPECT_EQ(tet_node_indices(3).size(), 20u);
  EXPECT_EQ(tri_node_indices(2).size(), 6u);
  EXPECT_EQ(tri_node_indices(3).size(), 10u);
  const auto p2 = tet_node_indices(2);
  for (int e = 0; e < 6; ++e) {
    EXPECT_EQ(p2[4 + e][kTetEdges[e][0]], 1);
    EXPECT_EQ(p2[4 + e][kTetEdges[e][1]], 1);
  }
  const auto p3 = tet_node_indices(3);
  // Edge 0 of a P3 tet: first node nearer vertex 0, then nearer vertex 1.
  EXPECT_EQ(p3[4], (std::array<int, 4>{2, 1, 0, 0}));
  EXPECT_EQ(p3[5], (std::array<int, 4>{1, 2, 0, 0}));
  // Face 0 (opposite vertex 0) center node.
  EXPECT_EQ(p3[16], (std::array<int, 4>{0, 1, 1, 1}));
  for (const auto& idx : p3) EXPECT_EQ(idx[0] + idx[1] + idx[2] + idx[3], 3);
}

TEST(HighOrder, EdgeNodesAreStoredOncePerEdgeAndReversible) {
  HighOrderNodes h;
  h.reset(3);
  const Vec3 n[2] = {Vec3(1, 0, 0), Vec3(2, 0, 0)};
  h.set_edge(7, 3, n);
  Vec3 out[2];
  ASSERT_TRUE(h.get_edge(3, 7, out));
  EXPECT_EQ(out[0], n[1]);
  EXPECT_EQ(out[1], n[0]);
  ASSERT_TRUE(h.get_edge(7, 3, out));
  EXPECT_EQ(out[0], n[0]);
  EXPECT_FALSE(h.get_edge(3, 8, out));
  EXPECT_EQ(h.num_edges(), 1u);
  EXPECT_THROW(h.reset(5), std::invalid_argument);
}

TEST(HighOrder, JournalListsEveryEntitySetOrErasedAndIsNotCopied) {
  HighOrderNodes h;
  h.reset(3);
  const Vec3 e[2] = {Vec3(1, 0, 0), Vec3(2, 0, 0)};
  const Vec3 f[1] = {Vec3(0, 1, 0)};
  h.set_edge(4, 9, e);  // before the journal: not listed
  std::vector<std::array<VertId, 3>> journal;
  h.set_journal(&journal);
  h.set_edge(7, 3, e);
  h.set_face(5, 2, 8, f);
  h.erase_edge(9, 4);
  h.erase_face(8, 5, 2);
  h.erase_edge(1, 2);  // nothing stored: listed all the same
  const HighOrderNodes copy = h;
  HighOrderNodes assigned;
  assigned = h;
  HighOrderNodes(copy).set_edge(0, 1, e);
  assigned.set_edge(0, 1, e);
  h.set_journal(nullptr);
  h.set_edge(0, 1, e);
  const std::vector<std::array<VertId, 3>> expected{
      {3, 7, kNone}, {2, 5, 8}, {4, 9, kNone}, {2, 5, 8}, {1, 2, kNone}};
  EXPECT_EQ(journal, expected);
}

TEST(HighOrder, ScatterGatherRoundTripSharesNodesBetweenTets) {
  for (int p : {2, 3}) {
    TetMesh m = make_box_mesh({2, 2, 2}, Vec3(0, 0, 0), Vec3(1, 1, 1), false);
    build_adjacency(m);
    m.high_order.reset(p);
    // Curve every node by a smooth map; shared nodes get the same position
    // from whichever tet stores them.
    auto warp = [](const Vec3& x) { return Vec3(x.x() + 0.05 * std::sin(3 * x.y()), x.y(), x.z() + 0.03 * x.x() * x.y()); };
    for (TetId t = 0; t < m.num_tets(); ++t) {
      std::vector<Vec3> straight(gather_tet_nodes(m, t).size());
      for (int c = 0; c < 4; ++c) straight[c] = m.coords[m.tet2verts[t][c]];
      const auto idx = tet_node_indices(p);
      for (std::size_t k = 4; k < idx.size(); ++k) {
        Vec3 x = Vec3::Zero();
        for (int c = 0; c < 4; ++c) x += (double(idx[k][c]) / p) * m.coords[m.tet2verts[t][c]];
        straight[k] = warp(x);
      }
      scatter_tet_nodes(m, t, straight);
    }
    EXPECT_EQ(m.high_order.num_faces() > 0, p == 3);
    const auto idx = tet_node_indices(p);
    for (TetId t = 0; t < m.num_tets(); ++t) {
      const auto nodes = gather_tet_nodes(m, t);
      for (std::size_t k = 4; k < idx.size(); ++k) {
        Vec3 x = Vec3::Zero();
        for (int c = 0; c < 4; ++c) x += (double(idx[k][c]) / p) * m.coords[m.tet2verts[t][c]];
        EXPECT_NEAR((nodes[k] - warp(x)).norm(), 0.0, 1e-15) << "p=" << p << " tet " << t << " node " << k;
      }
    }
    // Triangles see the same nodes as the tets they bound.
    const auto& tv = m.tet2verts[0];
    const auto tri_nodes = gather_tri_nodes(m, {tv[1], tv[2], tv[3]});
    const auto tidx = tri_node_indices(p);
    for (std::size_t k = 0; k < tidx.size(); ++k) {
      Vec3 x = (double(tidx[k][0]) / p) * m.coords[tv[1]] + (double(tidx[k][1]) / p) * m.coords[tv[2]] +
               (double(tidx[k][2]) / p) * m.coords[tv[3]];
      EXPECT_NEAR((tri_nodes[k] - (k < 3 ? x : warp(x))).norm(), 0.0, 1e-15);
    }
  }
}
