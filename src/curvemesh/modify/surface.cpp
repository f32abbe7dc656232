#include "curvemesh/modify/surface.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "curvemesh/core/predicates.hpp"
#include "curvemesh/mesh/adjacency.hpp"
#include "curvemesh/mesh/topology.hpp"
#include "curvemesh/quality/measures.hpp"

namespace cm::modify {

namespace {

std::array<VertId, 3> sorted_key(VertId a, VertId b, VertId c) {
  if (a > b) std::swap(a, b);
  if (b > c) std::swap(b, c);
  if (a > b) std::swap(a, b);
  return {a, b, c};
}

std::size_t hash_key(const std::array<VertId, 3>& k) {
  std::uint64_t h = k[0] * 0x9E3779B97F4A7C15ull;
  h ^= (k[1] + 0x632BE59BD9B4E019ull) * 0xC2B2AE3D27D4EB4Full;
  h ^= (k[2] + 0x85EBCA77C2B2AE63ull) * 0x165667B19E3779F9ull;
  return static_cast<std::size_t>(h ^ (h >> 29));
}

std::array<VertId, 3> tri_key(const std::array<VertId, 3>& v) { return sorted_key(v[0], v[1], v[2]); }
std::array<VertId, 3> edge_key(const std::array<VertId, 2>& v) { return sorted_key(v[0], v[1], kNone); }

}  // namespace

// --- BoundaryIndex ---------------------------------------------------------

Index BoundaryIndex::Table::find(const std::array<VertId, 3>& key) const {
  if (slots.empty()) return kNone;
  const std::size_t mask = slots.size() - 1;
  for (std::size_t i = hash_key(key) & mask;; i = (i + 1) & mask) {
    const Slot& s = slots[i];
    if (s.key[0] == kNone) return kNone;
    if (s.key == key) return s.value;
  }
}

void BoundaryIndex::Table::grow() {
  std::vector<Slot> old;
  old.swap(slots);
  slots.assign(std::max<std::size_t>(64, 2 * old.size()), {});
  const std::size_t mask = slots.size() - 1;
  for (const Slot& s : old) {
    if (s.key[0] == kNone) continue;
    std::size_t i = hash_key(s.key) & mask;
    while (slots[i].key[0] != kNone) i = (i + 1) & mask;
    slots[i] = s;
  }
}

bool BoundaryIndex::Table::insert(const std::array<VertId, 3>& key, Index value) {
  if (2 * (size + 1) > slots.size()) grow();
  const std::size_t mask = slots.size() - 1;
  for (std::size_t i = hash_key(key) & mask;; i = (i + 1) & mask) {
    Slot& s = slots[i];
    if (s.key == key) return false;
    if (s.key[0] == kNone) {
      s = {key, value};
      ++size;
      return true;
    }
  }
}

void BoundaryIndex::Table::assign(const std::array<VertId, 3>& key, Index value) {
  const std::size_t mask = slots.size() - 1;
  for (std::size_t i = hash_key(key) & mask;; i = (i + 1) & mask) {
    if (slots[i].key == key) {
      slots[i].value = value;
      return;
    }
    if (slots[i].key[0] == kNone) throw std::logic_error("BoundaryIndex: entry missing");
  }
}

void BoundaryIndex::Table::erase(const std::array<VertId, 3>& key) {
  const std::size_t mask = slots.size() - 1;
  std::size_t i = hash_key(key) & mask;
  while (slots[i].key != key) {
    if (slots[i].key[0] == kNone) throw std::logic_error("BoundaryIndex: entry missing");
    i = (i + 1) & mask;
  }
  // Backward shift: pull later members of the probe chain into the hole
  // unless their home slot lies cyclically in (hole, position].
  for (std::size_t j = i;;) {
    j = (j + 1) & mask;
    if (slots[j].key[0] == kNone) break;
    const std::size_t home = hash_key(slots[j].key) & mask;
    const bool stays = i <= j ? (i < home && home <= j) : (i < home || home <= j);
    if (stays) continue;
    slots[i] = slots[j];
    i = j;
  }
  slots[i] = {};
  --size;
}

BoundaryIndex::BoundaryIndex(mesh::TetMesh& m) : m_(&m) {
  for (Index i = 0; i < m.tris.size(); ++i)
    if (!tris_.insert(tri_key(m.tris[i].verts), i)) throw std::invalid_argument("BoundaryIndex: a triangle is listed twice");
  for (Index i = 0; i < m.edges.size(); ++i)
    if (!edges_.insert(edge_key(m.edges[i].verts), i)) throw std::invalid_argument("BoundaryIndex: an edge is listed twice");
}

Index BoundaryIndex::find_tri(VertId a, VertId b, VertId c) const { return tris_.find(sorted_key(a, b, c)); }
Index BoundaryIndex::find_edge(VertId a, VertId b) const { return edges_.find(sorted_key(a, b, kNone)); }

Index BoundaryIndex::add_tri(const mesh::ClassifiedTri& tri) {
  const auto i = static_cast<Index>(m_->tris.size());
  if (!tris_.insert(tri_key(tri.verts), i)) throw std::logic_error("BoundaryIndex: duplicate triangle");
  m_->tris.push_back(tri);
  return i;
}

void BoundaryIndex::set_tri(Index i, const std::array<VertId, 3>& verts) {
  tris_.erase(tri_key(m_->tris[i].verts));
  if (!tris_.insert(tri_key(verts), i)) throw std::logic_error("BoundaryIndex: duplicate triangle");
  m_->tris[i].verts = verts;
}

void BoundaryIndex::remove_tri(Index i) {
  auto& tris = m_->tris;
  tris_.erase(tri_key(tris[i].verts));
  if (i + 1 != tris.size()) {
    tris[i] = tris.back();
    tris_.assign(tri_key(tris[i].verts), i);
  }
  tris.pop_back();
}

Index BoundaryIndex::add_edge(const mesh::ClassifiedEdge& edge) {
  const auto i = static_cast<Index>(m_->edges.size());
  if (!edges_.insert(edge_key(edge.verts), i)) throw std::logic_error("BoundaryIndex: duplicate edge");
  m_->edges.push_back(edge);
  return i;
}

void BoundaryIndex::set_edge(Index i, const std::array<VertId, 2>& verts) {
  edges_.erase(edge_key(m_->edges[i].verts));
  if (!edges_.insert(edge_key(verts), i)) throw std::logic_error("BoundaryIndex: duplicate edge");
  m_->edges[i].verts = verts;
}

void BoundaryIndex::remove_edge(Index i) {
  auto& edges = m_->edges;
  edges_.erase(edge_key(edges[i].verts));
  if (i + 1 != edges.size()) {
    edges[i] = edges.back();
    edges_.assign(edge_key(edges[i].verts), i);
  }
  edges.pop_back();
}

// --- rebuild_open ------------------------------------------------------------

std::span<const TetId> rebuild_open(MeshEditor& ed, Cavity& cav, std::span<const NewTet> fill) {
  auto& m = ed.mesh();
  // Cavities are tens of tets: sorting the faces is simpler than hashing and
  // as fast at this size.
  struct Entry {
    std::array<VertId, 3> key;
    Index source;  // boundary face number | kBoundaryBit, or a new tet's packed face
    bool operator<(const Entry& o) const { return key < o.key || (key == o.key && source < o.source); }
  };
  constexpr Index kBoundaryBit = Index{1} << 31;
  thread_local std::vector<Entry> entries;
  thread_local std::vector<CavityFace> boundary;
  thread_local std::vector<VertId> verts;
  thread_local std::vector<TetId> created;
  boundary.assign(cav.boundary().begin(), cav.boundary().end());
  entries.clear();
  for (std::size_t i = 0; i < boundary.size(); ++i) {
    const auto& v = boundary[i].verts;
    entries.push_back({sorted_key(v[0], v[1], v[2]), static_cast<Index>(i) | kBoundaryBit});
  }
  verts.clear();
  for (TetId t : cav.tets()) {
    for (VertId v : m.tet2verts[t]) verts.push_back(v);
    ed.release(t);
  }
  created.clear();
  for (const NewTet& nt : fill) {
    const TetId t = ed.allocate(nt.verts, nt.region);
    created.push_back(t);
    for (int f = 0; f < 4; ++f) {
      const auto& fv = mesh::kFaceVerts[f];
      entries.push_back({sorted_key(nt.verts[fv[0]], nt.verts[fv[1]], nt.verts[fv[2]]), mesh::pack_face(t, f)});
    }
  }
  std::sort(entries.begin(), entries.end());
  for (std::size_t i = 0; i < entries.size();) {
    std::size_t j = i + 1;
    while (j < entries.size() && entries[j].key == entries[i].key) ++j;
    // New faces sort before boundary faces (the bit is the high one).
    const Index first = entries[i].source;
    if (j - i > 2 || ((first & kBoundaryBit) && j - i == 2))
      throw std::logic_error("rebuild_open: the new tets do not tile the cavity");
    if (j - i == 1) {
      // A boundary face alone is uncovered: its tet outside (if any) now
      // has it on the hull. A new face alone is a new hull face: allocate()
      // left it kNone.
      if (first & kBoundaryBit) {
        const Index outside = boundary[first & ~kBoundaryBit].outside;
        if (outside != kNone) m.tet2adj[outside] = kNone;
      }
    } else {
      const Index second = entries[i + 1].source;
      if (second & kBoundaryBit) {
        const CavityFace& bf = boundary[second & ~kBoundaryBit];
        m.tet2adj[first] = bf.outside;
        if (bf.outside != kNone) m.tet2adj[bf.outside] = first;
        if (bf.marked) ed.set_face_mark_one_side(first, true);
      } else {
        m.tet2adj[first] = second;
        m.tet2adj[second] = first;
      }
    }
    i = j;
  }
  if (!ed.seeds_deferred())
    for (VertId v : verts) {
      const TetId s = m.vert2tet[v];
      if (s != kNone && !ed.is_dead(s) && mesh::local_index(m, s, v) >= 0) continue;
      // Not in a new tet (allocate() would have seeded it): any tet across
      // the cavity's boundary through v still holds it.
      m.vert2tet[v] = kNone;
      for (const CavityFace& bf : boundary)
        if (bf.outside != kNone && (bf.verts[0] == v || bf.verts[1] == v || bf.verts[2] == v)) {
          m.vert2tet[v] = mesh::face_tet(bf.outside);
          break;
        }
    }
  ed.notify(created);
  return created;
}

// --- parameters and predicates ---------------------------------------------

std::optional<double> param_on_edge(const mesh::TetMesh& m, const geom::Model* model, VertId v, int edge,
                                    std::optional<double> near) {
  const mesh::ModelRef c = m.vert_class[v];
  if (c == mesh::ModelRef{1, edge}) {
    if (m.vert_param[v].has_u()) return m.vert_param[v].u;
    return {};
  }
  if (c.dim != 0 || !model) return {};
  const auto ends = model->edge_vertices(edge);
  const auto range = model->param_range({1, edge});
  const bool at0 = ends[0] == c.tag, at1 = ends[1] == c.tag;
  if (at0 && at1) return near && std::abs(*near - range.u1) < std::abs(*near - range.u0) ? range.u1 : range.u0;
  if (at0) return range.u0;
  if (at1) return range.u1;
  return {};
}

std::optional<Vec2> param_on_face(const mesh::TetMesh& m, const geom::Model* model, VertId v, int face) {
  const mesh::ModelRef c = m.vert_class[v];
  const mesh::Param& p = m.vert_param[v];
  if (c == mesh::ModelRef{2, face}) {
    if (p.has_u() && !std::isnan(p.v)) return Vec2(p.u, p.v);
    return {};
  }
  if (c.dim != 1 || !model || !p.has_u()) return {};
  try {
    return model->edge_param_on_face(c.tag, face, p.u);
  } catch (const std::invalid_argument&) {
    return {};  // the edge does not bound this face
  }
}

std::optional<Vec2> check_hint(const mesh::TetMesh& m, const std::array<VertId, 3>& verts, int face, VertId moved,
                               std::optional<Vec2> moved_param) {
  std::optional<Vec2> hint;
  for (VertId v : verts) {
    if (m.vert_class[v] != mesh::ModelRef{2, face}) continue;
    if (v == moved) hint = moved_param;
    else hint = Vec2(m.vert_param[v].u, m.vert_param[v].v);
  }
  return hint;
}

bool agrees_with_model(const geom::Model& model, int face, const Vec3& a, const Vec3& b, const Vec3& c,
                       std::optional<Vec2> hint) {
  // A plane's normal is the same at every parameter: no projection needed.
  if (model.type({2, face}) == geom::ShapeType::kPlane)
    return tri_normal(a, b, c).dot(model.face_normal(face, hint.value_or(Vec2::Zero()))) > 0;
  const geom::Projection p = model.closest_point({2, face}, (a + b + c) / 3, hint);
  return tri_normal(a, b, c).dot(model.face_normal(face, p.param)) > 0;
}

void tris_through(const mesh::TetMesh& m, const BoundaryIndex& boundary, VertId v, std::span<const TetId> ball,
                  std::vector<Index>& out) {
  out.clear();
  for (TetId t : ball) {
    const auto& tv = m.tet2verts[t];
    const int iv = mesh::local_index(m, t, v);
    for (int f = 0; f < 4; ++f) {
      if (f == iv) continue;
      const auto& fv = mesh::kFaceVerts[static_cast<std::size_t>(f)];
      const Index i = boundary.find_tri(tv[fv[0]], tv[fv[1]], tv[fv[2]]);
      if (i != kNone) out.push_back(i);
    }
  }
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
}

bool flat_per_face(const mesh::TetMesh& m, std::span<const Index> tris) {
  for (std::size_t i = 0; i < tris.size(); ++i) {
    const auto& tri = m.tris[tris[i]];
    std::size_t r = 0;
    while (m.tris[tris[r]].face_tag != tri.face_tag) ++r;
    if (r == i) continue;
    const auto& ref = m.tris[tris[r]].verts;
    for (VertId x : tri.verts)
      if (predicates::orient3d(m.coords[ref[0]].data(), m.coords[ref[1]].data(), m.coords[ref[2]].data(),
                               m.coords[x].data()) != 0)
        return false;
  }
  return true;
}

bool collinear(const Vec3& p, const Vec3& q, const Vec3& r) {
  for (int k = 0; k < 3; ++k) {
    const int i = k, j = (k + 1) % 3;
    const double a[2] = {p[i], p[j]}, b[2] = {q[i], q[j]}, c[2] = {r[i], r[j]};
    if (predicates::orient2d(a, b, c) != 0) return false;
  }
  return true;
}

std::optional<FlatBoundary> FlatBoundary::at(const mesh::TetMesh& m, const BoundaryIndex& boundary, VertId v,
                                             std::span<const Index> tris, std::span<const TetId> ball) {
  const int dim = m.vert_class[v].dim;
  if ((dim != 1 && dim != 2) || tris.empty() || !flat_per_face(m, tris)) return std::nullopt;
  FlatBoundary f;
  f.plane_ = dim == 2;
  if (f.plane_) {
    const auto& ref = m.tris[tris[0]].verts;
    f.a_ = m.coords[ref[0]], f.b_ = m.coords[ref[1]], f.c_ = m.coords[ref[2]];
    if (!((f.b_ - f.a_).cross(f.c_ - f.a_).squaredNorm() > 0)) return std::nullopt;
  } else {
    std::array<VertId, 2> ends{kNone, kNone};
    int found = 0;
    for (TetId t : ball)
      for (VertId w : m.tet2verts[t])
        if (w != v && w != ends[0] && found < 2 && boundary.find_edge(v, w) != kNone) ends[found++] = w;
    if (found != 2 || !collinear(m.coords[ends[0]], m.coords[v], m.coords[ends[1]])) return std::nullopt;
    f.a_ = m.coords[ends[0]], f.b_ = m.coords[ends[1]], f.c_ = m.coords[v];
  }
  // Coordinates every point of the plane or line shares are copied, so
  // that rounding cannot take the point off it.
  const Vec3& x = m.coords[v];
  for (int k = 0; k < 3; ++k)
    f.fixed_[static_cast<std::size_t>(k)] = f.b_[k] == f.a_[k] && f.c_[k] == f.a_[k] && x[k] == f.a_[k];
  return f;
}

std::optional<Vec3> FlatBoundary::slide(const Vec3& p) const {
  Vec3 x;
  if (plane_) {
    const Vec3 n = (b_ - a_).cross(c_ - a_);
    x = p - n * ((p - a_).dot(n) / n.squaredNorm());
  } else {
    const Vec3 d = b_ - a_;
    x = a_ + d * ((p - a_).dot(d) / d.squaredNorm());
  }
  for (int k = 0; k < 3; ++k)
    if (fixed_[static_cast<std::size_t>(k)]) x[k] = a_[k];
  const bool on = plane_ ? predicates::orient3d(a_.data(), b_.data(), c_.data(), x.data()) == 0 : collinear(a_, x, b_);
  return on ? std::optional<Vec3>(x) : std::nullopt;
}

double tet_quality_at(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) {
  if (predicates::orient3d(a.data(), b.data(), c.data(), d.data()) <= 0) return -1;
  return std::max(quality::tet_mean_ratio(a, b, c, d), 0.0);
}

}  // namespace cm::modify
