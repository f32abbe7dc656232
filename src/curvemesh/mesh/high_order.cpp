#include "curvemesh/mesh/high_order.hpp"

#include <algorithm>

#include "curvemesh/core/error.hpp"
#include "curvemesh/mesh/tet_mesh.hpp"
#include "curvemesh/mesh/topology.hpp"

namespace cm::mesh {

namespace {

std::vector<std::array<int, 3>> tri_interior_indices(int p) {
  std::vector<std::array<int, 3>> out;
  for (int i0 = p - 2; i0 >= 1; --i0)
    for (int i1 = p - 1 - i0; i1 >= 1; --i1) out.push_back({i0, i1, p - i0 - i1});
  return out;
}

// Position, in the canonical interior list of a triangle sorted by vertex id,
// of each interior node given relative to (a,b,c).
std::vector<int> face_permutation(int p, const std::array<VertId, 3>& abc) {
  std::array<int, 3> rank{0, 1, 2};  // rank[k]: position of abc[k] in sorted order
  std::array<int, 3> order{0, 1, 2};
  std::sort(order.begin(), order.end(), [&](int x, int y) { return abc[x] < abc[y]; });
  for (int s = 0; s < 3; ++s) rank[order[s]] = s;
  const auto interior = tri_interior_indices(p);
  std::vector<int> perm(interior.size());
  for (std::size_t n = 0; n < interior.size(); ++n) {
    std::array<int, 3> sorted_index{};
    for (int k = 0; k < 3; ++k) sorted_index[rank[k]] = interior[n][k];
    perm[n] = static_cast<int>(std::find(interior.begin(), interior.end(), sorted_index) - interior.begin());
  }
  return perm;
}

const std::vector<std::array<int, 3>>& cached_interior_indices(int p) {
  static const std::array<std::vector<std::array<int, 3>>, kMaxOrder + 1> cache = [] {
    std::array<std::vector<std::array<int, 3>>, kMaxOrder + 1> c;
    for (int q = 1; q <= kMaxOrder; ++q) c[q] = tri_interior_indices(q);
    return c;
  }();
  CM_ASSERT(p >= 1 && p <= kMaxOrder);
  return cache[p];
}

const std::vector<std::array<int, 4>>& cached_tet_indices(int p) {
  static const std::array<std::vector<std::array<int, 4>>, kMaxOrder + 1> cache = [] {
    std::array<std::vector<std::array<int, 4>>, kMaxOrder + 1> c;
    for (int q = 1; q <= kMaxOrder; ++q) c[q] = tet_node_indices(q);
    return c;
  }();
  CM_ASSERT(p >= 1 && p <= kMaxOrder);
  return cache[p];
}

const std::vector<std::array<int, 3>>& cached_tri_indices(int p) {
  static const std::array<std::vector<std::array<int, 3>>, kMaxOrder + 1> cache = [] {
    std::array<std::vector<std::array<int, 3>>, kMaxOrder + 1> c;
    for (int q = 1; q <= kMaxOrder; ++q) c[q] = tri_node_indices(q);
    return c;
  }();
  CM_ASSERT(p >= 1 && p <= kMaxOrder);
  return cache[p];
}

}  // namespace

std::vector<std::array<int, 3>> tri_node_indices(int p) {
  std::vector<std::array<int, 3>> out;
  for (int k = 0; k < 3; ++k) {
    std::array<int, 3> v{0, 0, 0};
    v[k] = p;
    out.push_back(v);
  }
  for (const auto& e : kTriEdges)
    for (int s = 1; s < p; ++s) {
      std::array<int, 3> v{0, 0, 0};
      v[e[0]] = p - s;
      v[e[1]] = s;
      out.push_back(v);
    }
  for (const auto& in : tri_interior_indices(p)) out.push_back(in);
  return out;
}

std::vector<std::array<int, 4>> tet_node_indices(int p) {
  std::vector<std::array<int, 4>> out;
  for (int k = 0; k < 4; ++k) {
    std::array<int, 4> v{0, 0, 0, 0};
    v[k] = p;
    out.push_back(v);
  }
  for (const auto& e : kTetEdges)
    for (int s = 1; s < p; ++s) {
      std::array<int, 4> v{0, 0, 0, 0};
      v[e[0]] = p - s;
      v[e[1]] = s;
      out.push_back(v);
    }
  const auto tri_in = tri_interior_indices(p);
  for (const auto& f : kFaceVerts)
    for (const auto& in : tri_in) {
      std::array<int, 4> v{0, 0, 0, 0};
      for (int k = 0; k < 3; ++k) v[f[k]] = in[k];
      out.push_back(v);
    }
  for (int i0 = p - 3; i0 >= 1; --i0)
    for (int i1 = p - 2 - i0; i1 >= 1; --i1)
      for (int i2 = p - 1 - i0 - i1; i2 >= 1; --i2) out.push_back({i0, i1, i2, p - i0 - i1 - i2});
  return out;
}

// --- the slot table: open addressing on sorted vertex triples ---------------

namespace {

std::size_t hash_key(const std::array<VertId, 3>& k) {
  std::uint64_t h = k[0];
  h = h * 0x9E3779B97F4A7C15ull ^ k[1];
  h = h * 0x9E3779B97F4A7C15ull ^ k[2];
  return static_cast<std::size_t>(h ^ (h >> 29));
}

std::array<VertId, 3> sorted_key(VertId a, VertId b, VertId c) {
  if (a > b) std::swap(a, b);
  if (b > c) std::swap(b, c);
  if (a > b) std::swap(a, b);
  return {a, b, c};
}

// An edge is the triple (a, b, kNone) with a < b.
std::array<VertId, 3> edge_triple(VertId a, VertId b) {
  if (a > b) std::swap(a, b);
  return {a, b, kNone};
}

}  // namespace

const std::uint32_t* HighOrderNodes::SlotTable::find(const std::array<VertId, 3>& key) const {
  if (entries.empty()) return nullptr;
  const std::size_t mask = entries.size() - 1;
  for (std::size_t i = hash_key(key) & mask;; i = (i + 1) & mask) {
    const Entry& e = entries[i];
    if (e.slot == kEmpty) return nullptr;
    if (e.key == key) return &e.slot;
  }
}

std::pair<std::uint32_t*, bool> HighOrderNodes::SlotTable::insert(const std::array<VertId, 3>& key) {
  if (2 * (size + 1) > entries.size()) grow();
  const std::size_t mask = entries.size() - 1;
  for (std::size_t i = hash_key(key) & mask;; i = (i + 1) & mask) {
    Entry& e = entries[i];
    if (e.slot == kEmpty) {
      e.key = key;
      ++size;
      return {&e.slot, true};
    }
    if (e.key == key) return {&e.slot, false};
  }
}

std::optional<std::uint32_t> HighOrderNodes::SlotTable::erase(const std::array<VertId, 3>& key) {
  if (entries.empty()) return std::nullopt;
  const std::size_t mask = entries.size() - 1;
  std::size_t i = hash_key(key) & mask;
  while (entries[i].slot != kEmpty && entries[i].key != key) i = (i + 1) & mask;
  if (entries[i].slot == kEmpty) return std::nullopt;
  const std::uint32_t slot = entries[i].slot;
  // Backward-shift deletion: no tombstones build up over many erases.
  for (std::size_t j = (i + 1) & mask; entries[j].slot != kEmpty; j = (j + 1) & mask) {
    const std::size_t home = hash_key(entries[j].key) & mask;
    if (((j - home) & mask) >= ((j - i) & mask)) {
      entries[i] = entries[j];
      i = j;
    }
  }
  entries[i].slot = kEmpty;
  --size;
  return slot;
}

void HighOrderNodes::SlotTable::grow() {
  std::vector<Entry> old = std::move(entries);
  entries.assign(std::max<std::size_t>(16, 2 * old.size()), Entry{});
  size = 0;
  for (const Entry& e : old)
    if (e.slot != kEmpty) *insert(e.key).first = e.slot;
}

void HighOrderNodes::SlotTable::clear() {
  entries.clear();
  size = 0;
}

// --- HighOrderNodes ------------------------------------------------------------

void HighOrderNodes::reset(int order) {
  if (order < 1 || order > kMaxOrder)
    throw std::invalid_argument(fmt::format("element order {} is not supported (1..{})", order, kMaxOrder));
  order_ = order;
  edge_slot_.clear();
  edge_nodes_.clear();
  face_slot_.clear();
  face_nodes_.clear();
  free_edge_slots_.clear();
  free_face_slots_.clear();
}

std::uint32_t HighOrderNodes::take_slot(std::vector<std::uint32_t>& free, std::vector<Vec3>& nodes, std::size_t n) {
  if (!free.empty()) {
    const std::uint32_t s = free.back();
    free.pop_back();
    return s;
  }
  const auto s = static_cast<std::uint32_t>(nodes.size() / n);
  nodes.resize(nodes.size() + n);
  return s;
}

void HighOrderNodes::set_edge(VertId a, VertId b, std::span<const Vec3> nodes_from_a) {
  const std::size_t n = nodes_per_edge();
  CM_ASSERT_OP(nodes_from_a.size(), ==, n);
  if (n == 0) return;
  if (journal_.to) journal_.to->push_back(edge_triple(a, b));
  const auto [slot, inserted] = edge_slot_.insert(edge_triple(a, b));
  if (inserted) *slot = take_slot(free_edge_slots_, edge_nodes_, n);
  Vec3* dst = edge_nodes_.data() + std::size_t{*slot} * n;
  for (std::size_t s = 0; s < n; ++s) dst[a < b ? s : n - 1 - s] = nodes_from_a[s];
}

bool HighOrderNodes::get_edge(VertId a, VertId b, Vec3* out_from_a) const {
  const std::size_t n = nodes_per_edge();
  if (n == 0) return false;
  const std::uint32_t* slot = edge_slot_.find(edge_triple(a, b));
  if (!slot) return false;
  const Vec3* src = edge_nodes_.data() + std::size_t{*slot} * n;
  for (std::size_t s = 0; s < n; ++s) out_from_a[s] = src[a < b ? s : n - 1 - s];
  return true;
}

void HighOrderNodes::set_face(VertId a, VertId b, VertId c, std::span<const Vec3> nodes) {
  const std::size_t n = nodes_per_face();
  CM_ASSERT_OP(nodes.size(), ==, n);
  if (n == 0) return;
  if (journal_.to) journal_.to->push_back(sorted_key(a, b, c));
  const auto [slot, inserted] = face_slot_.insert(sorted_key(a, b, c));
  if (inserted) *slot = take_slot(free_face_slots_, face_nodes_, n);
  Vec3* dst = face_nodes_.data() + std::size_t{*slot} * n;
  if (n == 1) {
    dst[0] = nodes[0];
    return;
  }
  const auto perm = face_permutation(order_, {a, b, c});
  for (std::size_t k = 0; k < n; ++k) dst[perm[k]] = nodes[k];
}

bool HighOrderNodes::get_face(VertId a, VertId b, VertId c, Vec3* out) const {
  const std::size_t n = nodes_per_face();
  if (n == 0) return false;
  const std::uint32_t* slot = face_slot_.find(sorted_key(a, b, c));
  if (!slot) return false;
  const Vec3* src = face_nodes_.data() + std::size_t{*slot} * n;
  if (n == 1) {
    out[0] = src[0];
    return true;
  }
  const auto perm = face_permutation(order_, {a, b, c});
  for (std::size_t k = 0; k < n; ++k) out[k] = src[perm[k]];
  return true;
}

void HighOrderNodes::remap_vertices(std::span<const VertId> old2new) {
  // Order-preserving renaming keeps each key's sorted order, so the stored
  // node order (relative to the sorted vertices) stays right.
  auto remap = [&](SlotTable& table, std::vector<std::uint32_t>& free) {
    SlotTable renamed;
    for (const SlotTable::Entry& e : table.entries) {
      if (e.slot == SlotTable::kEmpty) continue;
      std::array<VertId, 3> k = e.key;
      bool dropped = false;
      for (VertId& v : k)
        if (v != kNone) {
          v = old2new[v];
          dropped |= v == kNone;
        }
      if (dropped)
        free.push_back(e.slot);
      else
        *renamed.insert(k).first = e.slot;
    }
    table = std::move(renamed);
  };
  remap(edge_slot_, free_edge_slots_);
  remap(face_slot_, free_face_slots_);
}

bool HighOrderNodes::has_edge(VertId a, VertId b) const {
  return nodes_per_edge() > 0 && edge_slot_.find(edge_triple(a, b)) != nullptr;
}

bool HighOrderNodes::has_face(VertId a, VertId b, VertId c) const {
  return nodes_per_face() > 0 && face_slot_.find(sorted_key(a, b, c)) != nullptr;
}

void HighOrderNodes::erase_edge(VertId a, VertId b) {
  if (journal_.to) journal_.to->push_back(edge_triple(a, b));
  if (const auto slot = edge_slot_.erase(edge_triple(a, b))) free_edge_slots_.push_back(*slot);
}

void HighOrderNodes::erase_face(VertId a, VertId b, VertId c) {
  if (journal_.to) journal_.to->push_back(sorted_key(a, b, c));
  if (const auto slot = face_slot_.erase(sorted_key(a, b, c))) free_face_slots_.push_back(*slot);
}

namespace {

// Where each stored entity's nodes go in an element's node list, so that a
// gather looks the table up once per edge and per face rather than once per
// node: on a big mesh those lookups are cache misses, and they are most of
// what checking a curved mesh costs.
struct GatherEntity {
  int count = 0;                           // 2: an edge, 3: a face
  std::array<int, 3> local{};              // its local vertices, as the multi-indices list them
  std::vector<std::pair<int, int>> slots;  // (node, position in the entity's stored list)
};

template <std::size_t K>
std::vector<GatherEntity> make_gather_plan(int p, const std::vector<std::array<int, K>>& indices) {
  std::vector<GatherEntity> plan;
  const auto& interior = cached_interior_indices(p);
  for (std::size_t n = 0; n < indices.size(); ++n) {
    const auto& idx = indices[n];
    std::array<int, 4> nz{};
    int count = 0;
    for (std::size_t k = 0; k < K; ++k)
      if (idx[k] != 0) nz[static_cast<std::size_t>(count++)] = static_cast<int>(k);
    // Vertices are copied, a tet's interior nodes are linear.
    if (count != 2 && count != 3) continue;
    const std::array<int, 3> local{nz[0], nz[1], count == 3 ? nz[2] : -1};
    int position = idx[static_cast<std::size_t>(nz[1])] - 1;
    if (count == 3) {
      const std::array<int, 3> rel{idx[static_cast<std::size_t>(nz[0])], idx[static_cast<std::size_t>(nz[1])],
                                   idx[static_cast<std::size_t>(nz[2])]};
      position = static_cast<int>(std::find(interior.begin(), interior.end(), rel) - interior.begin());
    }
    auto it = std::find_if(plan.begin(), plan.end(), [&](const GatherEntity& e) { return e.local == local; });
    if (it == plan.end()) it = plan.insert(plan.end(), GatherEntity{count, local, {}});
    it->slots.emplace_back(static_cast<int>(n), position);
  }
  return plan;
}

// The plan of order p for a tet (K = 4) or a triangle (K = 3).
template <std::size_t K>
const std::vector<GatherEntity>& gather_plan(int p) {
  static const std::array<std::vector<GatherEntity>, kMaxOrder + 1> cache = [] {
    std::array<std::vector<GatherEntity>, kMaxOrder + 1> c;
    for (int q = 1; q <= kMaxOrder; ++q) {
      if constexpr (K == 4)
        c[static_cast<std::size_t>(q)] = make_gather_plan<4>(q, cached_tet_indices(q));
      else
        c[static_cast<std::size_t>(q)] = make_gather_plan<3>(q, cached_tri_indices(q));
    }
    return c;
  }();
  return cache[static_cast<std::size_t>(p)];
}

// Shared by tets and triangles: fills nodes from vertex ids and multi-indices.
template <std::size_t K>
bool gather_nodes(const TetMesh& m, const std::array<VertId, K>& v, const std::vector<std::array<int, K>>& indices,
                  const std::vector<GatherEntity>& plan, std::span<Vec3> out) {
  CM_ASSERT_OP(out.size(), ==, indices.size());
  const int p = m.high_order.order();
  // Stored nodes first; a bit per node says which ones were found.
  static_assert(kMaxTetNodes <= 64);
  std::uint64_t stored = 0;
  std::array<Vec3, kMaxOrder * kMaxOrder> buf;
  for (const GatherEntity& e : plan) {
    const bool found = e.count == 2 ? m.high_order.get_edge(v[e.local[0]], v[e.local[1]], buf.data())
                                    : m.high_order.get_face(v[e.local[0]], v[e.local[1]], v[e.local[2]], buf.data());
    if (!found) continue;
    for (const auto& [n, at] : e.slots) {
      out[static_cast<std::size_t>(n)] = buf[static_cast<std::size_t>(at)];
      stored |= std::uint64_t{1} << n;
    }
  }
  for (std::size_t n = 0; n < indices.size(); ++n) {
    if (stored >> n & 1) continue;
    const auto& idx = indices[n];
    int nonzero = 0;
    std::size_t last = 0;
    Vec3 linear = Vec3::Zero();
    for (std::size_t k = 0; k < K; ++k)
      if (idx[k] != 0) {
        ++nonzero;
        last = k;
        linear += (static_cast<double>(idx[k]) / p) * m.coords[v[k]];
      }
    out[n] = nonzero == 1 ? m.coords[v[last]] : linear;
  }
  return stored != 0;
}

template <std::size_t K>
void scatter_nodes(TetMesh& m, const std::array<VertId, K>& v,
                   const std::vector<std::array<int, K>>& indices, std::span<const Vec3> nodes) {
  const int p = m.high_order.order();
  CM_ASSERT_OP(nodes.size(), ==, indices.size());
  if (p == 1) return;
  const auto interior = tri_interior_indices(p);
  // Edge e of the element is identified by its two local vertices; collect its
  // nodes from the lower to the higher local index, then store.
  std::vector<Vec3> buf(static_cast<std::size_t>(p));
  std::vector<std::pair<std::array<int, 3>, std::vector<Vec3>>> faces;
  std::vector<std::pair<std::array<int, 2>, std::vector<Vec3>>> edges;
  for (std::size_t n = 0; n < indices.size(); ++n) {
    const auto& idx = indices[n];
    int nz[K];
    int count = 0;
    for (std::size_t k = 0; k < K; ++k)
      if (idx[k] != 0) nz[count++] = static_cast<int>(k);
    if (count == 2) {
      std::array<int, 2> key{nz[0], nz[1]};
      auto it = std::find_if(edges.begin(), edges.end(), [&](const auto& e) { return e.first == key; });
      if (it == edges.end()) {
        edges.push_back({key, std::vector<Vec3>(static_cast<std::size_t>(p - 1))});
        it = edges.end() - 1;
      }
      it->second[idx[nz[1]] - 1] = nodes[n];
    } else if (count == 3) {
      std::array<int, 3> key{nz[0], nz[1], nz[2]};
      auto it = std::find_if(faces.begin(), faces.end(), [&](const auto& f) { return f.first == key; });
      if (it == faces.end()) {
        faces.push_back({key, std::vector<Vec3>(interior.size())});
        it = faces.end() - 1;
      }
      const std::array<int, 3> rel{idx[nz[0]], idx[nz[1]], idx[nz[2]]};
      it->second[std::find(interior.begin(), interior.end(), rel) - interior.begin()] = nodes[n];
    }
  }
  for (const auto& [key, pts] : edges) m.high_order.set_edge(v[key[0]], v[key[1]], pts);
  for (const auto& [key, pts] : faces) m.high_order.set_face(v[key[0]], v[key[1]], v[key[2]], pts);
}

}  // namespace

std::vector<Vec3> gather_tet_nodes(const TetMesh& m, TetId t) { return gather_tet_nodes(m, m.tet2verts[t]); }

std::vector<Vec3> gather_tet_nodes(const TetMesh& m, const std::array<VertId, 4>& verts) {
  const TetNodes n = tet_nodes(m, verts);
  return {n.view().begin(), n.view().end()};
}

TetNodes tet_nodes(const TetMesh& m, const std::array<VertId, 4>& verts) {
  const int p = m.high_order.order();
  TetNodes out;
  out.count = cached_tet_indices(p).size();
  out.stored = gather_nodes<4>(m, verts, cached_tet_indices(p), gather_plan<4>(p),
                               std::span<Vec3>(out.buffer.data(), out.count));
  return out;
}

std::vector<Vec3> gather_tri_nodes(const TetMesh& m, const std::array<VertId, 3>& tri) {
  const int p = m.high_order.order();
  std::vector<Vec3> out(cached_tri_indices(p).size());
  gather_nodes<3>(m, tri, cached_tri_indices(p), gather_plan<3>(p), out);
  return out;
}

void scatter_tet_nodes(TetMesh& m, TetId t, std::span<const Vec3> nodes) {
  scatter_nodes<4>(m, m.tet2verts[t], cached_tet_indices(m.high_order.order()), nodes);
}

void scatter_tri_nodes(TetMesh& m, const std::array<VertId, 3>& tri, std::span<const Vec3> nodes) {
  scatter_nodes<3>(m, tri, cached_tri_indices(m.high_order.order()), nodes);
}

}  // namespace cm::mesh
