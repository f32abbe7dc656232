// Swaps and relocation: on a jittered box mesh full of poor tets, long random
// sequences of evaluated operators; whatever is applied must improve the
// worst quality of its cavity, and afterwards every invariant holds —
// adjacency, orientation, volume, boundary triangles untouched, regions.
#include <gtest/gtest.h>

#include <functional>
#include <limits>
#include <map>
#include <random>
#include <set>

#include "curvemesh/generate/delaunay3d.hpp"
#include "curvemesh/mesh/structured.hpp"
#include "curvemesh/modify/marks.hpp"
#include "curvemesh/modify/measure.hpp"
#include "curvemesh/modify/relocate.hpp"
#include "curvemesh/modify/ring_triangulation.hpp"
#include "curvemesh/modify/swap.hpp"
#include "curvemesh/optimize/improve.hpp"
#include "invariants.hpp"

using namespace cm;
using namespace cm::modify;
using cm::test::expect_invariants;

namespace {

// A 5x5x5 Kuhn box with interior vertices jittered hard: many slivers.
mesh::TetMesh jittered_box(unsigned seed) {
  auto m = mesh::make_box_mesh({5, 5, 5}, Vec3(0, 0, 0), Vec3(1, 1, 1), true);
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-0.06, 0.06);
  for (VertId v = 0; v < m.num_verts(); ++v)
    if (m.vert_class[v].dim == 3) m.coords[v] += Vec3(u(rng), u(rng), u(rng));
  return m;
}

std::set<std::array<VertId, 3>> face_set(const mesh::TetMesh& m, const MeshEditor& ed) {
  std::set<std::array<VertId, 3>> s;
  for (TetId t = 0; t < m.tet2verts.size(); ++t) {
    if (ed.is_dead(t)) continue;
    for (const auto& f : mesh::kFaceVerts) {
      std::array<VertId, 3> k{m.tet2verts[t][f[0]], m.tet2verts[t][f[1]], m.tet2verts[t][f[2]]};
      std::sort(k.begin(), k.end());
      s.insert(k);
    }
  }
  return s;
}

}  // namespace

TEST(Swap, RandomOperatorSequencesKeepInvariantsAndBoundary) {
  auto m = jittered_box(11);
  ASSERT_GT(m.num_tets(), 0u);
  for (TetId t = 0; t < m.num_tets(); ++t) ASSERT_GT(tet_quality(m, m.tet2verts[t]), 0) << "jitter too strong";
  MeshEditor ed(m);
  EXPECT_EQ(mark_boundary_faces(ed), 0u);
  Cavity cav;
  std::mt19937 rng(5);
  int removals = 0, swaps = 0, moves = 0;
  for (int step = 0; step < 6000; ++step) {
    TetId t;
    do t = static_cast<TetId>(rng() % m.tet2verts.size());
    while (ed.is_dead(t));
    const int kind = static_cast<int>(rng() % 3);
    if (kind == 0) {
      const auto& e = mesh::kTetEdges[rng() % 6];
      const auto p = plan_edge_removal(ed, cav, m.tet2verts[t][e[0]], m.tet2verts[t][e[1]], t);
      if (!p.improves()) continue;
      const auto created = apply(ed, cav, p);
      EXPECT_NEAR(min_quality(m, created), p.after, 1e-12);
      EXPECT_GT(p.after, p.before);
      ++removals;
    } else if (kind == 1) {
      const auto p = plan_face_swap(ed, cav, t, static_cast<int>(rng() % 4));
      if (!p.improves()) continue;
      const auto created = apply(ed, cav, p);
      EXPECT_EQ(created.size(), 3u);
      EXPECT_GT(min_quality(m, created), p.before);
      ++swaps;
    } else {
      const VertId v = m.tet2verts[t][rng() % 4];
      const auto r = plan_relocation(ed, cav, v);
      if (r.refusal != Refusal::kNone) continue;
      apply(ed, cav, v, r);
      ++moves;
    }
  }
  // A Kuhn box has few improvable configurations; the Delaunay test below
  // exercises many more.
  EXPECT_GT(removals, 5);
  EXPECT_GT(moves, 20);
  expect_invariants(ed, 1.0);
  // The box's boundary triangles are all still tet faces, and boundary
  // vertices did not move.
  const auto faces = face_set(m, ed);
  for (const auto& tri : m.tris) {
    auto k = tri.verts;
    std::sort(k.begin(), k.end());
    EXPECT_TRUE(faces.count(k)) << "boundary triangle lost";
  }
  const auto ref = mesh::make_box_mesh({5, 5, 5}, Vec3(0, 0, 0), Vec3(1, 1, 1), true);
  for (VertId v = 0; v < ref.num_verts(); ++v)
    if (ref.vert_class[v].dim < 3) {
      EXPECT_EQ(m.coords[v], ref.coords[v]);
    }
}

TEST(Swap, OnADelaunayMeshOfRandomPointsEveryShellSizeWorks) {
  // Delaunay tets of random points: slivers everywhere, shells of 3..12.
  mesh::TetMesh m;
  std::mt19937 rng(9);
  std::uniform_real_distribution<double> u(0, 1);
  for (int i = 0; i < 3000; ++i) m.add_vert(Vec3(u(rng), u(rng), u(rng)));
  m.resize_vertex_arrays();
  for (auto& c : m.vert_class) c = {3, 1};
  std::vector<VertId> ids(m.num_verts());
  for (VertId v = 0; v < ids.size(); ++v) ids[v] = v;
  generate::Delaunay3d dt(m, Vec3(0, 0, 0), Vec3(1, 1, 1));
  dt.insert_all(ids);
  for (VertId v : dt.far_vertices()) m.vert_class[v] = {0, 1};  // the far corners stay put
  auto& ed = dt.editor();
  ed.compact();
  mark_boundary_faces(ed);
  double volume = 0;
  for (TetId t = 0; t < m.num_tets(); ++t) volume += mesh::tet_volume(m, t);
  Cavity cav;
  std::set<std::size_t> shell_sizes;
  int removals = 0, swaps = 0, moves = 0;
  for (int step = 0; step < 20000; ++step) {
    TetId t;
    do t = static_cast<TetId>(rng() % m.tet2verts.size());
    while (ed.is_dead(t));
    const int kind = static_cast<int>(rng() % 3);
    if (kind == 0) {
      const auto& e = mesh::kTetEdges[rng() % 6];
      const auto p = plan_edge_removal(ed, cav, m.tet2verts[t][e[0]], m.tet2verts[t][e[1]], t);
      if (!p.improves()) continue;
      shell_sizes.insert(cav.tets().size());
      EXPECT_EQ(p.fill.size(), 2 * (cav.tets().size() - 2));
      const auto created = apply(ed, cav, p);
      EXPECT_NEAR(min_quality(m, created), p.after, 1e-12);
      ++removals;
    } else if (kind == 1) {
      const auto p = plan_face_swap(ed, cav, t, static_cast<int>(rng() % 4));
      if (!p.improves()) continue;
      EXPECT_GT(min_quality(m, apply(ed, cav, p)), p.before);
      ++swaps;
    } else {
      const VertId v = m.tet2verts[t][rng() % 4];
      const auto r = plan_relocation(ed, cav, v);
      if (r.refusal != Refusal::kNone) continue;
      apply(ed, cav, v, r);
      ++moves;
    }
    if (step % 5000 == 4999) expect_invariants(ed, volume);
  }
  EXPECT_GT(removals, 200);
  EXPECT_GT(swaps, 0);  // rare on Delaunay tets: a 2-3 of a Delaunay pair seldom helps
  EXPECT_GT(moves, 200);
  EXPECT_GE(shell_sizes.size(), 4u);  // 3-2, 4-4, 5-6, 6-8 at least
  expect_invariants(ed, volume);
}

// The best worst triangle of a polygon, by enumerating every triangulation:
// the edge (i, j) with apex k, then the two sides.
double brute_force_ring(int i, int j, const std::function<double(int, int, int)>& f) {
  if (j - i < 2) return std::numeric_limits<double>::infinity();
  double best = -std::numeric_limits<double>::infinity();
  for (int k = i + 1; k < j; ++k)
    best = std::max(best, std::min({f(i, k, j), brute_force_ring(i, k, f), brute_force_ring(k, j, f)}));
  return best;
}

TEST(RingTriangulation, IsOptimalAndTheFloorChangesNothing) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1, 1);
  for (int n = 3; n <= 9; ++n)
    for (int trial = 0; trial < 30; ++trial) {
      // A triangle's value is the min of two "tets", as in edge removal.
      std::map<std::array<int, 3>, std::array<double, 2>> values;
      for (int i = 0; i < n; ++i)
        for (int k = i + 1; k < n; ++k)
          for (int j = k + 1; j < n; ++j) values[{i, k, j}] = {u(rng), u(rng)};
      const auto exact = [&](int i, int k, int j) {
        const auto& v = values.at({i, k, j});
        return std::min(v[0], v[1]);
      };
      int full_calls = 0, floored_second = 0;
      const RingTriangulation plain = triangulate_ring(n, [&](int i, int k, int j) {
        ++full_calls;
        return exact(i, k, j);
      });
      const RingTriangulation floored = triangulate_ring(n, [&](int i, int k, int j, double floor) {
        const auto& v = values.at({i, k, j});
        if (v[0] <= floor) return v[0];
        ++floored_second;
        return std::min(v[0], v[1]);
      });
      EXPECT_DOUBLE_EQ(plain.worst, brute_force_ring(0, n - 1, exact)) << n;
      ASSERT_EQ(floored.count, n - 2);
      EXPECT_EQ(floored.worst, plain.worst);
      EXPECT_EQ(floored.triangles, plain.triangles);
      EXPECT_LE(floored_second, full_calls);
      // The triangles listed reach the worst value they claim.
      double worst = std::numeric_limits<double>::infinity();
      for (int t = 0; t < plain.count; ++t) {
        const auto& tri = plain.triangles[static_cast<std::size_t>(t)];
        worst = std::min(worst, exact(tri[0], tri[1], tri[2]));
      }
      EXPECT_EQ(worst, plain.worst);
    }
  EXPECT_EQ(triangulate_ring(2, [](int, int, int) { return 1.0; }).count, 0);
  EXPECT_EQ(triangulate_ring(kMaxRing + 1, [](int, int, int) { return 1.0; }).count, 0);
}

TEST(Swap, RefusalsAreValuesAndChangeNothing) {
  auto m = mesh::make_box_mesh({2, 2, 2}, Vec3(0, 0, 0), Vec3(1, 1, 1), true);
  MeshEditor ed(m);
  mark_boundary_faces(ed);
  Cavity cav;
  const auto before = m.tet2verts;
  // A hull face cannot be swapped; a boundary vertex does not relocate.
  for (TetId t = 0; t < m.num_tets(); ++t)
    for (int f = 0; f < 4; ++f)
      if (m.tet2adj[mesh::pack_face(t, f)] == kNone) {
        EXPECT_EQ(plan_face_swap(ed, cav, t, f).refusal, Refusal::kConstrainedFace);
      }
  EXPECT_EQ(plan_relocation(ed, cav, 0).refusal, Refusal::kClassification);
  EXPECT_EQ(m.tet2verts, before);
}

TEST(Improve, RaisesTheWorstQualityAndKeepsTheMeshValid) {
  auto m = jittered_box(3);
  const std::size_t tris = m.tris.size();
  const auto st = optimize::improve_quality(m);
  EXPECT_GT(st.min_after, st.min_before);
  EXPECT_LT(st.below_after, st.below_before);
  EXPECT_GT(st.edge_removals + st.face_swaps + st.relocations, 0u);
  EXPECT_EQ(m.tris.size(), tris);
  MeshEditor ed(m);
  expect_invariants(ed, 1.0);
}
