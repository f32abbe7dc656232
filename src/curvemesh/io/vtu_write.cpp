// VTK XML unstructured grid (.vtu) with the arrays in one raw appended block
// (ParaView's fastest form to write and read). Linear meshes use VTK_TETRA
// and VTK_TRIANGLE; order p >= 2 uses VTK_LAGRANGE_TETRAHEDRON and
// VTK_LAGRANGE_TRIANGLE, whose nodes are the mesh vertices plus one point per
// distinct high-order node (shared between the cells that contain it).
#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>
#include <set>
#include <span>
#include <stdexcept>
#include <string>
#include <unordered_map>
#include <vector>

#include "curvemesh/core/error.hpp"
#include "curvemesh/io/atomic_file.hpp"
#include "curvemesh/io/formats.hpp"

namespace cm::io {

namespace {

constexpr std::uint8_t kVtkTriangle = 5;
constexpr std::uint8_t kVtkTetra = 10;
constexpr std::uint8_t kVtkLagrangeTriangle = 69;
constexpr std::uint8_t kVtkLagrangeTetrahedron = 71;

static_assert(mesh::kMaxOrder <= 3,
              "vtk_tet_node_indices lists VTK's Lagrange node order up to order 3 only; higher "
              "orders add face "
              "nodes whose order inside the face, and interior nodes, must be added there");
static_assert(sizeof(Vec3) == 3 * sizeof(double),
              "points are written straight from the Vec3 arrays");

// Nodes of VTK's Lagrange tetrahedron of order p <= 3 as multi-indices (entry
// k: weight of local vertex k), from vtkHigherOrderTetra: the vertices; for
// each edge (0,1),(1,2),(2,0),(0,3),(1,3),(2,3) its p-1 nodes from the first
// vertex to the second; then the faces in the order (0,1,3),(1,2,3),(0,2,3),
// (0,1,2), one node each at order 3.
std::vector<std::array<int, 4>> vtk_tet_node_indices(int p) {
  std::vector<std::array<int, 4>> out;
  for (int k = 0; k < 4; ++k) {
    std::array<int, 4> w{0, 0, 0, 0};
    w[k] = p;
    out.push_back(w);
  }
  constexpr int kEdges[6][2] = {{0, 1}, {1, 2}, {2, 0}, {0, 3}, {1, 3}, {2, 3}};
  for (const auto& e : kEdges)
    for (int s = 1; s < p; ++s) {
      std::array<int, 4> w{0, 0, 0, 0};
      w[e[0]] = p - s;
      w[e[1]] = s;
      out.push_back(w);
    }
  if (p == 3) {
    constexpr int kMissingVertex[4] = {2, 0, 1, 3};
    for (int missing : kMissingVertex) {
      std::array<int, 4> w{1, 1, 1, 1};
      w[missing] = 0;
      out.push_back(w);
    }
  }
  return out;
}

// VTK's Lagrange triangle of order p <= 3 (vtkHigherOrderTriangle): vertices,
// edges (0,1),(1,2),(2,0) from first to second vertex, then the centroid.
std::vector<std::array<int, 3>> vtk_tri_node_indices(int p) {
  std::vector<std::array<int, 3>> out;
  for (int k = 0; k < 3; ++k) {
    std::array<int, 3> w{0, 0, 0};
    w[k] = p;
    out.push_back(w);
  }
  for (int e = 0; e < 3; ++e)
    for (int s = 1; s < p; ++s) {
      std::array<int, 3> w{0, 0, 0};
      w[e] = p - s;
      w[(e + 1) % 3] = s;
      out.push_back(w);
    }
  if (p == 3) out.push_back({1, 1, 1});
  return out;
}

// perm[k]: position, in curvemesh's internal node order, of VTK node k.
template <std::size_t K>
std::vector<int> vtk_permutation(const std::vector<std::array<int, K>>& vtk,
                                 const std::vector<std::array<int, K>>& internal) {
  CM_ASSERT_OP(vtk.size(), ==, internal.size());
  std::vector<int> perm;
  for (const auto& w : vtk) {
    const auto it = std::find(internal.begin(), internal.end(), w);
    CM_ASSERT(it != internal.end());
    perm.push_back(static_cast<int>(it - internal.begin()));
  }
  return perm;
}

// A mesh edge (c == kNone) or face (c set) by its sorted vertex ids.
struct EntityKey {
  std::uint64_t ab = ~std::uint64_t{0};
  VertId c = kNone;
  friend bool operator==(const EntityKey&, const EntityKey&) = default;
};

// Open-addressing map (linear probing, power-of-two capacity, load <= 1/2)
// from an edge or face to the index of its first high-order point. Numbering
// makes several lookups per tet, and std::unordered_map's chained nodes made
// them a third of the writing time.
class EntityIndexMap {
 public:
  explicit EntityIndexMap(std::size_t expected) { rehash(std::bit_ceil(2 * expected + 16)); }

  /// The value stored for `key`; if there is none, stores `value` and
  /// returns it with *inserted set.
  std::int64_t find_or_insert(const EntityKey& key, std::int64_t value, bool* inserted) {
    if (2 * (size_ + 1) > slots_.size()) rehash(2 * slots_.size());
    Slot& slot = probe(key);
    *inserted = slot.value < 0;
    if (*inserted) {
      slot = {key, value};
      ++size_;
    }
    return slot.value;
  }

 private:
  struct Slot {
    EntityKey key;
    std::int64_t value = -1;
  };
  Slot& probe(const EntityKey& key) {
    // Multiplicative hashing: the high bits of the product mix all key bits.
    const std::uint64_t h = (key.ab ^ (std::uint64_t{key.c} << 17)) * 0x9E3779B97F4A7C15ull;
    const std::size_t mask = slots_.size() - 1;
    for (std::size_t i = static_cast<std::size_t>(h >> (64 - std::countr_zero(slots_.size())));;
         i = (i + 1) & mask)
      if (slots_[i].value < 0 || slots_[i].key == key) return slots_[i];
  }
  void rehash(std::size_t capacity) {
    std::vector<Slot> old(capacity);
    old.swap(slots_);
    for (const Slot& s : old)
      if (s.value >= 0) probe(s.key) = s;
  }
  std::vector<Slot> slots_;
  std::size_t size_ = 0;
};

std::uint64_t edge_key(VertId a, VertId b) {
  if (a > b) std::swap(a, b);
  return (static_cast<std::uint64_t>(a) << 32) | b;
}

// Everything the file holds except the user's cell fields.
struct Grid {
  std::vector<Vec3> extra_points;  // high-order nodes, after the mesh vertices
  std::vector<std::int32_t> point_dim;
  std::vector<std::int32_t> point_tag;
  std::vector<std::int64_t> connectivity;
  std::vector<std::int64_t> offsets;  // VTK's: where each cell's nodes end in connectivity
  std::vector<std::uint8_t> types;
  std::vector<std::int32_t> cell_region;
  std::vector<std::int32_t> cell_dim;
};

void add_vertex_classification(const mesh::TetMesh& m, Grid& g) {
  g.point_dim.resize(m.num_verts(), -1);
  g.point_tag.resize(m.num_verts(), 0);
  for (std::size_t v = 0; v < std::min(m.num_verts(), m.vert_class.size()); ++v)
    if (m.vert_class[v].valid()) {
      g.point_dim[v] = m.vert_class[v].dim;
      g.point_tag[v] = m.vert_class[v].tag;
    }
}

// Closes a cell whose nodes were just appended to the connectivity.
void add_cell(Grid& g, std::uint8_t type, std::int32_t dim, std::int32_t region) {
  g.offsets.push_back(static_cast<std::int64_t>(g.connectivity.size()));
  g.types.push_back(type);
  g.cell_dim.push_back(dim);
  g.cell_region.push_back(region);
}

Grid build_linear_grid(const mesh::TetMesh& m) {
  Grid g;
  add_vertex_classification(m, g);
  g.connectivity.reserve(4 * m.num_tets() + 3 * m.tris.size());
  for (std::size_t t = 0; t < m.num_tets(); ++t) {
    for (VertId v : m.tet2verts[t]) g.connectivity.push_back(v);
    add_cell(g, kVtkTetra, 3, m.tet_region[t]);
  }
  for (const auto& tri : m.tris) {
    for (VertId v : tri.verts) g.connectivity.push_back(v);
    add_cell(g, kVtkTriangle, 2, tri.face_tag);
  }
  return g;
}

// Numbers the high-order nodes: one point per distinct node, classified on
// the model edge or face its mesh edge or face lies on, else on the region of
// the first tet (or face of the first triangle) that holds it. The p-1 nodes
// of an edge get consecutive points, from its lower to its higher vertex id.
class HighOrderNumbering {
 public:
  HighOrderNumbering(const mesh::TetMesh& m, Grid& g)
      : m_(m),
        g_(g),
        p_(m.high_order.order()),
        edges_(m.num_tets() + m.tris.size()),
        faces_(p_ > 2 ? 2 * m.num_tets() + m.tris.size() : 0) {
    for (const auto& tri : m.tris) {
      face_class_.try_emplace(face_key(tri.verts), mesh::ModelRef{2, tri.face_tag});
      for (const auto& e : mesh::kTriEdges)
        edge_class_.try_emplace(edge_key(tri.verts[e[0]], tri.verts[e[1]]),
                                mesh::ModelRef{2, tri.face_tag});
    }
    for (const auto& edge : m.edges)
      edge_class_[edge_key(edge.verts[0], edge.verts[1])] = {1, edge.edge_tag};
  }

  /// Point index of the node with weights `w` over `verts`, at position x;
  /// `fallback` classifies a node on no classified edge or face.
  template <std::size_t K>
  std::int64_t point(const std::array<VertId, K>& verts, const std::array<int, K>& w, const Vec3& x,
                     mesh::ModelRef fallback) {
    std::array<std::size_t, K> nonzero{};
    std::size_t n = 0;
    for (std::size_t k = 0; k < K; ++k)
      if (w[k] != 0) nonzero[n++] = k;
    if (n == 1) return verts[nonzero[0]];
    CM_ASSERT(n <= 3);  // orders <= 3 have no nodes inside a tet
    bool inserted = false;
    const auto next_point = static_cast<std::int64_t>(m_.num_verts() + g_.extra_points.size());
    if (n == 2) {
      const VertId a = verts[nonzero[0]], b = verts[nonzero[1]];
      const int weight_of_higher = a < b ? w[nonzero[1]] : w[nonzero[0]];
      const std::uint64_t key = edge_key(a, b);
      const std::int64_t first =
          edges_.find_or_insert(EntityKey{key, kNone}, next_point, &inserted);
      if (inserted) {
        const auto it = edge_class_.find(key);
        for (int s = 1; s < p_; ++s) add_point(it != edge_class_.end() ? it->second : fallback);
      }
      const std::int64_t index = first + weight_of_higher - 1;
      // The cell that inserts an edge visits all its nodes: each is placed once.
      Vec3& placed = g_.extra_points[static_cast<std::size_t>(index) - m_.num_verts()];
      if (std::isnan(placed[0])) placed = x;
      return index;
    }
    const EntityKey key = face_key({verts[nonzero[0]], verts[nonzero[1]], verts[nonzero[2]]});
    const std::int64_t index = faces_.find_or_insert(key, next_point, &inserted);
    if (inserted) {
      const auto it = face_class_.find(key);
      add_point(it != face_class_.end() ? it->second : fallback);
      g_.extra_points.back() = x;
    }
    return index;
  }

 private:
  static EntityKey face_key(std::array<VertId, 3> v) {
    std::sort(v.begin(), v.end());
    return {edge_key(v[0], v[1]), v[2]};
  }
  struct EntityKeyHash {
    std::size_t operator()(const EntityKey& k) const {
      return std::hash<std::uint64_t>()(k.ab) ^ k.c;
    }
  };

  void add_point(mesh::ModelRef cls) {
    g_.extra_points.emplace_back(Vec3::Constant(std::numeric_limits<double>::quiet_NaN()));
    g_.point_dim.push_back(cls.dim);
    g_.point_tag.push_back(cls.tag);
  }

  const mesh::TetMesh& m_;
  Grid& g_;
  int p_;
  EntityIndexMap edges_;
  EntityIndexMap faces_;
  std::unordered_map<std::uint64_t, mesh::ModelRef> edge_class_;
  std::unordered_map<EntityKey, mesh::ModelRef, EntityKeyHash> face_class_;
};

Grid build_high_order_grid(const mesh::TetMesh& m) {
  const int p = m.high_order.order();
  Grid g;
  add_vertex_classification(m, g);
  HighOrderNumbering numbering(m, g);
  const auto tet_nodes = mesh::tet_node_indices(p);
  const auto tri_nodes = mesh::tri_node_indices(p);
  const auto tet_perm = vtk_permutation(vtk_tet_node_indices(p), tet_nodes);
  const auto tri_perm = vtk_permutation(vtk_tri_node_indices(p), tri_nodes);
  g.connectivity.reserve(tet_nodes.size() * m.num_tets() + tri_nodes.size() * m.tris.size());
  for (std::size_t t = 0; t < m.num_tets(); ++t) {
    const auto x = mesh::gather_tet_nodes(m, static_cast<TetId>(t));
    const mesh::ModelRef region{3, m.tet_region[t]};
    for (int i : tet_perm)
      g.connectivity.push_back(numbering.point(m.tet2verts[t],
                                               tet_nodes[static_cast<std::size_t>(i)],
                                               x[static_cast<std::size_t>(i)], region));
    add_cell(g, kVtkLagrangeTetrahedron, 3, m.tet_region[t]);
  }
  for (const auto& tri : m.tris) {
    const auto x = mesh::gather_tri_nodes(m, tri.verts);
    const mesh::ModelRef face{2, tri.face_tag};
    for (int i : tri_perm)
      g.connectivity.push_back(numbering.point(tri.verts, tri_nodes[static_cast<std::size_t>(i)],
                                               x[static_cast<std::size_t>(i)], face));
    add_cell(g, kVtkLagrangeTriangle, 2, tri.face_tag);
  }
  return g;
}

std::string xml_escape(std::string_view s) {
  std::string out;
  for (char c : s) {
    switch (c) {
      case '&':
        out += "&amp;";
        break;
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '"':
        out += "&quot;";
        break;
      case '\'':
        out += "&apos;";
        break;
      default:
        out += c;
    }
  }
  return out;
}

// One DataArray of the appended block: its XML attributes and the pieces of
// memory that make up its data, written one after the other.
struct Array {
  std::string attributes;  // type, Name, NumberOfComponents
  std::vector<std::span<const std::byte>> pieces;
  std::uint64_t bytes() const {
    std::uint64_t n = 0;
    for (const auto& piece : pieces) n += piece.size();
    return n;
  }
};

template <class T>
std::span<const std::byte> bytes_of(const std::vector<T>& v) {
  return std::as_bytes(std::span<const T>(v));
}

// Writes the XML header naming every array, then the appended block: each
// array is a UInt64 byte count followed by its bytes, and each header entry's
// `offset` counts from the first byte after the '_' marker.
void write_appended_vtu(const std::string& path, std::size_t num_points, std::size_t num_cells,
                        const std::array<const std::vector<Array>*, 4>& groups) {
  std::string xml = fmt::format(
      "<?xml version=\"1.0\"?>\n"
      "<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"{}\" "
      "header_type=\"UInt64\">\n"
      "  <UnstructuredGrid>\n"
      "    <Piece NumberOfPoints=\"{}\" NumberOfCells=\"{}\">\n",
      std::endian::native == std::endian::little ? "LittleEndian" : "BigEndian", num_points,
      num_cells);
  std::uint64_t offset = 0;
  const std::array<std::string_view, 4> tags = {"PointData", "CellData", "Points", "Cells"};
  for (std::size_t g = 0; g < groups.size(); ++g) {
    xml += fmt::format("      <{}>\n", tags[g]);
    for (const Array& a : *groups[g]) {
      xml += fmt::format("        <DataArray {} format=\"appended\" offset=\"{}\"/>\n",
                         a.attributes, offset);
      offset += sizeof(std::uint64_t) + a.bytes();
    }
    xml += fmt::format("      </{}>\n", tags[g]);
  }
  xml += "    </Piece>\n  </UnstructuredGrid>\n  <AppendedData encoding=\"raw\">\n   _";

  AtomicFile file(path);
  file.write(xml);
  for (const auto* group : groups)
    for (const Array& a : *group) {
      const std::uint64_t n = a.bytes();
      file.write(&n, sizeof n);
      for (const auto& piece : a.pieces) file.write(piece.data(), piece.size());
    }
  file.write("\n  </AppendedData>\n</VTKFile>\n");
  file.commit();
}

}  // namespace

void write_vtu(const mesh::TetMesh& m, const std::string& path, std::span<const CellField> fields) {
  CM_ASSERT_OP(m.tet_region.size(), ==, m.num_tets());
  std::set<std::string> names{"region", "dim", "model_tag"};
  for (const CellField& f : fields) {
    if (f.values.size() != m.num_tets())
      throw std::invalid_argument(
          fmt::format("write_vtu: cell field '{}' has {} values for {} tets", f.name,
                      f.values.size(), m.num_tets()));
    if (!names.insert(f.name).second)
      throw std::invalid_argument(
          fmt::format("write_vtu: cell field name '{}' is used twice", f.name));
  }
  const Grid g = m.high_order.order() > 1 ? build_high_order_grid(m) : build_linear_grid(m);
  const std::size_t num_points = m.num_verts() + g.extra_points.size();
  const std::size_t num_cells = g.types.size();
  const std::vector<double> nan_for_tris(m.tris.size(), std::numeric_limits<double>::quiet_NaN());

  std::vector<Array> point_data, cell_data, points, cells;
  point_data.push_back({R"(type="Int32" Name="class_dim")", {bytes_of(g.point_dim)}});
  point_data.push_back({R"(type="Int32" Name="class_tag")", {bytes_of(g.point_tag)}});
  cell_data.push_back({R"(type="Int32" Name="region")", {bytes_of(g.cell_region)}});
  cell_data.push_back({R"(type="Int32" Name="dim")", {bytes_of(g.cell_dim)}});
  cell_data.push_back({R"(type="Int32" Name="model_tag")", {bytes_of(g.cell_region)}});
  for (const CellField& f : fields)
    cell_data.push_back({fmt::format(R"(type="Float64" Name="{}")", xml_escape(f.name)),
                         {bytes_of(f.values), bytes_of(nan_for_tris)}});
  points.push_back({R"(type="Float64" Name="Points" NumberOfComponents="3")",
                    {bytes_of(m.coords), bytes_of(g.extra_points)}});
  cells.push_back({R"(type="Int64" Name="connectivity")", {bytes_of(g.connectivity)}});
  cells.push_back({R"(type="Int64" Name="offsets")", {bytes_of(g.offsets)}});
  cells.push_back({R"(type="UInt8" Name="types")", {bytes_of(g.types)}});

  write_appended_vtu(path, num_points, num_cells, {&point_data, &cell_data, &points, &cells});
}

void write_vtu_grid(const VtuGrid& grid, const std::string& path) {
  const std::size_t num_points = grid.points.size(), num_cells = grid.types.size();
  if (grid.offsets.size() != num_cells)
    throw std::invalid_argument(
        fmt::format("write_vtu_grid: {} offsets for {} cells", grid.offsets.size(), num_cells));
  std::int64_t previous = 0;
  for (const std::int64_t end : grid.offsets) {
    if (end < previous || end > static_cast<std::int64_t>(grid.connectivity.size()))
      throw std::invalid_argument("write_vtu_grid: offsets must increase up to the connectivity size");
    previous = end;
  }
  if (previous != static_cast<std::int64_t>(grid.connectivity.size()))
    throw std::invalid_argument("write_vtu_grid: the last offset must be the connectivity size");
  for (const std::int64_t v : grid.connectivity)
    if (v < 0 || v >= static_cast<std::int64_t>(num_points))
      throw std::invalid_argument(fmt::format("write_vtu_grid: cell refers to point {} of {}", v, num_points));
  std::set<std::string> names;
  const auto check = [&](const VtuGrid::Field& f, std::size_t count, const char* what) {
    if (f.components != 1 && f.components != 3)
      throw std::invalid_argument(fmt::format("write_vtu_grid: field '{}' has {} components", f.name, f.components));
    if (f.values.size() != count * static_cast<std::size_t>(f.components))
      throw std::invalid_argument(fmt::format("write_vtu_grid: {} field '{}' has {} values for {} {}s", what,
                                              f.name, f.values.size(), count, what));
    if (!names.insert(f.name).second)
      throw std::invalid_argument(fmt::format("write_vtu_grid: field name '{}' is used twice", f.name));
  };
  for (const auto& f : grid.point_fields) check(f, num_points, "point");
  for (const auto& f : grid.cell_fields) check(f, num_cells, "cell");

  const auto field_arrays = [](const std::vector<VtuGrid::Field>& fields) {
    std::vector<Array> out;
    for (const auto& f : fields)
      out.push_back({fmt::format(R"(type="Float64" Name="{}" NumberOfComponents="{}")", xml_escape(f.name),
                                 f.components),
                     {bytes_of(f.values)}});
    return out;
  };
  const std::vector<Array> point_data = field_arrays(grid.point_fields);
  const std::vector<Array> cell_data = field_arrays(grid.cell_fields);
  const std::vector<Array> points = {
      {R"(type="Float64" Name="Points" NumberOfComponents="3")", {bytes_of(grid.points)}}};
  const std::vector<Array> cells = {{R"(type="Int64" Name="connectivity")", {bytes_of(grid.connectivity)}},
                                    {R"(type="Int64" Name="offsets")", {bytes_of(grid.offsets)}},
                                    {R"(type="UInt8" Name="types")", {bytes_of(grid.types)}}};
  write_appended_vtu(path, num_points, num_cells, {&point_data, &cell_data, &points, &cells});
}

}  // namespace cm::io
