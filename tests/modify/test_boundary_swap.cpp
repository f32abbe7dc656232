// Boundary edge swap (modify/boundary_swap.hpp): exact counts on a box face,
// every refusal reason, and long random sequences of swaps on meshes of
// curved built-ins and a shared CAD model with every invariant checked.
#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <map>
#include <random>
#include <set>

#include "curvemesh/modify/boundary_swap.hpp"
#include "curvemesh/modify/marks.hpp"
#include "point_ops_support.hpp"

using namespace cm;
using namespace cm::modify;

namespace {

// The edges of m.tris that are on no model edge, with a tet holding each.
std::vector<std::array<VertId, 2>> face_edges(const mesh::TetMesh& m, const BoundaryIndex& surf) {
  std::set<std::pair<VertId, VertId>> seen;
  std::vector<std::array<VertId, 2>> out;
  for (const auto& t : m.tris)
    for (const auto& e : mesh::kTriEdges) {
      VertId a = t.verts[e[0]], b = t.verts[e[1]];
      if (a > b) std::swap(a, b);
      if (surf.find_edge(a, b) != kNone || !seen.insert({a, b}).second) continue;
      out.push_back({a, b});
    }
  return out;
}

std::size_t live_tets(const MeshEditor& ed) { return ed.live_tets(); }

TEST(BoundarySwap, OnAPlanarFaceTheCountsAreExact) {
  auto r = cm::test::mesh_model("builtin:box", 0.4, false);
  MeshEditor ed(r.m);
  mark_boundary_faces(ed);
  BoundaryIndex surf(r.m);
  Cavity cav;
  const auto ref = cm::test::make_reference(ed, true);
  int applied = 0;
  for (const auto& e : face_edges(r.m, surf)) {
    const TetId start = cm::test::tet_with_edge(r.m, e[0], e[1]);
    if (start == kNone) continue;
    const BoundarySwap p = plan_boundary_edge_swap(ed, cav, surf, e[0], e[1], start, r.model.get());
    if (p.refusal != Refusal::kNone) continue;
    const std::size_t shell = cav.tets().size(), tris = r.m.tris.size(), before = live_tets(ed);
    EXPECT_EQ(p.fill.size(), 2 * (shell + 1 - 2));
    apply(ed, cav, surf, p);
    EXPECT_EQ(r.m.tris.size(), tris);
    EXPECT_EQ(live_tets(ed), before - shell + p.fill.size());
    // The old edge is gone from the surface, the new one is there.
    EXPECT_EQ(surf.find_tri(p.removed[0][0], p.removed[0][1], p.removed[0][2]), kNone);
    EXPECT_NE(surf.find_tri(p.added[0][0], p.added[0][1], p.added[0][2]), kNone);
    EXPECT_NE(surf.find_tri(p.added[1][0], p.added[1][1], p.added[1][2]), kNone);
    if (++applied == 20) break;
  }
  EXPECT_GT(applied, 5);
  // A planar surface: the volume is the box's, exactly as before.
  cm::test::expect_everything(ed, surf, ref, r.model.get(), r.size.field.get());
}

TEST(BoundarySwap, Refusals) {
  auto r = cm::test::mesh_model("builtin:cylinder", 0.5);
  MeshEditor ed(r.m);
  mark_boundary_faces(ed);
  BoundaryIndex surf(r.m);
  Cavity cav;
  std::map<Refusal, int> seen;
  // No model: the surface is the user's.
  const auto edges = face_edges(r.m, surf);
  ASSERT_FALSE(edges.empty());
  const auto& e0 = edges.front();
  EXPECT_EQ(plan_boundary_edge_swap(ed, cav, surf, e0[0], e0[1], cm::test::tet_with_edge(r.m, e0[0], e0[1]), nullptr)
                .refusal,
            Refusal::kConstrainedFace);
  // A model edge.
  const auto& me = r.m.edges.front();
  EXPECT_EQ(plan_boundary_edge_swap(ed, cav, surf, me.verts[0], me.verts[1],
                                    cm::test::tet_with_edge(r.m, me.verts[0], me.verts[1]), r.model.get())
                .refusal,
            Refusal::kClassification);
  // An interior edge: a closed shell.
  bool interior_done = false;
  for (TetId t = 0; t < r.m.num_tets() && !interior_done; ++t)
    for (const auto& e : mesh::kTetEdges) {
      const VertId a = r.m.tet2verts[t][e[0]], b = r.m.tet2verts[t][e[1]];
      if (r.m.vert_class[a].dim == 3 || r.m.vert_class[b].dim == 3) {
        EXPECT_EQ(plan_boundary_edge_swap(ed, cav, surf, a, b, t, r.model.get()).refusal, Refusal::kConstrainedFace);
        interior_done = true;
        break;
      }
    }
  EXPECT_TRUE(interior_done);
  for (const auto& e : edges)
    ++seen[plan_boundary_edge_swap(ed, cav, surf, e[0], e[1], cm::test::tet_with_edge(r.m, e[0], e[1]), r.model.get())
               .refusal];
  // On a curved cylinder face most flips either fold or go too far from it.
  EXPECT_GT(seen[Refusal::kNone] + seen[Refusal::kNoImprovement], 0);
  EXPECT_GT(seen[Refusal::kFoldedSurface], 0);
}

// Random swaps in rounds, everything checked after each round.
int shuffle_swaps(cm::test::MeshedModel& r, unsigned seed, int rounds) {
  MeshEditor ed(r.m);
  mark_boundary_faces(ed);
  BoundaryIndex surf(r.m);
  Cavity cav;
  const auto ref = cm::test::make_reference(ed, false);
  std::mt19937 rng(seed);
  std::map<Refusal, int> refusals;
  int applied = 0;
  for (int round = 0; round < rounds; ++round) {
    auto edges = face_edges(r.m, surf);
    std::shuffle(edges.begin(), edges.end(), rng);
    int here = 0;
    for (const auto& e : edges) {
      const TetId start = cm::test::tet_with_edge(r.m, e[0], e[1]);
      if (start == kNone || surf.find_edge(e[0], e[1]) != kNone) continue;
      BoundarySwapOptions o;
      o.max_relative_deviation = rng() % 2 ? 0.04 : 0.3;
      const BoundarySwap p = plan_boundary_edge_swap(ed, cav, surf, e[0], e[1], start, r.model.get(), nullptr,
                                                     nullptr, o);
      ++refusals[p.refusal];
      if (p.refusal != Refusal::kNone && p.refusal != Refusal::kNoImprovement) continue;
      apply(ed, cav, surf, p);
      ++here;
    }
    applied += here;
    cm::test::expect_everything(ed, surf, ref, r.model.get(), r.size.field.get());
    if (::testing::Test::HasFatalFailure() || here == 0) break;
  }
  std::printf("swapped %d;", applied);
  for (const auto& [why, n] : refusals) std::printf(" %s: %d;", std::string(to_string(why)).c_str(), n);
  std::printf("\n");
  return applied;
}

TEST(BoundarySwap, RandomSwapsOnCurvedModelsKeepEverything) {
  for (const auto& [spec, h] : {std::pair<std::string, double>{"builtin:sphere", 0.35}, {"builtin:torus", 0.3},
                                {"builtin:part", 0}}) {
    SCOPED_TRACE(spec);
    auto r = cm::test::mesh_model(spec, h);
    EXPECT_GT(shuffle_swaps(r, 17, 4), 50);
  }
}

TEST(BoundarySwap, RandomSwapsOnASharedCadModelKeepEverything) {
  const std::string path = std::string(CM_SHARED_DIR) + "/models/Zylkopf.stp";
  if (!std::filesystem::exists(path)) GTEST_SKIP() << "shared models not found";
  auto r = cm::test::mesh_model(path, 0);
  EXPECT_GT(shuffle_swaps(r, 5, 3), 200);
}

}  // namespace
