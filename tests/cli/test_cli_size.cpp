// `curvemesh size` as a user runs it: summary, JSON, .vtu outputs, sources
// and the errors of bad options.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>

#include <nlohmann/json.hpp>

#include "cli_runner.hpp"
#include "curvemesh/io/formats.hpp"
#include "curvemesh/io/mesh_io.hpp"
#include "curvemesh/mesh/structured.hpp"

using cm::test::run_cli;

TEST(CliSize, SphereWithChordDeviationReportsEquation43AndWritesTheOctree) {
  const std::string dir = cm::test::make_temp_dir("size");
  const auto r = run_cli("size builtin:sphere:r=2 --curv-eps 0.01 --hmax 1 --hmin 0.001 -o " + dir +
                         "/size.vtu --samples-out " + dir + "/samples.vtu --json " + dir + "/size.json");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto j = nlohmann::json::parse(cm::test::read_text(dir + "/size.json"));
  const double expect = std::sqrt(8 * 2 * 0.01 - 4 * 0.01 * 0.01);
  EXPECT_NEAR(j["samples"]["size_range"][0].get<double>(), expect, 1e-6 * expect);
  EXPECT_NEAR(j["samples"]["size_range"][1].get<double>(), expect, 1e-6 * expect);
  EXPECT_EQ(j["curvature"].get<std::string>(), "eps=0.01");
  EXPECT_GT(j["octree"]["leaves"].get<int>(), 100);
  EXPECT_GT(j["octree"]["leaves_by_source"]["face curvature"].get<int>(), 0);
  const std::string vtu = cm::test::read_text(dir + "/size.vtu");
  EXPECT_NE(vtu.find("Name=\"source\""), std::string::npos);
  EXPECT_NE(vtu.find("NumberOfCells=\"" + std::to_string(j["octree"]["leaves"].get<int>()) + "\""), std::string::npos);
  EXPECT_NE(cm::test::read_text(dir + "/samples.vtu").find("Name=\"dir1\""), std::string::npos);
}

TEST(CliSize, EntitySizeExpressionAndBackgroundAreSources) {
  const std::string dir = cm::test::make_temp_dir("size");
  // A scalar background size of 0.05 on a box around the unit cube.
  const cm::mesh::TetMesh bg =
      cm::mesh::make_box_mesh({2, 2, 2}, cm::Vec3::Constant(-0.5), cm::Vec3::Constant(1.5), false);
  cm::io::write_mesh(bg, dir + "/bg.mesh");
  cm::io::SolField sol;
  sol.values.assign(bg.num_verts(), 0.05);
  cm::io::write_sol(sol, dir + "/bg.sol", false);
  auto r = run_cli("size builtin:box --no-curvature --hmax 0.3 --background " + dir + "/bg.mesh --background-sol " +
                   dir + "/bg.sol --json " + dir + "/a.json -q");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_TRUE(r.output.empty()) << r.output;
  auto j = nlohmann::json::parse(cm::test::read_text(dir + "/a.json"));
  EXPECT_GT(j["octree"]["leaves_by_source"]["size field"].get<int>(), 0);

  r = run_cli("size builtin:box --no-curvature --hmax 0.3 --size face:1=0.02 --size-expr '0.1+0.1*x' --json " + dir +
              "/b.json -q");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  j = nlohmann::json::parse(cm::test::read_text(dir + "/b.json"));
  EXPECT_GT(j["octree"]["leaves_by_source"]["entity size"].get<int>(), 0);
  EXPECT_GT(j["octree"]["leaves_by_source"]["size field"].get<int>(), 0);
}

TEST(CliSize, RegionSizeRefinesTheNamedRegionOnly) {
  const std::string dir = cm::test::make_temp_dir("size");
  // builtin:blocks: two unit cubes side by side along x, sharing x = 1.
  auto r = run_cli("size builtin:blocks --no-curvature --hmax 0.4 --size region:1=0.05 --json " + dir +
                   "/one.json -o " + dir + "/one.vtu -q");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  auto j = nlohmann::json::parse(cm::test::read_text(dir + "/one.json"));
  // Inside: the region field; on its faces: the entity-size samples.
  EXPECT_GT(j["octree"]["leaves_by_source"]["size field"].get<int>(), 0);
  EXPECT_GT(j["octree"]["leaves_by_source"]["entity size"].get<int>(), 0);
  EXPECT_GT(j["octree"]["leaves_by_source"]["gradation"].get<int>(), 0);
  const int one_region = j["octree"]["leaves_by_source"]["size field"].get<int>();
  r = run_cli("size builtin:blocks --no-curvature --hmax 0.4 --size 3:1=0.05 --size region:2=0.05 --json " + dir +
              "/both.json -q");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  j = nlohmann::json::parse(cm::test::read_text(dir + "/both.json"));
  // Twice the volume at size 0.05: about twice the interior leaves.
  EXPECT_GT(j["octree"]["leaves_by_source"]["size field"].get<int>(), 1.8 * one_region);
}

TEST(CliSize, MissingRegionIsOneLineAndExitTwo) {
  const std::string dir = cm::test::make_temp_dir("size");
  const auto r = run_cli("size builtin:blocks --size region:3=0.1 -o " + dir + "/out.vtu");
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_EQ(r.output,
            "curvemesh: error: size on region 3: the model has no such entity (region tags are 1..2)\n");
  EXPECT_FALSE(std::filesystem::exists(dir + "/out.vtu"));
  EXPECT_NE(run_cli("size --help").output.find("region"), std::string::npos);
}

TEST(CliSize, BadOptionsGiveOneErrorAndExitTwo) {
  const std::string dir = cm::test::make_temp_dir("size");
  { std::ofstream(dir + "/short.sol") << "MeshVersionFormatted 2\nDimension 3\nSolAtVertices\n1\n1 1\n0.1\nEnd\n"; }
  const cm::mesh::TetMesh bg = cm::mesh::make_box_mesh({1, 1, 1}, cm::Vec3::Zero(), cm::Vec3::Ones(), false);
  cm::io::write_mesh(bg, dir + "/bg.mesh");
  const struct {
    std::string args, expect;
  } cases[] = {
      {"builtin:box --size face:99=0.1", "no such entity"},
      {"builtin:box --size cell:1=0.1", "expected DIM:TAG=H"},
      {"builtin:box --size region:2=0.1", "size on region 2: the model has no such entity (region tags are 1..1)"},
      {"builtin:box --size region:99999999999=0.1", "integer >= 1"},
      {"builtin:box --size face:1=-2", "finite and > 0"},
      {"builtin:box --size-expr 'sin(x'", "--size-expr"},
      {"builtin:box --size-expr '0-1'", "finite and > 0"},
      {"builtin:box --hmin 1 --hmax 0.1", "hmin"},
      {"builtin:box --curv-alpha 0.7", "curv-alpha"},
      {"builtin:box --curv-eps 0.1 --curv-alpha 0.1", "excludes"},
      {"builtin:box --background " + dir + "/bg.mesh --background-sol " + dir + "/short.sol", "short.sol"},
      {"builtin:box --background " + dir + "/bg.mesh", "requires"},
      {dir + "/missing.step", "no such file"},
  };
  for (const auto& c : cases) {
    const auto r = run_cli("size " + c.args + " -o " + dir + "/out.vtu");
    EXPECT_EQ(r.exit_code, 2) << c.args << "\n" << r.output;
    EXPECT_NE(r.output.find(c.expect), std::string::npos) << c.args << "\n" << r.output;
    EXPECT_FALSE(std::filesystem::exists(dir + "/out.vtu")) << c.args;
  }
}
