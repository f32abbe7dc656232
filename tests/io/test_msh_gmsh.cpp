// Reading real gmsh output: t20_data.step meshed by gmsh in each flavour we
// read (MSH 4.1 ASCII, binary and parametric, 2.2 ASCII and binary, orders 2
// and 3), checked against gmsh's own headers, against each other, against
// Gmsh's node ordering, and gmsh reading the files we write.
#include <gtest/gtest.h>

#include <cstdlib>
#include <map>
#include <set>
#include <sstream>

#include "curvemesh/io/atomic_file.hpp"
#include "curvemesh/io/formats.hpp"
#include "curvemesh/mesh/high_order.hpp"
#include "msh_test_support.hpp"

namespace cm::io::msh_test {
namespace {

// Coordinates (up to ~200 here) that went through gmsh's 16-digit text.
constexpr double kTextTolerance = 1e-12 * 200;

class GmshFiles : public ::testing::Test {
 protected:
  static void SetUpTestSuite() { dir_ = new TempDir(); }
  static void TearDownTestSuite() {
    delete dir_;
    dir_ = nullptr;
  }
  void SetUp() override {
    if (gmsh().empty()) GTEST_SKIP() << "gmsh was not found at configure time";
  }

  static std::string gmsh() { return CM_GMSH_EXECUTABLE; }
  // The path of a test file; gmsh makes the known ones on first use (ctest
  // runs each test in its own process, so each makes only what it reads).
  static std::string file(const std::string& name) {
    // name -> (file to convert, or "" to mesh the model; gmsh options)
    static const std::map<std::string, std::pair<std::string, std::string>> kRecipes{
        {"a41.msh", {"", ""}},
        {"par.msh", {"", "-setnumber Mesh.SaveParametric 1"}},
        {"p2.msh", {"", "-order 2"}},
        {"p3.msh", {"", "-order 3 -bin"}},
        {"b41.msh", {"a41.msh", "-format msh41 -bin"}},
        {"a22.msh", {"a41.msh", "-format msh22"}},
        {"b22.msh", {"a41.msh", "-format msh22 -bin"}},
        {"p2_22.msh", {"p2.msh", "-format msh22"}}};
    const std::string path = dir_->file(name);
    const auto recipe = kRecipes.find(name);
    if (recipe != kRecipes.end() && !fs::exists(path)) {
      const auto& [source, options] = recipe->second;
      if (source.empty())
        run("-3 " + std::string(CM_SHARED_DIR) +
            "/models/t20_data.step -setnumber Mesh.MeshSizeMax 6 -format msh41 " + options +
            " -o " + path);
      else
        run(file(source) + " -save " + options + " -o " + path);
    }
    return path;
  }
  static void run(const std::string& args) {
    const std::string command = gmsh() + " " + args + " > /dev/null 2>&1";
    if (std::system(command.c_str()) != 0) ADD_FAILURE() << "gmsh failed: " << command;
  }
  static TetMesh read(const std::string& name) { return read_path(file(name)); }

  static TempDir* dir_;
};

TempDir* GmshFiles::dir_ = nullptr;

// Counts straight from the text of an ASCII MSH 4.1 file.
struct HeaderCounts {
  std::size_t entities = 0, nodes = 0, tets = 0, tris = 0, lines = 0;
  std::set<std::uint64_t> corner_tags;
};

HeaderCounts count_msh41(const std::string& text) {
  HeaderCounts c;
  std::istringstream entities(text.substr(text.find("$Entities") + 9));
  for (int d = 0; d < 4; ++d) {
    std::size_t n;
    entities >> n;
    c.entities += n;
  }
  std::istringstream nodes(text.substr(text.find("$Nodes") + 6));
  std::size_t blocks;
  nodes >> blocks >> c.nodes;
  std::istringstream in(text.substr(text.find("$Elements") + 9));
  std::size_t total, lo, hi;
  in >> blocks >> total >> lo >> hi;
  // Linear types only: point, line, triangle, tet -> (nodes, corners).
  const std::map<int, std::pair<int, int>> kNodes{
      {15, {1, 0}}, {1, {2, 2}}, {2, {3, 3}}, {4, {4, 4}}};
  for (std::size_t b = 0; b < blocks; ++b) {
    int dim, tag, type;
    std::size_t n;
    in >> dim >> tag >> type >> n;
    const auto [num_nodes, corners] = kNodes.at(type);
    for (std::size_t i = 0; i < n; ++i) {
      std::uint64_t value;
      in >> value;
      for (int k = 0; k < num_nodes; ++k) {
        in >> value;
        if (k < corners) c.corner_tags.insert(value);
      }
    }
    if (type == 4) c.tets += n;
    if (type == 2) c.tris += n;
    if (type == 1) c.lines += n;
  }
  return c;
}

TEST_F(GmshFiles, Ascii41MatchesItsOwnHeaders) {
  const TetMesh m = read("a41.msh");
  const HeaderCounts c = count_msh41(read_file_bytes(file("a41.msh")));
  EXPECT_EQ(m.num_verts(), c.nodes);
  EXPECT_EQ(m.num_verts(), c.corner_tags.size());
  EXPECT_EQ(m.num_tets(), c.tets);
  EXPECT_EQ(m.tris.size(), c.tris);
  EXPECT_EQ(m.edges.size(), c.lines);
  EXPECT_EQ(m.entities.size(), c.entities);
  EXPECT_GT(m.num_tets(), 500u);
  for (TetId t = 0; t < m.num_tets(); ++t)
    ASSERT_GT(mesh::tet_volume(m, t), 0) << "gmsh tets are positive";
  for (const ModelRef& r : m.vert_class) ASSERT_TRUE(r.valid());
  for (const auto& e : m.edges)
    for (VertId v : e.verts) ASSERT_LE(m.vert_class[v].dim, 1);
}

TEST_F(GmshFiles, OtherFlavoursMatchAscii41) {
  const TetMesh a41 = read("a41.msh");
  EXPECT_TRUE(same_mesh(a41, read("b41.msh")));
  const TetMesh a22 = read("a22.msh");
  EXPECT_TRUE(same_mesh(a22, read("b22.msh")));
  ASSERT_EQ(a22.coords, a41.coords);
  EXPECT_EQ(a22.tet2verts, a41.tet2verts);
  EXPECT_EQ(a22.tet_region, a41.tet_region);
  ASSERT_EQ(a22.tris.size(), a41.tris.size());
  for (std::size_t i = 0; i < a22.tris.size(); ++i) {
    EXPECT_EQ(a22.tris[i].verts, a41.tris[i].verts);
    EXPECT_EQ(a22.tris[i].face_tag, a41.tris[i].face_tag);
  }
  ASSERT_EQ(a22.edges.size(), a41.edges.size());
  for (std::size_t i = 0; i < a22.edges.size(); ++i)
    EXPECT_EQ(a22.edges[i].edge_tag, a41.edges[i].edge_tag);
  // 2.2 classifies only the model vertices (from point elements).
  for (VertId v = 0; v < a22.num_verts(); ++v)
    EXPECT_EQ(a22.vert_class[v].valid() ? a22.vert_class[v] : ModelRef{},
              a41.vert_class[v].dim == 0 ? a41.vert_class[v] : ModelRef{});
}

TEST_F(GmshFiles, ParametricNodesGiveParameters) {
  const TetMesh a41 = read("a41.msh");
  const TetMesh par = read("par.msh");
  ASSERT_EQ(par.coords, a41.coords);
  EXPECT_EQ(par.vert_class, a41.vert_class);
  EXPECT_EQ(par.tet2verts, a41.tet2verts);
  std::size_t on_curves = 0, on_surfaces = 0;
  for (VertId v = 0; v < par.num_verts(); ++v) {
    const int dim = par.vert_class[v].dim;
    EXPECT_EQ(par.vert_param[v].has_u(), dim == 1 || dim == 2) << v;
    EXPECT_EQ(!std::isnan(par.vert_param[v].v), dim == 2) << v;
    EXPECT_FALSE(a41.vert_param[v].has_u());
    on_curves += dim == 1;
    on_surfaces += dim == 2;
  }
  EXPECT_GT(on_curves, 10u);
  EXPECT_GT(on_surfaces, 10u);
}

TEST_F(GmshFiles, SecondOrderNodesLieOnTheirEdges) {
  const TetMesh a41 = read("a41.msh");
  const TetMesh p2 = read("p2.msh");
  ASSERT_EQ(p2.high_order.order(), 2);
  ASSERT_EQ(p2.coords, a41.coords);
  ASSERT_EQ(p2.tet2verts, a41.tet2verts);
  const TetMesh p2_22 = read("p2_22.msh");
  for (TetId t = 0; t < p2.num_tets(); ++t)
    ASSERT_EQ(mesh::gather_tet_nodes(p2, t), mesh::gather_tet_nodes(p2_22, t));
  ASSERT_GT(p2.edges.size(), 0u);
  for (const auto& e : p2.edges) {
    Vec3 mid;
    ASSERT_TRUE(p2.high_order.get_edge(e.verts[0], e.verts[1], &mid));
    const Vec3 a = p2.coords[e.verts[0]], ab = p2.coords[e.verts[1]] - a;
    const double s = (mid - a).dot(ab) / ab.squaredNorm();
    EXPECT_GT(s, 0.3);
    EXPECT_LT(s, 0.7);
    EXPECT_LT((mid - a - s * ab).norm(), 0.1 * ab.norm());
  }
  // The edges of the tets: every stored node is near its edge's midpoint.
  for (TetId t = 0; t < p2.num_tets(); ++t) {
    const auto nodes = mesh::gather_tet_nodes(p2, t);
    for (std::size_t e = 0; e < 6; ++e) {
      const Vec3 a = nodes[mesh::kTetEdges[e][0]], b = nodes[mesh::kTetEdges[e][1]];
      ASSERT_LT((nodes[4 + e] - 0.5 * (a + b)).norm(), 0.1 * (b - a).norm())
          << "tet " << t << " edge " << e;
    }
  }
}

// Third-order edges have direction: node s of edge (a, b) must be near
// a + (s+1)/3 (b - a); a reversed edge would be off by a third of its length.
TEST_F(GmshFiles, ThirdOrderNodesFollowGmshOrdering) {
  const TetMesh a41 = read("a41.msh");
  const TetMesh p3 = read("p3.msh");
  ASSERT_EQ(p3.high_order.order(), 3);
  ASSERT_EQ(p3.tet2verts, a41.tet2verts);
  for (VertId v = 0; v < p3.num_verts(); ++v)
    ASSERT_LT((p3.coords[v] - a41.coords[v]).norm(), kTextTolerance);
  for (TetId t = 0; t < p3.num_tets(); ++t) {
    const auto nodes = mesh::gather_tet_nodes(p3, t);
    for (std::size_t e = 0; e < 6; ++e) {
      const Vec3 a = nodes[mesh::kTetEdges[e][0]], b = nodes[mesh::kTetEdges[e][1]];
      for (std::size_t s = 0; s < 2; ++s)
        ASSERT_LT((nodes[4 + 2 * e + s] - (a + (s + 1.0) / 3.0 * (b - a))).norm(),
                  0.1 * (b - a).norm())
            << "tet " << t << " edge " << e << " node " << s;
    }
    // A face node is where a cubic triangle puts its centre given its edge
    // nodes, (sum of edge nodes) / 4 - (sum of vertices) / 6, even on a
    // curved face; another face's node would be a third of an edge away.
    for (std::size_t f = 0; f < 4; ++f) {
      const auto& fv = mesh::kFaceVerts[f];
      const auto& tv = p3.tet2verts[t];
      const auto tri = mesh::gather_tri_nodes(p3, {tv[fv[0]], tv[fv[1]], tv[fv[2]]});
      ASSERT_EQ(tri[9], nodes[16 + f]);
      Vec3 centre = Vec3::Zero();
      for (std::size_t k = 3; k < 9; ++k) centre += tri[k] / 4.0;
      for (std::size_t k = 0; k < 3; ++k) centre -= tri[k] / 6.0;
      const double longest =
          std::max({(tri[1] - tri[0]).norm(), (tri[2] - tri[1]).norm(), (tri[0] - tri[2]).norm()});
      ASSERT_LT((tri[9] - centre).norm(), 0.1 * longest) << "tet " << t << " face " << f;
    }
  }
}

TEST_F(GmshFiles, RewritingGmshFilesIsExact) {
  TempDir out;
  for (const char* name : {"a41.msh", "b41.msh", "par.msh", "p2.msh", "p3.msh", "a22.msh"}) {
    const TetMesh m = read(name);
    const bool is41 = std::string(name) != "a22.msh";
    for (bool binary : {false, true}) {
      const TetMesh r = round_trip(m, binary, out);
      EXPECT_TRUE(same_mesh(m, r, {.entities = is41, .classification = is41}))
          << name << (binary ? " binary" : " ascii");
      // Writing what was read back gives the same bytes.
      write_msh41(m, out.file("first.msh"), binary);
      write_msh41(r, out.file("second.msh"), binary);
      EXPECT_EQ(read_file_bytes(out.file("first.msh")), read_file_bytes(out.file("second.msh")))
          << name;
    }
  }
}

// gmsh reads our files (entities, parametric blocks, order-3 elements) and
// writes them back as MSH 2.2 with the same mesh.
TEST_F(GmshFiles, GmshReadsOurFiles) {
  for (const char* name : {"par.msh", "p3.msh"}) {
    const TetMesh m = read(name);
    for (bool binary : {false, true}) {
      const std::string ours = file(std::string("ours_") + (binary ? "b_" : "a_") + name);
      write_msh41(m, ours, binary);
      const std::string back = ours + ".22.msh";
      run(ours + " -save -format msh22 -o " + back);
      const TetMesh r = read_path(back);
      // 2.2 carries neither vertex classification nor entities.
      EXPECT_TRUE(
          same_mesh(m, r, {.entities = false, .classification = false, .tol = kTextTolerance}))
          << name;
    }
  }
}

}  // namespace
}  // namespace cm::io::msh_test
