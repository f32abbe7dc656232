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

}  // namespace

TEST(FlatBoundary, CollapseOnAFlatFaceKeepsTheSurface) {
  Box b;
  auto& m = b.m;
  MeshEditor ed(m);
  mark_boundary_faces(ed);
  BoundaryIndex surf(m);
  Cavity cav;
  const VertId centre = vertex_at(m, Vec3(0.5, 0.5, 0)), side = vertex_at(m, Vec3(0, 0.5, 0)),
               other = vertex_at(m, Vec3(1, 0.5, 0));
  ASSERT_EQ(m.vert_class[centre].dim, 2);
  auto plan = plan_collapse(ed, cav, surf, centre, side, nullptr);
  ASSERT_EQ(plan.refusal, Refusal::kNone);
  EXPECT_TRUE(plan.keeps_surface);
  // The face bent at a vertex of the centre's triangles: the same collapse
  // is still possible but would change the surface.
  m.coords[other].z() = 0.01;
  plan = plan_collapse(ed, cav, surf, centre, side, nullptr);
  ASSERT_EQ(plan.refusal, Refusal::kNone);
  EXPECT_FALSE(plan.keeps_surface);
}

TEST(FlatBoundary, CollapseAlongAStraightEdgeKeepsTheSurface) {
  Box b;
  auto& m = b.m;
  MeshEditor ed(m);
  mark_boundary_faces(ed);
  BoundaryIndex surf(m);
  Cavity cav;
  const VertId mid = vertex_at(m, Vec3(0.5, 0, 0)), corner = vertex_at(m, Vec3(0, 0, 0)),
               far = vertex_at(m, Vec3(1, 0, 0));
  ASSERT_EQ(m.vert_class[mid].dim, 1);
  auto plan = plan_collapse(ed, cav, surf, mid, corner, nullptr);
  ASSERT_EQ(plan.refusal, Refusal::kNone);
  EXPECT_TRUE(plan.keeps_surface);
  // The far corner pulled inward along the face z = 0: that face stays
  // flat, but the model edge is no longer straight at mid.
  m.coords[far].y() = 0.01;
  plan = plan_collapse(ed, cav, surf, mid, corner, nullptr);
  ASSERT_EQ(plan.refusal, Refusal::kNone);
  EXPECT_FALSE(plan.keeps_surface);
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
      const auto x = slide_on_flat_boundary(m, surf, v, tris, ball, goal);
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
    const auto x = slide_on_flat_boundary(m, surf, v, tris, ball, m.coords[v] + Vec3(0.05, -0.02, 0.03));
    if (!x) continue;
    const auto& ref = m.tris[tris[0]].verts;
    EXPECT_EQ(predicates::orient3d(m.coords[ref[0]].data(), m.coords[ref[1]].data(), m.coords[ref[2]].data(),
                                   x->data()),
              0);
  }
}
