// The boundary without a model: where the surface is exactly flat (straight
// along a model edge) a collapse says it keeps the surface and a slide stays
// exactly on the plane or line; anywhere else neither claims it.
#include <gtest/gtest.h>

#include <random>

#include "curvemesh/core/predicates.hpp"
#include "curvemesh/mesh/adjacency.hpp"
#include "curvemesh/mesh/structured.hpp"
#include "curvemesh/modify/collapse.hpp"
#include "curvemesh/modify/marks.hpp"

using namespace cm;
using namespace cm::modify;

namespace {

VertId vertex_at(const mesh::TetMesh& m, const Vec3& x) {
  for (VertId v = 0; v < m.num_verts(); ++v)
    if (m.coords[v] == x) return v;
  ADD_FAILURE() << "no vertex at " << x.transpose();
  return kNone;
}

struct Box {
  mesh::TetMesh m = mesh::make_box_mesh({2, 2, 2}, Vec3(0, 0, 0), Vec3(1, 1, 1), true);
};

// Collapsing `from` (of dimension `dim`) into `to` keeps the surface; after
// `bend` moves a vertex the same collapse is still allowed but does not.
template <class Bend>
void expect_kept_until_bent(const Vec3& from_at, const Vec3& to_at, int dim, Bend bend) {
  Box b;
  auto& m = b.m;
  MeshEditor ed(m);
  mark_boundary_faces(ed);
  BoundaryIndex surf(m);
  Cavity cav;
  const VertId from = vertex_at(m, from_at), to = vertex_at(m, to_at);
  ASSERT_EQ(m.vert_class[from].dim, dim);
  auto plan = plan_collapse(ed, cav, surf, from, to, nullptr);
  ASSERT_EQ(plan.refusal, Refusal::kNone);
  EXPECT_TRUE(plan.keeps_surface);
  bend(m);
  plan = plan_collapse(ed, cav, surf, from, to, nullptr);
  ASSERT_EQ(plan.refusal, Refusal::kNone);
  EXPECT_FALSE(plan.keeps_surface);
}

}  // namespace

TEST(FlatBoundary, CollapseOnAFlatFaceKeepsTheSurface) {
  // The face bent at a vertex of the centre's triangles.
  expect_kept_until_bent(Vec3(0.5, 0.5, 0), Vec3(0, 0.5, 0), 2,
                         [](mesh::TetMesh& m) { m.coords[vertex_at(m, Vec3(1, 0.5, 0))].z() = 0.01; });
}

TEST(FlatBoundary, CollapseAlongAStraightEdgeKeepsTheSurface) {
  // The far corner pulled inward along the face z = 0: that face stays
  // flat, but the model edge is no longer straight at the middle vertex.
  expect_kept_until_bent(Vec3(0.5, 0, 0), Vec3(0, 0, 0), 1,
                         [](mesh::TetMesh& m) { m.coords[vertex_at(m, Vec3(1, 0, 0))].y() = 0.01; });
}

TEST(FlatBoundary, SlidesStayExactlyOnTheFaceOrTheEdge) {
  Box b;
  auto& m = b.m;
  BoundaryIndex surf(m);
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-0.3, 0.3);
  std::vector<TetId> ball;
  std::vector<Index> tris;
  int face_slides = 0, edge_slides = 0;
  for (VertId v = 0; v < m.num_verts(); ++v) {
    const int dim = m.vert_class[v].dim;
    mesh::collect_ball(m, v, ball);
    tris_through(m, surf, v, ball, tris);
    for (int k = 0; k < 5; ++k) {
      const Vec3 goal = m.coords[v] + Vec3(u(rng), u(rng), u(rng));
      const auto flat = FlatBoundary::at(m, surf, v, tris, ball);
      const auto x = flat ? flat->slide(goal) : std::nullopt;
      if (dim != 1 && dim != 2) {
        EXPECT_FALSE(x) << "vertex " << v << " of dimension " << dim;
        continue;
      }
      ASSERT_TRUE(x);
      // The coordinates the vertex's plane (line) fixes are exactly its own.
      int fixed = 0;
      for (int c = 0; c < 3; ++c)
        if (m.coords[v][c] == 0 || m.coords[v][c] == 1) {
          EXPECT_EQ((*x)[c], m.coords[v][c]);
          ++fixed;
        }
      EXPECT_EQ(fixed, 3 - dim);
      // And it is the nearest point of that plane (line) to the goal.
      for (int c = 0; c < 3; ++c) {
        if (m.coords[v][c] != 0 && m.coords[v][c] != 1) {
          EXPECT_NEAR((*x)[c], goal[c], 1e-15);
        }
      }
      ++(dim == 2 ? face_slides : edge_slides);
    }
  }
  EXPECT_EQ(face_slides, 6 * 5);  // one face vertex per side of the box
  EXPECT_EQ(edge_slides, 12 * 5);
}

TEST(FlatBoundary, ASlideOnATiltedPlaneIsExactOrRefused) {
  // The box turned about an oblique axis: its faces are still flat as point
  // sets but not to the last bit, so only exact answers may come back.
  Box b;
  auto& m = b.m;
  const Eigen::Matrix3d r = Eigen::AngleAxisd(0.7, Vec3(1, 2, 3).normalized()).toRotationMatrix();
  for (Vec3& x : m.coords) x = r * x;
  BoundaryIndex surf(m);
  std::vector<TetId> ball;
  std::vector<Index> tris;
  for (VertId v = 0; v < m.num_verts(); ++v) {
    if (m.vert_class[v].dim != 2) continue;
    mesh::collect_ball(m, v, ball);
    tris_through(m, surf, v, ball, tris);
    const auto flat = FlatBoundary::at(m, surf, v, tris, ball);
    const auto x = flat ? flat->slide(m.coords[v] + Vec3(0.05, -0.02, 0.03)) : std::nullopt;
    if (!x) continue;
    const auto& ref = m.tris[tris[0]].verts;
    EXPECT_EQ(predicates::orient3d(m.coords[ref[0]].data(), m.coords[ref[1]].data(), m.coords[ref[2]].data(),
                                   x->data()),
              0);
  }
}
