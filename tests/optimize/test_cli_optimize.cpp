// `curvemesh optimize` as a user runs it: round trips through .mesh and
// .msh, the JSON summary, size maps and metrics from .sol files, and the
// errors for bad input with their exit codes.
#include <gtest/gtest.h>

#include <algorithm>
#include <map>
#include <set>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "cli_runner.hpp"
#include "curvemesh/geom_occ/load.hpp"
#include "curvemesh/io/atomic_file.hpp"
#include "curvemesh/io/formats.hpp"
#include "curvemesh/io/mesh_io.hpp"
#include "curvemesh/mesh/validate.hpp"
#include "curvemesh/optimize/adapt.hpp"
#include "perturbed_box.hpp"

using namespace cm;
using cm::test::run_cli;

namespace {

std::multiset<std::pair<std::array<VertId, 3>, std::int32_t>> tagged_tris(const mesh::TetMesh& m) {
  std::multiset<std::pair<std::array<VertId, 3>, std::int32_t>> s;
  for (const auto& t : m.tris) {
    auto k = t.verts;
    std::sort(k.begin(), k.end());
    s.emplace(k, t.face_tag);
  }
  return s;
}

// Runs optimize on a perturbed box written as `ext`, checks the output
// against the input and returns the JSON summary.
nlohmann::json round_trip(const std::string& ext, const std::string& extra = "", bool adapt = false) {
  const std::string dir = test::make_temp_dir("optimize");
  const auto in = test::perturbed_box(5, 3, 0.45, 12);
  const std::string in_path = dir + "/in" + ext, out_path = dir + "/out" + ext, json = dir + "/r.json";
  io::write_mesh(in, in_path);
  const auto r = run_cli("optimize " + in_path + " -o " + out_path + " --json " + json + " " + extra);
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("check: valid"), std::string::npos) << r.output;
  const auto reread_in = io::read_mesh(in_path);
  const auto out = io::read_mesh(out_path);
  EXPECT_TRUE(mesh::validate(out, mesh::Level::kFull).valid());
  if (!adapt) {
    // Point insertion may append region vertices; the others keep their ids.
    EXPECT_GE(out.num_verts(), in.num_verts());
    EXPECT_TRUE(tagged_tris(out) == tagged_tris(reread_in)) << "boundary triangles or their tags changed";
    for (VertId v = 0; v < reread_in.num_verts(); ++v)
      if (reread_in.vert_class[v].dim != 3) {
        EXPECT_EQ(out.coords[v], reread_in.coords[v]);
      }
  } else {
    // Boundary vertices stay where they were (new ones may come, on the
    // same planar faces), and every face tag is still there.
    std::set<std::array<double, 3>> out_points;
    for (VertId v = 0; v < out.num_verts(); ++v) out_points.insert({out.coords[v].x(), out.coords[v].y(), out.coords[v].z()});
    for (VertId v = 0; v < reread_in.num_verts(); ++v)
      if (reread_in.vert_class[v].dim != 3) {
        const Vec3& x = reread_in.coords[v];
        EXPECT_TRUE(out_points.count({x.x(), x.y(), x.z()})) << "boundary vertex " << v << " moved or went";
      }
    std::set<std::int32_t> tags_in, tags_out;
    for (const auto& t : reread_in.tris) tags_in.insert(t.face_tag);
    for (const auto& t : out.tris) tags_out.insert(t.face_tag);
    EXPECT_EQ(tags_in, tags_out);
  }
  std::multiset<std::int32_t> regions_in(reread_in.tet_region.begin(), reread_in.tet_region.end());
  std::set<std::int32_t> region_tags_out(out.tet_region.begin(), out.tet_region.end());
  EXPECT_EQ(region_tags_out, std::set<std::int32_t>(regions_in.begin(), regions_in.end()));
  const auto before = optimize::summarize_mesh(reread_in), after = optimize::summarize_mesh(out);
  EXPECT_GT(after.min_mean_ratio, before.min_mean_ratio);
  EXPECT_GT(after.min_dihedral, before.min_dihedral);
  EXPECT_EQ(after.inverted, 0u);
  EXPECT_NEAR(after.volume, before.volume, 1e-12 * before.volume);
  return nlohmann::json::parse(test::read_text(json));
}

}  // namespace

TEST(CliOptimize, MeditRoundTrip) {
  const auto j = round_trip(".mesh");
  EXPECT_EQ(j["mode"], "isotropic");
  EXPECT_TRUE(j["valid"].get<bool>());
  EXPECT_GT(j["after"]["mean_ratio_min"].get<double>(), j["before"]["mean_ratio_min"].get<double>());
  EXPECT_GT(j["after"]["min_dihedral_deg"].get<double>(), j["before"]["min_dihedral_deg"].get<double>());
  EXPECT_GT(j["operators"]["relocations"].get<int>(), 0);
  EXPECT_EQ(j["after"]["inverted"].get<int>(), 0);
}

TEST(CliOptimize, GmshRoundTripAndSizeMap) {
  const auto j = round_trip(".msh", "--hmax 0.12 --hmin 0.05", true);
  EXPECT_EQ(j["mode"], "size map");
  // Cells of 0.2 asked to be at most 0.12: splits, and most lengths end in range.
  EXPECT_GT(j["operators"]["splits"].get<int>(), 100);
  EXPECT_GT(j["lengths_after"]["percent_in_0_7_1_4"].get<double>(),
            j["lengths_before"]["percent_in_0_7_1_4"].get<double>() + 20);
  EXPECT_GT(j["after"]["tets"].get<int>(), j["before"]["tets"].get<int>());
  EXPECT_TRUE(j.contains("lengths_after"));
  EXPECT_EQ(j["lengths_after"]["edges"].get<int>(),
            j["lengths_after"]["in_0_7_1_4"].get<int>() + j["lengths_after"]["too_short"].get<int>() +
                j["lengths_after"]["too_long"].get<int>());
}

TEST(CliOptimize, AnisotropicSolAndSolOut) {
  const std::string dir = test::make_temp_dir("optimize");
  const auto m = test::perturbed_box(4, 9, 0.4, 6, 8.0);
  io::write_mesh(m, dir + "/in.mesh");
  io::SolField sol;
  sol.type = io::SolField::Type::kTensor;
  for (VertId v = 0; v < m.num_verts(); ++v) sol.values.insert(sol.values.end(), {16, 0, 16, 0, 0, 0.25});
  io::write_sol(sol, dir + "/in.sol", false);
  const auto r = run_cli("optimize " + dir + "/in.mesh --sol " + dir + "/in.sol -o " + dir + "/out.mesh --sol-out " +
                         dir + "/out.sol --json " + dir + "/r.json");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto j = nlohmann::json::parse(test::read_text(dir + "/r.json"));
  EXPECT_EQ(j["mode"], "anisotropic");
  EXPECT_GT(j["after"]["metric_quality_min"].get<double>(), j["before"]["metric_quality_min"].get<double>());
  const auto out_sol = io::read_sol(io::read_file_bytes(dir + "/out.sol"), dir + "/out.sol");
  EXPECT_EQ(out_sol.type, io::SolField::Type::kTensor);
  EXPECT_EQ(out_sol.num_verts(), io::read_mesh(dir + "/out.mesh").num_verts());
  EXPECT_GT(j["operators"]["splits"].get<int>(), 0);  // diagonals of 1.41 and 1.73 in the metric
}

TEST(CliOptimize, SolWithWrongCountIsRefused) {
  const std::string dir = test::make_temp_dir("optimize");
  const auto m = test::perturbed_box(3, 1, 0.2, 0);
  io::write_mesh(m, dir + "/in.mesh");
  io::SolField sol;
  sol.values = {0.1, 0.2, 0.3};
  io::write_sol(sol, dir + "/sizes.sol", false);
  const auto r = run_cli("optimize " + dir + "/in.mesh --sol " + dir + "/sizes.sol -o " + dir + "/out.mesh");
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("sizes.sol"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find(fmt::format("3 sizes for the {} vertices", m.num_verts())), std::string::npos) << r.output;
  EXPECT_EQ(std::count(r.output.begin(), r.output.end(), '\n'), 1) << r.output;
  EXPECT_FALSE(std::filesystem::exists(dir + "/out.mesh"));
}

TEST(CliOptimize, BadInputsExitWithTwo) {
  const std::string dir = test::make_temp_dir("optimize");
  auto m = test::perturbed_box(3, 1, 0.2, 0);
  // An inverted tet: the input is not a valid mesh.
  std::swap(m.tet2verts[0][0], m.tet2verts[0][1]);
  io::write_mesh(m, dir + "/inverted.mesh");
  auto r = run_cli("optimize " + dir + "/inverted.mesh -o " + dir + "/out.mesh");
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("not valid"), std::string::npos) << r.output;
  EXPECT_FALSE(std::filesystem::exists(dir + "/out.mesh"));
  r = run_cli("optimize " + dir + "/missing.mesh -o " + dir + "/out.mesh");
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("missing.mesh"), std::string::npos) << r.output;
  r = run_cli("optimize " + dir + "/inverted.mesh");  // no -o
  EXPECT_EQ(r.exit_code, 2) << r.output;
  r = run_cli("optimize " + dir + "/inverted.mesh -o x.mesh --hmin 2 --hmax 1");
  EXPECT_EQ(r.exit_code, 2) << r.output;
}

TEST(CliOptimize, HminLargerThanHmaxIsAnError) {
  const std::string dir = test::make_temp_dir("optimize");
  io::write_mesh(test::perturbed_box(3, 1, 0.2, 0), dir + "/in.mesh");
  const auto r = run_cli("optimize " + dir + "/in.mesh -o " + dir + "/out.mesh --hmin 2 --hmax 1");
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("hmin"), std::string::npos) << r.output;
}

namespace {

// Distance of every boundary vertex of m to the model entity it is
// classified on, the largest over the mesh.
double farthest_from_model(const mesh::TetMesh& m, const geom::Model& model) {
  double worst = 0;
  for (VertId v = 0; v < m.num_verts(); ++v) {
    const auto c = m.vert_class[v];
    if (c.dim == 1 || c.dim == 2)
      worst = std::max(worst, model.closest_point({c.dim, c.tag}, m.coords[v]).distance);
    else if (c.dim == 0)
      worst = std::max(worst, (model.vertex_point(c.tag) - m.coords[v]).norm());
  }
  return worst;
}

}  // namespace

TEST(CliOptimize, WithTheModelBoundaryVerticesMoveOnIt) {
  // The path a user takes with a mesh curvemesh made: its vertices carry
  // classification and parameters, so --model may move them on the CAD.
  for (const std::string model : {"builtin:sphere", "builtin:cylinder:r=0.5,h=2"}) {
    SCOPED_TRACE(model);
    const std::string dir = test::make_temp_dir("optimize_model");
    auto r = run_cli("mesh " + model + " -o " + dir + "/m.msh --no-optimize -q");
    ASSERT_EQ(r.exit_code, 0) << r.output;
    r = run_cli("optimize " + dir + "/m.msh --model " + model + " -o " + dir + "/o.msh --json " + dir + "/r.json");
    ASSERT_EQ(r.exit_code, 0) << r.output;
    EXPECT_NE(r.output.find("check: valid"), std::string::npos) << r.output;
    EXPECT_EQ(run_cli("check " + dir + "/o.msh -q").exit_code, 0);
    const auto j = nlohmann::json::parse(test::read_text(dir + "/r.json"));
    EXPECT_GT(j["after"]["min_dihedral_deg"].get<double>(), j["before"]["min_dihedral_deg"].get<double>());
    EXPECT_GT(j["after"]["mean_ratio_min"].get<double>(), j["before"]["mean_ratio_min"].get<double>());
    EXPECT_GT(j["operators"]["boundary_relocations"].get<int>(), 0);
    EXPECT_TRUE(j["boundary_limit"].contains("pinned"));
    const auto loaded = geom_occ::load_model(model);
    const auto in = io::read_mesh(dir + "/m.msh"), out = io::read_mesh(dir + "/o.msh");
    EXPECT_LT(farthest_from_model(out, *loaded), 1e-6) << "a boundary vertex left its model entity";
    // Boundary vertices did move (else the model was not used).
    std::size_t moved = 0;
    for (VertId v = 0; v < in.num_verts(); ++v) moved += in.vert_class[v].dim == 2 && in.coords[v] != out.coords[v];
    EXPECT_GT(moved, 0u);
  }
}

TEST(CliOptimize, MetricExpressionAdaptsToUnitLengths) {
  const std::string dir = test::make_temp_dir("optimize");
  auto r = run_cli("mesh builtin:box -o " + dir + "/box.msh -q");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  // With the model the boundary vertices may go too: without it the box's
  // faces keep every vertex and their edges stay short across the shock.
  r = run_cli("optimize " + dir + "/box.msh --metric-expr '0.03 + 0.3*abs(x - 0.5); 0.15; 0.3' --model builtin:box -o " +
              dir + "/out.msh --json " + dir + "/r.json");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto j = nlohmann::json::parse(test::read_text(dir + "/r.json"));
  EXPECT_EQ(j["mode"], "anisotropic");
  // Measured: 39% -> 94%, metric quality min 0.075 -> 0.48 (threshold 0.9
  // in a metric; 89% at 0.6).
  EXPECT_GT(j["lengths_after"]["percent_in_0_7_1_4"].get<double>(), 90.0);
  EXPECT_GT(j["after"]["metric_quality_min"].get<double>(), 0.3);
  // Without the model, the box's faces may still adapt since they are flat.
  r = run_cli("optimize " + dir + "/box.msh --metric-expr '0.03 + 0.3*abs(x - 0.5); 0.15; 0.3' --move-flat-boundary -o " +
              dir + "/flat.msh --json " + dir + "/flat.json");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto f = nlohmann::json::parse(test::read_text(dir + "/flat.json"));
  EXPECT_TRUE(f["move_flat_boundary"].get<bool>());
  // Measured: 39% -> 94%, metric quality min 0.61; 58% with the boundary fixed.
  EXPECT_GT(f["lengths_after"]["percent_in_0_7_1_4"].get<double>(), 90.0);
  EXPECT_NEAR(f["after"]["volume"].get<double>(), f["before"]["volume"].get<double>(), 1e-12);
  EXPECT_NE(f["boundary"].get<std::string>().find("exactly flat"), std::string::npos);
  EXPECT_EQ(run_cli("check " + dir + "/flat.msh -q").exit_code, 0);
  // Shape optimization keeps boundary vertices fixed: the flag is an error there.
  r = run_cli("optimize " + dir + "/box.msh --move-flat-boundary -o " + dir + "/iso.msh");
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("--move-flat-boundary"), std::string::npos) << r.output;
  EXPECT_FALSE(std::filesystem::exists(dir + "/iso.msh"));
  r = run_cli("optimize " + dir + "/box.msh --metric-expr '0.1; 0.1' -o " + dir + "/bad.msh");
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("three sizes"), std::string::npos) << r.output;
}
