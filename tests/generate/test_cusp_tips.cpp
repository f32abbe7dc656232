// Cusp tips (geom/cusps.hpp) on SampleCrankshaft4A.stp, whose two sliver
// faces (16 and 86) taper to points at vertices 64 and 140 between tangent
// edges: where the tips are, the sizes along the strips, and the mesh
// around them (balls empty, needles from the vertex, fair angles).
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <set>

#include "curvemesh/generate/edge_mesh.hpp"
#include "curvemesh/generate/volume_mesh.hpp"
#include "curvemesh/geom/cusps.hpp"
#include "curvemesh/geom_occ/load.hpp"
#include "curvemesh/mesh/adjacency.hpp"
#include "curvemesh/mesh/validate.hpp"
#include "curvemesh/optimize/improve.hpp"
#include "curvemesh/quality/measures.hpp"
#include "curvemesh/size/build.hpp"
#include "curvemesh/size/sampling.hpp"

using namespace cm;

namespace {

const std::string kCrank = std::string(CM_SHARED_DIR) + "/models/SampleCrankshaft4A.stp";

struct Crank {
  std::unique_ptr<geom::Model> model = geom_occ::load_model(kCrank);
  size::SizeFieldResult size = size::build_size_field(*model, {});
};

const Crank& crank() {
  static const Crank c;
  return c;
}

double min_dihedral(const mesh::TetMesh& m, TetId t) {
  const auto& v = m.tet2verts[t];
  const auto a = quality::tet_dihedral_angles(m.coords[v[0]], m.coords[v[1]], m.coords[v[2]], m.coords[v[3]]);
  return *std::min_element(a.begin(), a.end());
}

double worst_dihedral(const mesh::TetMesh& m) {
  double worst = 180;
  for (TetId t = 0; t < m.num_tets(); ++t) worst = std::min(worst, min_dihedral(m, t));
  return worst;
}

// The size field at hmax = the model's bounding-box diagonal / n
// (run_models.sh's coarse size is n = 8, its fine one n = 35).
size::SizeFieldResult size_at_diagonal_over(const geom::Model& model, double n) {
  const geom::BoundingBox box = model.bounding_box();
  size::SizeOptions so;
  so.hmax = (box.max - box.min).norm() / n;
  return size::build_size_field(model, so);
}

// The volume mesh with its tips (in st), optimized as `curvemesh mesh`
// does; expected valid.
mesh::TetMesh optimized_mesh(const geom::Model& model, const size::SizeField& size, generate::VolumeMeshStats& st) {
  mesh::TetMesh m = generate::mesh_volume(model, size, {}, &st);
  optimize::ImproveOptions io;
  io.model = &model;
  io.tips = st.tips;
  optimize::improve_quality(m, io);
  EXPECT_TRUE(mesh::validate(m, mesh::Level::kFull).valid());
  return m;
}

// No vertex but a tip's own inside its ball (edge nodes land on the sphere
// to the edge search's tolerance).
void expect_balls_empty(const mesh::TetMesh& m, const std::vector<geom::CuspTip>& tips) {
  for (const auto& tip : tips)
    for (VertId v = 0; v < m.num_verts(); ++v) {
      const double d = (m.coords[v] - tip.point).norm();
      if (d > 0) {
        EXPECT_GE(d, tip.radius * (1 - 1e-6))
            << "vertex " << v << " (dim " << m.vert_class[v].dim << ") in the ball of model vertex " << tip.vertex;
      }
    }
}

}  // namespace

TEST(CuspTips, FoundAtTheTaperingFacesAndBoundedByTheModel) {
  const auto& c = crank();
  const double hmin = c.size.hmin;
  const auto tips = geom::cusp_tips(*c.model, [hmin](const Vec3&) { return hmin; });
  std::set<int> at;
  for (const auto& tip : tips) {
    at.insert(tip.vertex);
    EXPECT_GT(tip.radius, 2 * hmin) << "vertex " << tip.vertex;
    EXPECT_EQ(tip.point, c.model->vertex_point(tip.vertex));
    ASSERT_FALSE(tip.pairs.empty());
    // No edge at the vertex is shorter than the ball allows.
    for (const int e : c.model->upward({0, tip.vertex})) EXPECT_LE(tip.radius, 0.4 * c.model->length(e) + 1e-12);
    // At the sphere the strip is not yet hmin wide, or the ball was cut
    // short by the model: never wider than asked.
    for (const auto& pair : tip.pairs) {
      const int side = c.model->edge_vertices(pair[0])[0] == tip.vertex ? 0 : 1;
      const auto u = geom::param_at_distance(*c.model, pair[0], side, tip.radius);
      ASSERT_TRUE(u.has_value());
      const Vec3 x = c.model->edge_point(pair[0], *u);
      EXPECT_NEAR((x - tip.point).norm(), tip.radius, 1e-9 * tip.radius);
      EXPECT_LE(c.model->closest_point({1, pair[1]}, x).distance, 1.01 * hmin);
    }
    const geom::TipBalls balls({tip});
    const Vec3 out = c.model->edge_point(tip.pairs[0][0], *geom::param_at_distance(*c.model, tip.pairs[0][0],
                                                                                  c.model->edge_vertices(tip.pairs[0][0])[0] == tip.vertex ? 0 : 1,
                                                                                  1.01 * tip.radius));
    EXPECT_TRUE(balls.contains(tip.point + Vec3(0.5 * tip.radius, 0, 0)));
    EXPECT_FALSE(balls.contains(out));
  }
  EXPECT_EQ(at, (std::set<int>{64, 140}));
}

// Beyond the sphere the size along a strip is its width, below hmin while
// the strip is narrower (to a tenth of it); elsewhere hmin still holds.
TEST(CuspTips, StripSizesFollowTheWidthBelowHmin) {
  const auto& c = crank();
  const double hmin = c.size.hmin;
  std::size_t strip_samples = 0;
  for (const auto& s : c.size.samples)
    if (s.source == size::SizeSource::kCuspStrip) {
      ++strip_samples;
      EXPECT_GE(s.size, size::kCuspStripFloor * hmin * (1 - 1e-12));
    }
  EXPECT_GT(strip_samples, 20u);
  const auto tips = generate::cusp_tips(*c.model, *c.size.field);
  ASSERT_EQ(tips.size(), 2u);
  bool below = false;
  for (const auto& tip : tips) {
    const int e = tip.pairs[0][0], other = tip.pairs[0][1];
    const int side = c.model->edge_vertices(e)[0] == tip.vertex ? 0 : 1;
    for (const double f : {1.0, 1.2, 1.5}) {
      const auto u = geom::param_at_distance(*c.model, e, side, f * tip.radius);
      ASSERT_TRUE(u.has_value());
      const Vec3 x = c.model->edge_point(e, *u);
      const double width = c.model->closest_point({1, other}, x).distance;
      const double h = c.size.field->size(x);
      // The generator's sphere is a little inside the sampler's (it asks
      // for 0.9 sizes of width), where the width is a little less.
      EXPECT_LE(h, std::max(1.25 * width, size::kCuspStripFloor * hmin * 1.1)) << "vertex " << tip.vertex << " at " << f;
      below = below || h < hmin;
    }
  }
  EXPECT_TRUE(below);
  // Away from the strips, hmin is the floor.
  const geom::BoundingBox b = c.model->bounding_box();
  for (int i = 0; i <= 10; ++i) {
    const Vec3 x = b.min + (b.max - b.min) * (i / 10.0);
    EXPECT_GE(c.size.field->size(x), hmin * (1 - 1e-12));
  }
}

// The mesh: every edge at a tip vertex has its first node on the sphere,
// no other vertex inside the ball, and the tets at the vertex (needles to
// the sphere) and everywhere else keep fair angles once optimized: the
// crankshaft's worst dihedral angle was 3.4°, at these tips, before them.
TEST(CuspTips, MeshKeepsTheBallsEmptyAndTheNeedlesFair) {
  const auto& c = crank();
  generate::VolumeMeshStats st;
  const mesh::TetMesh m = optimized_mesh(*c.model, *c.size.field, st);
  ASSERT_EQ(st.tips.size(), 2u);
  for (const auto& tip : st.tips) {
    VertId centre = kNone;
    for (VertId v = 0; v < m.num_verts(); ++v) {
      const double d = (m.coords[v] - tip.point).norm();
      if (d == 0) {
        centre = v;
        continue;
      }
      EXPECT_GE(d, tip.radius * (1 - 1e-9)) << "vertex " << v << " in the ball of model vertex " << tip.vertex;
    }
    ASSERT_NE(centre, kNone);
    // The edges' first nodes, on the sphere, are the mesh neighbours of the
    // tip on those edges.
    std::set<int> edges_met;
    double worst = 180;
    for (TetId t = 0; t < m.num_tets(); ++t) {
      const auto& tv = m.tet2verts[t];
      if (std::find(tv.begin(), tv.end(), centre) == tv.end()) continue;
      worst = std::min(worst, min_dihedral(m, t));
      for (const VertId w : tv)
        if (m.vert_class[w].dim == 1) {
          edges_met.insert(m.vert_class[w].tag);
          EXPECT_NEAR((m.coords[w] - tip.point).norm(), tip.radius, 1e-6 * tip.radius);
        }
    }
    EXPECT_EQ(edges_met.size(), c.model->upward({0, tip.vertex}).size());
    EXPECT_GE(worst, 9.0) << "at model vertex " << tip.vertex;
  }
  EXPECT_GE(worst_dihedral(m), 9.0);
}

// At run_models.sh's fine size (the bounding-box diagonal / 35) the cap of
// a tip had two face nodes 0.0027 apart among cap points 0.01 apart. The
// optimizer first took a cap point off the sphere, then reconnected the cap
// across the hole into a needle on that short edge (4.98 deg): cap points
// now move over the sphere only, and a reconnection by a tip must keep the
// worst dihedral angle.
TEST(CuspTips, OptimizationKeepsTheCapsWholeAtAFineSize) {
  const auto& c = crank();
  const auto size = size_at_diagonal_over(*c.model, 35);
  generate::VolumeMeshStats st;
  const mesh::TetMesh m = optimized_mesh(*c.model, *size.field, st);
  EXPECT_GE(worst_dihedral(m), 10.0);
}

// 917_fusee.stp at a coarse hmax (the bounding-box diagonal / 8): one of its
// tips is cut short by the model (its strip is still about 30 times
// narrower than the size where it leaves the ball), so the faces' rings
// grade down to the strip's width next to it and the cap must follow them.
// Its points then go onto the sphere from tets of either side: the fan's
// (their far face's centre, centroid or longest edge's middle) and the flat
// ones just outside (their circumcentre, inside the ball, taken out). With
// the ring so graded and only the fan's tets refining the cap, the worst
// dihedral angle there was 3.9°.
TEST(CuspTips, CapsFollowARingGradedDownToTheStrip) {
  const auto model = geom_occ::load_model(std::string(CM_SHARED_DIR) + "/models/917_fusee.stp");
  const auto size = size_at_diagonal_over(*model, 8);
  generate::VolumeMeshStats st;
  const mesh::TetMesh m = optimized_mesh(*model, *size.field, st);
  ASSERT_GE(st.tips.size(), 5u);
  expect_balls_empty(m, st.tips);
  EXPECT_GE(worst_dihedral(m), 10.0);
}

// 917_fusee.stp has vertices with two cusp pairs (two tangent edges on each
// side) that no wedge span opens: they get one tip for both pairs. Without
// it the tets there were the model's worst, 11.0 deg at the default size.
TEST(CuspTips, TwoPairsThatNoSpanOpensShareOneTip) {
  const auto model = geom_occ::load_model(std::string(CM_SHARED_DIR) + "/models/917_fusee.stp");
  const auto size = size::build_size_field(*model, {});
  generate::VolumeMeshStats st;
  const mesh::TetMesh m = optimized_mesh(*model, *size.field, st);
  std::set<int> spanned;
  for (const auto& s : geom::wedge_spans(*model)) spanned.insert(s.vertex);
  int shared = 0;
  for (const auto& tip : st.tips) {
    if (tip.pairs.size() < 2) continue;
    ++shared;
    EXPECT_FALSE(spanned.count(tip.vertex)) << "model vertex " << tip.vertex;
  }
  EXPECT_GE(shared, 1);
  expect_balls_empty(m, st.tips);
  EXPECT_GE(worst_dihedral(m), 14.0);
}

// OCCT's CrankArm sample (occt-misc) at the bounding-box diagonal / 35: a
// tip's cap had a flat triangle whose cap point the search would not move,
// for it ranked the needles at the tip by their mean ratio (low by design,
// raised by widening cap triangles whatever their shape): 6.9 deg. Ranked
// by their angles, as the driver judges them, the cap point moves.
TEST(CuspTips, CapPointsMoveForTheNeedlesAngles) {
  const char* path = "/usr/share/opencascade/data/occ/CrankArm.brep";
  if (!std::filesystem::exists(path)) GTEST_SKIP() << path << " is missing: it comes with Debian's occt-misc";
  const auto model = geom_occ::load_model(path);
  const auto size = size_at_diagonal_over(*model, 35);
  generate::VolumeMeshStats st;
  const mesh::TetMesh m = optimized_mesh(*model, *size.field, st);
  ASSERT_FALSE(st.tips.empty());
  EXPECT_GE(worst_dihedral(m), 10.0);  // 6.9 before
}

// t20_data.step: at each of its six vertices on the top circle two chamfers
// die out, one on either side (two cusp pairs), over a right-angled corner
// of the solid. No tip there; every edge's first node at least the span's
// radius away instead, so the chamfer's triangle at the vertex has opened
// (7.8 deg worst dihedral angle at hmax 1.2 with the metric's first nodes),
// and no chamfer point inside that radius (3.2 deg at hmax 1.0 with them).
TEST(WedgeSpans, TwoChamfersDyingOutAtAVertexGetLongFirstSegments) {
  const auto model = geom_occ::load_model(std::string(CM_SHARED_DIR) + "/models/t20_data.step");
  const auto spans = geom::wedge_spans(*model);
  ASSERT_EQ(spans.size(), 6u);
  std::set<int> at;
  for (const auto& s : spans) {
    at.insert(s.vertex);
    for (const int e : model->upward({0, s.vertex})) EXPECT_LE(s.radius, 0.4 * model->length(e) + 1e-12);
    EXPECT_GT(s.radius, 3.0);  // the metric's first nodes at hmax 1.2: 1.5 to 1.8 away
    EXPECT_EQ(s.strips.size(), 2u) << "vertex " << s.vertex;
  }
  for (const auto& tip : geom::cusp_tips(*model, [](const Vec3&) { return 1e-3; })) EXPECT_FALSE(at.count(tip.vertex));
  for (const double hmax : {1.0, 1.2}) {
    size::SizeOptions so;
    so.hmax = hmax;
    const auto size = size::build_size_field(*model, so);
    generate::VolumeMeshStats st;
    mesh::TetMesh m = generate::mesh_volume(*model, *size.field, {}, &st);
    EXPECT_TRUE(st.tips.empty());
    for (const auto& s : spans) {
      const Vec3 p = model->vertex_point(s.vertex);
      for (const auto& e : m.edges) {
        const Vec3 a = m.coords[e.verts[0]], b = m.coords[e.verts[1]];
        if (a == p || b == p) {
          EXPECT_GE((a - b).norm(), s.radius * (1 - 1e-6)) << "edge " << e.edge_tag << " at hmax " << hmax;
        }
      }
      for (VertId v = 0; v < m.num_verts(); ++v) {
        const auto c = m.vert_class[v];
        if (c.dim == 2 && std::binary_search(s.strips.begin(), s.strips.end(), c.tag)) {
          EXPECT_GE((m.coords[v] - p).norm(), s.radius) << "face " << c.tag << " at hmax " << hmax;
        }
      }
    }
    optimize::ImproveOptions io;
    io.model = model.get();
    optimize::improve_quality(m, io);
    EXPECT_TRUE(mesh::validate(m, mesh::Level::kFull).valid());
    double worst = 180;
    for (TetId t = 0; t < m.num_tets(); ++t) worst = std::min(worst, min_dihedral(m, t));
    EXPECT_GE(worst, 10.0) << "hmax " << hmax;
  }
}
