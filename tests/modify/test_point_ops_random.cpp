// Property tests of the point operators: on meshes the project's volume
// mesher makes of real models, thousands of random splits, collapses,
// relocations, swaps and element deletions — half of them aimed at the
// boundary surface — and
// then every invariant checked from scratch (point_ops_support.hpp):
// validity, adjacency, seeds, marks, classification and parameters on the
// model, closed oriented region boundaries, region volumes on planar models.
#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <map>
#include <random>

#include "curvemesh/modify/collapse.hpp"
#include "curvemesh/modify/delete_tet.hpp"
#include "curvemesh/modify/marks.hpp"
#include "curvemesh/modify/measure.hpp"
#include "curvemesh/modify/relocate.hpp"
#include "curvemesh/modify/split.hpp"
#include "curvemesh/modify/swap.hpp"
#include "point_ops_support.hpp"

using namespace cm;
using namespace cm::modify;
using cm::test::expect_everything;
using cm::test::MeshedModel;

namespace {

struct Counts {
  int splits = 0, boundary_splits = 0, collapses = 0, boundary_collapses = 0, moves = 0, boundary_moves = 0,
      swaps = 0, deletions = 0, vertex_deletions = 0;
  std::map<Refusal, int> split_refusals, collapse_refusals, move_refusals, deletion_refusals;
};

// Runs `steps` random operations; checks everything every `check_every`
// steps and at the end. Splits and collapses alternate in the lead so the
// mesh size stays near its start.
Counts run_random(MeshedModel& r, int steps, unsigned seed, bool planar, int check_every) {
  auto& m = r.m;
  MeshEditor ed(m);
  EXPECT_EQ(mark_boundary_faces(ed), 0u);
  BoundaryIndex surf(m);
  const auto ref = cm::test::make_reference(ed, planar);
  int hook_tets = 0;
  ed.set_hook([&](const mesh::TetMesh&, std::span<const TetId> created) { hook_tets += static_cast<int>(created.size()); });
  Cavity cav;
  std::mt19937 rng(seed);
  Counts n;
  const std::size_t start_verts = m.num_verts();
  std::printf("start: %zu vertices, %zu tets, %zu triangles, %zu edges\n", m.num_verts(), m.num_tets(), m.tris.size(),
              m.edges.size());
  std::size_t live_verts = start_verts;
  const geom::Model* model = r.model.get();
  for (int step = 0; step < steps; ++step) {
    // The target: a random edge or vertex of a live tet, or of a boundary
    // triangle (so that the boundary cases are many).
    VertId a, b;
    const bool on_surface = rng() % 2 == 0 && !m.tris.empty();
    if (on_surface) {
      const auto& tri = m.tris[rng() % m.tris.size()];
      const int k = static_cast<int>(rng() % 3);
      a = tri.verts[static_cast<std::size_t>(k)];
      b = tri.verts[static_cast<std::size_t>((k + 1) % 3)];
    } else {
      TetId t;
      do t = static_cast<TetId>(rng() % m.tet2verts.size());
      while (ed.is_dead(t));
      const auto& e = mesh::kTetEdges[rng() % 6];
      a = m.tet2verts[t][static_cast<std::size_t>(e[0])];
      b = m.tet2verts[t][static_cast<std::size_t>(e[1])];
    }
    const TetId start = cm::test::tet_with_edge(m, a, b);
    if (start == kNone) {
      ADD_FAILURE() << "boundary triangle edge (" << a << ", " << b << ") is no mesh edge";
      return n;
    }
    const int kind = static_cast<int>(rng() % 5);
    if (kind == 4) {
      // A tet against the boundary: the one holding a random triangle, or a
      // neighbour of it (so that tets with two or three hull faces are hit).
      if (m.tris.empty()) continue;
      const auto tri = m.tris[rng() % m.tris.size()].verts;
      TetId t = cm::test::tet_with_face(m, tri);
      if (t == kNone) {
        ADD_FAILURE() << "boundary triangle is no tet face";
        return n;
      }
      if (rng() % 2) {
        // Half the time a tet with two or more hull faces, if there is one
        // (a scan: the meshes here are small).
        std::vector<TetId> capped;
        for (TetId u = 0; u < m.tet2verts.size(); ++u) {
          if (ed.is_dead(u)) continue;
          int hull = 0;
          for (int f = 0; f < 4; ++f) hull += m.tet2adj[mesh::pack_face(u, f)] == kNone;
          if (hull >= 2) capped.push_back(u);
        }
        if (!capped.empty()) t = capped[rng() % capped.size()];
      } else {
        const Index across = m.tet2adj[mesh::pack_face(t, static_cast<int>(rng() % 4))];
        if (across != kNone) t = mesh::face_tet(across);
      }
      // The mesher's chord rule, or a loose one so that many deletions apply
      // (and their invariants are checked) on coarse meshes of curved faces.
      const auto plan = plan_tet_deletion(ed, cav, surf, t, model, DeletionOptions{rng() % 2 ? 0.04 : 0.3});
      ++n.deletion_refusals[plan.refusal];
      if (plan.refusal != Refusal::kNone) continue;
      EXPECT_GT(plan.volume, 0);
      const std::size_t tris_before = m.tris.size(), tets_before = ed.live_tets();
      apply(ed, cav, surf, plan);
      EXPECT_EQ(ed.live_tets(), tets_before - 1);
      EXPECT_EQ(m.tris.size(), tris_before - static_cast<std::size_t>(plan.removed_count - plan.added_count));
      if (plan.removed_vertex != kNone) {
        EXPECT_EQ(m.vert2tet[plan.removed_vertex], kNone);
        --live_verts;
        ++n.vertex_deletions;
      }
      ++n.deletions;
    } else if (kind == 0) {
      // Grow only while the mesh is not much bigger than at the start.
      if (live_verts > start_verts + start_verts / 4) continue;
      const auto plan = plan_split(ed, cav, surf, a, b, start, model);
      ++n.split_refusals[plan.refusal];
      if (plan.refusal != Refusal::kNone) continue;
      const int before = hook_tets;
      const VertId p = apply(ed, cav, surf, plan);
      EXPECT_EQ(hook_tets - before, static_cast<int>(2 * cav.tets().size()));
      EXPECT_EQ(m.vert_class[p], plan.classification);
      ++live_verts;
      ++n.splits;
      n.boundary_splits += plan.classification.dim < 3;
    } else if (kind == 1) {
      if (live_verts + start_verts / 4 < start_verts) continue;
      const auto plan = plan_collapse(ed, cav, surf, a, b, model);
      ++n.collapse_refusals[plan.refusal];
      if (plan.refusal != Refusal::kNone) continue;
      apply(ed, cav, surf, plan);
      EXPECT_EQ(m.vert2tet[a], kNone);
      --live_verts;
      ++n.collapses;
      n.boundary_collapses += m.vert_class[a].dim < 3;
    } else if (kind == 2) {
      const auto plan = plan_relocation(ed, cav, surf, a, model);
      ++n.move_refusals[plan.refusal];
      if (plan.refusal != Refusal::kNone) continue;
      EXPECT_GT(plan.after, plan.before);
      apply(ed, cav, a, plan);
      EXPECT_EQ(m.coords[a], plan.target);
      ++n.moves;
      n.boundary_moves += m.vert_class[a].dim < 3;
    } else {
      const auto plan = plan_edge_removal(ed, cav, a, b, start);
      if (!plan.improves()) continue;
      apply(ed, cav, plan);
      ++n.swaps;
    }
    if (check_every > 0 && step % check_every == check_every - 1) {
      expect_everything(ed, surf, ref, model, r.size.field.get());
      if (::testing::Test::HasFatalFailure()) return n;
    }
  }
  expect_everything(ed, surf, ref, model, r.size.field.get());
  return n;
}

// `deletions`: how many element deletions must apply at least (none can on
// planar faces: a tet with two faces on one plane would be flat).
void expect_busy(const Counts& n, int steps, int deletions = 0) {
  // Tests that can fail: a good share of each operator must actually apply,
  // on the boundary too.
  EXPECT_GT(n.splits, steps / 40);
  EXPECT_GT(n.boundary_splits, steps / 100);
  EXPECT_GT(n.collapses, steps / 40);
  EXPECT_GT(n.boundary_collapses, steps / 200);
  EXPECT_GT(n.moves, steps / 100);
  EXPECT_GT(n.boundary_moves, steps / 400);
  EXPECT_GE(n.deletions, deletions);
  // The collapse's topological and classification rules do fire.
  EXPECT_GT(n.collapse_refusals.count(Refusal::kClassification) ? n.collapse_refusals.at(Refusal::kClassification) : 0, 0);
  EXPECT_GT(n.collapse_refusals.count(Refusal::kNonManifold) ? n.collapse_refusals.at(Refusal::kNonManifold) : 0, 0);
  std::printf("splits %d (boundary %d), collapses %d (boundary %d), moves %d (boundary %d), swaps %d, deletions %d "
              "(%d with their vertex)\n",
              n.splits, n.boundary_splits, n.collapses, n.boundary_collapses, n.moves, n.boundary_moves, n.swaps,
              n.deletions, n.vertex_deletions);
  for (const auto* map : {&n.split_refusals, &n.collapse_refusals, &n.move_refusals, &n.deletion_refusals}) {
    std::printf(" ");
    for (const auto& [r, c] : *map) std::printf(" %s: %d;", std::string(to_string(r)).c_str(), c);
    std::printf("\n");
  }
}

}  // namespace

TEST(PointOpsRandom, BoxKeepsEverythingAndItsVolume) {
  auto r = cm::test::mesh_model("builtin:box", 0.25);
  const int steps = 20000;
  expect_busy(run_random(r, steps, 1, true, 250), steps);
}

TEST(PointOpsRandom, FinerBoxKeepsEverythingAndItsVolume) {
  auto r = cm::test::mesh_model("builtin:box", 0.1);
  const int steps = 20000;
  expect_busy(run_random(r, steps, 11, true, 2000), steps);
}

TEST(PointOpsRandom, TwoBlocksKeepTheirRegionsAndInterface) {
  // Two regions sharing a face: interface edges and vertices split, collapse
  // and move with tets of both regions around them.
  auto r = cm::test::mesh_model("builtin:blocks", 0.3);
  const int steps = 20000;
  expect_busy(run_random(r, steps, 2, true, 250), steps);
}

TEST(PointOpsRandom, SphereStaysOnTheModel) {
  // A periodic face with a seam and two poles: parameters across the seam,
  // closest points with hints, folds checked against the model.
  auto r = cm::test::mesh_model("builtin:sphere", 0.35);
  const int steps = 20000;
  expect_busy(run_random(r, steps, 3, false, 250), steps, 5);
}

TEST(PointOpsRandom, CylinderStaysOnTheModel) {
  // Closed circle edges (periodic u), a seam, planar caps meeting a curved
  // face at sharp edges.
  auto r = cm::test::mesh_model("builtin:cylinder", 0.3);
  const int steps = 20000;
  expect_busy(run_random(r, steps, 4, false, 250), steps, 5);
}

TEST(PointOpsRandom, TorusStaysOnTheModel) {
  // Periodic in u and v, concave and convex parts.
  auto r = cm::test::mesh_model("builtin:torus", 0.3);
  const int steps = 20000;
  expect_busy(run_random(r, steps, 6, false, 500), steps, 5);
}

TEST(PointOpsRandom, InclusionKeepsItsCurvedInterface) {
  // A sphere inside a cube: two regions meeting on a curved face.
  auto r = cm::test::mesh_model("builtin:inclusion", 0.3);
  const int steps = 20000;
  expect_busy(run_random(r, steps, 7, false, 500), steps);
}

TEST(PointOpsRandom, PartWithFreeformFaceAndHoles) {
  auto r = cm::test::mesh_model("builtin:part", 0);
  const int steps = 10000;
  expect_busy(run_random(r, steps, 8, false, 1000), steps);
}

TEST(PointOpsRandom, SharedCadModel) {
  const std::string path = std::string(CM_SHARED_DIR) + "/models/Torus_1.brep";
  if (!std::filesystem::exists(path)) GTEST_SKIP() << "shared models not found";
  auto r = cm::test::mesh_model(path, 0);
  const int steps = 10000;
  expect_busy(run_random(r, steps, 5, false, 1000), steps, 5);
}
