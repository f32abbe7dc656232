// The curvemesh program as a user runs it: exit codes, messages, outputs.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include <nlohmann/json.hpp>

#include "cli_runner.hpp"
#include "curvemesh/io/mesh_io.hpp"
#include "curvemesh/mesh/adjacency.hpp"
#include "curvemesh/mesh/structured.hpp"

using namespace cm;
using cm::test::run_cli;

namespace {
mesh::TetMesh box(int n) { return mesh::make_box_mesh({n, n, n}, Vec3(0, 0, 0), Vec3(1, 2, 3), true); }
}  // namespace

TEST(Cli, UsageErrorsExitWithTwo) {
  EXPECT_EQ(run_cli("").exit_code, 2);
  EXPECT_EQ(run_cli("frobnicate").exit_code, 2);
  EXPECT_EQ(run_cli("check").exit_code, 2);
  EXPECT_EQ(run_cli("check --help").exit_code, 0);
  EXPECT_EQ(run_cli("convert --help").exit_code, 0);
  const auto r = run_cli("check a.msh --no-such-option");
  EXPECT_EQ(r.exit_code, 2);
}

TEST(Cli, UnreadableInputExitsWithTwoAndNamesTheFile) {
  const std::string dir = test::make_temp_dir("cli");
  auto r = run_cli("check " + dir + "/missing.msh");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.output.find("missing.msh"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("cannot open"), std::string::npos) << r.output;

  r = run_cli("check " + dir + "/mesh.stl");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.output.find("unknown file extension"), std::string::npos) << r.output;

  { std::ofstream(dir + "/empty.msh"); }
  r = run_cli("check " + dir + "/empty.msh");
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("empty.msh"), std::string::npos) << r.output;
  // One line of error, no crash report.
  EXPECT_EQ(std::count(r.output.begin(), r.output.end(), '\n'), 1) << r.output;
}

TEST(Cli, CheckValidMeshExitsZeroAndWritesJson) {
  const std::string dir = test::make_temp_dir("cli");
  io::write_mesh(box(4), dir + "/box.msh");
  const auto r = run_cli("check " + dir + "/box.msh --json " + dir + "/report.json");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("VALID"), std::string::npos);
  const auto j = nlohmann::json::parse(test::read_text(dir + "/report.json"));
  EXPECT_TRUE(j["valid"].get<bool>());
  EXPECT_EQ(j["counts"]["tets"].get<int>(), 6 * 64);
  EXPECT_EQ(j["counts"]["vertices"].get<int>(), 125);
  EXPECT_EQ(j["model_entities"]["faces"].get<int>(), 6);
  EXPECT_EQ(j["model_entities"]["edges"].get<int>(), 12);
  EXPECT_EQ(j["model_entities"]["vertices"].get<int>(), 8);
  EXPECT_EQ(j["validity"]["inverted"].get<int>(), 0);
  EXPECT_GT(j["quality"]["mean_ratio"]["min"].get<double>(), 0.4);  // cells of 1:2:3 aspect
}

TEST(Cli, CheckListsInvertedTetsAndExitsOne) {
  const std::string dir = test::make_temp_dir("cli");
  mesh::TetMesh m = box(3);
  std::swap(m.tet2verts[17][2], m.tet2verts[17][3]);
  io::write_mesh(m, dir + "/bad.mesh");
  const auto r = run_cli("check " + dir + "/bad.mesh --json " + dir + "/report.json");
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("INVALID"), std::string::npos);
  EXPECT_NE(r.output.find("tet 17 is inverted"), std::string::npos) << r.output;
  const auto j = nlohmann::json::parse(test::read_text(dir + "/report.json"));
  EXPECT_FALSE(j["valid"].get<bool>());
  EXPECT_EQ(j["validity"]["inverted"].get<int>(), 1);
  EXPECT_EQ(j["validity"]["inverted_tets"][0].get<int>(), 17);
}

TEST(Cli, ConvertRoundTripsThroughEveryFormat) {
  const std::string dir = test::make_temp_dir("cli");
  const mesh::TetMesh m = box(3);
  io::write_mesh(m, dir + "/a.msh");
  ASSERT_EQ(run_cli("convert " + dir + "/a.msh " + dir + "/b.mesh").exit_code, 0);
  ASSERT_EQ(run_cli("convert " + dir + "/b.mesh " + dir + "/c.meshb").exit_code, 0);
  ASSERT_EQ(run_cli("convert " + dir + "/c.meshb " + dir + "/d.msh --binary").exit_code, 0);
  ASSERT_EQ(run_cli("convert " + dir + "/d.msh " + dir + "/e.vtu").exit_code, 0);
  const mesh::TetMesh back = io::read_mesh(dir + "/d.msh");
  ASSERT_EQ(back.num_verts(), m.num_verts());
  ASSERT_EQ(back.num_tets(), m.num_tets());
  for (std::size_t v = 0; v < m.num_verts(); ++v) EXPECT_EQ(back.coords[v], m.coords[v]);
  for (std::size_t t = 0; t < m.num_tets(); ++t) EXPECT_EQ(back.tet2verts[t], m.tet2verts[t]);
  EXPECT_EQ(back.tris.size(), m.tris.size());
  for (std::size_t v = 0; v < m.num_verts(); ++v) EXPECT_EQ(back.vert_class[v].dim, m.vert_class[v].dim);
  EXPECT_TRUE(std::filesystem::file_size(dir + "/e.vtu") > 0);
}

TEST(Cli, FailedWriteLeavesNoPartialFile) {
  const std::string dir = test::make_temp_dir("cli");
  io::write_mesh(box(2), dir + "/a.msh");
  const auto r = run_cli("convert " + dir + "/a.msh " + dir + "/no_such_dir/out.msh");
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("out.msh"), std::string::npos) << r.output;
  // Writing a P2 mesh's output into an unsupported target leaves nothing either.
  EXPECT_FALSE(std::filesystem::exists(dir + "/no_such_dir"));
  for (const auto& entry : std::filesystem::directory_iterator(dir))
    EXPECT_EQ(entry.path().filename().string().find(".tmp-"), std::string::npos);
}
