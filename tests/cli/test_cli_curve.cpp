// Curved meshes from the command line: `curvemesh mesh --order 2|3` and
// `curvemesh curve MESH --model M`, their files (10/20-node tets read back
// certified valid by `check`), summaries and exit codes.
#include <gtest/gtest.h>

#include <filesystem>

#include <nlohmann/json.hpp>

#include "cli_runner.hpp"
#include "curvemesh/io/mesh_io.hpp"

using cm::test::run_cli;

namespace {

nlohmann::json read_json(const std::string& path) { return nlohmann::json::parse(cm::test::read_text(path)); }

}  // namespace

TEST(CliCurve, MeshAtOrderTwoWritesCertifiedValidTenNodeTets) {
  const std::string dir = cm::test::make_temp_dir("curve");
  const auto r = run_cli("mesh builtin:holes --curv-alpha 0.25 --order 2 -o " + dir + "/h2.msh --json " + dir + "/h2.json");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("curving: order 2"), std::string::npos) << r.output;
  const auto j = read_json(dir + "/h2.json");
  const auto& c = j["curving"];
  EXPECT_GT(c["before"]["invalid"].get<int>(), 0);  // coarse holes: curving alone breaks tets
  EXPECT_EQ(c["after"]["invalid"].get<int>(), 0);
  EXPECT_EQ(c["after"]["unacceptable"].get<int>(), 0);
  EXPECT_GE(c["after"]["min_scaled_jacobian"].get<double>(), 0.1);
  const cm::mesh::TetMesh m = cm::io::read_mesh(dir + "/h2.msh");
  EXPECT_EQ(m.high_order.order(), 2);
  EXPECT_EQ(m.num_tets(), j["counts"]["tets"].get<std::size_t>());
  // `check` certifies what was written (nodes read back from the file).
  const auto chk = run_cli("check " + dir + "/h2.msh --json " + dir + "/check.json");
  EXPECT_EQ(chk.exit_code, 0) << chk.output;
  EXPECT_NE(chk.output.find("invalid (det J <= 0 somewhere): 0"), std::string::npos) << chk.output;
}

TEST(CliCurve, CurveRaisesOurOwnMeshToOrderThree) {
  const std::string dir = cm::test::make_temp_dir("curve");
  ASSERT_EQ(run_cli("mesh builtin:torus --curv-alpha 0.25 -q -o " + dir + "/t1.msh").exit_code, 0);
  const auto r = run_cli("curve " + dir + "/t1.msh --model builtin:torus --order 3 -o " + dir + "/t3.msh --json " +
                         dir + "/t3.json");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("every element certified valid and acceptable"), std::string::npos) << r.output;
  const auto j = read_json(dir + "/t3.json");
  EXPECT_EQ(j["curving"]["order"].get<int>(), 3);
  EXPECT_LT(j["curving"]["geometric_error"]["curved_max"].get<double>(),
            0.1 * j["curving"]["geometric_error"]["straight_max"].get<double>());
  EXPECT_EQ(cm::io::read_mesh(dir + "/t3.msh").high_order.order(), 3);
  // Lagrange cells for ParaView.
  EXPECT_EQ(run_cli("curve " + dir + "/t1.msh --model builtin:torus -q -o " + dir + "/t2.vtu").exit_code, 0);
  // Curving the order-3 output again (its nodes replaced) gives a valid mesh too.
  EXPECT_EQ(run_cli("curve " + dir + "/t3.msh --model builtin:torus --order 2 -q -o " + dir + "/again.msh").exit_code, 0);
}

TEST(CliCurve, BadUseGivesOneErrorAndExitTwo) {
  const std::string dir = cm::test::make_temp_dir("curve");
  ASSERT_EQ(run_cli("mesh builtin:box -q -o " + dir + "/b.msh").exit_code, 0);
  EXPECT_EQ(run_cli("mesh builtin:box --order 4 -q").exit_code, 2);
  EXPECT_EQ(run_cli("curve " + dir + "/b.msh --order 2 -q").exit_code, 2);  // no model
  EXPECT_EQ(run_cli("curve " + dir + "/b.msh --model builtin:box --order 1 -q").exit_code, 2);
  const auto missing = run_cli("curve " + dir + "/none.msh --model builtin:box -q -o " + dir + "/x.msh");
  EXPECT_EQ(missing.exit_code, 2);
  EXPECT_NE(missing.output.find("none.msh"), std::string::npos) << missing.output;
  EXPECT_FALSE(std::filesystem::exists(dir + "/x.msh"));
  EXPECT_EQ(run_cli("curve " + dir + "/b.msh --model builtin:nosuchshape -q").exit_code, 2);
}

// Gmsh's own order-2 mesh of a shared model, folded where the torus is
// coarse (Gmsh 4.8.4 leaves one certified-invalid tet at MeshSizeMax 80):
// `curve` classifies it on the model, replaces its nodes and repairs it.
TEST(CliCurve, GmshsFoldedOrderTwoMeshComesOutValid) {
  if (std::string(CM_GMSH_EXECUTABLE).empty()) GTEST_SKIP() << "gmsh is not installed";
  const std::string model = std::string(CM_SHARED_DIR) + "/models/Torus_1.brep";
  if (!std::filesystem::exists(model)) GTEST_SKIP() << "shared models not found";
  const std::string dir = cm::test::make_temp_dir("curve");
  const auto g = cm::test::run_command(std::string(CM_GMSH_EXECUTABLE) + " -3 -order 2 " + model +
                                       " -setnumber Mesh.MeshSizeFromCurvature 12 -setnumber Mesh.MeshSizeMax 80 -format "
                                       "msh41 -o " + dir + "/g.msh");
  ASSERT_EQ(g.exit_code, 0) << g.output;
  const auto r = run_cli("curve " + dir + "/g.msh --model " + model + " -o " + dir + "/c.msh --json " + dir + "/c.json");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto j = read_json(dir + "/c.json");
  EXPECT_GE(j["input_curved"]["invalid"].get<int>(), 1);
  EXPECT_EQ(j["curving"]["after"]["invalid"].get<int>(), 0);
  EXPECT_EQ(j["curving"]["after"]["unacceptable"].get<int>(), 0);
  EXPECT_EQ(run_cli("check " + dir + "/c.msh -q").exit_code, 0);
}
