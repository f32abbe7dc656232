// The cavity kernel under long random sequences of the cavity shapes every
// operator uses — edge split (shell, star from a new point), relocation (ball,
// star from the moved vertex), collapse (ball of the removed vertex, star from
// the kept one) — checking after each batch that adjacency, vert2tet, the
// orientation of every tet and the total volume are exactly right.
#include <gtest/gtest.h>

#include <map>
#include <random>
#include <set>

#include "curvemesh/core/predicates.hpp"
#include "curvemesh/mesh/adjacency.hpp"
#include "curvemesh/mesh/structured.hpp"
#include "curvemesh/mesh/topology.hpp"
#include "curvemesh/modify/cavity.hpp"
#include "invariants.hpp"

using namespace cm;
using namespace cm::modify;
using cm::test::expect_invariants;

namespace {

// Ball of v by the adjacency walk (dead tets are unreachable from live ones).
void ball(const MeshEditor& ed, VertId v, std::vector<TetId>& out) { mesh::collect_ball(ed.mesh(), v, out); }

}  // namespace

TEST(Cavity, RandomSplitsRelocationsAndCollapsesKeepEveryInvariant) {
  auto m = mesh::make_box_mesh({4, 4, 4}, Vec3(0, 0, 0), Vec3(1, 1, 1), true);
  const double volume = 1.0;
  MeshEditor ed(m);
  Cavity cav;
  std::vector<TetId> tets;
  std::mt19937 rng(7);
  int splits = 0, moves = 0, collapses = 0, refused = 0, hook_calls = 0;
  ed.set_hook([&](const mesh::TetMesh&, std::span<const TetId> created) {
    ++hook_calls;
    EXPECT_FALSE(created.empty());
  });
  for (int step = 0; step < 3000; ++step) {
    // A random live tet and one of its edges.
    TetId t;
    do t = static_cast<TetId>(rng() % m.tet2verts.size());
    while (ed.is_dead(t));
    const auto& e = mesh::kTetEdges[rng() % 6];
    const VertId a = m.tet2verts[t][e[0]], b = m.tet2verts[t][e[1]];
    const int kind = static_cast<int>(rng() % 3);
    if (kind == 0) {  // split (a, b) at a random point of the edge
      // Interior edges only: a hull edge's split also splits hull faces,
      // which a star cannot express.
      const auto shell = mesh::collect_shell(m, a, b, t);
      if (!shell.closed) continue;
      cav.reset(ed);
      for (TetId x : shell.tets) cav.add(ed, x);
      std::uniform_real_distribution<double> s(0.3, 0.7);
      const double w = s(rng);
      const VertId p = m.add_vert((1 - w) * m.coords[a] + w * m.coords[b]);
      m.resize_vertex_arrays();
      m.vert_class[p] = {3, 1};  // an interior edge's split point is interior
      cav.compute_boundary(ed);
      // Rounding puts p just off the segment: near-flat shell tets (made by
      // earlier collapses) can then refuse it.
      if (check_star(m, cav, p) != Refusal::kNone) {
        ++refused;
        continue;
      }
      fill_star(ed, cav, p);
      ++splits;
    } else if (kind == 1) {  // relocate an interior vertex a little
      if (m.vert_class[a].dim != 3) continue;
      ball(ed, a, tets);
      cav.reset(ed);
      for (TetId x : tets) cav.add(ed, x);
      cav.compute_boundary(ed);
      const Vec3 old = m.coords[a];
      std::normal_distribution<double> g(0, 0.02);
      m.coords[a] += Vec3(g(rng), g(rng), g(rng));
      if (check_star(m, cav, a) != Refusal::kNone) {
        m.coords[a] = old;
        ++refused;
        continue;
      }
      fill_star(ed, cav, a);
      ++moves;
    } else {  // collapse interior a onto b
      if (m.vert_class[a].dim != 3) continue;
      ball(ed, a, tets);
      cav.reset(ed);
      for (TetId x : tets) cav.add(ed, x);
      cav.compute_boundary(ed);
      if (check_star(m, cav, b) != Refusal::kNone) {
        ++refused;
        continue;
      }
      fill_star(ed, cav, b);
      EXPECT_EQ(m.vert2tet[a], kNone) << "collapsed vertex keeps a seed";
      ++collapses;
    }
    if (step % 500 == 499) expect_invariants(ed, volume);
  }
  expect_invariants(ed, volume);
  EXPECT_GT(splits, 500);
  EXPECT_GT(moves, 50);
  EXPECT_GT(collapses, 50);
  EXPECT_EQ(hook_calls, splits + moves + collapses);
  // Compaction keeps everything and leaves no dead slot.
  const std::size_t live = ed.live_tets();
  ed.compact();
  EXPECT_EQ(m.tet2verts.size(), live);
  for (TetId t = 0; t < m.tet2verts.size(); ++t) ASSERT_FALSE(ed.is_dead(t));
  expect_invariants(ed, volume);
  auto copy = m;
  EXPECT_EQ(mesh::build_adjacency(copy), 0u);
  EXPECT_EQ(copy.tet2adj, m.tet2adj);
}

TEST(Cavity, AFillThatDoesNotTileTheCavityIsAnError) {
  auto m = mesh::make_box_mesh({1, 1, 1}, Vec3(0, 0, 0), Vec3(1, 1, 1), true);
  MeshEditor ed(m);
  Cavity cav;
  cav.reset(ed);
  cav.add(ed, 0);
  cav.add(ed, 1);
  cav.compute_boundary(ed);
  // Only one of the two tets back: the other's faces stay unmatched.
  const NewTet one{m.tet2verts[0], 1};
  EXPECT_THROW(rebuild(ed, cav, std::span<const NewTet>(&one, 1)), std::logic_error);
}

TEST(Cavity, StarFromAPointOutsideTheCavityIsRefused) {
  auto m = mesh::make_box_mesh({2, 2, 2}, Vec3(0, 0, 0), Vec3(1, 1, 1), true);
  MeshEditor ed(m);
  Cavity cav;
  cav.reset(ed);
  cav.add(ed, 0);
  cav.compute_boundary(ed);
  const VertId p = m.add_vert(Vec3(5, 5, 5));
  m.resize_vertex_arrays();
  EXPECT_EQ(check_star(m, cav, p), Refusal::kNotStarShaped);
  EXPECT_EQ(to_string(Refusal::kNotStarShaped), "not star-shaped");
}
