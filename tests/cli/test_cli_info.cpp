// `curvemesh info` as a user runs it: description, JSON, and bad input.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <numbers>

#include <nlohmann/json.hpp>

#include "cli_runner.hpp"

using cm::test::run_cli;

namespace {
int line_count(const std::string& s) { return static_cast<int>(std::count(s.begin(), s.end(), '\n')); }
}  // namespace

TEST(CliInfo, TorusJsonHasExactCountsMassAndCurvatureRange) {
  const std::string dir = cm::test::make_temp_dir("info");
  const auto r = run_cli("info builtin:torus:R=3,r=1 --json " + dir + "/t.json");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("1 regions, 1 faces"), std::string::npos) << r.output;
  EXPECT_EQ(r.output.find("-0,"), std::string::npos) << "negative zero printed:\n" << r.output;
  const auto j = nlohmann::json::parse(cm::test::read_text(dir + "/t.json"));
  EXPECT_EQ(j["counts"]["regions"].get<int>(), 1);
  EXPECT_EQ(j["counts"]["faces"].get<int>(), 1);
  const double pi = std::numbers::pi;
  EXPECT_NEAR(j["volume"].get<double>(), 2 * pi * pi * 3 * 1, 1e-6);
  EXPECT_NEAR(j["area"].get<double>(), 4 * pi * pi * 3 * 1, 1e-6);
  const auto& f = j["faces"][0];
  EXPECT_EQ(f["type"].get<std::string>(), "torus");
  // Tube curvature 1/r = 1; the other ranges over cos(v)/(R + r cos v) in [-1/2, 1/4].
  EXPECT_NEAR(f["curvature"]["max"].get<double>(), 1.0, 1e-9);
  EXPECT_NEAR(f["curvature"]["min"].get<double>(), -0.5, 0.01);
  const auto& bb = j["bounding_box"];
  EXPECT_NEAR(bb["max"][0].get<double>(), 4.0, 1e-6);
  EXPECT_NEAR(bb["max"][2].get<double>(), 1.0, 1e-6);
  EXPECT_GT(j["edges"].size(), 0u);
}

TEST(CliInfo, RealModelCountsMatchItsTable) {
  const std::string path = std::string(CM_SHARED_DIR) + "/models/Zylkopf.stp";
  const auto r = run_cli("info " + path);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("units: mm"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("1 regions, 137 faces, 404 edges, 270 vertices"), std::string::npos) << r.output;
}

TEST(CliInfo, BadInputsGiveOneErrorLineAndExitTwo) {
  const std::string dir = cm::test::make_temp_dir("info");
  { std::ofstream(dir + "/empty.step"); }
  { std::ofstream(dir + "/text.step") << "this is not a STEP file\n"; }
  {
    // A B-rep cut in the middle of its geometry section.
    const std::string full = cm::test::read_text(std::string(CM_SHARED_DIR) + "/models/ring.brep");
    std::ofstream(dir + "/broken.brep") << full.substr(0, full.size() / 3);
  }
  {
    std::ofstream out(dir + "/nosolid.step");
    out << "ISO-10303-21;\nHEADER;\nFILE_DESCRIPTION((''),'2;1');\nFILE_NAME('x','',(''),(''),'','','');\n"
           "FILE_SCHEMA(('AUTOMOTIVE_DESIGN'));\nENDSEC;\nDATA;\n#1=CARTESIAN_POINT('',(0.,0.,0.));\nENDSEC;\n"
           "END-ISO-10303-21;\n";
  }
  const struct {
    std::string arg, expect;
  } cases[] = {
      {dir + "/missing.step", "no such file"},
      {dir + "/empty.step", "empty file"},
      {dir + "/text.step", "not a STEP file"},
      {dir + "/broken.brep", "broken.brep"},
      {dir + "/nosolid.step", "nosolid.step"},
      {"builtin:nosuch", "unknown built-in model"},
      {"builtin:sphere:R=-1", "builtin:sphere"},
  };
  for (const auto& c : cases) {
    const auto r = run_cli("info " + c.arg);
    EXPECT_EQ(r.exit_code, 2) << c.arg << "\n" << r.output;
    EXPECT_NE(r.output.find(c.expect), std::string::npos) << c.arg << "\n" << r.output;
    EXPECT_EQ(line_count(r.output), 1) << c.arg << "\n" << r.output;
  }
  EXPECT_EQ(run_cli("info").exit_code, 2);
  EXPECT_EQ(run_cli("info --help").exit_code, 0);
}

// STEP, IGES, the built-ins and the fuse of several solids are plugins loaded
// on first use (geom_occ/detail/plugin.hpp): a single-solid B-rep needs none,
// a missing plugin is one clear error, and plugins found through
// CURVEMESH_PLUGIN_DIR work from anywhere.
TEST(CliInfo, PluginsLoadOnlyWhenTheInputNeedsThem) {
  namespace fs = std::filesystem;
  const std::string empty = cm::test::make_temp_dir("no_plugins");
  const std::string models = std::string(CM_SHARED_DIR) + "/models/";
  const std::string without = "env CURVEMESH_PLUGIN_DIR=" + empty + " ";
  const std::string cli = std::string(CM_CLI_EXECUTABLE) + " ";

  const auto brep = cm::test::run_command(without + cli + "info " + models + "full_sphere.brep");
  EXPECT_EQ(brep.exit_code, 0) << brep.output;

  const auto step = cm::test::run_command(without + cli + "info " + models + "t20_data.step");
  EXPECT_EQ(step.exit_code, 3) << step.output;
  EXPECT_NE(step.output.find("cannot load the STEP reader"), std::string::npos) << step.output;
  EXPECT_NE(step.output.find(empty), std::string::npos) << "the error names the path tried:\n" << step.output;

  const auto builtin = cm::test::run_command(without + cli + "info builtin:box");
  EXPECT_EQ(builtin.exit_code, 3) << builtin.output;
  EXPECT_NE(builtin.output.find("cannot load the built-in shapes"), std::string::npos) << builtin.output;

  // The STEP plugin alone, copied elsewhere, is enough for a STEP model.
  const fs::path built = fs::path(CM_CLI_EXECUTABLE).parent_path() / "plugins" / "libcurvemesh_occ_step.so";
  ASSERT_TRUE(fs::exists(built)) << built;
  const std::string moved = cm::test::make_temp_dir("moved_plugins");
  fs::copy_file(built, fs::path(moved) / built.filename());
  const auto relocated = cm::test::run_command("env CURVEMESH_PLUGIN_DIR=" + moved + " " + cli + "info " + models +
                                               "t20_data.step");
  EXPECT_EQ(relocated.exit_code, 0) << relocated.output;
}
