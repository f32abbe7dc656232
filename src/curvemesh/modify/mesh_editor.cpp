#include "curvemesh/modify/mesh_editor.hpp"

#include <algorithm>

namespace cm::modify {

MeshEditor::MeshEditor(mesh::TetMesh& m) : m_(&m) {
  if (m.tet2adj.size() != 4 * m.tet2verts.size()) m.tet2adj.assign(4 * m.tet2verts.size(), kNone);
  if (m.tet_region.size() != m.tet2verts.size()) m.tet_region.resize(m.tet2verts.size(), 0);
  if (m.vert2tet.size() != m.coords.size()) m.vert2tet.resize(m.coords.size(), kNone);
  for (TetId t = 0; t < m.tet2verts.size(); ++t)
    if (m.tet2verts[t][0] == kNone) free_.push_back(t);
  // Reuse low slots first so compact() moves little.
  std::sort(free_.rbegin(), free_.rend());
}

void MeshEditor::reserve(std::size_t tets) {
  auto& m = *m_;
  m.tet2verts.reserve(tets);
  m.tet_region.reserve(tets);
  m.tet2adj.reserve(4 * tets);
  stamps_.reserve(tets + tets / 2 + 16);
}

void MeshEditor::defer_seeds(bool on) {
  if (on == seeds_deferred_) return;
  seeds_deferred_ = on;
  if (on) return;
  auto& m = *m_;
  m.vert2tet.assign(m.coords.size(), kNone);
  for (TetId t = 0; t < m.tet2verts.size(); ++t)
    if (!is_dead(t))
      for (VertId v : m.tet2verts[t]) m.vert2tet[v] = t;
}

TetId MeshEditor::append(const std::array<VertId, 4>& v, std::int32_t region) {
  auto& m = *m_;
  const auto t = static_cast<TetId>(m.tet2verts.size());
  if (m.tet2verts.size() == m.tet2verts.capacity()) {
    const std::size_t cap = m.tet2verts.size() + m.tet2verts.size() / 2 + 64;
    m.tet2verts.reserve(cap);
    m.tet_region.reserve(cap);
    m.tet2adj.reserve(4 * cap);
  }
  m.tet2verts.push_back(v);
  m.tet_region.push_back(region);
  m.tet2adj.insert(m.tet2adj.end(), 4, kNone);
  return t;
}

void MeshEditor::mark_face(Index packed) {
  set_face_mark_one_side(packed, true);
  const Index other = m_->tet2adj[packed];
  if (other != kNone) set_face_mark_one_side(other, true);
}

void MeshEditor::set_face_mark_one_side(Index packed, bool on) {
  const TetId t = mesh::face_tet(packed);
  if (face_marks_.size() <= t) {
    if (!on) return;
    face_marks_.resize(m_->tet2verts.size(), 0);
  }
  const auto bit = static_cast<std::uint8_t>(1u << mesh::face_index(packed));
  face_marks_[t] = on ? (face_marks_[t] | bit) : (face_marks_[t] & ~bit);
}

std::uint32_t MeshEditor::next_epoch() {
  // Two stamp values per epoch (member, rejected), so epochs step by 2.
  epoch_ += 2;
  if (epoch_ >= 0xFFFFFFF0u) {  // about to wrap: old stamps could alias a new epoch
    std::fill(stamps_.begin(), stamps_.end(), 0);
    epoch_ = 1;
  }
  return epoch_;
}

std::vector<TetId> MeshEditor::compact() {
  auto& m = *m_;
  const std::size_t n = m.tet2verts.size();
  std::vector<TetId> remap(n, kNone);
  TetId next = 0;
  for (TetId t = 0; t < n; ++t)
    if (m.tet2verts[t][0] != kNone) remap[t] = next++;
  for (TetId t = 0; t < n; ++t) {
    const TetId nt = remap[t];
    if (nt == kNone) continue;
    m.tet2verts[nt] = m.tet2verts[t];
    m.tet_region[nt] = m.tet_region[t];
    if (t < face_marks_.size()) face_marks_[nt] = face_marks_[t];
    for (int f = 0; f < 4; ++f) {
      const Index a = m.tet2adj[4 * t + f];
      m.tet2adj[4 * nt + f] = a == kNone ? kNone : mesh::pack_face(remap[mesh::face_tet(a)], mesh::face_index(a));
    }
  }
  m.tet2verts.resize(next);
  m.tet_region.resize(next);
  if (face_marks_.size() > next) face_marks_.resize(next);
  m.tet2adj.resize(4 * static_cast<std::size_t>(next));
  m.vert2tet.assign(m.coords.size(), kNone);
  for (TetId t = 0; t < next; ++t)
    for (VertId v : m.tet2verts[t]) m.vert2tet[v] = t;
  free_.clear();
  stamps_.assign(stamps_.size(), 0);
  epoch_ = 1;
  return remap;
}

std::vector<VertId> drop_unused_vertices(mesh::TetMesh& m) {
  const std::size_t nv = m.num_verts();
  std::vector<VertId> old2new(nv, kNone);
  for (const auto& tv : m.tet2verts)
    for (VertId v : tv) old2new[v] = 0;
  VertId next = 0;
  for (VertId v = 0; v < nv; ++v)
    if (old2new[v] == 0) old2new[v] = next++;
  if (next == nv) return {};
  for (VertId v = 0; v < nv; ++v) {
    const VertId w = old2new[v];
    if (w == kNone) continue;
    m.coords[w] = m.coords[v];
    m.vert_class[w] = m.vert_class[v];
    m.vert_param[w] = m.vert_param[v];
    if (v < m.vert2tet.size()) m.vert2tet[w] = m.vert2tet[v];
  }
  m.coords.resize(next);
  m.vert_class.resize(next);
  m.vert_param.resize(next);
  m.vert2tet.resize(next);
  for (auto& tv : m.tet2verts)
    for (VertId& v : tv) v = old2new[v];
  for (auto& t : m.tris)
    for (VertId& v : t.verts) v = old2new[v];
  for (auto& e : m.edges)
    for (VertId& v : e.verts) v = old2new[v];
  return old2new;
}

}  // namespace cm::modify
