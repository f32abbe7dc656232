// Medit .mesh (text) and .meshb (binary) meshes: Vertices, Edges, Triangles
// and Tetrahedra with their references. Element references become the
// classification tags (tet region, triangle face tag, edge tag); vertex
// references are ignored on reading, since mesh_io derives the vertex
// classification, and written as the vertex classification tag.
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "curvemesh/io/atomic_file.hpp"
#include "curvemesh/io/formats.hpp"
#include "curvemesh/io/medit_common.hpp"

namespace cm::io {

namespace {

using gmf::Where;

// Vertex ids must stay below kNone.
constexpr std::int64_t kMaxVerts = static_cast<std::int64_t>(kNone) - 1;

struct ElementKind {
  std::string_view name;
  int code;
  int num_verts;
};
constexpr ElementKind kEdgeKind{"Edges", gmf::kKwEdges, 2};
constexpr ElementKind kTriKind{"Triangles", gmf::kKwTriangles, 3};
constexpr ElementKind kTetKind{"Tetrahedra", gmf::kKwTetrahedra, 4};

// Why the 1-based vertex indices of an element are unusable, or empty.
// num_verts < 0: the Vertices section has not been read yet, so only the
// range of a vertex id is checked here and the rest later.
std::string check_indices(const std::int64_t* idx, int n, std::int64_t num_verts) {
  const std::int64_t max = num_verts >= 0 ? num_verts : kMaxVerts;
  for (int k = 0; k < n; ++k)
    if (idx[k] < 1 || idx[k] > max) {
      if (num_verts == 0)
        return fmt::format("vertex index {} but the file has no vertices", idx[k]);
      return fmt::format("vertex index {} out of range 1..{}", idx[k], max);
    }
  for (int a = 0; a < n; ++a)
    for (int b = a + 1; b < n; ++b)
      if (idx[a] == idx[b]) return fmt::format("vertex index {} appears twice", idx[a]);
  return {};
}

void store_element(mesh::TetMesh& m, const ElementKind& kind, const std::int64_t* idx,
                   std::int32_t ref) {
  const auto id = [&](int k) { return static_cast<VertId>(idx[k] - 1); };
  if (kind.code == gmf::kKwEdges)
    m.edges.push_back({{id(0), id(1)}, ref});
  else if (kind.code == gmf::kKwTriangles)
    m.tris.push_back({{id(0), id(1), id(2)}, ref});
  else
    m.add_tet({id(0), id(1), id(2), id(3)}, ref);
}

void reserve_elements(mesh::TetMesh& m, const ElementKind& kind, std::int64_t count) {
  const auto n = static_cast<std::size_t>(count);
  if (kind.code == gmf::kKwEdges) {
    m.edges.reserve(n);
  } else if (kind.code == gmf::kKwTriangles) {
    m.tris.reserve(n);
  } else {
    m.tet2verts.reserve(n);
    m.tet_region.reserve(n);
  }
}

// First element of `kind` that uses a vertex beyond num_verts, as
// (record number, 1-based index); record 0 if none.
std::pair<std::int64_t, std::int64_t> find_index_beyond(const mesh::TetMesh& m,
                                                        const ElementKind& kind,
                                                        std::int64_t num_verts) {
  const auto beyond = [&](const auto& verts) -> std::int64_t {
    for (VertId v : verts)
      if (static_cast<std::int64_t>(v) >= num_verts) return static_cast<std::int64_t>(v) + 1;
    return 0;
  };
  std::int64_t record = 0;
  const auto scan = [&](const auto& elements,
                        const auto& get_verts) -> std::pair<std::int64_t, std::int64_t> {
    for (const auto& e : elements) {
      ++record;
      if (const std::int64_t bad = beyond(get_verts(e))) return {record, bad};
    }
    return {0, 0};
  };
  if (kind.code == gmf::kKwEdges) return scan(m.edges, [](const auto& e) { return e.verts; });
  if (kind.code == gmf::kKwTriangles) return scan(m.tris, [](const auto& t) { return t.verts; });
  return scan(m.tet2verts, [](const auto& t) { return t; });
}

class TextMeshReader {
 public:
  TextMeshReader(std::string_view bytes, const std::string& file) : in_(bytes, file) {}

  mesh::TetMesh read() {
    std::string_view token = in_.next();
    if (token.empty()) in_.fail("not a Medit mesh: the file is empty");
    if (token != "MeshVersionFormatted")
      in_.fail(fmt::format("not a Medit mesh: expected 'MeshVersionFormatted', found {}",
                           gmf::quote(token)));
    const std::int64_t version = in_.read_int(Where{"MeshVersionFormatted"});
    if (version < 1 || version > 4)
      in_.fail(fmt::format("unsupported MeshVersionFormatted {} (1 to 4 are defined)", version));
    token = in_.next();
    while (!token.empty() && token != "End") {
      if (!gmf::TextCursor::starts_keyword(token))
        in_.fail(fmt::format("expected a keyword, found {} (does a count above match its records?)",
                             gmf::quote(token)));
      if (token == "MeshVersionFormatted") {
        in_.fail("duplicate MeshVersionFormatted");
      } else if (token == "Dimension") {
        read_dimension();
      } else if (token == "Vertices") {
        require_dimension(token);
        read_vertices();
      } else if (token == "Edges" || token == "Triangles" || token == "Tetrahedra") {
        require_dimension(token);
        read_elements(token == "Edges" ? kEdgeKind : token == "Triangles" ? kTriKind : kTetKind);
      } else if (gmf::is_high_order_keyword(token)) {
        in_.fail(fmt::format(
            "{}: high-order Medit elements are not supported (curvemesh reads linear Medit "
            "meshes only)",
            token));
      } else {
        // Corners, Ridges, RequiredVertices, Normals, ...: not needed.
        token = in_.skip_to_keyword();
        continue;
      }
      token = in_.next();
    }
    // Writers end with End; without it the file was most likely cut short.
    if (token.empty()) in_.fail("missing End keyword (is the file truncated?)");
    check_late_vertices();
    m_.resize_vertex_arrays();
    return std::move(m_);
  }

 private:
  void read_dimension() {
    if (has_dimension_) in_.fail("duplicate Dimension");
    const std::int64_t dim = in_.read_int(Where{"Dimension"});
    if (dim == 2) in_.fail("Dimension 2 is not supported: curvemesh reads 3D meshes only");
    if (dim != 3) in_.fail(fmt::format("invalid Dimension {} (expected 3)", dim));
    has_dimension_ = true;
  }

  void require_dimension(std::string_view keyword) {
    if (!has_dimension_) in_.fail(fmt::format("{} before Dimension", keyword));
  }

  void read_vertices() {
    if (num_verts_ >= 0) in_.fail("duplicate Vertices section");
    const std::int64_t count = in_.read_count("Vertices", 4);
    if (count > kMaxVerts)
      in_.fail(
          fmt::format("Vertices: count {} exceeds the {} curvemesh can index", count, kMaxVerts));
    m_.coords.resize(static_cast<std::size_t>(count));
    for (std::int64_t r = 0; r < count; ++r) {
      const Where where{"Vertices", r + 1, count};
      Vec3& x = m_.coords[static_cast<std::size_t>(r)];
      for (int c = 0; c < 3; ++c) {
        x[c] = in_.read_real(where);
        if (!std::isfinite(x[c]))
          in_.fail(fmt::format("{}: coordinate {} is not finite", where.describe(), x[c]));
      }
      in_.read_int(where);  // vertex reference: the classification is derived later
    }
    num_verts_ = count;
  }

  void read_elements(const ElementKind& kind) {
    auto& seen = kind.code == gmf::kKwEdges       ? has_edges_
                 : kind.code == gmf::kKwTriangles ? has_tris_
                                                  : has_tets_;
    if (seen) in_.fail(fmt::format("duplicate {} section", kind.name));
    seen = true;
    const std::int64_t section_line = in_.line();
    const std::int64_t count = in_.read_count(kind.name, kind.num_verts + 1);
    reserve_elements(m_, kind, count);
    std::int64_t idx[4] = {0, 0, 0, 0};
    for (std::int64_t r = 0; r < count; ++r) {
      const Where where{kind.name, r + 1, count};
      for (int k = 0; k < kind.num_verts; ++k) idx[k] = in_.read_int(where);
      const std::int64_t ref = in_.read_int(where);
      if (std::string reason = check_indices(idx, kind.num_verts, num_verts_); !reason.empty())
        in_.fail(fmt::format("{}: {}", where.describe(), reason));
      if (!gmf::fits_int32(ref))
        in_.fail(fmt::format("{}: reference {} does not fit in 32 bits", where.describe(), ref));
      store_element(m_, kind, idx, static_cast<std::int32_t>(ref));
    }
    if (num_verts_ < 0 && count > 0) late_checks_.push_back({kind, section_line, count});
  }

  // Elements read before the Vertices section are checked against the
  // number of vertices once it is known; the error names the section's line.
  void check_late_vertices() const {
    const std::int64_t num_verts = std::max<std::int64_t>(num_verts_, 0);
    for (const LateCheck& check : late_checks_) {
      const auto [record, index] = find_index_beyond(m_, check.kind, num_verts);
      if (record == 0) continue;
      const std::string range = num_verts == 0 ? std::string("but the file has no vertices")
                                               : fmt::format("out of range 1..{}", num_verts);
      throw InputError(in_.file(), check.line, -1,
                       fmt::format("{} record {} of {}: vertex index {} {}", check.kind.name,
                                   record, check.count, index, range));
    }
  }

  struct LateCheck {
    ElementKind kind;
    std::int64_t line;
    std::int64_t count;
  };

  gmf::TextCursor in_;
  mesh::TetMesh m_;
  bool has_dimension_ = false;
  bool has_edges_ = false;
  bool has_tris_ = false;
  bool has_tets_ = false;
  std::int64_t num_verts_ = -1;
  std::vector<LateCheck> late_checks_;
};

void read_binary_vertices(const gmf::BinaryCursor& in, const gmf::BinarySection& s,
                          mesh::TetMesh& m) {
  const std::size_t rb = in.layout().real_bytes();
  const std::size_t record_bytes = 3 * rb + in.layout().int_bytes();
  std::size_t at = 0;
  const std::int64_t count = gmf::read_binary_count(in, s, "Vertices", record_bytes, 0, &at);
  if (count > kMaxVerts)
    in.fail(s.data,
            fmt::format("Vertices: count {} exceeds the {} curvemesh can index", count, kMaxVerts));
  m.coords.resize(static_cast<std::size_t>(count));
  for (std::int64_t r = 0; r < count; ++r) {
    const std::size_t record = at + static_cast<std::size_t>(r) * record_bytes;
    Vec3& x = m.coords[static_cast<std::size_t>(r)];
    for (int c = 0; c < 3; ++c) {
      x[c] = in.real_at(record + static_cast<std::size_t>(c) * rb);
      if (!std::isfinite(x[c]))
        in.fail(record + static_cast<std::size_t>(c) * rb,
                fmt::format("Vertices record {} of {}: coordinate {} is not finite", r + 1, count,
                            x[c]));
    }
  }
}

void read_binary_elements(const gmf::BinaryCursor& in, const gmf::BinarySection& s,
                          const ElementKind& kind, mesh::TetMesh& m) {
  const std::size_t ib = in.layout().int_bytes();
  const std::size_t record_bytes = static_cast<std::size_t>(kind.num_verts + 1) * ib;
  std::size_t at = 0;
  const std::int64_t count = gmf::read_binary_count(in, s, kind.name, record_bytes, 0, &at);
  const auto num_verts = static_cast<std::int64_t>(m.coords.size());
  reserve_elements(m, kind, count);
  std::int64_t idx[4] = {0, 0, 0, 0};
  for (std::int64_t r = 0; r < count; ++r) {
    const std::size_t record = at + static_cast<std::size_t>(r) * record_bytes;
    for (int k = 0; k < kind.num_verts; ++k)
      idx[k] = in.int_at(record + static_cast<std::size_t>(k) * ib);
    if (std::string reason = check_indices(idx, kind.num_verts, num_verts); !reason.empty())
      in.fail(record, fmt::format("{} record {} of {}: {}", kind.name, r + 1, count, reason));
    const std::size_t ref_at = record + static_cast<std::size_t>(kind.num_verts) * ib;
    const std::int64_t ref = in.int_at(ref_at);
    if (!gmf::fits_int32(ref))
      in.fail(ref_at, fmt::format("{} record {} of {}: reference {} does not fit in 32 bits",
                                  kind.name, r + 1, count, ref));
    store_element(m, kind, idx, static_cast<std::int32_t>(ref));
  }
}

mesh::TetMesh read_binary(std::string_view bytes, const std::string& file) {
  const gmf::BinaryCursor in(bytes, file, ".meshb");
  // Sections by keyword code; read once the chain is known so that the
  // Vertices come first whatever their place in the file.
  std::array<gmf::BinarySection, gmf::kKwTetrahedra + 1> sections{};
  bool has_dimension = false;
  gmf::walk_binary_keywords(in, [&](const gmf::BinarySection& s) {
    if (s.code == gmf::kKwDimension) {
      if (has_dimension) in.fail(s.header, "duplicate Dimension");
      has_dimension = true;
      const std::int32_t dim = gmf::read_binary_dimension(in, s);
      if (dim == 2) in.fail(s.data, "Dimension 2 is not supported: curvemesh reads 3D meshes only");
      if (dim != 3) in.fail(s.data, fmt::format("invalid Dimension {} (expected 3)", dim));
    } else if (s.code == gmf::kKwVertices || s.code == gmf::kKwEdges ||
               s.code == gmf::kKwTriangles || s.code == gmf::kKwTetrahedra) {
      gmf::BinarySection& slot = sections[static_cast<std::size_t>(s.code)];
      if (slot.code != 0) in.fail(s.header, fmt::format("duplicate keyword code {}", s.code));
      slot = s;
    } else if (gmf::is_high_order_keyword(s.code)) {
      in.fail(s.header,
              fmt::format("{}: high-order Medit elements are not supported (curvemesh reads linear "
                          "Medit meshes only)",
                          gmf::high_order_keyword_name(s.code)));
    }
  });
  mesh::TetMesh m;
  if (sections[gmf::kKwVertices].code != 0) read_binary_vertices(in, sections[gmf::kKwVertices], m);
  for (const ElementKind& kind : {kEdgeKind, kTriKind, kTetKind})
    if (sections[static_cast<std::size_t>(kind.code)].code != 0)
      read_binary_elements(in, sections[static_cast<std::size_t>(kind.code)], kind, m);
  m.resize_vertex_arrays();
  return m;
}

std::int32_t vertex_ref(const mesh::TetMesh& m, std::size_t v) {
  return v < m.vert_class.size() && m.vert_class[v].valid() ? m.vert_class[v].tag : 0;
}

void write_text(const mesh::TetMesh& m, gmf::OutputBuffer& out) {
  auto& buf = out.text();
  fmt::format_to(fmt::appender(buf), "MeshVersionFormatted 2\n\nDimension 3\n\nVertices\n{}\n",
                 m.num_verts());
  for (std::size_t v = 0; v < m.num_verts(); ++v) {
    const Vec3& x = m.coords[v];
    fmt::format_to(fmt::appender(buf), "{} {} {} {}\n", x[0], x[1], x[2], vertex_ref(m, v));
    out.maybe_flush();
  }
  if (!m.edges.empty()) {
    fmt::format_to(fmt::appender(buf), "\nEdges\n{}\n", m.edges.size());
    for (const auto& e : m.edges) {
      fmt::format_to(fmt::appender(buf), "{} {} {}\n", e.verts[0] + 1, e.verts[1] + 1, e.edge_tag);
      out.maybe_flush();
    }
  }
  if (!m.tris.empty()) {
    fmt::format_to(fmt::appender(buf), "\nTriangles\n{}\n", m.tris.size());
    for (const auto& t : m.tris) {
      fmt::format_to(fmt::appender(buf), "{} {} {} {}\n", t.verts[0] + 1, t.verts[1] + 1,
                     t.verts[2] + 1, t.face_tag);
      out.maybe_flush();
    }
  }
  if (m.num_tets() > 0) {
    fmt::format_to(fmt::appender(buf), "\nTetrahedra\n{}\n", m.num_tets());
    for (std::size_t t = 0; t < m.num_tets(); ++t) {
      const auto& v = m.tet2verts[t];
      fmt::format_to(fmt::appender(buf), "{} {} {} {} {}\n", v[0] + 1, v[1] + 1, v[2] + 1, v[3] + 1,
                     m.tet_region[t]);
      out.maybe_flush();
    }
  }
  fmt::format_to(fmt::appender(buf), "\nEnd\n");
}

void write_binary(const mesh::TetMesh& m, gmf::OutputBuffer& out) {
  const std::uint64_t nv = m.num_verts(), ne = m.edges.size(), nt = m.tris.size(),
                      nk = m.num_tets();
  const auto int32_max = static_cast<std::uint64_t>(std::numeric_limits<std::int32_t>::max());
  const bool wide_ints = nv > int32_max || ne > int32_max || nt > int32_max || nk > int32_max;
  const auto file_bytes = [&](int version) {
    const gmf::BinaryLayout layout{false, version};
    const std::uint64_t ib = layout.int_bytes(), header = 4 + layout.position_bytes();
    std::uint64_t total = 8 + header + 4 + header;  // endianness, version, Dimension, End
    if (nv > 0) total += header + ib + nv * (3 * 8 + ib);
    if (ne > 0) total += header + ib + ne * 3 * ib;
    if (nt > 0) total += header + ib + nt * 4 * ib;
    if (nk > 0) total += header + ib + nk * 5 * ib;
    return total;
  };
  const int version = gmf::choose_binary_version(file_bytes(2), wide_ints);
  const gmf::BinaryLayout layout{false, version};
  const std::uint64_t ib = layout.int_bytes(), header = 4 + layout.position_bytes();
  const auto put_int = [&](std::int64_t v) {
    if (version == 4)
      out.put<std::int64_t>(v);
    else
      out.put<std::int32_t>(static_cast<std::int32_t>(v));
  };

  out.put<std::int32_t>(1);
  out.put<std::int32_t>(version);
  std::uint64_t position = 8 + header + 4;
  gmf::put_keyword(out, version, gmf::kKwDimension, position, -1);
  out.put<std::int32_t>(3);
  if (nv > 0) {
    position += header + ib + nv * (3 * 8 + ib);
    gmf::put_keyword(out, version, gmf::kKwVertices, position, static_cast<std::int64_t>(nv));
    for (std::size_t v = 0; v < nv; ++v) {
      for (int c = 0; c < 3; ++c) out.put<double>(m.coords[v][c]);
      put_int(vertex_ref(m, v));
      out.maybe_flush();
    }
  }
  if (ne > 0) {
    position += header + ib + ne * 3 * ib;
    gmf::put_keyword(out, version, gmf::kKwEdges, position, static_cast<std::int64_t>(ne));
    for (const auto& e : m.edges) {
      for (VertId v : e.verts) put_int(static_cast<std::int64_t>(v) + 1);
      put_int(e.edge_tag);
      out.maybe_flush();
    }
  }
  if (nt > 0) {
    position += header + ib + nt * 4 * ib;
    gmf::put_keyword(out, version, gmf::kKwTriangles, position, static_cast<std::int64_t>(nt));
    for (const auto& t : m.tris) {
      for (VertId v : t.verts) put_int(static_cast<std::int64_t>(v) + 1);
      put_int(t.face_tag);
      out.maybe_flush();
    }
  }
  if (nk > 0) {
    position += header + ib + nk * 5 * ib;
    gmf::put_keyword(out, version, gmf::kKwTetrahedra, position, static_cast<std::int64_t>(nk));
    for (std::size_t t = 0; t < nk; ++t) {
      for (VertId v : m.tet2verts[t]) put_int(static_cast<std::int64_t>(v) + 1);
      put_int(m.tet_region[t]);
      out.maybe_flush();
    }
  }
  gmf::put_keyword(out, version, gmf::kKwEnd, 0, -1);
  CM_ASSERT_OP(position + header, ==, file_bytes(version));
}

}  // namespace

mesh::TetMesh read_medit(std::string_view bytes, const std::string& file_name) {
  if (gmf::looks_binary(bytes)) return read_binary(bytes, file_name);
  return TextMeshReader(bytes, file_name).read();
}

void write_medit(const mesh::TetMesh& m, const std::string& path, bool binary) {
  if (m.high_order.order() > 1)
    throw std::runtime_error(
        fmt::format("{}: Medit format holds linear meshes only (this mesh has order {}); "
                    "write .msh or .vtu for curved meshes",
                    path, m.high_order.order()));
  CM_ASSERT_OP(m.tet_region.size(), ==, m.num_tets());
  AtomicFile file(path);
  gmf::OutputBuffer out(file);
  if (binary)
    write_binary(m, out);
  else
    write_text(m, out);
  out.flush();
  file.commit();
}

}  // namespace cm::io
