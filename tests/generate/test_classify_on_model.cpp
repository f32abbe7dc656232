// classify_on_model: exact counts on structured boxes, curvemesh's own meshes
// of the builtins (with their tags scrambled, merged and split) and of every
// shared model through MSH given back exactly as written, Gmsh's meshes of
// every shared model (orders 1 and 2) passing the boundary check, physical
// groups, a Gmsh mesh whose seam is not the model's, meshes of other models,
// and the optimize command on a Gmsh mesh with --model.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>

#include <fmt/format.h>

#include "cli_runner.hpp"
#include "../common/gmsh_support.hpp"
#include "curvemesh/core/error.hpp"
#include "curvemesh/core/timer.hpp"
#include "curvemesh/generate/boundary_check.hpp"
#include "curvemesh/generate/classify_on_model.hpp"
#include "curvemesh/generate/volume_mesh.hpp"
#include "curvemesh/geom_occ/load.hpp"
#include "curvemesh/io/mesh_io.hpp"
#include "curvemesh/mesh/adjacency.hpp"
#include "curvemesh/mesh/classification.hpp"
#include "curvemesh/mesh/structured.hpp"
#include "curvemesh/mesh/validate.hpp"
#include "curvemesh/size/build.hpp"
#include "curvemesh/size/size_field.hpp"

using namespace cm;

namespace {

std::string models_dir() { return std::string(CM_SHARED_DIR) + "/models"; }

std::string summary(const generate::ModelClassification& c) {
  std::string s = fmt::format(
      "{} boundary tris, {} input faces ({} whole), {} searched, {} flipped; vertices {} / {} / {} / {} (model "
      "vertex/edge/face/inside); {} mesh edges on model edges; changed: {} vertices, {} tris, {} edges, {} tets; "
      "max distance {:.3g} ({:.3g} of tolerance); {:.3f} s",
      c.boundary_triangles, c.input_faces, c.input_faces_whole, c.triangles_searched, c.triangles_flipped,
      c.vertices_on_model_vertices, c.vertices_on_model_edges, c.vertices_on_model_faces, c.interior_vertices,
      c.mesh_edges_on_model_edges, c.vertices_changed, c.triangles_changed, c.edges_changed, c.tets_changed,
      c.max_distance, c.max_relative_distance, c.seconds);
  for (const auto& p : c.problems) s += "\n  problem: " + p;
  return s;
}

// What a reader of a foreign file gives: no vertex classification or
// parameters, no model edges, the input's own triangle tags, regions
// renumbered, classification derived from the mesh alone.
enum class Scramble { kPermute, kOneTag, kSplit };
void make_foreign(mesh::TetMesh& m, Scramble how) {
  for (auto& t : m.tris) {
    const Vec3 c = (m.coords[t.verts[0]] + m.coords[t.verts[1]] + m.coords[t.verts[2]]) / 3;
    switch (how) {
      case Scramble::kPermute: t.face_tag = 1000 - t.face_tag; break;
      case Scramble::kOneTag: t.face_tag = 1; break;
      // Every face in two input faces, and pairs of faces merged.
      case Scramble::kSplit: t.face_tag = 10 + t.face_tag / 2 + (c.x() + 0.37 * c.y() > 0.1 ? 100 : 0); break;
    }
    std::swap(t.verts[1], t.verts[2]);
  }
  m.edges.clear();
  m.entities.clear();
  for (auto& r : m.tet_region) r += 40;
  std::fill(m.vert_class.begin(), m.vert_class.end(), mesh::ModelRef{});
  std::fill(m.vert_param.begin(), m.vert_param.end(), mesh::Param{});
  mesh::derive_classification(m);
}

using TriSet = std::set<std::pair<std::array<VertId, 3>, int>>;
// Oriented: rotated to start at the smallest vertex.
TriSet tri_set(const mesh::TetMesh& m) {
  TriSet s;
  for (const auto& t : m.tris) {
    auto v = t.verts;
    std::rotate(v.begin(), std::min_element(v.begin(), v.end()), v.end());
    s.insert({v, t.face_tag});
  }
  return s;
}
std::set<std::tuple<VertId, VertId, int>> edge_set(const mesh::TetMesh& m) {
  std::set<std::tuple<VertId, VertId, int>> s;
  for (const auto& e : m.edges) s.insert({std::min(e.verts[0], e.verts[1]), std::max(e.verts[0], e.verts[1]), e.edge_tag});
  return s;
}

// Parameters equal up to round-off, or a period on periodic entities.
bool same_param(double a, double b, bool periodic, double period, double scale) {
  if (std::isnan(a) || std::isnan(b)) return std::isnan(a) && std::isnan(b);
  double d = std::abs(a - b);
  if (periodic && period > 0) d = std::min(d, std::abs(d - period));
  return d <= 1e-9 * std::max(1.0, scale);
}

// After classifying a foreign copy of `original` (curvemesh's own mesh),
// everything curvemesh wrote is back.
void expect_same_classification(const mesh::TetMesh& original, const mesh::TetMesh& m, const geom::Model& model) {
  ASSERT_EQ(original.num_verts(), m.num_verts());
  std::size_t wrong_class = 0, wrong_param = 0;
  for (VertId v = 0; v < m.num_verts(); ++v) {
    const mesh::ModelRef c = original.vert_class[v];
    if (m.vert_class[v] != c) {
      if (++wrong_class <= 5)
        ADD_FAILURE() << "vertex " << v << " at " << m.coords[v].transpose() << ": (" << m.vert_class[v].dim << ", "
                      << m.vert_class[v].tag << ") instead of (" << c.dim << ", " << c.tag << ")";
      continue;
    }
    if (c.dim != 1 && c.dim != 2) continue;
    const geom::ParamRange r = model.param_range({c.dim, c.tag});
    const double scale = std::max({std::abs(r.u0), std::abs(r.u1), std::abs(r.v0), std::abs(r.v1)});
    const bool ok = same_param(m.vert_param[v].u, original.vert_param[v].u, r.periodic_u, r.period_u, scale) &&
                    (c.dim == 1 || same_param(m.vert_param[v].v, original.vert_param[v].v, r.periodic_v, r.period_v, scale));
    if (!ok && ++wrong_param <= 5)
      ADD_FAILURE() << "vertex " << v << " on (" << c.dim << ", " << c.tag << "): param (" << m.vert_param[v].u << ", "
                    << m.vert_param[v].v << ") instead of (" << original.vert_param[v].u << ", "
                    << original.vert_param[v].v << ")";
  }
  EXPECT_EQ(wrong_class, 0u);
  EXPECT_EQ(wrong_param, 0u);
  EXPECT_TRUE(tri_set(m) == tri_set(original)) << "boundary triangles, their tags or orientation differ";
  EXPECT_TRUE(edge_set(m) == edge_set(original)) << "m.edges differ";
  EXPECT_EQ(m.tet_region, original.tet_region);
  ASSERT_EQ(m.entities.size(), original.entities.size());
  for (std::size_t i = 0; i < m.entities.size(); ++i) {
    EXPECT_EQ(m.entities[i].dim, original.entities[i].dim);
    EXPECT_EQ(m.entities[i].tag, original.entities[i].tag);
    EXPECT_EQ(m.entities[i].bounding, original.entities[i].bounding) << "entity (" << m.entities[i].dim << ", " << m.entities[i].tag << ")";
  }
}

// Parameters inside their entity's range, periodic directions wrapped into
// [u0, u0 + period): what the curving step interpolates between neighbours.
std::size_t params_out_of_range(const mesh::TetMesh& m, const geom::Model& model) {
  std::size_t out = 0;
  const auto inside = [](double t, double lo, double hi, bool periodic, double period) {
    if (periodic && period > 0) return t >= lo && t < lo + period;
    const double slack = 1e-9 * std::max(1.0, hi - lo);
    return t >= lo - slack && t <= hi + slack;
  };
  for (VertId v = 0; v < m.num_verts(); ++v) {
    const mesh::ModelRef c = m.vert_class[v];
    if (c.dim != 1 && c.dim != 2) continue;
    const geom::ParamRange r = model.param_range({c.dim, c.tag});
    const bool ok = inside(m.vert_param[v].u, r.u0, r.u1, r.periodic_u, r.period_u) &&
                    (c.dim == 1 || inside(m.vert_param[v].v, r.v0, r.v1, r.periodic_v, r.period_v));
    if (!ok && ++out <= 3)
      ADD_FAILURE() << "vertex " << v << " on (" << c.dim << ", " << c.tag << "): (" << m.vert_param[v].u << ", "
                    << m.vert_param[v].v << ") outside [" << r.u0 << ", " << r.u1 << "] x [" << r.v0 << ", " << r.v1
                    << "]";
  }
  return out;
}

void expect_valid_on_model(const mesh::TetMesh& m, const geom::Model& model, double h) {
  EXPECT_EQ(params_out_of_range(m, model), 0u);
  const auto rep = mesh::validate(m, mesh::Level::kFull);
  EXPECT_TRUE(rep.valid()) << rep.num_issues << " issues, first: " << (rep.issues.empty() ? "" : rep.issues.front().message);
  const size::UniformSizeField size(h);
  const generate::BoundaryReport b = generate::check_boundary(model, m, size);
  EXPECT_EQ(b.vertices_off_entity, 0u) << "max " << b.max_vertex_distance << " of tolerance; "
                                        << (b.problems.empty() ? "" : b.problems.front());
  EXPECT_EQ(b.folded_triangles, 0u) << (b.problems.empty() ? "" : b.problems.front());
  EXPECT_EQ(b.open_region_edges, 0u);
  EXPECT_EQ(b.unmeshed_faces, 0u);
}

}  // namespace

// --- exact counts ------------------------------------------------------------

TEST(ClassifyOnModel, StructuredBoxExactCounts) {
  // A 4^3 Kuhn box read as a foreign mesh would be: one tag for the whole
  // hull, so every triangle is placed on its own.
  const auto model = geom_occ::load_model("builtin:box");
  mesh::TetMesh m = mesh::make_box_mesh({4, 4, 4}, Vec3(0, 0, 0), Vec3(1, 1, 1), false);
  m.resize_vertex_arrays();
  mesh::build_adjacency(m);
  mesh::derive_classification(m);
  const auto c = generate::classify_on_model(m, *model);
  SCOPED_TRACE(summary(c));
  EXPECT_EQ(c.boundary_triangles, 6u * 16 * 2);
  EXPECT_EQ(c.input_faces, 1u);
  EXPECT_EQ(c.input_faces_whole, 0u);
  EXPECT_EQ(c.triangles_searched, 6u * 16 * 2);
  EXPECT_EQ(c.vertices_on_model_vertices, 8u);
  EXPECT_EQ(c.vertices_on_model_edges, 12u * 3);
  EXPECT_EQ(c.vertices_on_model_faces, 6u * 9);
  EXPECT_EQ(c.interior_vertices, 27u);
  EXPECT_EQ(c.mesh_edges_on_model_edges, 12u * 4);
  EXPECT_EQ(c.num_problems, 0u);
  EXPECT_EQ(c.max_distance, 0.0);
  // Each model face takes exactly one side of the box.
  std::map<int, std::set<std::pair<int, double>>> sides;  // face -> (axis, value)
  for (const auto& t : m.tris)
    for (int k = 0; k < 3; ++k)
      if (m.coords[t.verts[0]][k] == m.coords[t.verts[1]][k] && m.coords[t.verts[1]][k] == m.coords[t.verts[2]][k])
        sides[t.face_tag].insert({k, m.coords[t.verts[0]][k]});
  EXPECT_EQ(sides.size(), 6u);
  for (const auto& [face, s] : sides) EXPECT_EQ(s.size(), 1u) << "face " << face;
  expect_valid_on_model(m, *model, 0.25);
}

TEST(ClassifyOnModel, StructuredBoxTagsMapOneToOne) {
  // make_box_mesh's own tags (-x, +x, -y, +y, -z, +z = 1..6) name other faces
  // than the model's: a permutation, each input face whole.
  const auto model = geom_occ::load_model("builtin:box:dx=2,dy=1,dz=0.5");
  mesh::TetMesh m = mesh::make_box_mesh({6, 3, 2}, Vec3(0, 0, 0), Vec3(2, 1, 0.5), true);
  const auto c = generate::classify_on_model(m, *model);
  SCOPED_TRACE(summary(c));
  EXPECT_EQ(c.input_faces, 6u);
  EXPECT_EQ(c.input_faces_whole, 6u);
  EXPECT_EQ(c.triangles_searched, 0u);
  ASSERT_EQ(c.face_map.size(), 6u);
  std::set<int> targets;
  for (const auto& f : c.face_map) {
    EXPECT_EQ(f.others, 0u);
    targets.insert(f.model);
  }
  EXPECT_EQ(targets.size(), 6u);
  EXPECT_EQ(c.vertices_on_model_vertices, 8u);
  EXPECT_EQ(c.vertices_on_model_edges, 4u * (5 + 2 + 1));
  EXPECT_EQ(c.mesh_edges_on_model_edges, 4u * (6 + 3 + 2));
  EXPECT_EQ(c.num_problems, 0u);
  expect_valid_on_model(m, *model, 0.3);
}

// --- curvemesh's own meshes ------------------------------------------------

struct BuiltinCase {
  const char* spec;
  double hmax;
  Scramble how;
  std::size_t model_vertices;
};

void PrintTo(const BuiltinCase& c, std::ostream* os) { *os << c.spec << " hmax " << c.hmax; }

class OwnMesh : public ::testing::TestWithParam<BuiltinCase> {};

std::string builtin_case_name(const ::testing::TestParamInfo<BuiltinCase>& p) {
  return std::string(p.param.spec).substr(8) + "_" + std::to_string(p.index);
}

TEST_P(OwnMesh, GivesBackItsClassification) {
  const BuiltinCase& bc = GetParam();
  const auto model = geom_occ::load_model(bc.spec);
  const size::UniformSizeField size(bc.hmax);
  const mesh::TetMesh original = generate::mesh_volume(*model, size);
  mesh::TetMesh m = original;
  make_foreign(m, bc.how);
  const auto c = generate::classify_on_model(m, *model);
  SCOPED_TRACE(summary(c));
  EXPECT_EQ(c.vertices_on_model_vertices, bc.model_vertices);
  EXPECT_EQ(c.mesh_edges_on_model_edges, original.edges.size());
  EXPECT_EQ(c.boundary_triangles, original.tris.size());
  EXPECT_EQ(c.num_problems, 0u);
  // curvemesh's vertices are its entities evaluated at their parameters:
  // only Newton's round-off is left.
  EXPECT_LT(c.max_distance, 1e-14 * model->bounding_box().diagonal());
  if (bc.how == Scramble::kPermute) {
    EXPECT_EQ(c.input_faces_whole, static_cast<std::size_t>(model->count(2)));
    EXPECT_EQ(c.triangles_searched, 0u);
  }
  EXPECT_EQ(c.triangles_flipped, original.tris.size()) << "make_foreign reversed every triangle";
  expect_same_classification(original, m, *model);
  expect_valid_on_model(m, *model, bc.hmax);
}

INSTANTIATE_TEST_SUITE_P(
    Builtins, OwnMesh,
    ::testing::Values(BuiltinCase{"builtin:box", 0.3, Scramble::kPermute, 8},
                      BuiltinCase{"builtin:box", 0.3, Scramble::kOneTag, 8},
                      BuiltinCase{"builtin:cylinder", 0.4, Scramble::kPermute, 2},
                      BuiltinCase{"builtin:cylinder", 0.4, Scramble::kSplit, 2},
                      BuiltinCase{"builtin:torus", 0.35, Scramble::kPermute, 1},
                      BuiltinCase{"builtin:torus", 0.35, Scramble::kSplit, 1},
                      BuiltinCase{"builtin:sphere", 0.3, Scramble::kPermute, 2},
                      BuiltinCase{"builtin:sphere", 0.3, Scramble::kOneTag, 2},
                      BuiltinCase{"builtin:blocks", 0.3, Scramble::kSplit, 12},
                      BuiltinCase{"builtin:inclusion", 0.35, Scramble::kPermute, 10}),
    builtin_case_name);

TEST(ClassifyOnModel, PhysicalGroupsFollowTheirElements) {
  const auto model = geom_occ::load_model("builtin:cylinder");
  const mesh::TetMesh original = generate::mesh_volume(*model, size::UniformSizeField(0.4));
  mesh::TetMesh m = original;
  make_foreign(m, Scramble::kPermute);  // input face 1000 - f is model face f
  for (auto& e : m.entities) {
    if (e.dim == 2) e.physicals = {10 + 1000 - e.tag};
    if (e.dim == 3) e.physicals = {99};
    if (e.dim == 3) e.name = "solid";
  }
  auto c = generate::classify_on_model(m, *model);
  EXPECT_EQ(c.num_problems, 0u) << summary(c);
  for (const auto& e : m.entities) {
    if (e.dim == 2) {
      EXPECT_EQ(e.physicals, std::vector<std::int32_t>{10 + e.tag}) << "face " << e.tag;
    } else if (e.dim == 3) {
      EXPECT_EQ(e.physicals, std::vector<std::int32_t>{99});
      EXPECT_EQ(e.name, "solid");
    }
  }
  // Two input faces with different groups onto one model face: both
  // groups, and a warning.
  m = original;
  make_foreign(m, Scramble::kSplit);
  for (auto& e : m.entities)
    if (e.dim == 2) e.physicals = {e.tag};
  c = generate::classify_on_model(m, *model);
  ASSERT_GT(c.num_problems, 0u);
  EXPECT_NE(c.problems.front().find("with different physical groups"), std::string::npos) << c.problems.front();
}

class OwnMshFile : public ::testing::TestWithParam<const char*> {};

std::string model_case_name(const ::testing::TestParamInfo<const char*>& p) {
  std::string n = p.param;
  n = n.substr(0, n.find('.'));
  for (char& ch : n)
    if (!std::isalnum(static_cast<unsigned char>(ch))) ch = '_';
  return n;
}

TEST_P(OwnMshFile, GivesBackItsClassification) {
  // The whole path a user takes: curvemesh's mesh of a shared model written
  // to MSH 4.1, read back, classified again: nothing changes.
  const std::string file = models_dir() + "/" + GetParam();
  if (!std::filesystem::exists(file)) GTEST_SKIP() << "no shared model " << file;
  const auto model = geom_occ::load_model(file);
  size::SizeOptions so;  // curvature-graded, as `curvemesh mesh --hmax` sizes it
  so.hmax = model->bounding_box().diagonal() / 15;
  const size::SizeFieldResult size = size::build_size_field(*model, so);
  const mesh::TetMesh original = generate::mesh_volume(*model, *size.field);
  const std::string dir = test::make_temp_dir("classify_own");
  io::write_mesh(original, dir + "/own.msh");
  mesh::TetMesh m = io::read_mesh(dir + "/own.msh");
  const auto c = generate::classify_on_model(m, *model, {dir + "/own.msh"});
  SCOPED_TRACE(summary(c));
  EXPECT_EQ(c.vertices_changed, 0u);
  EXPECT_EQ(c.triangles_changed, 0u);
  EXPECT_EQ(c.triangles_flipped, 0u);
  EXPECT_EQ(c.edges_changed, 0u);
  EXPECT_EQ(c.tets_changed, 0u);
  EXPECT_EQ(c.num_problems, 0u);
  expect_same_classification(original, m, *model);
}

// --- Gmsh's meshes of the shared models --------------------------------------

namespace {

// Classifies Gmsh's mesh at orders 2 and 1 and checks the boundary. Where the
// regions were meshed each on its own (Gmsh without Coherence), the faces
// they share are reported as not conforming, and nothing else.
void check_gmsh_mesh(const std::string& name, const std::string& path, double h, const geom::Model& model,
                     bool conforming) {
  mesh::TetMesh order2 = io::read_mesh(path);
  ASSERT_EQ(order2.high_order.order(), 2);
  // Gmsh's order-1 mesh is its order-2 mesh without the edge nodes (the
  // same vertices: high-order optimization is off by default).
  mesh::TetMesh order1 = order2;
  order1.high_order.reset(1);
  std::size_t shared_faces = 0;
  for (int f = 1; f <= model.count(2); ++f) shared_faces += model.upward({2, f}).size() > 1;
  for (mesh::TetMesh* m : {&order2, &order1}) {
    SCOPED_TRACE(fmt::format("{} order {} H={:.4g}", name, m->high_order.order(), h));
    const auto c = generate::classify_on_model(*m, model, {path});
    std::printf("%s order %d H=%.4g: %zu tets, %s\n", name.c_str(), m->high_order.order(), h, m->num_tets(),
                summary(c).c_str());
    if (conforming) {
      EXPECT_EQ(c.num_problems, 0u) << summary(c);
    } else {
      EXPECT_EQ(c.num_problems, shared_faces) << summary(c);
      for (const auto& p : c.problems) EXPECT_NE(p.find("does not conform"), std::string::npos) << p;
    }
    EXPECT_LE(c.max_relative_distance, 1.0);
    expect_valid_on_model(*m, model, h);
  }
  // Both orders agree: the edge nodes only help.
  EXPECT_EQ(order1.vert_class, order2.vert_class);
  EXPECT_TRUE(tri_set(order1) == tri_set(order2));
  EXPECT_TRUE(edge_set(order1) == edge_set(order2));
}

}  // namespace

class GmshMesh : public ::testing::TestWithParam<const char*> {};

TEST_P(GmshMesh, ClassifiedBoundaryPassesTheCheck) {
  if (!test::have_gmsh()) GTEST_SKIP() << "gmsh is not on PATH";
  const std::string file = models_dir() + "/" + GetParam();
  if (!std::filesystem::exists(file)) GTEST_SKIP() << "no shared model " << file;
  const auto model = geom_occ::load_model(file);
  const std::string dir = test::make_temp_dir("classify_gmsh");
  double h = 0;
  std::string path = test::gmsh_order2_mesh(file, *model, dir, h);
  ASSERT_FALSE(path.empty()) << "gmsh failed to mesh " << file;
  check_gmsh_mesh(GetParam(), path, h, *model, model->count(3) == 1);
  if (model->count(3) > 1) {
    // What a user wanting one conforming mesh of several solids runs.
    std::ofstream(dir + "/coherent.geo") << "SetFactory(\"OpenCASCADE\");\nMerge \"" << file << "\";\nCoherence;\n";
    path = test::gmsh_order2_mesh(dir + "/coherent.geo", *model, dir, h);
    ASSERT_FALSE(path.empty()) << "gmsh failed to mesh " << file << " with Coherence";
    check_gmsh_mesh(std::string(GetParam()) + " with Coherence", path, h, *model, true);
  }
}

const auto kSharedModels =
    ::testing::Values("1385_Laufrad_1000.stp", "917_fusee.stp", "918_pump_carter_sup_21_03_2006.stp",
                      "SampleCrankshaft4A.stp", "Torus_1.brep", "Zylkopf.stp", "dlr_f6.brep", "full_sphere.brep",
                      "metallmeister_gear.step", "ring.brep", "t20_data.step");
INSTANTIATE_TEST_SUITE_P(SharedModels, OwnMshFile, kSharedModels, model_case_name);
INSTANTIATE_TEST_SUITE_P(SharedModels, GmshMesh, kSharedModels, model_case_name);

// --- meshes of another model --------------------------------------------------

TEST(ClassifyOnModel, MeshOfAnotherModelIsOneClearError) {
  const auto box = geom_occ::load_model("builtin:box");
  const auto cylinder = geom_occ::load_model("builtin:cylinder");
  mesh::TetMesh m = generate::mesh_volume(*cylinder, size::UniformSizeField(0.4));
  const mesh::TetMesh before = m;
  try {
    generate::classify_on_model(m, *box, {"cylinder.msh"});
    FAIL() << "no error";
  } catch (const InputError& e) {
    const std::string what = e.what();
    EXPECT_EQ(e.file(), "cylinder.msh");
    EXPECT_NE(what.find("not of this model"), std::string::npos) << what;
    EXPECT_NE(what.find("bounding box"), std::string::npos) << what;
  }
  // Nothing was changed.
  EXPECT_EQ(m.vert_class, before.vert_class);
  EXPECT_TRUE(tri_set(m) == tri_set(before));
  EXPECT_EQ(m.tet_region, before.tet_region);
}

TEST(ClassifyOnModel, MeshOfASlightlyDifferentModelNamesAVertexOffIt) {
  // The regions agree (the centroids are inside), the boundary does not.
  const auto thinner = geom_occ::load_model("builtin:cylinder:r=0.98");
  const auto cylinder = geom_occ::load_model("builtin:cylinder");
  mesh::TetMesh m = generate::mesh_volume(*cylinder, size::UniformSizeField(0.4));
  try {
    generate::classify_on_model(m, *thinner, {"cylinder.msh"});
    FAIL() << "no error";
  } catch (const InputError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("not of this model"), std::string::npos) << what;
    EXPECT_NE(what.find("lies on no model face: its vertex at"), std::string::npos) << what;
  }
}

TEST(ClassifyOnModel, MeshInOtherUnitsNamesTheScale) {
  const auto box = geom_occ::load_model("builtin:box");
  mesh::TetMesh m = mesh::make_box_mesh({3, 3, 3}, Vec3(0, 0, 0), Vec3(25.4, 25.4, 25.4), true);
  try {
    generate::classify_on_model(m, *box);
    FAIL() << "no error";
  } catch (const InputError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("25.4 times the size of the model"), std::string::npos) << what;
  }
}

TEST(ClassifyOnModel, GmshMeshOfAnotherShapeIsOneClearError) {
  if (!test::have_gmsh()) GTEST_SKIP() << "gmsh is not on PATH";
  const std::string t20 = models_dir() + "/t20_data.step", zyl = models_dir() + "/Zylkopf.stp";
  if (!std::filesystem::exists(t20) || !std::filesystem::exists(zyl)) GTEST_SKIP() << "no shared models";
  const auto model = geom_occ::load_model(zyl);
  const std::string dir = test::make_temp_dir("classify_other");
  const auto r = test::run_command(fmt::format("{} -3 -nt 1 -setnumber Mesh.MeshSizeMax 4 '{}' -o '{}/t20.msh' -format msh41",
                                               CM_GMSH_EXECUTABLE, t20, dir));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  mesh::TetMesh m = io::read_mesh(dir + "/t20.msh");
  EXPECT_THROW(generate::classify_on_model(m, *model, {dir + "/t20.msh"}), InputError);
}

TEST(ClassifyOnModel, GmshMeshWithItsSeamElsewhere) {
  // The same cylinder as builtin:cylinder, turned by 60 degrees about its
  // axis: Gmsh's seam and circle vertices are not the model's. Its vertices
  // there go on the model's face and circles, and what the mesh lacks (a
  // mesh of the model's seam, vertices at the model's vertices) is reported.
  if (!test::have_gmsh()) GTEST_SKIP() << "gmsh is not on PATH";
  const std::string dir = test::make_temp_dir("classify_seam");
  std::ofstream(dir + "/cylinder.geo") << "SetFactory(\"OpenCASCADE\");\nCylinder(1) = {0, 0, 0, 0, 0, 2, 1};\n"
                                          "Rotate {{0, 0, 1}, {0, 0, 0}, Pi/3} { Volume{1}; }\n";
  const auto r = test::run_command(fmt::format("{} -3 -nt 1 -order 2 -setnumber Mesh.MeshSizeMax 0.3 '{}/cylinder.geo' "
                                               "-o '{}/cylinder.msh' -format msh41",
                                               CM_GMSH_EXECUTABLE, dir, dir));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto model = geom_occ::load_model("builtin:cylinder");
  mesh::TetMesh m = io::read_mesh(dir + "/cylinder.msh");
  const auto c = generate::classify_on_model(m, *model);
  SCOPED_TRACE(summary(c));
  EXPECT_EQ(c.vertices_on_model_vertices, 0u);
  EXPECT_EQ(c.num_problems, 3u);
  std::size_t seam = 0, corners = 0;
  for (const auto& p : c.problems) {
    seam += p.find("has no mesh edge") != std::string::npos;
    corners += p.find("has no mesh vertex") != std::string::npos;
  }
  EXPECT_EQ(seam, 1u);
  EXPECT_EQ(corners, 2u);
  expect_valid_on_model(m, *model, 0.3);
}

// --- the optimize command ------------------------------------------------------

TEST(ClassifyOnModel, OptimizeGmshMeshWithModel) {
  if (!test::have_gmsh()) GTEST_SKIP() << "gmsh is not on PATH";
  const std::string file = models_dir() + "/Zylkopf.stp";
  if (!std::filesystem::exists(file)) GTEST_SKIP() << "no shared model " << file;
  const std::string dir = test::make_temp_dir("classify_optimize");
  auto r = test::run_command(fmt::format(
      "{} -3 -nt 1 -setnumber Mesh.Optimize 0 -setnumber Mesh.MeshSizeFromCurvature 12 -setnumber Mesh.MeshSizeMax 2 "
      "'{}' -o '{}/in.msh' -format msh41",
      CM_GMSH_EXECUTABLE, file, dir));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  r = test::run_cli(fmt::format("optimize {0}/in.msh --model '{1}' -o {0}/out.msh --json {0}/r.json", dir, file));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("classified on the model"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("check: valid"), std::string::npos) << r.output;
  // The output carries the model's classification: classifying it again
  // changes nothing, and its boundary is on the model.
  const auto model = geom_occ::load_model(file);
  mesh::TetMesh out = io::read_mesh(dir + "/out.msh");
  const auto c = generate::classify_on_model(out, *model);
  SCOPED_TRACE(summary(c));
  EXPECT_EQ(c.vertices_changed, 0u);
  EXPECT_EQ(c.triangles_changed, 0u);
  EXPECT_EQ(c.edges_changed, 0u);
  EXPECT_EQ(c.num_problems, 0u);
  expect_valid_on_model(out, *model, 2);
}
