// VTU writer: the file is parsed back here (XML attributes and the raw
// appended block) and every node of every Lagrange cell is checked against
// the point VTK's node convention puts it at.
#include <fmt/format.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <map>
#include <set>
#include <string>
#include <vector>

#include "curvemesh/io/atomic_file.hpp"
#include "curvemesh/io/formats.hpp"
#include "curvemesh/mesh/high_order.hpp"
#include "curvemesh/mesh/tet_mesh.hpp"
#include "curvemesh/mesh/topology.hpp"

namespace fs = std::filesystem;
using cm::Vec3;
using cm::VertId;
using cm::mesh::TetMesh;

namespace {

// Parametric coordinates (r, s, t) of the nodes of VTK_LAGRANGE_TETRAHEDRON,
// transcribed from vtkHigherOrderTetra (vertices at the origin and the unit
// points; edges 01 12 20 03 13 23; faces 013 123 023 012).
const std::vector<std::array<double, 3>> kVtkTet2 = {
    {0, 0, 0},   {1, 0, 0},  {0, 1, 0},  {0, 0, 1},   {.5, 0, 0},
    {.5, .5, 0}, {0, .5, 0}, {0, 0, .5}, {.5, 0, .5}, {0, .5, .5}};
constexpr double k1 = 1.0 / 3, k2 = 2.0 / 3;
// clang-format off
const std::vector<std::array<double, 3>> kVtkTet3 = {
    {0, 0, 0},   {1, 0, 0},    {0, 1, 0},   {0, 0, 1},                            // vertices
    {k1, 0, 0},  {k2, 0, 0},   {k2, k1, 0}, {k1, k2, 0},  {0, k2, 0},  {0, k1, 0},  // edges 01 12 20
    {0, 0, k1},  {0, 0, k2},   {k2, 0, k1}, {k1, 0, k2},  {0, k2, k1}, {0, k1, k2}, // edges 03 13 23
    {k1, 0, k1}, {k1, k1, k1}, {0, k1, k1}, {k1, k1, 0}};                         // faces
// clang-format on
// VTK_LAGRANGE_TRIANGLE (vtkHigherOrderTriangle): vertices, edges 01 12 20, center.
const std::vector<std::array<double, 2>> kVtkTri2 = {{0, 0},  {1, 0},   {0, 1},
                                                     {.5, 0}, {.5, .5}, {0, .5}};
const std::vector<std::array<double, 2>> kVtkTri3 = {
    {0, 0}, {1, 0}, {0, 1}, {k1, 0}, {k2, 0}, {k2, k1}, {k1, k2}, {0, k2}, {0, k1}, {k1, k1}};

// The curved geometry: high-order nodes sit at F(straight position), F
// nonlinear, so a node in the wrong slot lands on the wrong point.
Vec3 warp(const Vec3& x) {
  return x + 0.1 * Vec3(x.y() * x.z(), x.x() * x.x() - x.z(), x.x() * x.y() * x.y());
}

// The unit cube split into 6 tets around its diagonal, hull triangles tagged
// by side (11..16), vertex 0's three cube edges tagged 21..23, vertices
// classified on the cube corners.
TetMesh make_cube() {
  TetMesh m;
  for (int b = 0; b < 8; ++b) m.add_vert(Vec3(b & 1, b >> 1 & 1, b >> 2 & 1));
  const int perms[6][3] = {{1, 2, 4}, {1, 4, 2}, {2, 1, 4}, {2, 4, 1}, {4, 1, 2}, {4, 2, 1}};
  for (const auto& p : perms) {
    const cm::TetId t = m.add_tet(
        {0, static_cast<VertId>(p[0]), static_cast<VertId>(p[0] | p[1]), 7}, p[0] == 1 ? 1 : 2);
    if (cm::mesh::tet_volume(m, t) < 0) std::swap(m.tet2verts[t][2], m.tet2verts[t][3]);
  }
  std::map<std::array<VertId, 3>, std::pair<int, std::array<VertId, 3>>> faces;
  for (const auto& t : m.tet2verts)
    for (const auto& f : cm::mesh::kFaceVerts) {
      std::array<VertId, 3> oriented{t[f[0]], t[f[1]], t[f[2]]}, key = oriented;
      std::sort(key.begin(), key.end());
      ++faces[key].first;
      faces[key].second = oriented;
    }
  for (const auto& [key, entry] : faces) {
    if (entry.first != 1) continue;
    int tag = 0;
    for (int axis = 0; axis < 3; ++axis)
      for (int side = 0; side < 2; ++side)
        if (std::all_of(key.begin(), key.end(),
                        [&](VertId v) { return (v >> axis & 1) == static_cast<VertId>(side); }))
          tag = 11 + 2 * axis + side;
    m.tris.push_back({entry.second, tag});
  }
  m.edges = {{{0, 1}, 21}, {{0, 2}, 22}, {{0, 4}, 23}};
  for (VertId v = 0; v < 8; ++v) m.vert_class[v] = {0, static_cast<std::int32_t>(v + 1)};
  return m;
}

// Gives the cube order p, with every edge and face node at warp(straight).
void curve(TetMesh& m, int p) {
  m.high_order.reset(p);
  const auto place = [&](const auto& verts, const auto& indices) {
    std::vector<Vec3> nodes;
    for (const auto& w : indices) {
      Vec3 x = Vec3::Zero();
      int nonzero = 0;
      for (std::size_t k = 0; k < w.size(); ++k) {
        x += (static_cast<double>(w[k]) / p) * m.coords[verts[k]];
        nonzero += w[k] != 0;
      }
      nodes.push_back(nonzero == 1 ? x : warp(x));
    }
    return nodes;
  };
  for (cm::TetId t = 0; t < m.num_tets(); ++t)
    cm::mesh::scatter_tet_nodes(m, t, place(m.tet2verts[t], cm::mesh::tet_node_indices(p)));
  for (const auto& tri : m.tris)
    cm::mesh::scatter_tri_nodes(m, tri.verts, place(tri.verts, cm::mesh::tri_node_indices(p)));
}

struct DataArray {
  std::string type;
  std::uint64_t offset = 0;
  int components = 1;
};

// A .vtu with a raw appended block, as far as this writer uses the format.
class Vtu {
 public:
  explicit Vtu(std::string bytes) : bytes_(std::move(bytes)) {
    const std::size_t appended = bytes_.find("<AppendedData encoding=\"raw\">");
    if (appended == std::string::npos) throw std::runtime_error("no raw AppendedData");
    raw_ = bytes_.find('_', appended) + 1;
    const std::string xml = bytes_.substr(0, appended);
    num_points = std::stoll(attribute(xml, xml.find("<Piece"), "NumberOfPoints"));
    num_cells = std::stoll(attribute(xml, xml.find("<Piece"), "NumberOfCells"));
    for (std::size_t at = xml.find("<DataArray"); at != std::string::npos;
         at = xml.find("<DataArray", at + 1)) {
      DataArray a;
      a.type = attribute(xml, at, "type");
      a.offset = std::stoull(attribute(xml, at, "offset"));
      const std::string components = attribute(xml, at, "NumberOfComponents");
      if (!components.empty()) a.components = std::stoi(components);
      if (attribute(xml, at, "format") != "appended") throw std::runtime_error("not appended");
      arrays[attribute(xml, at, "Name")] = a;
    }
  }

  template <class T>
  std::vector<T> get(const std::string& name, const std::string& vtk_type) const {
    const auto it = arrays.find(name);
    if (it == arrays.end()) throw std::runtime_error("no array " + name);
    EXPECT_EQ(it->second.type, vtk_type) << name;
    std::uint64_t bytes = 0;
    std::memcpy(&bytes, bytes_.data() + raw_ + it->second.offset, 8);
    EXPECT_EQ(bytes % sizeof(T), 0u);
    std::vector<T> out(bytes / sizeof(T));
    std::memcpy(out.data(), bytes_.data() + raw_ + it->second.offset + 8, bytes);
    return out;
  }
  // Bytes after the last array.
  std::string tail() const {
    std::uint64_t end = 0;
    for (const auto& [name, a] : arrays) {
      std::uint64_t bytes = 0;
      std::memcpy(&bytes, bytes_.data() + raw_ + a.offset, 8);
      end = std::max(end, a.offset + 8 + bytes);
    }
    return bytes_.substr(raw_ + end);
  }

  std::int64_t num_points = 0;
  std::int64_t num_cells = 0;
  std::map<std::string, DataArray> arrays;

 private:
  static std::string attribute(const std::string& xml, std::size_t element,
                               const std::string& name) {
    const std::size_t close = xml.find('>', element);
    const std::size_t at = xml.find(" " + name + "=\"", element);
    if (at == std::string::npos || at > close) return {};
    const std::size_t begin = at + name.size() + 3;
    return xml.substr(begin, xml.find('"', begin) - begin);
  }
  std::string bytes_;
  std::size_t raw_ = 0;
};

std::uint64_t edge_key(VertId a, VertId b) {
  return (std::uint64_t{std::min(a, b)} << 32) | std::max(a, b);
}

class VtuTest : public ::testing::TestWithParam<int> {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / fmt::format("cm_test_vtu_{}", static_cast<long>(getpid()));
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  fs::path dir_;
};

}  // namespace

TEST_P(VtuTest, CellsNodesAndDataFollowVtkConventions) {
  const int p = GetParam();
  TetMesh m = make_cube();
  if (p > 1) curve(m, p);
  std::vector<cm::io::CellField> fields(1);
  fields[0].name = "quality <&\">";
  for (std::size_t t = 0; t < m.num_tets(); ++t)
    fields[0].values.push_back(0.5 + 0.01 * static_cast<double>(t));
  const std::string file = (dir_ / "cube.vtu").string();
  cm::io::write_vtu(m, file, fields);
  const std::string bytes = cm::io::read_file_bytes(file);
  ASSERT_EQ(
      bytes.rfind("<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" "
                  "byte_order=\"LittleEndian\" header_type=\"UInt64\">",
                  0),
      0u);
  const Vtu vtu(bytes);
  EXPECT_EQ(vtu.tail(), "\n  </AppendedData>\n</VTKFile>\n");

  // Expected points: the vertices, then one per distinct edge node and face node.
  std::set<std::uint64_t> mesh_edges;
  std::set<std::array<VertId, 3>> mesh_faces;
  for (const auto& t : m.tet2verts) {
    for (const auto& e : cm::mesh::kTetEdges) mesh_edges.insert(edge_key(t[e[0]], t[e[1]]));
    for (const auto& f : cm::mesh::kFaceVerts) {
      std::array<VertId, 3> key{t[f[0]], t[f[1]], t[f[2]]};
      std::sort(key.begin(), key.end());
      mesh_faces.insert(key);
    }
  }
  ASSERT_EQ(m.tris.size(), 12u);
  ASSERT_EQ(mesh_edges.size(), 19u);
  ASSERT_EQ(mesh_faces.size(), 18u);
  const std::size_t tet_nodes = static_cast<std::size_t>((p + 1) * (p + 2) * (p + 3) / 6);
  const std::size_t tri_nodes = static_cast<std::size_t>((p + 1) * (p + 2) / 2);
  EXPECT_EQ(vtu.num_points,
            static_cast<std::int64_t>(8 + mesh_edges.size() * static_cast<std::size_t>(p - 1) +
                                      (p == 3 ? mesh_faces.size() : 0)));
  ASSERT_EQ(vtu.num_cells, 18);

  const auto points = vtu.get<double>("Points", "Float64");
  ASSERT_EQ(vtu.arrays.at("Points").components, 3);
  ASSERT_EQ(points.size(), 3 * static_cast<std::size_t>(vtu.num_points));
  const auto point = [&](std::int64_t i) {
    return Vec3(points[3 * i], points[3 * i + 1], points[3 * i + 2]);
  };
  const auto connectivity = vtu.get<std::int64_t>("connectivity", "Int64");
  const auto offsets = vtu.get<std::int64_t>("offsets", "Int64");
  const auto types = vtu.get<std::uint8_t>("types", "UInt8");
  const auto region = vtu.get<std::int32_t>("region", "Int32");
  const auto dim = vtu.get<std::int32_t>("dim", "Int32");
  const auto model_tag = vtu.get<std::int32_t>("model_tag", "Int32");
  const auto quality = vtu.get<double>("quality &lt;&amp;&quot;&gt;", "Float64");
  const auto class_dim = vtu.get<std::int32_t>("class_dim", "Int32");
  const auto class_tag = vtu.get<std::int32_t>("class_tag", "Int32");
  ASSERT_EQ(connectivity.size(), 6 * tet_nodes + 12 * tri_nodes);
  ASSERT_EQ(offsets.size(), 18u);
  ASSERT_EQ(class_dim.size(), static_cast<std::size_t>(vtu.num_points));
  for (VertId v = 0; v < 8; ++v) {
    EXPECT_EQ(point(v), m.coords[v]);
    EXPECT_EQ(class_dim[v], 0);
    EXPECT_EQ(class_tag[v], static_cast<std::int32_t>(v + 1));
  }

  std::map<std::uint64_t, int> edge_tag, edge_face;
  std::map<std::array<VertId, 3>, int> face_tag;
  for (const auto& e : m.edges) edge_tag[edge_key(e.verts[0], e.verts[1])] = e.edge_tag;
  for (const auto& tri : m.tris) {
    std::array<VertId, 3> key = tri.verts;
    std::sort(key.begin(), key.end());
    face_tag[key] = tri.face_tag;
    for (const auto& e : cm::mesh::kTriEdges)
      edge_face.try_emplace(edge_key(tri.verts[e[0]], tri.verts[e[1]]), tri.face_tag);
  }
  std::int64_t begin = 0;
  for (std::size_t c = 0; c < 18; ++c) {
    const bool is_tet = c < 6;
    const std::size_t n = is_tet ? tet_nodes : tri_nodes;
    ASSERT_EQ(offsets[c], begin + static_cast<std::int64_t>(n)) << c;
    EXPECT_EQ(types[c], is_tet ? (p == 1 ? 10 : 71) : (p == 1 ? 5 : 69));
    const int expected_region = is_tet ? m.tet_region[c] : m.tris[c - 6].face_tag;
    EXPECT_EQ(region[c], expected_region);
    EXPECT_EQ(model_tag[c], expected_region);
    EXPECT_EQ(dim[c], is_tet ? 3 : 2);
    if (is_tet)
      EXPECT_EQ(quality[c], fields[0].values[c]);
    else
      EXPECT_TRUE(std::isnan(quality[c]));

    const std::int64_t* nodes = connectivity.data() + begin;
    std::vector<VertId> verts;
    for (std::size_t k = 0; k < (is_tet ? 4u : 3u); ++k)
      verts.push_back(static_cast<VertId>(nodes[k]));
    if (is_tet)
      EXPECT_TRUE(std::equal(verts.begin(), verts.end(), m.tet2verts[c].begin()));
    else
      EXPECT_TRUE(std::equal(verts.begin(), verts.end(), m.tris[c - 6].verts.begin()));
    for (std::size_t k = 0; k < n; ++k) {
      ASSERT_GE(nodes[k], 0);
      ASSERT_LT(nodes[k], vtu.num_points);
      // Weights of the cell's vertices at VTK's parametric point of node k.
      std::vector<double> w(verts.size(), 0.0);
      if (p == 1) {
        w[k] = 1;  // linear cells: the vertices in the mesh's order
      } else if (is_tet) {
        const auto& r = (p == 3 ? kVtkTet3 : kVtkTet2)[k];
        w = {1 - r[0] - r[1] - r[2], r[0], r[1], r[2]};
      } else {
        const auto& r = (p == 3 ? kVtkTri3 : kVtkTri2)[k];
        w = {1 - r[0] - r[1], r[0], r[1]};
      }
      Vec3 straight = Vec3::Zero();
      std::vector<VertId> support;
      for (std::size_t j = 0; j < verts.size(); ++j) {
        straight += w[j] * m.coords[verts[j]];
        if (w[j] > 1e-9) support.push_back(verts[j]);
      }
      const Vec3 expected = support.size() == 1 ? straight : warp(straight);
      EXPECT_LT((point(nodes[k]) - expected).norm(), 1e-14) << "cell " << c << " node " << k;
      // High-order nodes: classified on the mesh edge or face they lie on.
      if (support.size() == 1) continue;
      std::sort(support.begin(), support.end());
      int want_dim = is_tet ? 3 : 2, want_tag = expected_region;
      if (support.size() == 2) {
        const std::uint64_t key = edge_key(support[0], support[1]);
        if (edge_tag.count(key))
          want_dim = 1, want_tag = edge_tag[key];
        else if (edge_face.count(key))
          want_dim = 2, want_tag = edge_face[key];
      } else if (support.size() == 3 && face_tag.count({support[0], support[1], support[2]})) {
        want_dim = 2, want_tag = face_tag[{support[0], support[1], support[2]}];
      }
      if (want_dim == 3) want_tag = class_tag[nodes[k]];  // any region sharing the node
      EXPECT_EQ(class_dim[nodes[k]], want_dim) << "cell " << c << " node " << k;
      EXPECT_EQ(class_tag[nodes[k]], want_tag) << "cell " << c << " node " << k;
    }
    begin += static_cast<std::int64_t>(n);
  }
}

INSTANTIATE_TEST_SUITE_P(Orders, VtuTest, ::testing::Values(1, 2, 3));

TEST(Vtu, RejectsFieldsThatDoNotFit) {
  const TetMesh m = make_cube();
  const std::string file = (fs::temp_directory_path() /
                            fmt::format("cm_test_vtu_bad_{}.vtu", static_cast<long>(getpid())))
                               .string();
  std::vector<cm::io::CellField> fields{{"short", {1.0, 2.0}}};
  EXPECT_THROW(cm::io::write_vtu(m, file, fields), std::invalid_argument);
  fields = {{"a", std::vector<double>(6, 1.0)}, {"a", std::vector<double>(6, 2.0)}};
  EXPECT_THROW(cm::io::write_vtu(m, file, fields), std::invalid_argument);
  fields = {{"region", std::vector<double>(6, 1.0)}};
  EXPECT_THROW(cm::io::write_vtu(m, file, fields), std::invalid_argument);
  EXPECT_FALSE(fs::exists(file));
}

TEST(VtuGrid, VoxelsAndPointFieldsReadBack) {
  cm::io::VtuGrid g;
  // Two voxels side by side with unshared corners, plus a vertex cell.
  for (int v = 0; v < 2; ++v)
    for (int c = 0; c < 8; ++c) {
      g.connectivity.push_back(static_cast<std::int64_t>(g.points.size()));
      g.points.push_back(cm::Vec3(v + (c & 1), (c >> 1) & 1, (c >> 2) & 1));
      if (c == 7) {
        g.offsets.push_back(static_cast<std::int64_t>(g.connectivity.size()));
        g.types.push_back(11);
      }
    }
  g.connectivity.push_back(0);
  g.offsets.push_back(17);
  g.types.push_back(1);
  g.cell_fields.push_back({"size", 1, {0.5, 0.25, 1.0}});
  std::vector<double> dirs;
  for (std::size_t i = 0; i < g.points.size(); ++i)
    for (int a = 0; a < 3; ++a) dirs.push_back(a == 0 ? double(i) : 0.0);
  g.point_fields.push_back({"dir", 3, dirs});
  const fs::path file = fs::temp_directory_path() / fmt::format("cm_test_vtugrid_{}.vtu", static_cast<long>(getpid()));
  cm::io::write_vtu_grid(g, file.string());
  const Vtu vtu(cm::io::read_file_bytes(file.string()));
  fs::remove(file);
  EXPECT_EQ(vtu.num_points, 16);
  EXPECT_EQ(vtu.num_cells, 3);
  EXPECT_EQ(vtu.tail(), "\n  </AppendedData>\n</VTKFile>\n");
  EXPECT_EQ(vtu.get<double>("size", "Float64"), (std::vector<double>{0.5, 0.25, 1.0}));
  EXPECT_EQ(vtu.arrays.at("dir").components, 3);
  EXPECT_EQ(vtu.get<double>("dir", "Float64"), dirs);
  EXPECT_EQ(vtu.get<std::uint8_t>("types", "UInt8"), (std::vector<std::uint8_t>{11, 11, 1}));
  EXPECT_EQ(vtu.get<std::int64_t>("offsets", "Int64"), (std::vector<std::int64_t>{8, 16, 17}));
  const auto points = vtu.get<double>("Points", "Float64");
  ASSERT_EQ(points.size(), 48u);
  EXPECT_EQ(points[3 * 15], 2.0);

  cm::io::VtuGrid bad = g;
  bad.connectivity.back() = 99;
  EXPECT_THROW(cm::io::write_vtu_grid(bad, file.string()), std::invalid_argument);
  bad = g;
  bad.cell_fields[0].values.pop_back();
  EXPECT_THROW(cm::io::write_vtu_grid(bad, file.string()), std::invalid_argument);
  bad = g;
  bad.offsets[0] = 20;
  EXPECT_THROW(cm::io::write_vtu_grid(bad, file.string()), std::invalid_argument);
  EXPECT_FALSE(fs::exists(file));
}
