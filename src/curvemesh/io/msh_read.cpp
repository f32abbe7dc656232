// Gmsh MSH reading: $MeshFormat and dispatch to the 2.2 / 4.1 parsers, the
// byte cursor, element tables, and the assembly of the mesh from the parsed
// nodes and elements (shared by both versions).
#include <algorithm>
#include <charconv>
#include <cmath>
#include <numeric>

#include "curvemesh/io/formats.hpp"
#include "curvemesh/io/msh_common.hpp"

namespace cm::io {
namespace msh {

namespace {

bool is_space(char ch) {
  return ch == ' ' || ch == '\n' || ch == '\t' || ch == '\r' || ch == '\v' || ch == '\f';
}

// from_chars rejects a leading '+', which hand-written files may contain.
std::string_view strip_plus(std::string_view t) {
  return t.size() > 1 && t[0] == '+' && t[1] != '-' ? t.substr(1) : t;
}

std::int32_t byteswap32(std::int32_t v) {
  const auto u = static_cast<std::uint32_t>(v);
  return static_cast<std::int32_t>((u >> 24) | ((u >> 8) & 0xff00u) | ((u << 8) & 0xff0000u) |
                                   (u << 24));
}

}  // namespace

std::string quote(std::string_view token) {
  constexpr std::size_t kMaxShown = 32;
  std::string out = "'";
  for (std::size_t k = 0; k < token.size() && k < kMaxShown; ++k) {
    const auto ch = static_cast<unsigned char>(token[k]);
    if (ch >= 0x20 && ch < 0x7f)
      out += static_cast<char>(ch);
    else
      out += fmt::format("\\x{:02x}", ch);
  }
  if (token.size() > kMaxShown) out += "...";
  return out + "'";
}

void Cursor::fail_at(Position pos, const std::string& reason) const {
  throw InputError(file_, binary_ ? -1 : pos, binary_ ? pos : -1, reason);
}

void Cursor::skip_whitespace() {
  while (pos_ < bytes_.size() && is_space(bytes_[pos_])) {
    if (bytes_[pos_] == '\n') ++line_;
    ++pos_;
  }
}

bool Cursor::at_end() {
  skip_whitespace();
  item_offset_ = pos_;
  item_line_ = line_;
  return pos_ == bytes_.size();
}

std::string_view Cursor::next_token(const char* what) {
  if (at_end()) fail(fmt::format("unexpected end of file while reading {}", what));
  const std::size_t start = pos_;
  while (pos_ < bytes_.size() && !is_space(bytes_[pos_])) ++pos_;
  return bytes_.substr(start, pos_ - start);
}

void Cursor::expect_token(std::string_view expected) {
  const std::string what(expected);
  const auto token = next_token(what.c_str());
  if (token != expected) fail(fmt::format("expected {}, got {}", expected, quote(token)));
}

void Cursor::end_line() {
  while (pos_ < bytes_.size() &&
         (bytes_[pos_] == ' ' || bytes_[pos_] == '\t' || bytes_[pos_] == '\r'))
    ++pos_;
  item_offset_ = pos_;
  item_line_ = line_;
  if (pos_ == bytes_.size()) fail("unexpected end of file before binary data");
  if (bytes_[pos_] != '\n') fail("expected the end of the line before binary data");
  ++pos_;
  ++line_;
}

void Cursor::skip_section(std::string_view name) {
  const Position start = position();
  const std::string end_marker = fmt::format("$End{}", name.substr(1));
  std::size_t from = pos_;
  for (;;) {
    const std::size_t hit = bytes_.find(end_marker, from);
    if (hit == std::string_view::npos)
      fail_at(start, fmt::format("missing {} for section {}", end_marker, name));
    const std::size_t after = hit + end_marker.size();
    const bool starts_token = hit == 0 || is_space(bytes_[hit - 1]);
    if (starts_token && (after == bytes_.size() || is_space(bytes_[after]))) {
      line_ += std::count(bytes_.begin() + static_cast<std::ptrdiff_t>(pos_),
                          bytes_.begin() + static_cast<std::ptrdiff_t>(after), '\n');
      pos_ = after;
      return;
    }
    from = hit + 1;
  }
}

std::int64_t Cursor::text_int(const char* what, std::int64_t lo, std::int64_t hi) {
  const auto token = next_token(what);
  const auto digits = strip_plus(token);
  std::int64_t value = 0;
  const auto [end, ec] = std::from_chars(digits.data(), digits.data() + digits.size(), value);
  if (ec == std::errc::result_out_of_range)
    fail(fmt::format("{} {} is out of range", what, quote(token)));
  if (ec != std::errc() || end != digits.data() + digits.size())
    fail(fmt::format("expected an integer ({}), got {}", what, quote(token)));
  if (value < lo || value > hi)
    fail(fmt::format("{} {} is out of range [{}, {}]", what, value, lo, hi));
  return value;
}

double Cursor::text_double(const char* what, bool finite_only) {
  const auto token = next_token(what);
  const auto digits = strip_plus(token);
  double value = 0;
  const auto [end, ec] = std::from_chars(digits.data(), digits.data() + digits.size(), value);
  if (ec == std::errc() && end == digits.data() + digits.size()) {
    if (finite_only && !std::isfinite(value))
      fail(fmt::format("non-finite {} {}", what, quote(token)));
    return value;
  }
  if (ec == std::errc::result_out_of_range && end == digits.data() + digits.size())
    fail(fmt::format("{} {} is out of the range of a double", what, quote(token)));
  fail(fmt::format("expected a number ({}), got {}", what, quote(token)));
}

void Cursor::require(std::size_t n, const char* what) {
  item_offset_ = pos_;
  item_line_ = line_;
  if (bytes_.size() - pos_ < n) fail(fmt::format("unexpected end of file while reading {}", what));
}

std::int32_t Cursor::bin_int32(const char* what) { return read_binary<std::int32_t>(what); }

std::int32_t Cursor::get_int(const char* what, std::int64_t lo, std::int64_t hi) {
  if (!binary_) return static_cast<std::int32_t>(text_int(what, lo, hi));
  const std::int32_t value = read_binary<std::int32_t>(what);
  if (value < lo || value > hi)
    fail(fmt::format("{} {} is out of range [{}, {}]", what, value, lo, hi));
  return value;
}

std::uint64_t Cursor::get_size(const char* what) {
  if (binary_) return read_binary<std::uint64_t>(what);
  return static_cast<std::uint64_t>(text_int(what, 0, INT64_MAX));
}

double Cursor::get_double(const char* what, bool finite_only) {
  if (!binary_) return text_double(what, finite_only);
  const double value = read_binary<double>(what);
  if (finite_only && !std::isfinite(value)) fail(fmt::format("non-finite {}", what));
  return value;
}

void Cursor::check_count(std::uint64_t count, std::uint64_t text_tokens, std::uint64_t binary_bytes,
                         const char* what) const {
  const std::uint64_t remaining = bytes_.size() - pos_;
  // Each text token takes at least one character and one separator.
  const std::uint64_t per_item = binary_ ? binary_bytes : 2 * text_tokens;
  const bool fits = per_item == 0 || count <= (remaining + 1) / per_item;
  if (!fits) fail(fmt::format("{} {} is more than the rest of the file can hold", what, count));
  if (count >= kNone)
    fail(fmt::format("{} {} exceeds the supported maximum {}", what, count, kNone - 1));
}

// ---------------------------------------------------------------------------
// Element types and node orders.

namespace {

constexpr std::array<ElementType, 10> kElementTypes{{
    {15, ElementKind::kPoint, 1, 1},
    {1, ElementKind::kLine, 1, 2},
    {8, ElementKind::kLine, 2, 3},
    {26, ElementKind::kLine, 3, 4},
    {2, ElementKind::kTri, 1, 3},
    {9, ElementKind::kTri, 2, 6},
    {21, ElementKind::kTri, 3, 10},
    {4, ElementKind::kTet, 1, 4},
    {11, ElementKind::kTet, 2, 10},
    {29, ElementKind::kTet, 3, 20},
}};

// Barycentric multi-indices of Gmsh's order-p nodes (see gmsh_to_internal).
std::vector<std::array<int, 4>> gmsh_tet_indices(int p) {
  constexpr std::array<std::array<int, 2>, 6> kGmshEdges{
      {{0, 1}, {1, 2}, {2, 0}, {3, 0}, {3, 2}, {3, 1}}};
  constexpr std::array<std::array<int, 3>, 4> kGmshFaces{
      {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {3, 1, 2}}};
  std::vector<std::array<int, 4>> out;
  for (int k = 0; k < 4; ++k) {
    std::array<int, 4> v{};
    v[k] = p;
    out.push_back(v);
  }
  for (const auto& e : kGmshEdges)
    for (int s = 1; s < p; ++s) {
      std::array<int, 4> v{};
      v[e[0]] = p - s;
      v[e[1]] = s;
      out.push_back(v);
    }
  // Up to order 3 a face has at most one inner node, its centroid.
  if (p == 3)
    for (const auto& f : kGmshFaces) {
      std::array<int, 4> v{};
      for (int k : f) v[k] = 1;
      out.push_back(v);
    }
  return out;
}

template <std::size_t K>
std::vector<int> match_indices(const std::vector<std::array<int, K>>& gmsh,
                               const std::vector<std::array<int, K>>& internal) {
  CM_ASSERT_OP(gmsh.size(), ==, internal.size());
  std::vector<int> perm(gmsh.size());
  for (std::size_t k = 0; k < gmsh.size(); ++k) {
    const auto it = std::find(internal.begin(), internal.end(), gmsh[k]);
    CM_ASSERT(it != internal.end());
    perm[k] = static_cast<int>(it - internal.begin());
  }
  return perm;
}

}  // namespace

const ElementType* find_element_type(int gmsh_type) {
  for (const auto& t : kElementTypes)
    if (t.gmsh_type == gmsh_type) return &t;
  return nullptr;
}

int gmsh_type_of(ElementKind kind, int order) {
  for (const auto& t : kElementTypes)
    if (t.kind == kind && (t.order == order || kind == ElementKind::kPoint)) return t.gmsh_type;
  CM_ASSERT(false);
  return 0;
}

int kind_dim(ElementKind kind) { return static_cast<int>(kind); }

std::string unsupported_type_message(std::int64_t gmsh_type) {
  static constexpr std::array<std::pair<int, const char*>, 23> kNames{{
      {3, "4-node quadrangle"},
      {5, "8-node hexahedron"},
      {6, "6-node prism"},
      {7, "5-node pyramid"},
      {10, "9-node quadrangle"},
      {12, "27-node hexahedron"},
      {13, "18-node prism"},
      {14, "14-node pyramid"},
      {16, "8-node quadrangle"},
      {17, "20-node hexahedron"},
      {18, "15-node prism"},
      {19, "13-node pyramid"},
      {20, "9-node incomplete triangle"},
      {22, "12-node incomplete triangle"},
      {23, "15-node triangle"},
      {24, "15-node incomplete triangle"},
      {25, "21-node triangle"},
      {27, "5-node line"},
      {28, "6-node line"},
      {30, "35-node tetrahedron"},
      {31, "56-node tetrahedron"},
      {92, "64-node hexahedron"},
      {93, "125-node hexahedron"},
  }};
  for (const auto& [type, name] : kNames)
    if (type == gmsh_type) return fmt::format("unsupported element type {} ({})", gmsh_type, name);
  return fmt::format("unsupported element type {}", gmsh_type);
}

const std::vector<int>& gmsh_to_internal(ElementKind kind, int order) {
  using Table = std::array<std::array<std::vector<int>, mesh::kMaxOrder + 1>, 4>;
  static const Table tables = [] {
    Table t;
    for (int p = 1; p <= mesh::kMaxOrder; ++p) {
      t[0][p] = {0};
      t[1][p].resize(static_cast<std::size_t>(p + 1));
      std::iota(t[1][p].begin(), t[1][p].end(), 0);
      // Gmsh's triangle numbering (edges 0-1, 1-2, 2-0, then the centroid)
      // is curvemesh's, so this is the identity; computed to prove it.
      t[2][p] = match_indices<3>(mesh::tri_node_indices(p), mesh::tri_node_indices(p));
      t[3][p] = match_indices<4>(gmsh_tet_indices(p), mesh::tet_node_indices(p));
    }
    return t;
  }();
  CM_ASSERT(order >= 1 && order <= mesh::kMaxOrder);
  return tables[static_cast<std::size_t>(kind)][static_cast<std::size_t>(order)];
}

// ---------------------------------------------------------------------------
// Raw data.

void NodeTagMap::reserve(std::uint64_t expected_nodes) {
  dense_limit_ = std::max<std::uint64_t>(dense_limit_, 4 * expected_nodes + 1024);
  sparse_.clear();
  dense_.clear();
  dense_.resize(static_cast<std::size_t>(std::min<std::uint64_t>(expected_nodes + 1, dense_limit_)),
                kNone);
}

bool NodeTagMap::insert(std::uint64_t tag, Index node) {
  if (tag < dense_limit_) {
    if (tag >= dense_.size())
      dense_.resize(
          static_cast<std::size_t>(std::min(dense_limit_, std::max(tag + 1, 2 * dense_.size()))),
          kNone);
    if (dense_[tag] != kNone) return false;
    dense_[tag] = node;
    return true;
  }
  return sparse_.emplace(tag, node).second;
}

void RawNodes::add(const Cursor& c, Position pos, std::uint64_t tag, const Vec3& x,
                   mesh::ModelRef ref, const mesh::Param& p) {
  if (!map.insert(tag, static_cast<Index>(tags.size())))
    c.fail_at(pos, fmt::format("duplicate node tag {}", tag));
  tags.push_back(tag);
  coords.push_back(x);
  entity.push_back(ref);
  param.push_back(p);
}

RawElements& RawMesh::begin_elements(Cursor& c, const ElementType& type) {
  if (type.kind != ElementKind::kPoint) {
    if (order == 0) order = type.order;
    if (order != type.order)
      c.fail(fmt::format(
          "element type {} has order {} but earlier elements have order {} (mixed orders are "
          "not supported)",
          type.gmsh_type, type.order, order));
  }
  RawElements* e = &points;
  if (type.kind == ElementKind::kLine) e = &lines;
  if (type.kind == ElementKind::kTri) e = &tris;
  if (type.kind == ElementKind::kTet) e = &tets;
  e->nodes_per = type.num_nodes;
  return *e;
}

void RawMesh::add_element(Cursor& c, RawElements& e, std::uint64_t tag, std::int32_t entity,
                          const std::uint64_t* node_tags, Position pos) {
  const int corners = e.nodes_per == 1 ? 1 : (&e == &lines ? 2 : (&e == &tris ? 3 : 4));
  for (int k = 0; k < e.nodes_per; ++k) {
    const Index node = nodes.map.find(node_tags[k]);
    if (node == kNone)
      c.fail_at(pos, fmt::format("element {} references undefined node {}", tag, node_tags[k]));
    for (int j = 0; j < k && k < corners; ++j)
      if (node_tags[j] == node_tags[k])
        c.fail_at(pos, fmt::format("element {} has the repeated node {}", tag, node_tags[k]));
    e.nodes.push_back(node);
  }
  e.entity_tag.push_back(entity);
  e.tag.push_back(tag);
  e.pos.push_back(pos);
}

// ---------------------------------------------------------------------------
// Assembly.

namespace {

// Elements in increasing tag order (a no-op for Gmsh's files, whose tags
// increase through the file), so a mesh written by write_msh41 reads back in
// its own order.
void order_by_tag(RawElements& e) {
  if (std::is_sorted(e.tag.begin(), e.tag.end())) return;
  std::vector<std::size_t> perm(e.size());
  std::iota(perm.begin(), perm.end(), std::size_t{0});
  std::stable_sort(perm.begin(), perm.end(),
                   [&](std::size_t a, std::size_t b) { return e.tag[a] < e.tag[b]; });
  RawElements out;
  out.nodes_per = e.nodes_per;
  const auto np = static_cast<std::size_t>(e.nodes_per);
  out.nodes.reserve(e.nodes.size());
  for (std::size_t i : perm) {
    out.nodes.insert(out.nodes.end(), e.nodes.begin() + static_cast<std::ptrdiff_t>(i * np),
                     e.nodes.begin() + static_cast<std::ptrdiff_t>((i + 1) * np));
    out.entity_tag.push_back(e.entity_tag[i]);
    out.tag.push_back(e.tag[i]);
    out.pos.push_back(e.pos[i]);
  }
  e = std::move(out);
}

// Stores the high-order nodes of the elements into m.high_order, each edge
// and face once: the first element to mention it stores its nodes (in
// curvemesh's order, the one scatter_tet_nodes uses: an edge's nodes from its
// first to its second vertex, a face's relative to its vertex list), later
// ones must agree. Storing edge by edge rather than through
// scatter_tet_nodes costs one hash lookup per shared edge and no allocation.
class HighOrderAssembler {
 public:
  HighOrderAssembler(mesh::TetMesh& m, const RawMesh& raw,
                     const std::vector<std::uint64_t>& vert_tag, const Cursor& c)
      : m_(m), raw_(raw), vert_tag_(vert_tag), c_(c), p_(raw.order) {
    m_.high_order.reset(p_);
    buf_.resize(static_cast<std::size_t>(p_ * p_));
  }

  void add_tets() {
    const RawElements& e = raw_.tets;
    for (std::size_t i = 0; i < e.size(); ++i) {
      gather(e, i, ElementKind::kTet);
      const auto& v = m_.tet2verts[i];
      store_edges(e, i, v.data(), mesh::kTetEdges, 4);
      store_faces(e, i, v.data(), mesh::kFaceVerts, 4 + 6 * (p_ - 1));
    }
  }

  void add_tris() {
    const RawElements& e = raw_.tris;
    for (std::size_t i = 0; i < e.size(); ++i) {
      gather(e, i, ElementKind::kTri);
      const auto& v = m_.tris[i].verts;
      store_edges(e, i, v.data(), mesh::kTriEdges, 3);
      constexpr std::array<std::array<int, 3>, 1> kOneFace{{{0, 1, 2}}};
      store_faces(e, i, v.data(), kOneFace, 3 + 3 * (p_ - 1));
    }
  }

  void add_lines() {
    const RawElements& e = raw_.lines;
    for (std::size_t i = 0; i < e.size(); ++i) {
      gather(e, i, ElementKind::kLine);
      constexpr std::array<std::array<int, 2>, 1> kOneEdge{{{0, 1}}};
      store_edges(e, i, m_.edges[i].verts.data(), kOneEdge, 2);
    }
  }

 private:
  // nodes_ = the element's nodes in curvemesh's internal order.
  void gather(const RawElements& e, std::size_t i, ElementKind kind) {
    const auto& perm = gmsh_to_internal(kind, p_);
    nodes_.resize(perm.size());
    const Index* elem = e.nodes.data() + i * static_cast<std::size_t>(e.nodes_per);
    for (std::size_t k = 0; k < perm.size(); ++k)
      nodes_[static_cast<std::size_t>(perm[k])] = raw_.nodes.coords[elem[k]];
  }

  // Edge k of the element joins local vertices edges[k]; its nodes start at
  // nodes_[first + k * (p - 1)].
  template <std::size_t N>
  void store_edges(const RawElements& e, std::size_t i, const VertId* v,
                   const std::array<std::array<int, 2>, N>& edges, int first) {
    const auto per_edge = static_cast<std::size_t>(p_ - 1);
    for (std::size_t k = 0; k < N; ++k) {
      const VertId a = v[edges[k][0]], b = v[edges[k][1]];
      const Vec3* mine = nodes_.data() + static_cast<std::size_t>(first) + k * per_edge;
      if (!m_.high_order.get_edge(a, b, buf_.data())) {
        m_.high_order.set_edge(a, b, std::span<const Vec3>(mine, per_edge));
        continue;
      }
      if (!std::equal(mine, mine + per_edge, buf_.data()))
        c_.fail_at(
            e.pos[i],
            fmt::format("element {}: its high-order nodes on the edge of nodes {} and {} differ "
                        "from those of another element on that edge",
                        e.tag[i], vert_tag_[a], vert_tag_[b]));
    }
  }

  template <std::size_t N>
  void store_faces(const RawElements& e, std::size_t i, const VertId* v,
                   const std::array<std::array<int, 3>, N>& faces, int first) {
    const std::size_t per_face = m_.high_order.nodes_per_face();
    if (per_face == 0) return;
    for (std::size_t k = 0; k < N; ++k) {
      const VertId a = v[faces[k][0]], b = v[faces[k][1]], c = v[faces[k][2]];
      const Vec3* mine = nodes_.data() + static_cast<std::size_t>(first) + k * per_face;
      if (!m_.high_order.get_face(a, b, c, buf_.data())) {
        m_.high_order.set_face(a, b, c, std::span<const Vec3>(mine, per_face));
        continue;
      }
      if (!std::equal(mine, mine + per_face, buf_.data()))
        c_.fail_at(
            e.pos[i],
            fmt::format("element {}: its high-order nodes on the face of nodes {}, {}, {} differ "
                        "from those of another element on that face",
                        e.tag[i], vert_tag_[a], vert_tag_[b], vert_tag_[c]));
    }
  }

  mesh::TetMesh& m_;
  const RawMesh& raw_;
  const std::vector<std::uint64_t>& vert_tag_;
  const Cursor& c_;
  const int p_;
  std::vector<Vec3> nodes_;
  std::vector<Vec3> buf_;
};

}  // namespace

mesh::TetMesh assemble_mesh(RawMesh&& raw, const Cursor& c) {
  for (RawElements* e : {&raw.points, &raw.lines, &raw.tris, &raw.tets}) order_by_tag(*e);
  const RawNodes& nodes = raw.nodes;

  // Vertices: the corner nodes, numbered by increasing tag.
  std::vector<Index> node2vert(nodes.tags.size(), kNone);
  constexpr Index kCorner = kNone - 1;
  const auto mark_corners = [&](const RawElements& e, int corners) {
    for (std::size_t i = 0; i < e.size(); ++i)
      for (int k = 0; k < corners; ++k)
        node2vert[e.nodes[i * static_cast<std::size_t>(e.nodes_per) +
                          static_cast<std::size_t>(k)]] = kCorner;
  };
  mark_corners(raw.lines, 2);
  mark_corners(raw.tris, 3);
  mark_corners(raw.tets, 4);
  std::vector<Index> vert2node;
  for (Index n = 0; n < node2vert.size(); ++n)
    if (node2vert[n] == kCorner) vert2node.push_back(n);
  const auto by_tag = [&](Index a, Index b) { return nodes.tags[a] < nodes.tags[b]; };
  if (!std::is_sorted(vert2node.begin(), vert2node.end(), by_tag))
    std::sort(vert2node.begin(), vert2node.end(), by_tag);

  mesh::TetMesh m;
  m.coords.reserve(vert2node.size());
  std::vector<std::uint64_t> vert_tag(vert2node.size());
  for (Index v = 0; v < vert2node.size(); ++v) {
    const Index n = vert2node[v];
    node2vert[n] = v;
    vert_tag[v] = nodes.tags[n];
    m.coords.push_back(nodes.coords[n]);
    m.vert_class.push_back(nodes.entity[n]);
    m.vert_param.push_back(nodes.param[n]);
  }
  m.vert2tet.assign(m.coords.size(), kNone);

  const auto vert = [&](const RawElements& e, std::size_t i, int k) {
    return node2vert[e.nodes[i * static_cast<std::size_t>(e.nodes_per) +
                             static_cast<std::size_t>(k)]];
  };
  m.tet2verts.reserve(raw.tets.size());
  m.tet_region.reserve(raw.tets.size());
  for (std::size_t i = 0; i < raw.tets.size(); ++i)
    m.add_tet(
        {vert(raw.tets, i, 0), vert(raw.tets, i, 1), vert(raw.tets, i, 2), vert(raw.tets, i, 3)},
        raw.tets.entity_tag[i]);
  m.tris.reserve(raw.tris.size());
  for (std::size_t i = 0; i < raw.tris.size(); ++i)
    m.tris.push_back({{vert(raw.tris, i, 0), vert(raw.tris, i, 1), vert(raw.tris, i, 2)},
                      raw.tris.entity_tag[i]});
  m.edges.reserve(raw.lines.size());
  for (std::size_t i = 0; i < raw.lines.size(); ++i)
    m.edges.push_back({{vert(raw.lines, i, 0), vert(raw.lines, i, 1)}, raw.lines.entity_tag[i]});

  // A point element marks its node as a model vertex; it only classifies a
  // vertex the format left unclassified (MSH 2.2).
  for (std::size_t i = 0; i < raw.points.size(); ++i) {
    const VertId v = node2vert[raw.points.nodes[i]];
    if (v != kNone && !m.vert_class[v].valid()) m.vert_class[v] = {0, raw.points.entity_tag[i]};
  }

  if (raw.order > 1) {
    HighOrderAssembler ho(m, raw, vert_tag, c);
    ho.add_tets();
    ho.add_tris();
    ho.add_lines();
  }
  m.entities = std::move(raw.entities);
  return m;
}

}  // namespace msh

mesh::TetMesh read_msh(std::string_view bytes, const std::string& file_name) {
  msh::Cursor c(bytes, file_name);
  if (c.at_end()) c.fail("empty file (expected $MeshFormat)");
  const auto first = c.next_token("$MeshFormat");
  if (first != "$MeshFormat")
    c.fail(fmt::format("not a Gmsh MSH file: expected $MeshFormat, got {}", msh::quote(first)));

  const auto version_token = c.next_token("the MSH version");
  double version = 0;
  const auto [end, ec] =
      std::from_chars(version_token.data(), version_token.data() + version_token.size(), version);
  if (ec != std::errc() || end != version_token.data() + version_token.size())
    c.fail(fmt::format("bad MSH version {}", msh::quote(version_token)));
  const bool is41 = std::abs(version - 4.1) < 1e-9;
  const bool is2x = version >= 2.0 && version < 3.0;
  if (!is41 && !is2x)
    c.fail(fmt::format("unsupported MSH version {} (curvemesh reads versions 2.2 and 4.1)",
                       msh::quote(version_token)));
  const auto file_type = c.text_int("file type (0 for ASCII, 1 for binary)", 0, 1);
  const auto data_size = c.text_int("data size", INT64_MIN, INT64_MAX);
  if (data_size != 8)
    c.fail(fmt::format("unsupported data size {} (only 8 is supported)", data_size));
  if (file_type == 1) {
    c.end_line();
    // The integer 1 written in the writer's byte order tells its endianness.
    const std::int32_t marker = c.bin_int32("the endianness marker");
    c.set_binary(marker != 1 && msh::byteswap32(marker) == 1);
    if (marker != 1 && msh::byteswap32(marker) != 1)
      c.fail(fmt::format(
          "invalid endianness marker {} in binary $MeshFormat (expected the integer 1)", marker));
  }
  c.expect_token("$EndMeshFormat");

  msh::RawMesh raw;
  if (is41)
    msh::parse_msh41(c, raw);
  else
    msh::parse_msh22(c, raw);
  return msh::assemble_mesh(std::move(raw), c);
}

}  // namespace cm::io
