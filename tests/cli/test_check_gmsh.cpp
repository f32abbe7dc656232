// `check` against an independent checker: Gmsh's own report on the meshes it
// makes (node counts, and its count of P2 elements with a negative Jacobian),
// and the 1M-tet lossless conversion round trip.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <regex>

#include <nlohmann/json.hpp>

#include "cli_runner.hpp"
#include "curvemesh/io/mesh_io.hpp"

using namespace cm;
using cm::test::run_cli;
using cm::test::run_command;

namespace {

bool have_gmsh() { return std::string(CM_GMSH_EXECUTABLE).size() > 0; }

std::string model(const std::string& name) { return std::string(CM_SHARED_DIR) + "/models/" + name; }

struct GmshRun {
  std::string log;
  int nodes = -1;
  int negative_jacobians = 0;
  double worst_distortion = 1;
};

GmshRun run_gmsh(const std::string& args, const std::string& out) {
  const auto r = run_command(std::string(CM_GMSH_EXECUTABLE) + " " + args + " -o " + out);
  GmshRun g;
  g.log = r.output;
  std::smatch m;
  const std::regex nodes(R"(Info\s*:\s*(\d+) nodes \d+ elements)");
  for (auto it = std::sregex_iterator(g.log.begin(), g.log.end(), nodes); it != std::sregex_iterator(); ++it)
    g.nodes = std::stoi((*it)[1]);
  const std::regex dist(R"(Volume mesh: worst distortion = ([-0-9.e+]+) \(avg = [-0-9.e+]+, (\d+) elements with jac\. < 0\))");
  if (std::regex_search(g.log, m, dist)) {
    g.worst_distortion = std::stod(m[1]);
    g.negative_jacobians = std::stoi(m[2]);
  }
  return g;
}

struct CheckRun {
  int exit_code;
  nlohmann::json report;
  std::string output;
};

CheckRun check(const std::string& mesh, const std::string& dir) {
  const auto r = run_cli("check " + mesh + " --json " + dir + "/report.json");
  CheckRun c{r.exit_code, {}, r.output};
  if (std::filesystem::exists(dir + "/report.json"))
    c.report = nlohmann::json::parse(test::read_text(dir + "/report.json"));
  return c;
}

}  // namespace

TEST(CheckVsGmsh, LinearMeshesOfRealModelsAreValid) {
  if (!have_gmsh()) GTEST_SKIP() << "gmsh not installed";
  for (const auto& [file, h] : {std::pair<std::string, std::string>{"t20_data.step", "4"}, {"Zylkopf.stp", "2"},
                                {"ring.brep", "80"}}) {
    const std::string dir = test::make_temp_dir("gmsh");
    const GmshRun g = run_gmsh("-3 " + model(file) + " -setnumber Mesh.MeshSizeFromCurvature 12 -setnumber Mesh.MeshSizeMax " + h,
                               dir + "/m.msh");
    ASSERT_GT(g.nodes, 0) << g.log;
    const CheckRun c = check(dir + "/m.msh", dir);
    EXPECT_EQ(c.exit_code, 0) << file << "\n" << c.output;
    EXPECT_EQ(c.report["counts"]["vertices"].get<int>(), g.nodes) << file;
    EXPECT_GT(c.report["quality"]["min_dihedral_deg"]["min"].get<double>(), 0.0);
    if (file == "ring.brep") {
      EXPECT_EQ(c.report["model_entities"]["regions"].get<int>(), 2);
    }
  }
}

TEST(CheckVsGmsh, SecondOrderMeshesWithFoldedElementsAreInvalid) {
  if (!have_gmsh()) GTEST_SKIP() << "gmsh not installed";
  // Coarse curvature-based sizes at which gmsh -order 2 leaves elements with
  // det J < 0 (its own count is the reference).
  for (const auto& [file, h] : {std::pair<std::string, std::string>{"Torus_1.brep", "80"}, {"Zylkopf.stp", "2"},
                                {"918_pump_carter_sup_21_03_2006.stp", "20"}}) {
    const std::string dir = test::make_temp_dir("gmsh");
    const GmshRun g = run_gmsh("-3 -order 2 " + model(file) +
                                   " -setnumber Mesh.MeshSizeFromCurvature 12 -setnumber Mesh.MeshSizeMax " + h,
                               dir + "/m.msh");
    ASSERT_GT(g.nodes, 0) << g.log;
    ASSERT_GT(g.negative_jacobians, 0) << "gmsh no longer folds elements on " << file;
    const CheckRun c = check(dir + "/m.msh", dir);
    EXPECT_EQ(c.exit_code, 1) << file << "\n" << c.output;
    EXPECT_EQ(c.report["counts"]["order"].get<int>(), 2);
    EXPECT_EQ(c.report["validity"]["inverted"].get<int>(), 0) << "the straight-sided tets are fine";
    EXPECT_EQ(c.report["curved"]["invalid"].get<int>(), g.negative_jacobians) << file;
    EXPECT_TRUE(c.report["curved"]["undetermined_tets"].empty());
    EXPECT_LT(c.report["curved"]["scaled_jacobian"]["min"].get<double>(), 0.0);
    EXPECT_LT(g.worst_distortion, 0.0);
  }
}

TEST(CheckVsGmsh, SecondOrderMeshOfFinerSizeIsValid) {
  if (!have_gmsh()) GTEST_SKIP() << "gmsh not installed";
  const std::string dir = test::make_temp_dir("gmsh");
  const GmshRun g = run_gmsh("-3 -order 2 " + model("Torus_1.brep") +
                                 " -setnumber Mesh.MeshSizeFromCurvature 12 -setnumber Mesh.MeshSizeMax 40",
                             dir + "/m.msh");
  ASSERT_EQ(g.negative_jacobians, 0) << g.log;
  const CheckRun c = check(dir + "/m.msh", dir);
  EXPECT_EQ(c.exit_code, 0) << c.output;
  EXPECT_GT(c.report["curved"]["scaled_jacobian"]["min"].get<double>(), 0.0);
}

TEST(ConvertLarge, MillionTetBinaryMshToMeditAndBackIsLossless) {
  if (!have_gmsh()) GTEST_SKIP() << "gmsh not installed";
  const std::string dir = test::make_temp_dir("big");
  {
    std::ofstream geo(dir + "/box.geo");
    geo << "SetFactory(\"OpenCASCADE\");\nBox(1) = {0,0,0,1,1,1};\nMesh.MeshSizeMax = 0.0155;\nMesh.MeshSizeMin = 0.0155;\n";
  }
  const GmshRun g = run_gmsh("-3 " + dir + "/box.geo -setnumber Mesh.Algorithm3D 10 -bin -format msh41", dir + "/a.msh");
  ASSERT_GT(g.nodes, 0) << g.log;
  ASSERT_EQ(run_cli("convert " + dir + "/a.msh " + dir + "/b.mesh").exit_code, 0);
  ASSERT_EQ(run_cli("convert " + dir + "/b.mesh " + dir + "/c.msh --binary").exit_code, 0);
  const mesh::TetMesh a = io::read_mesh(dir + "/a.msh");
  const mesh::TetMesh c = io::read_mesh(dir + "/c.msh");
  ASSERT_GE(a.num_tets(), 1000000u);
  ASSERT_EQ(a.num_verts(), c.num_verts());
  ASSERT_EQ(a.num_tets(), c.num_tets());
  EXPECT_TRUE(std::equal(a.coords.begin(), a.coords.end(), c.coords.begin()));
  EXPECT_TRUE(std::equal(a.tet2verts.begin(), a.tet2verts.end(), c.tet2verts.begin()));
  EXPECT_EQ(a.tet_region, c.tet_region);
  ASSERT_EQ(a.tris.size(), c.tris.size());
  for (std::size_t i = 0; i < a.tris.size(); ++i) {
    EXPECT_EQ(a.tris[i].verts, c.tris[i].verts);
    EXPECT_EQ(a.tris[i].face_tag, c.tris[i].face_tag);
  }
  ASSERT_EQ(a.edges.size(), c.edges.size());
  for (std::size_t v = 0; v < a.num_verts(); ++v) ASSERT_EQ(a.vert_class[v].dim, c.vert_class[v].dim) << v;
}
