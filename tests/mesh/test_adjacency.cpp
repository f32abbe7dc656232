#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <set>

#include "curvemesh/mesh/adjacency.hpp"
#include "curvemesh/mesh/structured.hpp"

using namespace cm;
using namespace cm::mesh;

namespace {
std::vector<TetId> brute_ball(const TetMesh& m, VertId v) {
  std::vector<TetId> out;
  for (TetId t = 0; t < m.num_tets(); ++t)
    if (local_index(m, t, v) >= 0) out.push_back(t);
  return out;
}
}  // namespace

TEST(Adjacency, BoxHullFaceCountAndSymmetry) {
  TetMesh m = make_box_mesh({3, 4, 5}, Vec3(0, 0, 0), Vec3(1, 2, 3), false);
  ASSERT_EQ(m.num_tets(), 6u * 3 * 4 * 5);
  EXPECT_EQ(build_adjacency(m), 0u);
  std::size_t hull = 0;
  for (Index f = 0; f < m.tet2adj.size(); ++f) {
    if (m.tet2adj[f] == kNone) {
      ++hull;
      continue;
    }
    EXPECT_EQ(m.tet2adj[m.tet2adj[f]], f);
  }
  EXPECT_EQ(hull, 2u * 2 * (3 * 4 + 4 * 5 + 3 * 5));
  for (TetId t = 0; t < m.num_tets(); ++t) EXPECT_GT(tet_volume(m, t), 0.0);
}

TEST(Adjacency, BallMatchesBruteForce) {
  TetMesh m = make_box_mesh({4, 4, 4}, Vec3(0, 0, 0), Vec3(1, 1, 1), false);
  build_adjacency(m);
  std::vector<TetId> ball;
  for (VertId v = 0; v < m.num_verts(); ++v) {
    collect_ball(m, v, ball);
    std::sort(ball.begin(), ball.end());
    EXPECT_EQ(ball, brute_ball(m, v)) << "vertex " << v;
  }
  // An interior vertex of the Kuhn subdivision has 24 tets around it.
  const VertId center = 2 + 5 * (2 + 5 * 2);
  collect_ball(m, center, ball);
  EXPECT_EQ(ball.size(), 24u);
  std::vector<TetId> scratch;
  std::size_t count = 0;
  for (TetId t : BallRange(m, center, scratch)) count += local_index(m, t, center) >= 0;
  EXPECT_EQ(count, 24u);
}

TEST(Adjacency, ShellIsCyclicAndComplete) {
  TetMesh m = make_box_mesh({3, 3, 3}, Vec3(0, 0, 0), Vec3(1, 1, 1), false);
  build_adjacency(m);
  std::set<std::pair<VertId, VertId>> edges;
  for (const auto& tv : m.tet2verts)
    for (const auto& e : kTetEdges) edges.insert(std::minmax(tv[e[0]], tv[e[1]]));
  std::size_t closed = 0, open = 0;
  for (const auto& [a, b] : edges) {
    std::vector<TetId> expected;
    for (TetId t = 0; t < m.num_tets(); ++t)
      if (local_index(m, t, a) >= 0 && local_index(m, t, b) >= 0) expected.push_back(t);
    const Shell shell = collect_shell(m, a, b, expected[expected.size() / 2]);
    std::vector<TetId> got = shell.tets;
    std::sort(got.begin(), got.end());
    ASSERT_EQ(got, expected) << a << "-" << b;
    // Consecutive tets share a face that contains the edge.
    const std::size_t n = shell.tets.size();
    for (std::size_t i = 0; i + 1 < n + (shell.closed ? 1 : 0); ++i) {
      const TetId t = shell.tets[i], u = shell.tets[(i + 1) % n];
      bool adjacent = false;
      for (int f = 0; f < 4; ++f)
        if (m.tet2adj[pack_face(t, f)] != kNone && face_tet(m.tet2adj[pack_face(t, f)]) == u) adjacent = true;
      EXPECT_TRUE(adjacent);
    }
    (shell.closed ? closed : open)++;
  }
  EXPECT_GT(closed, 0u);
  EXPECT_GT(open, 0u);
}

TEST(Adjacency, NonManifoldFacesAreCounted) {
  TetMesh m = make_box_mesh({1, 1, 1}, Vec3(0, 0, 0), Vec3(1, 1, 1), false);
  m.add_tet(m.tet2verts[0], 1);  // the same tet twice: its 4 faces now have 3 users or 2
  const std::size_t bad = build_adjacency(m);
  EXPECT_GT(bad, 0u);
}
