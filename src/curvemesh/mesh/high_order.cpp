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

std::uint64_t edge_key(VertId a, VertId b) {
  if (a > b) std::swap(a, b);
  return (static_cast<std::uint64_t>(a) << 32) | b;
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

std::size_t HighOrderNodes::FaceKeyHash::operator()(const FaceKey& k) const {
  std::uint64_t h = k.v[0];
  h = h * 0x9E3779B97F4A7C15ull ^ k.v[1];
  h = h * 0x9E3779B97F4A7C15ull ^ k.v[2];
  return static_cast<std::size_t>(h ^ (h >> 29));
}

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

void HighOrderNodes::set_edge(VertId a, VertId b, std::span<const Vec3> nodes_from_a) {
  const std::size_t n = nodes_per_edge();
  CM_ASSERT_OP(nodes_from_a.size(), ==, n);
  if (n == 0) return;
  auto [it, inserted] = edge_slot_.try_emplace(edge_key(a, b), 0u);
  if (inserted) {
    if (!free_edge_slots_.empty()) {
      it->second = free_edge_slots_.back();
      free_edge_slots_.pop_back();
    } else {
      it->second = static_cast<std::uint32_t>(edge_nodes_.size() / n);
      edge_nodes_.resize(edge_nodes_.size() + n);
    }
  }
  Vec3* dst = edge_nodes_.data() + it->second * n;
  for (std::size_t s = 0; s < n; ++s) dst[a < b ? s : n - 1 - s] = nodes_from_a[s];
}

bool HighOrderNodes::get_edge(VertId a, VertId b, Vec3* out_from_a) const {
  const std::size_t n = nodes_per_edge();
  if (n == 0) return false;
  auto it = edge_slot_.find(edge_key(a, b));
  if (it == edge_slot_.end()) return false;
  const Vec3* src = edge_nodes_.data() + it->second * n;
  for (std::size_t s = 0; s < n; ++s) out_from_a[s] = src[a < b ? s : n - 1 - s];
  return true;
}

void HighOrderNodes::set_face(VertId a, VertId b, VertId c, std::span<const Vec3> nodes) {
  const std::size_t n = nodes_per_face();
  CM_ASSERT_OP(nodes.size(), ==, n);
  if (n == 0) return;
  std::array<VertId, 3> s{a, b, c};
  std::sort(s.begin(), s.end());
  auto [it, inserted] = face_slot_.try_emplace(FaceKey{{s[0], s[1], s[2]}}, 0u);
  if (inserted) {
    if (!free_face_slots_.empty()) {
      it->second = free_face_slots_.back();
      free_face_slots_.pop_back();
    } else {
      it->second = static_cast<std::uint32_t>(face_nodes_.size() / n);
      face_nodes_.resize(face_nodes_.size() + n);
    }
  }
  Vec3* dst = face_nodes_.data() + it->second * n;
  const auto perm = face_permutation(order_, {a, b, c});
  for (std::size_t k = 0; k < n; ++k) dst[perm[k]] = nodes[k];
}

void HighOrderNodes::remap_vertices(std::span<const VertId> old2new) {
  // Order-preserving renaming keeps each key's sorted order, so the stored
  // node order (relative to the sorted vertices) stays right.
  std::unordered_map<std::uint64_t, std::uint32_t> edges;
  for (const auto& [key, slot] : edge_slot_) {
    const VertId a = old2new[key >> 32], b = old2new[key & 0xffffffffu];
    if (a == kNone || b == kNone)
      free_edge_slots_.push_back(slot);
    else
      edges.emplace(edge_key(a, b), slot);
  }
  edge_slot_ = std::move(edges);
  std::unordered_map<FaceKey, std::uint32_t, FaceKeyHash> faces;
  for (const auto& [key, slot] : face_slot_) {
    const VertId a = old2new[key.v[0]], b = old2new[key.v[1]], c = old2new[key.v[2]];
    if (a == kNone || b == kNone || c == kNone)
      free_face_slots_.push_back(slot);
    else
      faces.emplace(FaceKey{{a, b, c}}, slot);
  }
  face_slot_ = std::move(faces);
}

bool HighOrderNodes::has_edge(VertId a, VertId b) const {
  return nodes_per_edge() > 0 && edge_slot_.count(edge_key(a, b)) > 0;
}

bool HighOrderNodes::has_face(VertId a, VertId b, VertId c) const {
  if (nodes_per_face() == 0) return false;
  std::array<VertId, 3> s{a, b, c};
  std::sort(s.begin(), s.end());
  return face_slot_.count(FaceKey{{s[0], s[1], s[2]}}) > 0;
}

void HighOrderNodes::erase_edge(VertId a, VertId b) {
  const auto it = edge_slot_.find(edge_key(a, b));
  if (it == edge_slot_.end()) return;
  free_edge_slots_.push_back(it->second);
  edge_slot_.erase(it);
}

void HighOrderNodes::erase_face(VertId a, VertId b, VertId c) {
  std::array<VertId, 3> s{a, b, c};
  std::sort(s.begin(), s.end());
  const auto it = face_slot_.find(FaceKey{{s[0], s[1], s[2]}});
  if (it == face_slot_.end()) return;
  free_face_slots_.push_back(it->second);
  face_slot_.erase(it);
}

bool HighOrderNodes::get_face(VertId a, VertId b, VertId c, Vec3* out) const {
  const std::size_t n = nodes_per_face();
  if (n == 0) return false;
  std::array<VertId, 3> s{a, b, c};
  std::sort(s.begin(), s.end());
  auto it = face_slot_.find(FaceKey{{s[0], s[1], s[2]}});
  if (it == face_slot_.end()) return false;
  const Vec3* src = face_nodes_.data() + it->second * n;
  const auto perm = face_permutation(order_, {a, b, c});
  for (std::size_t k = 0; k < n; ++k) out[k] = src[perm[k]];
  return true;
}

namespace {

// Shared by tets and triangles: fills nodes from vertex ids and multi-indices.
template <std::size_t K>
std::vector<Vec3> gather_nodes(const TetMesh& m, const std::array<VertId, K>& v,
                               const std::vector<std::array<int, K>>& indices) {
  const int p = m.high_order.order();
  std::vector<Vec3> out(indices.size());
  std::vector<Vec3> buf(static_cast<std::size_t>(p * p));
  for (std::size_t n = 0; n < indices.size(); ++n) {
    const auto& idx = indices[n];
    int nz[K];
    int count = 0;
    Vec3 linear = Vec3::Zero();
    for (std::size_t k = 0; k < K; ++k)
      if (idx[k] != 0) {
        nz[count++] = static_cast<int>(k);
        linear += (static_cast<double>(idx[k]) / p) * m.coords[v[k]];
      }
    out[n] = linear;
    if (count == 1) {
      out[n] = m.coords[v[nz[0]]];
    } else if (count == 2) {
      if (m.high_order.get_edge(v[nz[0]], v[nz[1]], buf.data())) out[n] = buf[idx[nz[1]] - 1];
    } else if (count == 3) {
      if (m.high_order.get_face(v[nz[0]], v[nz[1]], v[nz[2]], buf.data())) {
        const auto interior = tri_interior_indices(p);
        const std::array<int, 3> rel{idx[nz[0]], idx[nz[1]], idx[nz[2]]};
        out[n] = buf[std::find(interior.begin(), interior.end(), rel) - interior.begin()];
      }
    }
  }
  return out;
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

std::vector<Vec3> gather_tet_nodes(const TetMesh& m, TetId t) {
  return gather_nodes<4>(m, m.tet2verts[t], cached_tet_indices(m.high_order.order()));
}

std::vector<Vec3> gather_tet_nodes(const TetMesh& m, const std::array<VertId, 4>& verts) {
  return gather_nodes<4>(m, verts, cached_tet_indices(m.high_order.order()));
}

std::vector<Vec3> gather_tri_nodes(const TetMesh& m, const std::array<VertId, 3>& tri) {
  return gather_nodes<3>(m, tri, cached_tri_indices(m.high_order.order()));
}

void scatter_tet_nodes(TetMesh& m, TetId t, std::span<const Vec3> nodes) {
  scatter_nodes<4>(m, m.tet2verts[t], cached_tet_indices(m.high_order.order()), nodes);
}

void scatter_tri_nodes(TetMesh& m, const std::array<VertId, 3>& tri, std::span<const Vec3> nodes) {
  scatter_nodes<3>(m, tri, cached_tri_indices(m.high_order.order()), nodes);
}

}  // namespace cm::mesh
