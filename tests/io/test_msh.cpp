// Gmsh MSH reader and writer: exact round trips (orders 1-3, ASCII and
// binary, classification, parameters, entities), the written text itself,
// real gmsh output in every flavour, and malformed input.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <random>
#include <set>
#include <sstream>

#include "curvemesh/core/error.hpp"
#include "curvemesh/io/atomic_file.hpp"
#include "curvemesh/io/formats.hpp"
#include "curvemesh/mesh/high_order.hpp"
#include "curvemesh/mesh/tet_mesh.hpp"
#include "msh_test_support.hpp"

namespace cm::io::msh_test {
namespace {

// ---------------------------------------------------------------------------
// Fixture: an n^3 grid of cubes, 6 tets each, classified on the cube model
// [0,n]^3 (corners 1..8, curves 1..12, faces 1..6, volumes 1 (x < n/2) and 2).

struct Constraint {
  int axis, side;
  friend auto operator<=>(const Constraint&, const Constraint&) = default;
};

std::vector<Constraint> constraints(const std::array<int, 3>& ijk, int n) {
  std::vector<Constraint> out;
  for (int a = 0; a < 3; ++a)
    if (ijk[a] == 0 || ijk[a] == n) out.push_back({a, ijk[a] == n ? 1 : 0});
  return out;
}

// Curve tag from the two constraints fixing it: free axis a, sides s1, s2 of
// the other two axes in increasing order.
int curve_tag(const std::vector<Constraint>& c) {
  const int free_axis = 3 - c[0].axis - c[1].axis;
  return 1 + 4 * free_axis + c[0].side + 2 * c[1].side;
}

TetMesh make_grid(int n, bool classify) {
  TetMesh m;
  const double h = 1.0 / 3.0;
  std::vector<std::array<int, 3>> ijk;
  for (int k = 0; k <= n; ++k)
    for (int j = 0; j <= n; ++j)
      for (int i = 0; i <= n; ++i) {
        Vec3 x(i * h, j * h, k * h);
        const auto c = constraints({i, j, k}, n);
        // Move points within their entity so coordinates use all digits.
        for (int a = 0; a < 3; ++a) {
          const int idx = a == 0 ? i : a == 1 ? j : k;
          if (idx != 0 && idx != n) x[a] += 1e-3 * std::sin(7.0 * i + 3.0 * j + k + a);
        }
        const VertId v = m.add_vert(x);
        ijk.push_back({i, j, k});
        if (!classify) continue;
        if (c.size() == 3) {
          m.vert_class[v] = {0, 1 + (i == n) + 2 * (j == n) + 4 * (k == n)};
        } else if (c.size() == 2) {
          m.vert_class[v] = {1, curve_tag(c)};
          m.vert_param[v].u = x[3 - c[0].axis - c[1].axis];
        } else if (c.size() == 1) {
          m.vert_class[v] = {2, 1 + 2 * c[0].axis + c[0].side};
          m.vert_param[v] = {x[(c[0].axis + 1) % 3], x[(c[0].axis + 2) % 3]};
        } else {
          m.vert_class[v] = {3, 2 * i < n ? 1 : 2};
        }
      }
  const auto id = [&](int i, int j, int k) {
    return static_cast<VertId>(i + (n + 1) * (j + (n + 1) * k));
  };
  std::array<int, 3> perm{0, 1, 2};
  std::set<std::uint64_t> seen_edges;
  for (int k = 0; k < n; ++k)
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        std::sort(perm.begin(), perm.end());
        do {
          std::array<int, 3> p{i, j, k};
          std::array<VertId, 4> t{id(i, j, k), 0, 0, 0};
          for (int s = 0; s < 3; ++s) {
            ++p[perm[s]];
            t[s + 1] = id(p[0], p[1], p[2]);
          }
          const Vec3& a = m.coords[t[0]];
          if ((m.coords[t[1]] - a).cross(m.coords[t[2]] - a).dot(m.coords[t[3]] - a) < 0)
            std::swap(t[2], t[3]);
          const TetId tet = m.add_tet(t, 2 * i < n ? 1 : 2);
          if (!classify) continue;
          for (const auto& f : mesh::kFaceVerts) {
            std::vector<Constraint> common = constraints(ijk[t[f[0]]], n);
            for (int q = 1; q < 3; ++q) {
              const auto other = constraints(ijk[t[f[q]]], n);
              std::vector<Constraint> both;
              std::set_intersection(common.begin(), common.end(), other.begin(), other.end(),
                                    std::back_inserter(both));
              common = both;
            }
            if (!common.empty())
              m.tris.push_back(
                  {{t[f[0]], t[f[1]], t[f[2]]}, 1 + 2 * common[0].axis + common[0].side});
          }
          for (const auto& e : mesh::kTetEdges) {
            const VertId a0 = m.tet2verts[tet][e[0]], b0 = m.tet2verts[tet][e[1]];
            const auto ca = constraints(ijk[a0], n), cb = constraints(ijk[b0], n);
            std::vector<Constraint> both;
            std::set_intersection(ca.begin(), ca.end(), cb.begin(), cb.end(),
                                  std::back_inserter(both));
            const std::uint64_t key = (std::uint64_t{std::min(a0, b0)} << 32) | std::max(a0, b0);
            if (both.size() >= 2 && seen_edges.insert(key).second)
              m.edges.push_back({{a0, b0}, curve_tag(both)});
          }
        } while (std::next_permutation(perm.begin(), perm.end()));
      }
  return m;
}

Vec3 bump(const Vec3& x) {
  return 0.02 * Vec3(std::sin(3 * x.y()), std::cos(2 * x.z()), std::sin(x.x() + x.y()));
}

// Curves every edge and face of the grid's tets (order p).
void curve_grid(TetMesh& m, int p) {
  m.high_order.reset(p);
  std::vector<Vec3> nodes(static_cast<std::size_t>(p));
  for (const auto& t : m.tet2verts) {
    for (const auto& e : mesh::kTetEdges) {
      const Vec3 &a = m.coords[t[e[0]]], &b = m.coords[t[e[1]]];
      for (int s = 1; s < p; ++s) {
        const Vec3 x = a + (static_cast<double>(s) / p) * (b - a);
        nodes[static_cast<std::size_t>(s - 1)] = x + bump(x);
      }
      m.high_order.set_edge(t[e[0]], t[e[1]],
                            std::span<const Vec3>(nodes.data(), static_cast<std::size_t>(p - 1)));
    }
    if (p == 3)
      for (const auto& f : mesh::kFaceVerts) {
        const Vec3 c = (m.coords[t[f[0]]] + m.coords[t[f[1]]] + m.coords[t[f[2]]]) / 3.0;
        nodes[0] = c + bump(c);
        m.high_order.set_face(t[f[0]], t[f[1]], t[f[2]], std::span<const Vec3>(nodes.data(), 1));
      }
  }
}

// x(λ) of an order-p Lagrange tet from its nodes in internal order.
Vec3 eval_lagrange(int p, const std::vector<Vec3>& nodes, const std::array<double, 4>& bary) {
  const auto idx = mesh::tet_node_indices(p);
  Vec3 x = Vec3::Zero();
  for (std::size_t n = 0; n < idx.size(); ++n) {
    double w = 1;
    for (int k = 0; k < 4; ++k)
      for (int j = 0; j < idx[n][k]; ++j) w *= (p * bary[k] - j) / (j + 1);
    x += w * nodes[n];
  }
  return x;
}

// ---------------------------------------------------------------------------

TEST(MshWrite, SingleTetText) {
  TetMesh m;
  for (const Vec3& x : {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 0.1, 0), Vec3(0, 0, 1e-7)})
    m.add_vert(x);
  m.add_tet({0, 1, 2, 3}, 7);
  TempDir dir;
  write_msh41(m, dir.file("t.msh"), false);
  EXPECT_EQ(read_file_bytes(dir.file("t.msh")),
            "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n"
            "$Entities\n0 0 0 1\n7 0 0 0 1 0.1 1e-07 0 0\n$EndEntities\n"
            "$Nodes\n1 4 1 4\n3 7 0 4\n1\n2\n3\n4\n0 0 0\n1 0 0\n0 0.1 0\n0 0 1e-07\n$EndNodes\n"
            "$Elements\n1 1 1 1\n3 7 4 1\n1 1 2 3 4\n$EndElements\n");
}

TEST(MshWrite, SecondOrderTetUsesGmshNodeOrder) {
  TetMesh m;
  for (const Vec3& x : {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(0, 0, 1)}) m.add_vert(x);
  m.add_tet({0, 1, 2, 3}, 1);
  m.high_order.reset(2);
  TempDir dir;
  write_msh41(m, dir.file("t.msh"), false);
  // Gmsh's 10-node tet: edges 0-1, 1-2, 2-0, 3-0, 3-2, 3-1. Map each written
  // node tag to its coordinates and check the midpoints come in that order.
  std::istringstream in(read_file_bytes(dir.file("t.msh")));
  std::string line;
  while (std::getline(in, line) && line != "$Nodes") {
  }
  std::map<int, Vec3> xyz;
  int blocks, total, lo, hi;
  in >> blocks >> total >> lo >> hi;
  for (int b = 0; b < blocks; ++b) {
    int dim, tag, par, n;
    in >> dim >> tag >> par >> n;
    std::vector<int> tags(static_cast<std::size_t>(n));
    for (int& t : tags) in >> t;
    for (int t : tags) in >> xyz[t].x() >> xyz[t].y() >> xyz[t].z();
  }
  while (std::getline(in, line) && line != "$Elements") {
  }
  int dim, tag, type, n, elem;
  in >> blocks >> total >> lo >> hi >> dim >> tag >> type >> n >> elem;
  EXPECT_EQ(type, 11);
  std::array<int, 10> nodes;
  for (int& t : nodes) in >> t;
  const std::array<std::array<int, 2>, 6> gmsh_edges{
      {{0, 1}, {1, 2}, {2, 0}, {3, 0}, {3, 2}, {3, 1}}};
  for (int k = 0; k < 6; ++k) {
    const Vec3 mid = 0.5 * (m.coords[gmsh_edges[k][0]] + m.coords[gmsh_edges[k][1]]);
    EXPECT_EQ(xyz[nodes[4 + k]], mid) << "node " << 4 + k;
  }
}

TEST(MshRoundTrip, ClassifiedGridWithDerivedEntities) {
  const TetMesh m = make_grid(3, true);
  ASSERT_EQ(m.num_tets(), 162u);
  ASSERT_EQ(m.tris.size(), 108u);
  ASSERT_EQ(m.edges.size(), 36u);
  TempDir dir;
  for (bool binary : {false, true}) {
    const TetMesh r = round_trip(m, binary, dir);
    EXPECT_TRUE(same_mesh(m, r, {.entities = false})) << (binary ? "binary" : "ascii");
    // Entities derived by the writer from the classification.
    ASSERT_EQ(r.entities.size(), 8u + 12u + 6u + 2u);
    EXPECT_EQ(find_entity(r, 1, 1)->bounding, (std::vector<int>{1, 2}));
    EXPECT_EQ(find_entity(r, 2, 1)->bounding, (std::vector<int>{5, 7, 9, 11}));
    EXPECT_EQ(find_entity(r, 3, 1)->bounding, (std::vector<int>{1, 3, 4, 5, 6}));
    EXPECT_EQ(find_entity(r, 3, 2)->bounding, (std::vector<int>{2, 3, 4, 5, 6}));
    EXPECT_TRUE(find_entity(r, 0, 8)->bounding.empty());
  }
}

TEST(MshRoundTrip, GivenEntitiesAreKeptAsTheyAre) {
  TetMesh m = make_grid(2, true);
  m.entities.push_back({3, 1, {-1, 3, 4, 5, 6}, {100, 101}, ""});
  m.entities.push_back({2, 1, {5, -7, 9, -11}, {10}, ""});
  m.entities.push_back({0, 42, {}, {7}, ""});  // a model vertex with no mesh vertex
  TempDir dir;
  for (bool binary : {false, true}) {
    const TetMesh r = round_trip(m, binary, dir);
    EXPECT_TRUE(same_mesh(m, r, {.entities = false}));
    EXPECT_EQ(find_entity(r, 3, 1)->bounding, (std::vector<int>{-1, 3, 4, 5, 6}));
    EXPECT_EQ(find_entity(r, 3, 1)->physicals, (std::vector<int>{100, 101}));
    EXPECT_EQ(find_entity(r, 2, 1)->bounding, (std::vector<int>{5, -7, 9, -11}));
    ASSERT_NE(find_entity(r, 0, 42), nullptr);
    EXPECT_EQ(find_entity(r, 0, 42)->physicals, (std::vector<int>{7}));
    // A second round trip reproduces the first exactly, entities included.
    EXPECT_TRUE(same_mesh(r, round_trip(r, binary, dir)));
  }
}

TEST(MshRoundTrip, UnclassifiedVerticesGoToTheirLowestTetsRegion) {
  TetMesh m = make_grid(2, false);
  m.add_vert(Vec3(5, 5, 5));  // in no element: a volume entity of its own
  TempDir dir;
  const TetMesh r = round_trip(m, true, dir);
  ASSERT_EQ(r.num_verts(), m.num_verts() - 1);  // only element corners are vertices
  for (VertId v = 0; v < r.num_verts(); ++v) {
    TetId first = kNone;
    for (TetId t = 0; t < m.num_tets() && first == kNone; ++t)
      if (std::count(m.tet2verts[t].begin(), m.tet2verts[t].end(), v)) first = t;
    ASSERT_NE(first, kNone);
    EXPECT_EQ(r.vert_class[v], (ModelRef{3, m.tet_region[first]})) << v;
  }
  EXPECT_NE(find_entity(r, 3, 3), nullptr);  // the isolated vertex's volume
}

class MshCurved : public ::testing::TestWithParam<int> {};

TEST_P(MshCurved, RoundTripKeepsNodesAndGeometry) {
  const int p = GetParam();
  TetMesh m = make_grid(2, true);
  curve_grid(m, p);
  const std::vector<std::array<double, 4>> samples{{0.25, 0.25, 0.25, 0.25},
                                                   {0.1, 0.2, 0.3, 0.4},
                                                   {0.7, 0.1, 0.1, 0.1},
                                                   {0.05, 0.05, 0.45, 0.45}};
  TempDir dir;
  for (bool binary : {false, true}) {
    const TetMesh r = round_trip(m, binary, dir);
    ASSERT_TRUE(same_mesh(m, r, {.entities = false}));
    ASSERT_EQ(r.high_order.order(), p);
    EXPECT_EQ(r.high_order.num_edges(), m.high_order.num_edges());
    EXPECT_EQ(r.high_order.num_faces(), m.high_order.num_faces());
    for (TetId t = 0; t < m.num_tets(); ++t) {
      const auto original = mesh::gather_tet_nodes(m, t), read = mesh::gather_tet_nodes(r, t);
      const auto idx = mesh::tet_node_indices(p);
      for (std::size_t n = 0; n < idx.size(); ++n) {
        const std::array<double, 4> at{idx[n][0] / double(p), idx[n][1] / double(p),
                                       idx[n][2] / double(p), idx[n][3] / double(p)};
        ASSERT_LT((eval_lagrange(p, read, at) - read[n]).norm(), 1e-12);
      }
      for (const auto& s : samples) {
        const Vec3 curved = eval_lagrange(p, read, s);
        ASSERT_EQ(curved, eval_lagrange(p, original, s)) << "tet " << t;
        Vec3 straight = Vec3::Zero();
        for (int k = 0; k < 4; ++k) straight += s[k] * m.coords[m.tet2verts[t][k]];
        ASSERT_GT((curved - straight).norm(), 1e-5);  // the nodes really are curved
      }
    }
  }
}

INSTANTIATE_TEST_SUITE_P(Orders, MshCurved, ::testing::Values(2, 3));

// ---------------------------------------------------------------------------
// Valid input in the less common forms.

TEST(MshRead, SparseUnorderedTagsAndUnusedNodes) {
  const std::string text =
      "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n"
      "$Nodes\n2 5 7 1000000000000\n"
      "3 4 0 3\n1000000000000\n7\n500\n1 0 0\n0 0 0\n0 1 0\n"
      "3 4 0 2\n20\n3\n0 0 1\n9 9 9\n$EndNodes\n"
      "$Elements\n1 1 5 5\n3 4 4 1\n5 7 1000000000000 500 20\n$EndElements\n";
  const TetMesh m = read_msh(text, "sparse.msh");
  ASSERT_EQ(m.num_verts(), 4u);           // node 3 is in no element
  EXPECT_EQ(m.coords[0], Vec3(0, 0, 0));  // tag 7
  EXPECT_EQ(m.coords[1], Vec3(0, 0, 1));  // tag 20
  EXPECT_EQ(m.coords[2], Vec3(0, 1, 0));  // tag 500
  EXPECT_EQ(m.coords[3], Vec3(1, 0, 0));  // tag 10^12
  ASSERT_EQ(m.num_tets(), 1u);
  EXPECT_EQ(m.tet2verts[0], (std::array<VertId, 4>{0, 3, 2, 1}));
  EXPECT_EQ(m.tet_region[0], 4);
  EXPECT_EQ(m.vert_class[1], (ModelRef{3, 4}));
}

TEST(MshRead, Msh22ElementaryTagsPhysicalsAndPointHints) {
  const std::string text =
      "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n"
      "$Nodes\n4\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 1\n$EndNodes\n"
      "$Elements\n4\n1 15 2 0 3 1\n2 1 2 0 5 1 2\n3 2 2 9 6 1 3 2\n4 4 3 8 2 5 1 2 3 "
      "4\n$EndElements\n";
  const TetMesh m = read_msh(text, "a22.msh");
  ASSERT_EQ(m.num_tets(), 1u);
  EXPECT_EQ(m.tet_region[0], 2);
  ASSERT_EQ(m.tris.size(), 1u);
  EXPECT_EQ(m.tris[0].face_tag, 6);
  ASSERT_EQ(m.edges.size(), 1u);
  EXPECT_EQ(m.edges[0].edge_tag, 5);
  EXPECT_EQ(m.vert_class[0], (ModelRef{0, 3}));
  EXPECT_FALSE(m.vert_class[1].valid());
  ASSERT_EQ(m.entities.size(), 4u);
  EXPECT_EQ(find_entity(m, 3, 2)->physicals, (std::vector<int>{8}));
  EXPECT_EQ(find_entity(m, 2, 6)->physicals, (std::vector<int>{9}));
  EXPECT_TRUE(find_entity(m, 1, 5)->physicals.empty());
}

// A binary 4.1 file written big-endian by hand reads like its text twin.
TEST(MshRead, BigEndianBinaryIsSwapped) {
  std::string b = "$MeshFormat\n4.1 1 8\n";
  const auto put = [&](auto v) {
    const auto* p = reinterpret_cast<const char*>(&v);
    for (std::size_t k = sizeof(v); k-- > 0;) b.push_back(p[k]);
  };
  put(std::int32_t{1});
  b += "\n$EndMeshFormat\n$Entities\n";
  for (std::uint64_t c : {0, 0, 0, 1}) put(c);
  put(std::int32_t{5});
  for (double x : {0.0, 0.0, 0.0, 1.0, 1.0, 1.0}) put(x);
  put(std::uint64_t{1});
  put(std::int32_t{50});
  put(std::uint64_t{0});
  b += "\n$EndEntities\n$Nodes\n";
  for (std::uint64_t c : {1, 4, 1, 4}) put(c);
  put(std::int32_t{3});
  put(std::int32_t{5});
  put(std::int32_t{0});
  put(std::uint64_t{4});
  for (std::uint64_t t : {1, 2, 3, 4}) put(t);
  for (double x : {0.0, 0.0, 0.0, 1.5, 0.0, 0.0, 0.0, 1.0 / 3, 0.0, 0.0, 0.0, 0.1}) put(x);
  b += "\n$EndNodes\n$Elements\n";
  for (std::uint64_t c : {1, 1, 1, 1}) put(c);
  for (std::int32_t v : {3, 5, 4}) put(v);
  put(std::uint64_t{1});
  for (std::uint64_t t : {1, 1, 2, 3, 4}) put(t);
  b += "\n$EndElements\n";
  const TetMesh m = read_msh(b, "be.msh");
  ASSERT_EQ(m.num_verts(), 4u);
  EXPECT_EQ(m.coords[1], Vec3(1.5, 0, 0));
  EXPECT_EQ(m.coords[2], Vec3(0, 1.0 / 3, 0));
  EXPECT_EQ(m.tet2verts[0], (std::array<VertId, 4>{0, 1, 2, 3}));
  EXPECT_EQ(m.tet_region[0], 5);
  ASSERT_EQ(m.entities.size(), 1u);
  EXPECT_EQ(m.entities[0].physicals, (std::vector<int>{50}));
}

// ---------------------------------------------------------------------------
// Malformed input: each file of data/msh gives exactly this message.

struct BadFile {
  const char* name;
  const char* message;
};

constexpr BadFile kBadFiles[] = {
    {"empty.msh", "empty.msh:1: empty file (expected $MeshFormat)"},
    {"not_msh.msh", "not_msh.msh:1: not a Gmsh MSH file: expected $MeshFormat, got 'solid'"},
    {"version_30.msh",
     "version_30.msh:2: unsupported MSH version '3.0' (curvemesh reads versions 2.2 and 4.1)"},
    {"version_40.msh",
     "version_40.msh:2: unsupported MSH version '4' (curvemesh reads versions 2.2 and 4.1)"},
    {"data_size_4.msh", "data_size_4.msh:2: unsupported data size 4 (only 8 is supported)"},
    {"truncated_nodes.msh",
     "truncated_nodes.msh:14: unexpected end of file while reading node coordinate"},
    {"node_count_mismatch.msh",
     "node_count_mismatch.msh:5: the $Nodes header announces 5 nodes but its blocks hold 4"},
    {"absurd_count.msh",
     "absurd_count.msh:5: number of nodes 900000000000 is more than the rest of the file can hold"},
    {"negative_count.msh",
     "negative_count.msh:5: number of nodes -4 is out of range [0, 9223372036854775807]"},
    {"undefined_node.msh", "undefined_node.msh:19: element 1 references undefined node 9"},
    {"duplicate_node.msh", "duplicate_node.msh:9: duplicate node tag 2"},
    {"nan_coordinate.msh", "nan_coordinate.msh:13: non-finite node coordinate 'nan'"},
    {"huge_coordinate.msh",
     "huge_coordinate.msh:12: node coordinate '1e999' is out of the range of a double"},
    {"bad_number.msh", "bad_number.msh:11: expected a number (node coordinate), got '0,5'"},
    {"hexahedron.msh", "hexahedron.msh:26: unsupported element type 5 (8-node hexahedron)"},
    {"unknown_type.msh", "unknown_type.msh:18: unsupported element type 77"},
    {"missing_elements.msh", "missing_elements.msh:16: missing $Elements section"},
    {"missing_end.msh", "missing_end.msh:15: expected $EndNodes, got '$Elements'"},
    {"mixed_orders.msh",
     "mixed_orders.msh:24: element type 9 has order 2 but earlier elements have order 1 (mixed "
     "orders are not supported)"},
    {"repeated_node.msh", "repeated_node.msh:19: element 1 has the repeated node 2"},
    {"entity_dim.msh", "entity_dim.msh:6: entity dimension 5 is out of range [0, 3]"},
    {"wrong_block_dim.msh",
     "wrong_block_dim.msh:18: element type 4 has dimension 3 but its block's entity has dimension "
     "2"},
    {"unterminated_section.msh",
     "unterminated_section.msh:4: missing $EndComments for section $Comments"},
    {"partitioned.msh",
     "partitioned.msh:4: partitioned meshes ($PartitionedEntities) are not supported"},
    {"elements_first.msh", "elements_first.msh:4: $Elements section before the $Nodes section"},
    {"duplicate_section.msh", "duplicate_section.msh:16: duplicate $Nodes section"},
    {"ho_conflict.msh",
     "ho_conflict.msh:48: element 2: its high-order nodes on the edge of nodes 1 and 2 differ from "
     "those of another element on that edge"},
    {"msh22_quad.msh", "msh22_quad.msh:14: unsupported element type 3 (4-node quadrangle)"},
    {"msh22_truncated.msh",
     "msh22_truncated.msh:13: unexpected end of file while reading node tag"},
    {"msh22_undefined_node.msh",
     "msh22_undefined_node.msh:13: element 1 references undefined node 5"},
    {"msh22_bad_tag_count.msh",
     "msh22_bad_tag_count.msh:13: number of tags -2 is out of range [0, 2147483647]"},
};

TEST(MshMalformed, CorpusGivesExactMessages) {
  for (const BadFile& bad : kBadFiles) {
    const std::string bytes = read_file_bytes(std::string(CM_TEST_DATA_DIR) + "/msh/" + bad.name);
    try {
      read_msh(bytes, bad.name);
      ADD_FAILURE() << bad.name << " was accepted";
    } catch (const InputError& e) {
      EXPECT_EQ(std::string(e.what()), bad.message);
      EXPECT_GT(e.line(), 0) << bad.name;
    }
  }
}

std::string written_bytes(const TetMesh& m, bool binary, const TempDir& dir) {
  write_msh41(m, dir.file("w.msh"), binary);
  return read_file_bytes(dir.file("w.msh"));
}

TEST(MshMalformed, EveryTruncationFails) {
  TetMesh m = make_grid(1, true);
  curve_grid(m, 3);
  TempDir dir;
  for (bool binary : {false, true}) {
    const std::string bytes = written_bytes(m, binary, dir);
    const std::size_t header = bytes.find("$EndMeshFormat");
    for (std::size_t len = 0; len + 1 < bytes.size(); ++len) {
      try {
        read_msh(std::string_view(bytes).substr(0, len), "cut.msh");
        ADD_FAILURE() << "truncation at " << len << " accepted";
      } catch (const InputError& e) {
        if (binary && len > header) {
          EXPECT_EQ(e.line(), -1);
          EXPECT_GE(e.byte_offset(), 0);
          EXPECT_LE(e.byte_offset(), static_cast<std::int64_t>(len));
        }
      }
    }
    EXPECT_NO_THROW(read_msh(std::string_view(bytes).substr(0, bytes.size() - 1), "cut.msh"));
  }
}

TEST(MshMalformed, BadEndiannessMarker) {
  TempDir dir;
  std::string bytes = written_bytes(make_grid(1, true), true, dir);
  const std::size_t marker = bytes.find("4.1 1 8\n") + 8;
  bytes[marker] = 2;
  try {
    read_msh(bytes, "e.msh");
    ADD_FAILURE() << "accepted";
  } catch (const InputError& e) {
    EXPECT_EQ(e.reason(),
              "invalid endianness marker 2 in binary $MeshFormat (expected the integer 1)");
    EXPECT_EQ(e.byte_offset(), static_cast<std::int64_t>(marker));
  }
}

// Random byte edits: the reader either succeeds or throws InputError.
TEST(MshMalformed, RandomEditsOnlyThrowInputError) {
  TetMesh m = make_grid(1, true);
  curve_grid(m, 2);
  TempDir dir;
  std::mt19937 rng(12345);
  int rejected = 0, total = 0;
  for (bool binary : {false, true}) {
    const std::string original = written_bytes(m, binary, dir);
    for (int trial = 0; trial < 1500; ++trial) {
      std::string bytes = original;
      const int edits = 1 + static_cast<int>(rng() % 4);
      for (int k = 0; k < edits; ++k) {
        const std::size_t at = rng() % bytes.size();
        const char choices[] = {'0', '9', '-', ' ', '\n', '$', static_cast<char>(rng()), 'e'};
        bytes[at] = choices[rng() % sizeof(choices)];
      }
      ++total;
      try {
        read_msh(bytes, "edit.msh");
      } catch (const InputError&) {
        ++rejected;
      }
    }
  }
  EXPECT_GT(rejected, total / 4);  // the edits do reach the checks
}

TEST(MshWrite, FailureLeavesNoFile) {
  TempDir dir;
  const std::string path = dir.file("missing_dir/out.msh");
  EXPECT_THROW(write_msh41(make_grid(1, true), path, false), std::runtime_error);
  EXPECT_FALSE(fs::exists(path));
}

}  // namespace
}  // namespace cm::io::msh_test
