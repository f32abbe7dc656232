#include "curvemesh/modify/cavity.hpp"

#include <algorithm>
#include <stdexcept>

#include "curvemesh/core/predicates.hpp"
#include "curvemesh/mesh/adjacency.hpp"
#include "curvemesh/mesh/topology.hpp"

namespace cm::modify {

namespace {
constexpr int kNext[4] = {1, 2, 0, 1};  // (k + 1) % 3 for k < 4
constexpr Index kBoundaryBit = Index{1} << 31;

std::array<VertId, 3> sorted(std::array<VertId, 3> k) {
  if (k[0] > k[1]) std::swap(k[0], k[1]);
  if (k[1] > k[2]) std::swap(k[1], k[2]);
  if (k[0] > k[1]) std::swap(k[0], k[1]);
  return k;
}

std::size_t hash3(const std::array<VertId, 3>& k) {
  std::uint64_t h = k[0] * 0x9E3779B97F4A7C15ull;
  h ^= (k[1] + 0x632BE59BD9B4E019ull) * 0xC2B2AE3D27D4EB4Full;
  h ^= (k[2] + 0x85EBCA77C2B2AE63ull) * 0x165667B19E3779F9ull;
  return static_cast<std::size_t>(h ^ (h >> 29));
}
}  // namespace

std::string_view to_string(Refusal r) {
  switch (r) {
    case Refusal::kNone: return "none";
    case Refusal::kNotStarShaped: return "not star-shaped";
    case Refusal::kNoImprovement: return "no improvement";
    case Refusal::kClassification: return "classification";
    case Refusal::kConstrainedFace: return "constrained face";
    case Refusal::kDuplicatePoint: return "duplicate point";
    case Refusal::kOutsideDomain: return "outside the domain";
    case Refusal::kTooClose: return "too close to a vertex";
    case Refusal::kFoldedSurface: return "folded boundary surface";
    case Refusal::kNonManifold: return "non-manifold";
  }
  return "?";
}

void Cavity::reset(MeshEditor& ed) {
  ed.next_epoch();
  tets_.clear();
  boundary_.clear();
}

void Cavity::add(MeshEditor& ed, TetId t) {
  if (ed.marked(t)) return;
  ed.mark(t);
  tets_.push_back(t);
}

std::span<const CavityFace> Cavity::compute_boundary(const MeshEditor& ed) {
  const auto& m = ed.mesh();
  boundary_.clear();
  for (TetId t : tets_) {
    const auto& tv = m.tet2verts[t];
    for (int f = 0; f < 4; ++f) {
      const Index across = m.tet2adj[4 * t + f];
      if (across != kNone && ed.marked(mesh::face_tet(across))) continue;
      const auto& fv = mesh::kFaceVerts[f];
      boundary_.push_back({{tv[fv[0]], tv[fv[1]], tv[fv[2]]}, mesh::pack_face(t, f), across,
                           ed.face_marked(mesh::pack_face(t, f))});
    }
  }
  return boundary_;
}

std::span<const TetId> rebuild(MeshEditor& ed, Cavity& cav, std::span<const NewTet> fill) {
  auto& m = ed.mesh();
  const std::size_t faces = cav.boundary_.size() + 4 * fill.size();
  std::size_t cap = 16;
  while (cap < 2 * faces) cap *= 2;
  cav.table_.assign(cap, {});
  const std::size_t mask = cap - 1;
  std::size_t open = 0;  // entries inserted but not yet matched

  auto find_or_insert = [&](const std::array<VertId, 3>& key, Index value) -> Index {
    for (std::size_t i = hash3(key) & mask;; i = (i + 1) & mask) {
      auto& s = cav.table_[i];
      if (s.key[0] == kNone) {
        s.key = key;
        s.value = value;
        ++open;
        return kNone;
      }
      if (s.key == key && s.value != kNone) {
        const Index found = s.value;
        s.value = kNone;  // matched: a tombstone that keeps the probe chain intact
        --open;
        return found;
      }
    }
  };

  for (std::size_t i = 0; i < cav.boundary_.size(); ++i)
    find_or_insert(sorted(cav.boundary_[i].verts), static_cast<Index>(i) | kBoundaryBit);

  // Vertices whose seed tet is being deleted: re-seeded by allocate() if they
  // are in a new tet, cleared below if not (a collapse removes one).
  cav.verts_.clear();
  for (TetId t : cav.tets_) {
    for (VertId v : m.tet2verts[t]) cav.verts_.push_back(v);
    ed.release(t);
  }

  cav.created_.clear();
  for (const NewTet& nt : fill) {
    const TetId t = ed.allocate(nt.verts, nt.region);
    cav.created_.push_back(t);
    for (int f = 0; f < 4; ++f) {
      const auto& fv = mesh::kFaceVerts[f];
      const Index here = mesh::pack_face(t, f);
      const Index other = find_or_insert(sorted({nt.verts[fv[0]], nt.verts[fv[1]], nt.verts[fv[2]]}), here);
      if (other == kNone) continue;
      if (other & kBoundaryBit) {
        const CavityFace& bf = cav.boundary_[other & ~kBoundaryBit];
        const Index outside = bf.outside;
        if (bf.marked) ed.set_face_mark_one_side(here, true);
        m.tet2adj[here] = outside;
        if (outside != kNone) m.tet2adj[outside] = here;
      } else {
        m.tet2adj[here] = other;
        m.tet2adj[other] = here;
      }
    }
  }
  if (open != 0) throw std::logic_error("cavity rebuild: the new tets do not tile the cavity");

  // Removed vertices (a collapse) keep no stale seed.
  for (VertId v : cav.verts_) {
    const TetId s = m.vert2tet[v];
    if (s != kNone && (ed.is_dead(s) || mesh::local_index(m, s, v) < 0)) m.vert2tet[v] = kNone;
  }
  ed.notify(cav.created_);
  return cav.created_;
}

Refusal check_star(const mesh::TetMesh& m, const Cavity& cav, VertId p) {
  const double* x = m.coords[p].data();
  for (const CavityFace& f : cav.boundary()) {
    if (f.verts[0] == p || f.verts[1] == p || f.verts[2] == p) continue;
    // The face's normal points out of the cavity: p must lie behind it.
    if (predicates::orient3d(m.coords[f.verts[0]].data(), m.coords[f.verts[1]].data(),
                             m.coords[f.verts[2]].data(), x) >= 0)
      return Refusal::kNotStarShaped;
  }
  return Refusal::kNone;
}

// Links the star faces (Cavity::side_) through a matrix indexed by the
// boundary's local vertex numbers: a boundary of nb faces that is a closed
// surface has nb / 2 + 2 vertices, under 64 for all but huge cavities, so
// directed edge a -> b has a cell of its own and nothing is hashed or
// searched. Local numbers come from a per-vertex tag (generation | number),
// so nothing is cleared per call; cells are reset as they are read. Returns
// false (nothing linked) when the boundary has too many vertices.
bool link_star_by_local_edges(mesh::TetMesh& m, Cavity& cav) {
  constexpr std::uint32_t kMaxLocal = 64;
  constexpr std::uint16_t kEmpty = 0xFFFF;
  const std::size_t nb = cav.boundary_.size();
  if (nb > 2 * kMaxLocal - 4) return false;
  if (cav.local_.size() < m.coords.size())
    cav.local_.resize(m.coords.size() + m.coords.size() / 4, 0);
  if (cav.edge_cell_.empty()) cav.edge_cell_.assign(kMaxLocal * kMaxLocal, kEmpty);
  if (++cav.local_generation_ >= (1u << 26)) {  // the tags would wrap
    std::fill(cav.local_.begin(), cav.local_.end(), 0);
    cav.local_generation_ = 1;
  }
  const std::uint32_t tag = cav.local_generation_ << 6;
  // Raw pointers, and numbers stored as 32-bit words: stores through
  // std::uint8_t (a character type) would make the compiler reload every
  // pointer after each.
  std::uint32_t* const local = cav.local_.data();
  const CavityFace* const faces = cav.boundary_.data();
  cav.local_ids_.resize(nb);
  std::array<std::uint32_t, 3>* const ids = cav.local_ids_.data();
  std::uint32_t count = 0;
  for (std::size_t i = 0; i < nb; ++i)
    for (int k = 0; k < 3; ++k) {
      std::uint32_t& x = local[faces[i].verts[k]];
      if ((x & ~63u) != tag) {
        if (count == kMaxLocal) return false;  // not a closed surface
        x = tag | count++;
      }
      ids[i][k] = x & 63u;
    }
  // Directed edge a -> b has cell a << 6 | b.
  std::uint16_t* const cell = cav.edge_cell_.data();
  for (std::size_t i = 0; i < nb; ++i) {
    const auto [a, b, c] = ids[i];
    cell[b << 6 | c] = static_cast<std::uint16_t>(3 * i);
    cell[c << 6 | a] = static_cast<std::uint16_t>(3 * i + 1);
    cell[a << 6 | b] = static_cast<std::uint16_t>(3 * i + 2);
  }
  bool closed = true;
  const Index* const side = cav.side_.data();
  Index* const adj = m.tet2adj.data();
  auto link = [&](std::size_t here, std::uint32_t reversed) {
    const std::uint16_t there = cell[reversed];
    cell[reversed] = kEmpty;
    closed &= there != kEmpty;
    adj[side[here]] = there != kEmpty ? side[there] : kNone;
  };
  for (std::size_t i = 0; i < nb; ++i) {
    const auto [a, b, c] = ids[i];
    link(3 * i, c << 6 | b);
    link(3 * i + 1, a << 6 | c);
    link(3 * i + 2, b << 6 | a);
  }
  if (!closed) throw std::logic_error("fill_star: the star does not tile the cavity");
  return true;
}

// The same for any boundary: directed edges in a hash of chains (heads
// cleared per call, entries in order).
void link_star_by_hashed_edges(mesh::TetMesh& m, Cavity& cav) {
  const std::size_t nb = cav.boundary_.size();
  int bits = 9;
  while ((std::size_t{1} << bits) < 6 * nb) ++bits;
  cav.edge_heads_.assign(std::size_t{1} << bits, -1);
  cav.edge_entries_.resize(3 * nb);
  auto hash = [bits](VertId u, VertId w) {
    return static_cast<std::size_t>((u * 0x9E3779B1u) ^ (w * 0x85EBCA77u)) >> (32 - bits);
  };
  for (std::size_t i = 0; i < nb; ++i) {
    const CavityFace& bf = cav.boundary_[i];
    for (int k = 0; k < 3; ++k) {
      const VertId u = bf.verts[kNext[k]], w = bf.verts[kNext[k + 1]];
      const std::size_t e = 3 * i + static_cast<std::size_t>(k);
      std::int32_t& head = cav.edge_heads_[hash(u, w)];
      cav.edge_entries_[e] = {u, w, head};
      head = static_cast<std::int32_t>(e);
    }
  }
  for (std::size_t e = 0; e < 3 * nb; ++e) {
    const Cavity::EdgeEntry& x = cav.edge_entries_[e];
    std::int32_t k = cav.edge_heads_[hash(x.b, x.a)];
    while (k >= 0 && !(cav.edge_entries_[k].a == x.b && cav.edge_entries_[k].b == x.a))
      k = cav.edge_entries_[k].next;
    if (k < 0) throw std::logic_error("fill_star: the star does not tile the cavity");
    m.tet2adj[cav.side_[e]] = cav.side_[static_cast<std::size_t>(k)];
  }
}

std::span<const TetId> fill_star(MeshEditor& ed, Cavity& cav, VertId p) {
  auto& m = ed.mesh();
  const std::size_t nb = cav.boundary_.size();
  // New tet i keeps boundary face i, with the local numbering of the cavity
  // tet it came from (p in the slot facing the face), so the face keeps its
  // orientation and the tet is positive. Regions are read now: released slots
  // are reused below.
  cav.star_.resize(nb);
  bool touches_p = false;
  for (std::size_t i = 0; i < nb; ++i) {
    const CavityFace& f = cav.boundary_[i];
    touches_p |= f.verts[0] == p || f.verts[1] == p || f.verts[2] == p;
    const TetId t = mesh::face_tet(f.inside);
    NewTet& nt = cav.star_[i];
    nt.verts = m.tet2verts[t];
    nt.verts[mesh::face_index(f.inside)] = p;
    nt.region = m.tet_region[t];
  }
  if (touches_p) {
    // A boundary face through p (a collapse) is matched by a star face: the
    // general face matching handles it.
    std::erase_if(cav.star_, [p](const NewTet& nt) {
      int with_p = 0;
      for (VertId v : nt.verts) with_p += v == p;
      return with_p > 1;
    });
    return rebuild(ed, cav, cav.star_);
  }

  // Insertion, split, relocation: the three other faces of new tet i hold p
  // and one edge of boundary face i, and are shared with the new tet of the
  // boundary face across that edge. So matching edges of the boundary is all
  // the linking there is — the hot path of Delaunay insertion. The boundary
  // is a closed surface with faces oriented out of the cavity, so edge u -> w
  // of one face is w -> u in its neighbour: every directed edge is recorded
  // first, then every star face looks up its reversed edge.
  //
  // Vertices of the cavity lose their seed, and those in new tets get one
  // back from allocate(): a vertex strictly inside the cavity (on no boundary
  // face, never one of a Delaunay insertion) is left with none.
  if (!ed.seeds_deferred())
    for (TetId t : cav.tets_)
      for (VertId v : m.tet2verts[t]) m.vert2tet[v] = kNone;
  for (TetId t : cav.tets_) ed.release(t);
  cav.created_.resize(nb);
  // side_[3 i + k]: the star face of new tet i opposite boundary vertex k; it
  // holds p and the edge k+1 -> k+2 of boundary face i.
  cav.side_.resize(3 * nb);
  for (std::size_t i = 0; i < nb; ++i) {
    const CavityFace& bf = cav.boundary_[i];
    const NewTet& nt = cav.star_[i];
    const TetId t = ed.allocate(nt.verts, nt.region);
    cav.created_[i] = t;
    const int fb = mesh::face_index(bf.inside);
    const Index base = mesh::pack_face(t, fb);
    m.tet2adj[base] = bf.outside;
    if (bf.outside != kNone) m.tet2adj[bf.outside] = base;
    if (bf.marked) ed.set_face_mark_one_side(base, true);
    for (int k = 0; k < 3; ++k) cav.side_[3 * i + k] = mesh::pack_face(t, mesh::kFaceVerts[fb][k]);
  }
  if (!link_star_by_local_edges(m, cav)) link_star_by_hashed_edges(m, cav);
  ed.notify(cav.created_);
  return cav.created_;
}

}  // namespace cm::modify
