#include "curvemesh/mesh/tet_mesh.hpp"

namespace cm::mesh {

VertId TetMesh::add_vert(const Vec3& x) {
  coords.push_back(x);
  vert2tet.push_back(kNone);
  vert_class.emplace_back();
  vert_param.emplace_back();
  return static_cast<VertId>(coords.size() - 1);
}

TetId TetMesh::add_tet(const std::array<VertId, 4>& v, std::int32_t region) {
  tet2verts.push_back(v);
  tet_region.push_back(region);
  return static_cast<TetId>(tet2verts.size() - 1);
}

void TetMesh::resize_vertex_arrays() {
  vert2tet.resize(coords.size(), kNone);
  vert_class.resize(coords.size());
  vert_param.resize(coords.size());
}

std::size_t TetMesh::memory_bytes() const {
  return coords.capacity() * sizeof(Vec3) + tet2verts.capacity() * sizeof(tet2verts[0]) +
         tet_region.capacity() * sizeof(std::int32_t) + tet2adj.capacity() * sizeof(Index) +
         vert2tet.capacity() * sizeof(TetId) + vert_class.capacity() * sizeof(ModelRef) +
         vert_param.capacity() * sizeof(Param) + tris.capacity() * sizeof(ClassifiedTri) +
         edges.capacity() * sizeof(ClassifiedEdge);
}

double tet_volume(const TetMesh& m, TetId t) {
  const auto& v = m.tet2verts[t];
  const Vec3& a = m.coords[v[0]];
  return (m.coords[v[1]] - a).cross(m.coords[v[2]] - a).dot(m.coords[v[3]] - a) / 6.0;
}

std::vector<VertId> drop_unused_vertices(TetMesh& m) {
  const std::size_t nv = m.num_verts();
  std::vector<VertId> old2new(nv, kNone);
  for (const auto& tv : m.tet2verts)
    for (VertId v : tv)
      if (v != kNone) old2new[v] = 0;
  VertId next = 0;
  for (VertId v = 0; v < nv; ++v)
    if (old2new[v] != kNone) old2new[v] = next++;
  if (next == nv) return {};
  const bool seeds = m.vert2tet.size() == nv;
  for (VertId v = 0; v < nv; ++v) {
    const VertId w = old2new[v];
    if (w == kNone) continue;
    m.coords[w] = m.coords[v];
    if (v < m.vert_class.size()) m.vert_class[w] = m.vert_class[v];
    if (v < m.vert_param.size()) m.vert_param[w] = m.vert_param[v];
    if (seeds) m.vert2tet[w] = m.vert2tet[v];
  }
  m.coords.resize(next);
  if (m.vert_class.size() == nv) m.vert_class.resize(next);
  if (m.vert_param.size() == nv) m.vert_param.resize(next);
  if (seeds) m.vert2tet.resize(next);
  for (auto& tv : m.tet2verts)
    for (VertId& v : tv) v = old2new[v];
  for (auto& t : m.tris)
    for (VertId& v : t.verts) v = old2new[v];
  for (auto& e : m.edges)
    for (VertId& v : e.verts) v = old2new[v];
  m.high_order.remap_vertices(old2new);
  return old2new;
}

}  // namespace cm::mesh
