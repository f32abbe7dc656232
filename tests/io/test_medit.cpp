// Medit .mesh/.meshb and MMG .sol/.solb: exact round trips, files built
// byte by byte from the libMeshb layout (all versions, both byte orders),
// gmsh's output, and a corpus of malformed files with their exact messages.
#include <fmt/format.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <limits>
#include <map>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "curvemesh/core/error.hpp"
#include "curvemesh/io/atomic_file.hpp"
#include "curvemesh/io/formats.hpp"
#include "curvemesh/mesh/tet_mesh.hpp"
#include "curvemesh/mesh/topology.hpp"

namespace fs = std::filesystem;
using cm::InputError;
using cm::Vec3;
using cm::VertId;
using cm::mesh::TetMesh;

namespace {

const std::string kData = std::string(CM_TEST_DATA_DIR) + "/medit/";

class MeditTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / fmt::format("cm_test_medit_{}", static_cast<long>(getpid()));
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string path(const std::string& name) const { return (dir_ / name).string(); }
  fs::path dir_;
};

// An n x n x n grid of cubes, each split into 6 tets around its diagonal,
// with coordinates that use all 53 bits of the mantissa. Hull triangles are
// tagged by box side (1..6), x-parallel box edges by their corner (1..4), and
// each vertex is classified with tag 1000 + id.
TetMesh make_grid_mesh(int n, unsigned seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> jitter(-0.05, 0.05);
  TetMesh m;
  std::vector<std::array<int, 3>> grid;
  const auto id = [&](int i, int j, int k) {
    return static_cast<VertId>((k * (n + 1) + j) * (n + 1) + i);
  };
  for (int k = 0; k <= n; ++k)
    for (int j = 0; j <= n; ++j)
      for (int i = 0; i <= n; ++i) {
        m.add_vert(Vec3(i + jitter(rng), j + jitter(rng), k + jitter(rng)) / 3.0);
        grid.push_back({i, j, k});
      }
  const int perms[6][3] = {{1, 2, 4}, {1, 4, 2}, {2, 1, 4}, {2, 4, 1}, {4, 1, 2}, {4, 2, 1}};
  for (int k = 0; k < n; ++k)
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        const auto corner = [&](int b) {
          return id(i + (b & 1), j + (b >> 1 & 1), k + (b >> 2 & 1));
        };
        for (const auto& p : perms) {
          std::array<VertId, 4> t{corner(0), corner(p[0]), corner(p[0] | p[1]), corner(7)};
          const cm::TetId tid = m.add_tet(t, i < n / 2 ? 1 : 2);
          if (cm::mesh::tet_volume(m, tid) < 0) std::swap(m.tet2verts[tid][2], m.tet2verts[tid][3]);
        }
      }
  std::map<std::array<VertId, 3>, std::pair<int, std::array<VertId, 3>>> faces;
  for (const auto& t : m.tet2verts)
    for (const auto& f : cm::mesh::kFaceVerts) {
      std::array<VertId, 3> oriented{t[f[0]], t[f[1]], t[f[2]]}, key = oriented;
      std::sort(key.begin(), key.end());
      auto& entry = faces[key];
      ++entry.first;
      entry.second = oriented;
    }
  for (const auto& [key, entry] : faces) {
    if (entry.first != 1) continue;
    int tag = 0;
    for (int axis = 0; axis < 3 && tag == 0; ++axis)
      for (int side = 0; side < 2 && tag == 0; ++side) {
        const int value = side == 0 ? 0 : n;
        if (grid[key[0]][axis] == value && grid[key[1]][axis] == value &&
            grid[key[2]][axis] == value)
          tag = 1 + 2 * axis + side;
      }
    m.tris.push_back({entry.second, tag});
  }
  for (int corner = 0; corner < 4; ++corner)
    for (int i = 0; i < n; ++i) {
      const int j = (corner & 1) ? n : 0, k = (corner & 2) ? n : 0;
      m.edges.push_back({{id(i, j, k), id(i + 1, j, k)}, corner + 1});
    }
  for (std::size_t v = 0; v < m.num_verts(); ++v)
    m.vert_class[v] = {0, static_cast<std::int32_t>(1000 + v)};
  return m;
}

void expect_same_mesh(const TetMesh& a, const TetMesh& b) {
  ASSERT_EQ(a.num_verts(), b.num_verts());
  for (std::size_t v = 0; v < a.num_verts(); ++v)
    for (int c = 0; c < 3; ++c) ASSERT_EQ(a.coords[v][c], b.coords[v][c]) << "vertex " << v;
  ASSERT_EQ(a.tet2verts, b.tet2verts);
  ASSERT_EQ(a.tet_region, b.tet_region);
  ASSERT_EQ(a.tris.size(), b.tris.size());
  for (std::size_t t = 0; t < a.tris.size(); ++t) {
    EXPECT_EQ(a.tris[t].verts, b.tris[t].verts);
    EXPECT_EQ(a.tris[t].face_tag, b.tris[t].face_tag);
  }
  ASSERT_EQ(a.edges.size(), b.edges.size());
  for (std::size_t e = 0; e < a.edges.size(); ++e) {
    EXPECT_EQ(a.edges[e].verts, b.edges[e].verts);
    EXPECT_EQ(a.edges[e].edge_tag, b.edges[e].edge_tag);
  }
  // Vertex references are not read back: classification is derived later.
  ASSERT_EQ(b.vert_class.size(), b.num_verts());
  for (const auto& c : b.vert_class) EXPECT_FALSE(c.valid());
}

// Builds a binary GMF file field by field, following the libMeshb layout
// independently of the library's writer. Fields are little-endian, or
// big-endian when `big_endian`.
class GmfBuilder {
 public:
  GmfBuilder(int version, bool big_endian) : version_(version), big_endian_(big_endian) {
    i32(1);
    i32(version);
  }
  void i32(std::int32_t v) { put(static_cast<std::uint32_t>(v), 4); }
  void i64(std::int64_t v) { put(static_cast<std::uint64_t>(v), 8); }
  void integer(std::int64_t v) { version_ == 4 ? i64(v) : i32(static_cast<std::int32_t>(v)); }
  void real(double v) {
    if (version_ == 1)
      put(std::bit_cast<std::uint32_t>(static_cast<float>(v)), 4);
    else
      put(std::bit_cast<std::uint64_t>(v), 8);
  }
  // Starts a keyword; the previous keyword's next position points here.
  void keyword(int code) {
    if (next_field_ != 0) put_at(next_field_, bytes_.size(), version_ >= 3 ? 8 : 4);
    i32(code);
    next_field_ = bytes_.size();
    version_ >= 3 ? i64(0) : i32(0);
  }
  std::string finish() {
    keyword(54);  // End, with next position 0
    return bytes_;
  }

 private:
  void put(std::uint64_t v, int n) {
    bytes_.resize(bytes_.size() + static_cast<std::size_t>(n));
    put_at(bytes_.size() - static_cast<std::size_t>(n), v, n);
  }
  void put_at(std::size_t at, std::uint64_t v, int n) {
    for (int i = 0; i < n; ++i)
      bytes_[at + static_cast<std::size_t>(i)] =
          static_cast<char>(v >> (8 * (big_endian_ ? n - 1 - i : i)));
  }
  int version_;
  bool big_endian_;
  std::string bytes_;
  std::size_t next_field_ = 0;
};

// The mesh's sections through GmfBuilder, vertex references 0 (as written
// for unclassified vertices), Tetrahedra first when `tets_first`.
std::string build_meshb(const TetMesh& m, int version, bool big_endian, bool tets_first) {
  GmfBuilder b(version, big_endian);
  b.keyword(3);
  b.i32(3);
  const auto tets = [&] {
    b.keyword(8);
    b.integer(static_cast<std::int64_t>(m.num_tets()));
    for (std::size_t t = 0; t < m.num_tets(); ++t) {
      for (VertId v : m.tet2verts[t]) b.integer(v + 1);
      b.integer(m.tet_region[t]);
    }
  };
  if (tets_first) tets();
  b.keyword(4);
  b.integer(static_cast<std::int64_t>(m.num_verts()));
  for (const Vec3& x : m.coords) {
    for (int c = 0; c < 3; ++c) b.real(x[c]);
    b.integer(0);
  }
  b.keyword(5);
  b.integer(static_cast<std::int64_t>(m.edges.size()));
  for (const auto& e : m.edges) {
    for (VertId v : e.verts) b.integer(v + 1);
    b.integer(e.edge_tag);
  }
  b.keyword(6);
  b.integer(static_cast<std::int64_t>(m.tris.size()));
  for (const auto& t : m.tris) {
    for (VertId v : t.verts) b.integer(v + 1);
    b.integer(t.face_tag);
  }
  if (!tets_first) tets();
  return b.finish();
}

// Count following `keyword` in a text Medit file, read without the library.
std::int64_t count_after(const std::string& text, const std::string& keyword) {
  std::istringstream in(text);
  std::string token;
  while (in >> token)
    if (token == keyword && in >> token) return std::stoll(token);
  return 0;
}

// 1-based line of the first line that is `keyword` (trimmed), or 0.
std::int64_t line_of(const std::string& text, const std::string& keyword) {
  std::istringstream in(text);
  std::string line;
  for (std::int64_t n = 1; std::getline(in, line); ++n) {
    std::istringstream words(line);
    std::string word;
    if (words >> word && word == keyword) return n;
  }
  return 0;
}

struct TextCase {
  const char* file;
  std::int64_t line;
  const char* reason;
};

struct BinaryCase {
  std::string name;
  std::string bytes;
  std::int64_t offset;
  std::string reason;
};

template <class Read>
void expect_input_error(const std::string& bytes, const std::string& name, std::int64_t line,
                        std::int64_t offset, const std::string& reason, Read&& read) {
  try {
    read(bytes, name);
    ADD_FAILURE() << name << ": no error, expected: " << reason;
  } catch (const InputError& e) {
    EXPECT_EQ(e.file(), name);
    EXPECT_EQ(e.line(), line) << name << ": " << e.what();
    EXPECT_EQ(e.byte_offset(), offset) << name << ": " << e.what();
    EXPECT_NE(e.reason().find(reason), std::string::npos) << name << ": got '" << e.reason() << "'";
  }
}

// A 4-vertex, 1-tet version 2 file: Dimension at 8, Vertices at 20 (count at
// 28, 28-byte records from 32), Tetrahedra at 144 (count 152, record 156),
// End at 176; 184 bytes.
std::string small_meshb() {
  TetMesh m;
  m.add_vert({0, 0, 0});
  m.add_vert({1, 0, 0});
  m.add_vert({0, 1, 0});
  m.add_vert({0, 0, 1});
  m.add_tet({0, 1, 2, 3}, 7);
  GmfBuilder b(2, false);
  b.keyword(3);
  b.i32(3);
  b.keyword(4);
  b.integer(4);
  for (const Vec3& x : m.coords) {
    for (int c = 0; c < 3; ++c) b.real(x[c]);
    b.integer(0);
  }
  b.keyword(8);
  b.integer(1);
  for (int v = 1; v <= 4; ++v) b.integer(v);
  b.integer(7);
  return b.finish();
}

std::string patched(std::string bytes, std::size_t at, const void* value, std::size_t n) {
  std::memcpy(bytes.data() + at, value, n);
  return bytes;
}
std::string patched_i32(const std::string& bytes, std::size_t at, std::int32_t v) {
  return patched(bytes, at, &v, 4);
}

}  // namespace

TEST_F(MeditTest, TextRoundTripIsExact) {
  const TetMesh m = make_grid_mesh(3, 1);
  ASSERT_EQ(m.num_tets(), 162u);
  ASSERT_EQ(m.tris.size(), 108u);
  cm::io::write_medit(m, path("grid.mesh"), false);
  const std::string text = cm::io::read_file_bytes(path("grid.mesh"));
  expect_same_mesh(m, cm::io::read_medit(text, path("grid.mesh")));
  // Vertex references carry the vertex classification tag.
  std::istringstream in(text.substr(text.find("Vertices")));
  std::string keyword;
  std::size_t count = 0;
  in >> keyword >> count;
  ASSERT_EQ(count, m.num_verts());
  for (std::size_t v = 0; v < count; ++v) {
    double x, y, z;
    long ref;
    in >> x >> y >> z >> ref;
    ASSERT_EQ(ref, 1000 + static_cast<long>(v));
  }
}

TEST_F(MeditTest, BinaryRoundTripIsExactAndMatchesTheLayout) {
  TetMesh m = make_grid_mesh(3, 2);
  cm::io::write_medit(m, path("grid.meshb"), true);
  const std::string bytes = cm::io::read_file_bytes(path("grid.meshb"));
  expect_same_mesh(m, cm::io::read_medit(bytes, path("grid.meshb")));
  // With unclassified vertices the writer's bytes are exactly the layout built
  // field by field: version 2, keywords in the order Vertices, Edges,
  // Triangles, Tetrahedra.
  m.vert_class.assign(m.num_verts(), {});
  cm::io::write_medit(m, path("plain.meshb"), true);
  EXPECT_EQ(cm::io::read_file_bytes(path("plain.meshb")), build_meshb(m, 2, false, false));
}

TEST_F(MeditTest, ReadsEveryBinaryVersionInBothByteOrders) {
  const TetMesh m = make_grid_mesh(2, 3);
  for (int version = 1; version <= 4; ++version)
    for (bool big_endian : {false, true}) {
      SCOPED_TRACE(
          fmt::format("version {} {}", version, big_endian ? "big-endian" : "little-endian"));
      const TetMesh r =
          cm::io::read_medit(build_meshb(m, version, big_endian, version == 3), "built.meshb");
      if (version > 1) {
        expect_same_mesh(m, r);
        continue;
      }
      ASSERT_EQ(r.num_verts(), m.num_verts());
      for (std::size_t v = 0; v < m.num_verts(); ++v)
        for (int c = 0; c < 3; ++c)
          ASSERT_EQ(r.coords[v][c], static_cast<double>(static_cast<float>(m.coords[v][c])));
      EXPECT_EQ(r.tet2verts, m.tet2verts);
      EXPECT_EQ(r.tet_region, m.tet_region);
    }
}

TEST_F(MeditTest, SkipsKeywordsItDoesNotNeed) {
  const std::string file = kData + "valid_extras.mesh";
  const TetMesh m = cm::io::read_medit(cm::io::read_file_bytes(file), file);
  ASSERT_EQ(m.num_verts(), 5u);
  EXPECT_EQ(m.coords[1], Vec3(1.5, 0, 0));
  EXPECT_EQ(m.coords[2], Vec3(0, 2, 0));
  EXPECT_EQ(m.coords[3], Vec3(0, 0, 2.5));
  ASSERT_EQ(m.num_tets(), 2u);
  EXPECT_EQ(m.tet2verts[1], (std::array<VertId, 4>{0, 1, 4, 3}));
  EXPECT_EQ(m.tet_region, (std::vector<std::int32_t>{31, 32}));
  ASSERT_EQ(m.tris.size(), 2u);
  EXPECT_EQ(m.tris[0].verts, (std::array<VertId, 3>{0, 2, 1}));
  EXPECT_EQ(m.tris[1].face_tag, 22);
  ASSERT_EQ(m.edges.size(), 1u);
  EXPECT_EQ(m.edges[0].edge_tag, 11);
}

TEST_F(MeditTest, ReadsElementsWrittenBeforeTheVertices) {
  const std::string file = kData + "valid_late_vertices.mesh";
  const TetMesh m = cm::io::read_medit(cm::io::read_file_bytes(file), file);
  EXPECT_EQ(m.num_verts(), 4u);
  EXPECT_EQ(m.num_tets(), 1u);
  ASSERT_EQ(m.tris.size(), 1u);
  EXPECT_EQ(m.tris[0].face_tag, 5);
}

TEST_F(MeditTest, MalformedTextFilesGiveLineAndReason) {
  const TextCase cases[] = {
      {"empty.mesh", 1, "not a Medit mesh: the file is empty"},
      {"not_medit.mesh", 1,
       "not a Medit mesh: expected 'MeshVersionFormatted', found '$MeshFormat'"},
      {"bad_version.mesh", 1, "unsupported MeshVersionFormatted 9 (1 to 4 are defined)"},
      {"dimension2.mesh", 3, "Dimension 2 is not supported: curvemesh reads 3D meshes only"},
      {"bad_dimension.mesh", 3, "invalid Dimension 4 (expected 3)"},
      {"vertices_before_dimension.mesh", 5, "Vertices before Dimension"},
      {"truncated_vertices.mesh", 9, "unexpected end of file in Vertices record 3 of 4"},
      {"count_too_small.mesh", 10,
       "expected a keyword, found '0' (does a count above match its records?)"},
      {"count_too_large.mesh", 12, "Vertices record 5 of 5: expected a number, found 'Tetrahedra'"},
      {"count_exceeds_file.mesh", 13,
       "Tetrahedra: count 2 is larger than the rest of the file can hold (16 bytes)"},
      {"absurd_count.mesh", 6,
       "Vertices: count 999999999999 is larger than the rest of the file can hold"},
      {"negative_count.mesh", 6, "Vertices: negative count -4"},
      {"index_zero.mesh", 14, "Tetrahedra record 1 of 1: vertex index 0 out of range 1..4"},
      {"index_too_big.mesh", 14, "Tetrahedra record 1 of 1: vertex index 5 out of range 1..4"},
      {"repeated_vertex.mesh", 14, "Tetrahedra record 1 of 1: vertex index 2 appears twice"},
      {"nan_coordinate.mesh", 9, "Vertices record 3 of 4: coordinate nan is not finite"},
      {"inf_coordinate.mesh", 9, "Vertices record 3 of 4: coordinate -inf is not finite"},
      {"huge_coordinate.mesh", 8,
       "Vertices record 2 of 4: number '1e999' is out of the range of a double"},
      {"float_index.mesh", 14, "Tetrahedra record 1 of 1: expected an integer, found '2.5'"},
      {"bad_number.mesh", 8, "Vertices record 2 of 4: expected a number, found '1.0D+00'"},
      {"ref_overflow.mesh", 14,
       "Tetrahedra record 1 of 1: reference 4294967296 does not fit in 32 bits"},
      {"high_order.mesh", 12, "TetrahedraP2: high-order Medit elements are not supported"},
      {"duplicate_vertices.mesh", 11, "duplicate Vertices section"},
      {"late_vertices_bad_index.mesh", 5,
       "Tetrahedra record 2 of 2: vertex index 9 out of range 1..4"},
      {"no_vertices.mesh", 3,
       "Tetrahedra record 1 of 1: vertex index 1 but the file has no vertices"},
  };
  for (const TextCase& c : cases) {
    const std::string file = kData + c.file;
    expect_input_error(cm::io::read_file_bytes(file), file, c.line, -1, c.reason,
                       cm::io::read_medit);
  }
  // The message leads with "file:line: ".
  try {
    cm::io::read_medit("MeshVersionFormatted 2\nDimension 2\n", "x.mesh");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_STREQ(e.what(),
                 "x.mesh:2: Dimension 2 is not supported: curvemesh reads 3D meshes only");
  }
}

TEST_F(MeditTest, MalformedBinaryFilesGiveOffsetAndReason) {
  const std::string good = small_meshb();
  ASSERT_EQ(good.size(), 184u);
  ASSERT_EQ(cm::io::read_medit(good, "good.meshb").num_tets(), 1u);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  GmfBuilder dup(2, false);
  dup.keyword(3);
  dup.i32(3);
  for (int k = 0; k < 2; ++k) {
    dup.keyword(4);
    dup.integer(0);
  }
  GmfBuilder high(2, false);
  high.keyword(3);
  high.i32(3);
  high.keyword(30);
  high.integer(0);
  GmfBuilder wide(4, false);
  wide.keyword(3);
  wide.i32(3);
  wide.keyword(4);
  wide.integer(2);
  for (int v = 0; v < 2; ++v) {
    for (int c = 0; c < 3; ++c) wide.real(v + c);
    wide.integer(0);
  }
  wide.keyword(5);
  wide.integer(1);
  wide.integer(1);
  wide.integer(2);
  wide.integer(std::int64_t{1} << 40);
  const BinaryCase cases[] = {
      {"short", good.substr(0, 3), -1, ""},  // shorter than the endianness word: read as text
      {"header", good.substr(0, 7), 0, "file too short for a .meshb header (7 bytes)"},
      {"version", patched_i32(good, 4, 5), 4, "unsupported .meshb version 5 (1 to 4 are defined)"},
      {"first keyword", patched_i32(good, 8, 4), 8,
       "expected the Dimension keyword (code 3) first, found code 4"},
      {"dimension 2", patched_i32(good, 16, 2), 16,
       "Dimension 2 is not supported: curvemesh reads 3D meshes only"},
      {"loop back", patched_i32(good, 24, 8), 24,
       "keyword code 4: next keyword position 8 is outside 28..184"},
      {"loop on itself", patched_i32(good, 24, 20), 24,
       "next keyword position 20 is outside 28..184"},
      {"beyond end", patched_i32(good, 148, 1000), 148,
       "keyword code 8: next keyword position 1000 is outside 152..184"},
      {"short keyword", patched_i32(good, 24, 100), 28,
       "Vertices: count 4 of 28-byte records does not fit in the 68 bytes the keyword holds"},
      {"absurd count", patched_i32(good, 28, 0x7fffffff), 28,
       "Vertices: count 2147483647 of 28-byte records does not fit in the 112 bytes"},
      {"negative count", patched_i32(good, 28, -1), 28, "Vertices: negative count -1"},
      {"index 0", patched_i32(good, 156, 0), 156,
       "Tetrahedra record 1 of 1: vertex index 0 out of range 1..4"},
      {"index 9", patched_i32(good, 168, 9), 156,
       "Tetrahedra record 1 of 1: vertex index 9 out of range 1..4"},
      {"nan", patched(good, 68, &nan, 8), 68,
       "Vertices record 2 of 4: coordinate nan is not finite"},
      {"duplicate", dup.finish(), 32, "duplicate keyword code 4"},
      {"high order", high.finish(), 20,
       "TetrahedraP2: high-order Medit elements are not supported"},
      {"wide ref", wide.finish(), 144,
       "Edges record 1 of 1: reference 1099511627776 does not fit in 32 bits"},
  };
  for (const BinaryCase& c : cases) {
    if (c.offset < 0) {
      EXPECT_THROW(cm::io::read_medit(c.bytes, c.name), InputError);
      continue;
    }
    expect_input_error(c.bytes, c.name, -1, c.offset, c.reason, cm::io::read_medit);
  }
}

TEST_F(MeditTest, EveryTruncatedBinaryFileFails) {
  const std::string good = build_meshb(make_grid_mesh(1, 4), 2, false, false);
  for (std::size_t n = 0; n < good.size(); ++n) {
    try {
      cm::io::read_medit(good.substr(0, n), "cut.meshb");
      ADD_FAILURE() << "prefix of " << n << " bytes was accepted";
    } catch (const InputError& e) {
      if (n >= 4) {
        EXPECT_GE(e.byte_offset(), 0) << n;
      }
    }
  }
}

TEST_F(MeditTest, EveryTruncatedTextFileFails) {
  cm::io::write_medit(make_grid_mesh(1, 5), path("cut.mesh"), false);
  const std::string good = cm::io::read_file_bytes(path("cut.mesh"));
  const std::size_t end = good.rfind("End") + 3;
  for (std::size_t n = 0; n < end; ++n) {
    try {
      cm::io::read_medit(good.substr(0, n), "cut.mesh");
      ADD_FAILURE() << "prefix of " << n << " bytes was accepted";
    } catch (const InputError& e) {
      EXPECT_GE(e.line(), 1);
    }
  }
  EXPECT_NO_THROW(cm::io::read_medit(good.substr(0, end), "cut.mesh"));
}

TEST_F(MeditTest, RefusesToWriteCurvedMeshes) {
  TetMesh m = make_grid_mesh(1, 6);
  m.high_order.reset(2);
  try {
    cm::io::write_medit(m, path("curved.mesh"), false);
    FAIL();
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("Medit format holds linear meshes only"),
              std::string::npos);
  }
  EXPECT_TRUE(fs::is_empty(dir_));  // no partial or temporary file left
}

TEST_F(MeditTest, ReadsGmshOutput) {
  const std::string gmsh = CM_GMSH_EXECUTABLE;
  if (gmsh.empty()) GTEST_SKIP() << "gmsh not installed";
  const std::string model = std::string(CM_SHARED_DIR) + "/models/t20_data.step";
  for (int order : {1, 2}) {
    const std::string out = path(fmt::format("t20_p{}.mesh", order));
    const std::string command =
        fmt::format("'{}' -3 '{}' -setnumber Mesh.MeshSizeMax 6 -order {} -o '{}' > '{}.log' 2>&1",
                    gmsh, model, order, out, out);
    ASSERT_EQ(std::system(command.c_str()), 0) << command;
    const std::string text = cm::io::read_file_bytes(out);
    if (order == 2) {
      expect_input_error(text, out, line_of(text, "EdgesP2"), -1,
                         "EdgesP2: high-order Medit elements are not supported",
                         cm::io::read_medit);
      continue;
    }
    const TetMesh m = cm::io::read_medit(text, out);
    EXPECT_EQ(static_cast<std::int64_t>(m.num_verts()), count_after(text, "Vertices"));
    EXPECT_EQ(static_cast<std::int64_t>(m.num_tets()), count_after(text, "Tetrahedra"));
    EXPECT_EQ(static_cast<std::int64_t>(m.tris.size()), count_after(text, "Triangles"));
    EXPECT_EQ(static_cast<std::int64_t>(m.edges.size()), count_after(text, "Edges"));
    EXPECT_GT(m.num_tets(), 500u);
    // gmsh orients its tets as curvemesh does: every one is positive.
    std::size_t positive = 0;
    for (cm::TetId t = 0; t < m.num_tets(); ++t) positive += cm::mesh::tet_volume(m, t) > 0;
    EXPECT_EQ(positive, m.num_tets());
    for (auto region : m.tet_region) EXPECT_GT(region, 0);
    for (const auto& tri : m.tris) EXPECT_GT(tri.face_tag, 0);
  }
}

// ---------------------------------------------------------------------------
// .sol / .solb

namespace {

std::vector<double> random_values(std::size_t n, unsigned seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> value(-1e3, 1e3);
  std::vector<double> out(n);
  for (double& v : out) v = value(rng) / 7.0;
  return out;
}

std::string build_solb(int version, bool big_endian, const std::vector<int>& types,
                       std::int64_t count, const std::vector<double>& values) {
  GmfBuilder b(version, big_endian);
  b.keyword(3);
  b.i32(3);
  b.keyword(62);
  b.integer(count);
  b.i32(static_cast<std::int32_t>(types.size()));
  for (int t : types) b.i32(t);
  for (double v : values) b.real(v);
  return b.finish();
}

}  // namespace

TEST_F(MeditTest, SolRoundTripsAreExact) {
  for (auto type : {cm::io::SolField::Type::kScalar, cm::io::SolField::Type::kTensor})
    for (bool binary : {false, true}) {
      SCOPED_TRACE(fmt::format("type {} binary {}", static_cast<int>(type), binary));
      cm::io::SolField sol;
      sol.type = type;
      sol.values = random_values(type == cm::io::SolField::Type::kScalar ? 57 : 6 * 57, 7);
      const std::string file = path(binary ? "f.solb" : "f.sol");
      cm::io::write_sol(sol, file, binary);
      const std::string bytes = cm::io::read_file_bytes(file);
      const cm::io::SolField r = cm::io::read_sol(bytes, file);
      EXPECT_EQ(r.type, type);
      EXPECT_EQ(r.num_verts(), 57u);
      EXPECT_EQ(r.values, sol.values);
      if (binary) {
        EXPECT_EQ(bytes, build_solb(2, false, {static_cast<int>(type)}, 57, sol.values));
      }
    }
}

TEST_F(MeditTest, SolTextLayoutFollowsMmg) {
  cm::io::SolField sol;
  sol.type = cm::io::SolField::Type::kTensor;
  sol.values = {1, 0.5, 2, 0.25, 0.125, 3};  // m11 m12 m22 m13 m23 m33
  cm::io::write_sol(sol, path("t.sol"), false);
  EXPECT_EQ(cm::io::read_file_bytes(path("t.sol")),
            "MeshVersionFormatted 2\n\nDimension 3\n\nSolAtVertices\n1\n1 3\n1 0.5 2 0.25 0.125 "
            "3\n\nEnd\n");
  const std::string mmg = kData + "sol_tensor_mmg.sol";
  const cm::io::SolField r = cm::io::read_sol(cm::io::read_file_bytes(mmg), mmg);
  EXPECT_EQ(r.type, cm::io::SolField::Type::kTensor);
  EXPECT_EQ(r.values, (std::vector<double>{1, 0.5, 2, 0.25, 0.125, 3, 4, 0, 5, 0, 0, 6}));
}

TEST_F(MeditTest, SolReadsTheFirstScalarOrTensorField) {
  const std::string multi = kData + "sol_multi.sol";
  const cm::io::SolField text = cm::io::read_sol(cm::io::read_file_bytes(multi), multi);
  EXPECT_EQ(text.type, cm::io::SolField::Type::kScalar);
  EXPECT_EQ(text.values, (std::vector<double>{0.5, 0.75}));
  // Binary, version 1 (float), big-endian: vector, tensor, scalar fields.
  std::vector<double> values;
  for (int v = 0; v < 3; ++v) {
    for (int c = 0; c < 3; ++c) values.push_back(100 * v + c);
    for (int c = 0; c < 6; ++c) values.push_back(v + 0.125 * c);
    values.push_back(-v);
  }
  const cm::io::SolField bin =
      cm::io::read_sol(build_solb(1, true, {2, 3, 1}, 3, values), "m.solb");
  EXPECT_EQ(bin.type, cm::io::SolField::Type::kTensor);
  ASSERT_EQ(bin.num_verts(), 3u);
  for (int v = 0; v < 3; ++v)
    for (int c = 0; c < 6; ++c)
      EXPECT_EQ(bin.values[static_cast<std::size_t>(6 * v + c)], v + 0.125 * c);
}

TEST_F(MeditTest, MalformedSolFilesGiveLineOrOffsetAndReason) {
  const TextCase text_cases[] = {
      {"sol_bad_type.sol", 5, "SolAtVertices: unknown field type 7 (1 to 4 are defined)"},
      {"sol_vector_only.sol", 5,
       "SolAtVertices holds no scalar (type 1) or symmetric tensor (type 3) field (types: 2)"},
      {"sol_truncated.sol", 6, "unexpected end of file in SolAtVertices record 2 of 3"},
      {"sol_nan.sol", 7, "SolAtVertices record 2 of 3: value nan is not finite"},
      {"sol_dimension2.sol", 2, "Dimension 2 is not supported: curvemesh reads 3D solutions only"},
      {"sol_absurd_count.sol", 4,
       "SolAtVertices: count 123456789 is larger than the rest of the file can hold"},
      {"sol_missing.sol", 3, "no SolAtVertices section"},
      {"sol_count_too_small.sol", 8, "expected a keyword, found '3'"},
      {"not_medit.mesh", 1,
       "not a solution file: expected 'MeshVersionFormatted', found '$MeshFormat'"},
  };
  for (const TextCase& c : text_cases) {
    const std::string file = kData + c.file;
    expect_input_error(cm::io::read_file_bytes(file), file, c.line, -1, c.reason, cm::io::read_sol);
  }
  // SolAtVertices at 20: next position 24, count 28, number of fields 32,
  // types from 36.
  const std::string good = build_solb(2, false, {1}, 2, {1.0, 2.0});
  ASSERT_EQ(cm::io::read_sol(good, "good.solb").values, (std::vector<double>{1.0, 2.0}));
  const double inf = std::numeric_limits<double>::infinity();
  const BinaryCase binary_cases[] = {
      {"type", patched_i32(good, 36, 7), 36,
       "SolAtVertices: unknown field type 7 (1 to 4 are defined)"},
      {"no fields", patched_i32(good, 32, 0), 32,
       "SolAtVertices: number of fields 0 is outside 1..1000"},
      {"many fields", patched_i32(good, 32, 1 << 30), 32,
       "SolAtVertices: number of fields 1073741824 is outside 1..1000"},
      {"fields beyond", patched_i32(good, 32, 6), 32,
       "SolAtVertices: keyword ends before its field types"},
      {"count", patched_i32(good, 28, 3), 28,
       "SolAtVertices: count 3 of 8-byte records does not fit in the 16 bytes the keyword holds"},
      {"inf", patched(good, 48, &inf, 8), 48,
       "SolAtVertices record 2 of 2: value inf is not finite"},
      {"dimension", patched_i32(good, 16, 2), 16,
       "Dimension 2 is not supported: curvemesh reads 3D solutions only"},
      {"missing", build_meshb(TetMesh{}, 2, false, false), 8, "no SolAtVertices keyword"},
  };
  for (const BinaryCase& c : binary_cases)
    expect_input_error(c.bytes, c.name, -1, c.offset, c.reason, cm::io::read_sol);
  for (std::size_t n = 4; n < good.size(); ++n)
    EXPECT_THROW(cm::io::read_sol(good.substr(0, n), "cut.solb"), InputError) << n;
}

TEST_F(MeditTest, SolWriterRejectsBadFields) {
  cm::io::SolField sol;
  sol.type = cm::io::SolField::Type::kTensor;
  sol.values = {1, 2, 3, 4, 5, 6, 7};
  EXPECT_THROW(cm::io::write_sol(sol, path("bad.sol"), false), std::invalid_argument);
  sol.type = cm::io::SolField::Type::kScalar;
  sol.values = {1, std::nan("")};
  EXPECT_THROW(cm::io::write_sol(sol, path("bad.sol"), true), std::invalid_argument);
  EXPECT_TRUE(fs::is_empty(dir_));
}
