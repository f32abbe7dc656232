// Model-aware relocation: boundary vertices move on their own entity (a
// plane of the box stays exactly that plane, an edge of the box that line,
// the sphere's vertices stay at radius 1), their parameters follow them,
// model vertices never move, and without a model nothing on the boundary
// moves.
#include <gtest/gtest.h>

#include "curvemesh/modify/marks.hpp"
#include "curvemesh/modify/relocate.hpp"
#include "point_ops_support.hpp"

using namespace cm;
using namespace cm::modify;

namespace {

struct Moves {
  int on_face = 0, on_edge = 0, refused_vertices = 0;
};

// Sweeps every vertex a few times, applying every improving relocation.
Moves sweep(cm::test::MeshedModel& r, MeshEditor& ed, BoundaryIndex& surf, int passes,
            const std::function<void(VertId)>& after_move) {
  auto& m = r.m;
  Cavity cav;
  Moves n;
  for (int pass = 0; pass < passes; ++pass)
    for (VertId v = 0; v < m.num_verts(); ++v) {
      const auto plan = plan_relocation(ed, cav, surf, v, r.model.get());
      const int dim = m.vert_class[v].dim;
      if (dim == 0) {
        EXPECT_EQ(plan.refusal, Refusal::kClassification);
      }
      if (plan.refusal != Refusal::kNone) continue;
      EXPECT_GT(plan.after, plan.before);
      apply(ed, cav, v, plan);
      if (dim == 1) ++n.on_edge;
      if (dim == 2) ++n.on_face;
      if (dim < 3) {
        // The parameters are the position's.
        const auto c = m.vert_class[v];
        const Vec3 on = c.dim == 1 ? r.model->edge_point(c.tag, m.vert_param[v].u)
                                   : r.model->face_point(c.tag, Vec2(m.vert_param[v].u, m.vert_param[v].v));
        EXPECT_LT((on - m.coords[v]).norm(), 1e-12);
      }
      after_move(v);
    }
  return n;
}

}  // namespace

TEST(RelocateModel, BoxVerticesStayOnTheirPlanesAndLines) {
  auto r = cm::test::mesh_model("builtin:box", 0.25);
  auto& m = r.m;
  const auto start = m.coords;
  MeshEditor ed(m);
  mark_boundary_faces(ed);
  BoundaryIndex surf(m);
  const auto ref = cm::test::make_reference(ed, true);
  // Which box sides (x=0, x=1, y=0, ...) a point is on.
  auto sides = [](const Vec3& x) {
    int s = 0;
    for (int k = 0; k < 3; ++k) {
      s |= (x[k] == 0.0) << (2 * k);
      s |= (x[k] == 1.0) << (2 * k + 1);
    }
    return s;
  };
  // Closest points on a plane or a line of OCC are exact to rounding:
  // compare the fixed coordinates to within a few ulps.
  auto near_sides = [](const Vec3& x) {
    int s = 0;
    for (int k = 0; k < 3; ++k) {
      s |= (std::abs(x[k]) < 1e-15) << (2 * k);
      s |= (std::abs(x[k] - 1) < 1e-15) << (2 * k + 1);
    }
    return s;
  };
  const auto n = sweep(r, ed, surf, 3, [&](VertId v) {
    EXPECT_EQ(near_sides(m.coords[v]), sides(start[v])) << "vertex " << v << " left its side";
  });
  EXPECT_GT(n.on_face, 30);
  EXPECT_GT(n.on_edge, 5);
  for (VertId v = 0; v < m.num_verts(); ++v)
    if (m.vert_class[v].dim == 0) {
      EXPECT_EQ(m.coords[v], start[v]);
    }
  cm::test::expect_everything(ed, surf, ref, r.model.get(), r.size.field.get());
}

TEST(RelocateModel, SphereVerticesStayOnTheSphere) {
  auto r = cm::test::mesh_model("builtin:sphere", 0.3);
  auto& m = r.m;
  MeshEditor ed(m);
  mark_boundary_faces(ed);
  BoundaryIndex surf(m);
  const auto ref = cm::test::make_reference(ed, false);
  const auto n = sweep(r, ed, surf, 3, [&](VertId v) {
    if (m.vert_class[v].dim == 2) {
      EXPECT_NEAR(m.coords[v].norm(), 1.0, 1e-12);
    }
  });
  EXPECT_GT(n.on_face, 30);
  cm::test::expect_everything(ed, surf, ref, r.model.get(), r.size.field.get());
}

TEST(RelocateModel, WithoutAModelTheBoundaryStays) {
  auto r = cm::test::mesh_model("builtin:box", 0.3);
  auto& m = r.m;
  MeshEditor ed(m);
  mark_boundary_faces(ed);
  BoundaryIndex surf(m);
  Cavity cav;
  const auto coords = m.coords;
  for (VertId v = 0; v < m.num_verts(); ++v) {
    const auto plan = plan_relocation(ed, cav, surf, v, nullptr);
    if (m.vert_class[v].dim < 3) {
      EXPECT_EQ(plan.refusal, Refusal::kClassification);
    }
  }
  EXPECT_EQ(m.coords, coords);  // plans move nothing
}
