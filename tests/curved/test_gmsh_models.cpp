// Gmsh's own order-2 meshes of every shared model (about the diagonal / 15,
// MeshSizeFromCurvature 12: the coarse curved meshes where Gmsh leaves
// certified-invalid elements), read, classified on the model and curved by
// curvemesh at orders 2 and 3: not one element left certified invalid or
// unacceptable, the straight mesh still valid on its model.
#include <filesystem>
#include <fstream>

#include <gtest/gtest.h>

#include "../common/gmsh_support.hpp"
#include "curved_support.hpp"
#include "curvemesh/generate/classify_on_model.hpp"
#include "curvemesh/io/mesh_io.hpp"
#include "curvemesh/mesh/adjacency.hpp"
#include "curvemesh/mesh/validate.hpp"

namespace cm::test {
namespace {

class CurvedGmshModels : public ::testing::TestWithParam<const char*> {};

TEST_P(CurvedGmshModels, GmshsOrderTwoMeshCurvedByUsEndsValidAndAcceptable) {
  if (!have_gmsh()) GTEST_SKIP() << "gmsh is not installed";
  const std::string file = model_path(GetParam());
  if (!std::filesystem::exists(file)) GTEST_SKIP() << "no shared model " << file;
  const auto model = geom_occ::load_model(file);
  // One conforming mesh of several solids is what Gmsh's Coherence gives.
  const std::string dir = make_temp_dir("curved_gmsh");
  std::string input = file;
  if (model->count(3) > 1) {
    input = dir + "/coherent.geo";
    std::ofstream(input) << "SetFactory(\"OpenCASCADE\");\nMerge \"" << file << "\";\nCoherence;\n";
  }
  double h = 0;
  const std::string path = gmsh_order2_mesh(input, *model, dir, h);
  ASSERT_FALSE(path.empty()) << "gmsh failed to mesh " << file;
  mesh::TetMesh gmsh = io::read_mesh(path);
  ASSERT_EQ(gmsh.high_order.order(), 2);
  const std::size_t gmsh_invalid = curved::check_mesh(gmsh, {}).invalid.size();
  mesh::build_adjacency(gmsh);
  generate::classify_on_model(gmsh, *model, {path});
  for (int order : {2, 3}) {
    mesh::TetMesh m = gmsh;
    curved::CurveOptions o;
    o.order = order;
    const curved::CurveReport r = curved::curve_mesh(m, *model, o);
    std::printf("%s H=%.4g order %d: %zu tets, Gmsh's own nodes %zu invalid; ours %zu unacceptable before repair, "
                "%zu invalid / %zu unacceptable after, min scaled Jacobian %.3f, %zu edges straightened\n",
                GetParam(), h, order, m.num_tets(), gmsh_invalid, r.unacceptable_before, r.after.invalid.size(),
                r.after.unacceptable.size(), r.after.min_scaled_jacobian, r.repair.edges_straightened);
    EXPECT_EQ(r.after.invalid.size(), 0u) << "order " << order;
    EXPECT_EQ(r.after.unacceptable.size(), 0u) << "order " << order;
    EXPECT_TRUE(mesh::validate(m, mesh::Level::kFull).valid()) << "order " << order;
  }
}

INSTANTIATE_TEST_SUITE_P(Models, CurvedGmshModels,
                         ::testing::Values("1385_Laufrad_1000.stp", "917_fusee.stp", "918_pump_carter_sup_21_03_2006.stp",
                                           "SampleCrankshaft4A.stp", "Torus_1.brep", "Zylkopf.stp", "dlr_f6.brep",
                                           "full_sphere.brep", "metallmeister_gear.step", "ring.brep",
                                           "t20_data.step"),
                         [](const auto& param_info) {
                           std::string s = param_info.param;
                           for (char& c : s)
                             if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
                           return s;
                         });

}  // namespace
}  // namespace cm::test
