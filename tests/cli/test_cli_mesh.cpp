// `curvemesh mesh --dim 2` as a user runs it: classified surface mesh out,
// summary and exit codes.
#include <gtest/gtest.h>

#include <set>

#include <nlohmann/json.hpp>

#include "cli_runner.hpp"
#include "curvemesh/io/atomic_file.hpp"
#include "curvemesh/io/formats.hpp"

using cm::test::run_cli;

TEST(CliMesh, SurfaceMeshOfABuiltinIsWrittenClassifiedAndChecked) {
  const std::string dir = cm::test::make_temp_dir("mesh");
  const auto r = run_cli("mesh builtin:cylinder --dim 2 -o " + dir + "/cyl.msh --json " + dir + "/cyl.json");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("check: valid"), std::string::npos) << r.output;
  const auto j = nlohmann::json::parse(cm::test::read_text(dir + "/cyl.json"));
  EXPECT_TRUE(j["check"]["valid"].get<bool>());
  // A surface mesh: read with the MSH reader itself (read_mesh wants tets).
  const cm::mesh::TetMesh m = cm::io::read_msh(cm::io::read_file_bytes(dir + "/cyl.msh"), dir + "/cyl.msh");
  EXPECT_EQ(m.tris.size(), j["counts"]["triangles"].get<std::size_t>());
  EXPECT_EQ(m.num_verts(), j["counts"]["vertices"].get<std::size_t>());
  std::set<int> faces;
  for (const auto& t : m.tris) faces.insert(t.face_tag);
  EXPECT_EQ(faces.size(), 3u);  // lateral face and two caps
  for (std::size_t v = 0; v < m.num_verts(); ++v) {
    ASSERT_TRUE(m.vert_class[v].valid());
    if (m.vert_class[v].dim == 2) {
      EXPECT_TRUE(m.vert_param[v].has_u());
    }
  }
  EXPECT_EQ(run_cli("mesh builtin:cylinder --dim 2 -q -o " + dir + "/cyl.vtu").exit_code, 0);
}

TEST(CliMesh, BadUseExitsTwo) {
  EXPECT_EQ(run_cli("mesh builtin:box").exit_code, 2);           // --dim is required
  EXPECT_EQ(run_cli("mesh builtin:box --dim 3").exit_code, 2);   // only the boundary mesh so far
  EXPECT_EQ(run_cli("mesh builtin:nosuch --dim 2").exit_code, 2);
}
