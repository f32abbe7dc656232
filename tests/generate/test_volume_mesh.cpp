// The volume mesher end to end on built-in shapes and shared models: valid
// (positive, conforming, classification consistent), every boundary triangle
// a face of exactly one tet (or two at a region interface), Steiner points on
// the model, volume equal to the model's (exactly for planar faces, within
// the chord error for curved ones), interior sizes near the size field.
#include <gtest/gtest.h>

#include <filesystem>
#include <map>

#include "curvemesh/generate/boundary_check.hpp"
#include "curvemesh/generate/volume_mesh.hpp"
#include "curvemesh/geom_occ/load.hpp"
#include "curvemesh/mesh/adjacency.hpp"
#include "curvemesh/mesh/validate.hpp"
#include "curvemesh/optimize/improve.hpp"
#include "curvemesh/size/build.hpp"

using namespace cm;

namespace {

struct Meshed {
  std::unique_ptr<geom::Model> model;
  size::SizeFieldResult size;
  mesh::TetMesh m;
  generate::VolumeMeshStats st;
};

Meshed mesh_model(const std::string& spec, double hmax = 0) {
  Meshed r;
  r.model = geom_occ::load_model(spec);
  size::SizeOptions so;
  so.hmax = hmax;
  r.size = size::build_size_field(*r.model, so);
  r.m = generate::mesh_volume(*r.model, *r.size.field, {}, &r.st);
  return r;
}

double mesh_volume_of(const mesh::TetMesh& m) {
  double v = 0;
  for (TetId t = 0; t < m.num_tets(); ++t) v += mesh::tet_volume(m, t);
  return v;
}

double model_volume(const geom::Model& g) {
  double v = 0;
  for (int r = 1; r <= g.count(3); ++r) v += g.volume(r);
  return v;
}

void expect_valid(const Meshed& r) {
  const auto& m = r.m;
  const auto rep = mesh::validate(m, mesh::Level::kFull);
  ASSERT_TRUE(rep.valid()) << rep.num_issues << " issues, first: "
                           << (rep.issues.empty() ? "" : rep.issues.front().message);
  const auto b = generate::check_boundary(*r.model, m, *r.size.field);
  EXPECT_EQ(b.vertices_off_entity, 0u);
  EXPECT_EQ(b.folded_triangles, 0u);
  EXPECT_EQ(b.open_region_edges, 0u);
  for (TetId t = 0; t < m.num_tets(); ++t) {
    ASSERT_GE(m.tet_region[t], 1);
    ASSERT_LE(m.tet_region[t], r.model->count(3));
  }
  EXPECT_EQ(r.st.region_conflicts, 0u);
}

}  // namespace

TEST(VolumeMesh, BoxVolumeIsExact) {
  const auto r = mesh_model("builtin:box");
  expect_valid(r);
  EXPECT_NEAR(mesh_volume_of(r.m), 1.0, 1e-9);
  EXPECT_GT(r.st.interior_points, 100u);
}

TEST(VolumeMesh, PlanarPartVolumeIsExactAtTwoSizes) {
  // builtin:box with a finer and a coarser hmax: planar faces, so the volume
  // is the model's to round-off whatever the size.
  for (double h : {0.05, 0.3}) {
    const auto r = mesh_model("builtin:box", h);
    expect_valid(r);
    EXPECT_NEAR(mesh_volume_of(r.m), 1.0, 1e-9) << "hmax " << h;
  }
}

TEST(VolumeMesh, CurvedBuiltinsAreValidAndCloseInVolume) {
  for (const char* spec : {"builtin:sphere", "builtin:torus", "builtin:cylinder", "builtin:part", "builtin:cone"}) {
    SCOPED_TRACE(spec);
    const auto r = mesh_model(spec);
    expect_valid(r);
    // Default curvature sizing (alpha = 0.04: chord/length) bounds the
    // relative volume error to a few percent.
    const double v = model_volume(*r.model);
    EXPECT_NEAR(mesh_volume_of(r.m), v, 0.03 * v);
  }
}

TEST(VolumeMesh, InteriorEdgesFollowTheSizeField) {
  const auto r = mesh_model("builtin:box", 0.1);
  // Mean interior edge length within [0.6, 1.4] of the requested size.
  double sum = 0;
  std::size_t n = 0;
  for (const auto& tv : r.m.tet2verts)
    for (const auto& e : mesh::kTetEdges) {
      const Vec3 a = r.m.coords[tv[e[0]]], b = r.m.coords[tv[e[1]]];
      sum += (a - b).norm() / r.size.field->size(0.5 * (a + b));
      ++n;
    }
  const double mean = sum / static_cast<double>(n);
  EXPECT_GT(mean, 0.6);
  EXPECT_LT(mean, 1.4);
}

TEST(VolumeMesh, SteinerPointsStayOnTheModel) {
  // The sphere's pole fans need recovery: Steiner points appear and the
  // boundary check (vertices on their entity at their parameters) holds.
  const auto r = mesh_model("builtin:sphere");
  expect_valid(r);
  std::map<int, int> by_dim;
  for (const auto& c : r.m.vert_class) ++by_dim[c.dim];
  EXPECT_GT(by_dim[2], 0);
  EXPECT_GT(by_dim[3], 0);
}

TEST(VolumeMesh, SharedModels) {
  const std::string dir = std::string(CM_SHARED_DIR) + "/models/";
  for (const char* name : {"Torus_1.brep", "full_sphere.brep", "t20_data.step"}) {
    SCOPED_TRACE(name);
    if (!std::filesystem::exists(dir + name)) GTEST_SKIP() << "shared models not found";
    const auto r = mesh_model(dir + name);
    expect_valid(r);
    const double v = model_volume(*r.model);
    EXPECT_NEAR(mesh_volume_of(r.m), v, 0.03 * v);
  }
}

TEST(VolumeMesh, OptimizationRemovesSliversAndKeepsEverythingElse) {
  for (const char* spec : {"builtin:torus", "builtin:part"}) {
    SCOPED_TRACE(spec);
    auto r = mesh_model(spec);
    const double vol = mesh_volume_of(r.m);
    const auto tris = r.m.tris;
    const auto st = optimize::improve_quality(r.m);
    expect_valid(r);
    EXPECT_NEAR(mesh_volume_of(r.m), vol, 1e-10 * vol);
    EXPECT_EQ(r.m.tris.size(), tris.size());
    EXPECT_GT(st.min_after, st.min_before);
    EXPECT_LT(st.below_after, st.below_before);
  }
}
