#include "curvemesh/modify/cavity.hpp"

#include <algorithm>
#include <stdexcept>

#include "curvemesh/core/predicates.hpp"
#include "curvemesh/mesh/adjacency.hpp"
#include "curvemesh/mesh/topology.hpp"

namespace cm::modify {

namespace {
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
  if (ed.hook()) ed.hook()(m, cav.created_);
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

std::span<const TetId> fill_star(MeshEditor& ed, Cavity& cav, VertId p) {
  auto& m = ed.mesh();
  cav.star_.clear();
  bool touches_p = false;
  for (const CavityFace& f : cav.boundary()) {
    if (f.verts[0] == p || f.verts[1] == p || f.verts[2] == p) {
      touches_p = true;
      continue;
    }
    const TetId t = mesh::face_tet(f.inside);
    NewTet nt{m.tet2verts[t], m.tet_region[t]};
    // Same local numbering as the cavity tet, so face f keeps its orientation.
    nt.verts[mesh::face_index(f.inside)] = p;
    cav.star_.push_back(nt);
  }
  // A boundary face through p (a collapse) is matched by a star face: the
  // general face matching handles it.
  if (touches_p) return rebuild(ed, cav, cav.star_);

  // Insertion, split, relocation: new tet i keeps boundary face i and its
  // three other faces hold p and one edge of face i, shared with exactly one
  // other new tet. Matching those by edge is all the linking there is — the
  // hot path of Delaunay insertion.
  const std::size_t n = cav.star_.size();
  std::size_t cap = 16;
  while (cap < 4 * n) cap *= 2;
  cav.edge_table_.assign(cap, {kNone, kNone, kNone});
  const std::size_t mask = cap - 1;
  cav.verts_.clear();
  for (TetId t : cav.tets_) {
    for (VertId v : m.tet2verts[t]) cav.verts_.push_back(v);
    ed.release(t);
  }
  cav.created_.clear();
  std::size_t bi = 0;
  for (const CavityFace& bf : cav.boundary_) {
    const NewTet& nt = cav.star_[bi++];
    const TetId t = ed.allocate(nt.verts, nt.region);
    cav.created_.push_back(t);
    const int fb = mesh::face_index(bf.inside);
    m.tet2adj[mesh::pack_face(t, fb)] = bf.outside;
    if (bf.marked) ed.set_face_mark_one_side(mesh::pack_face(t, fb), true);
    if (bf.outside != kNone) m.tet2adj[bf.outside] = mesh::pack_face(t, fb);
    for (int f = 0; f < 4; ++f) {
      if (f == fb) continue;
      // Face f holds p (at slot fb) and the two vertices other than f, fb.
      VertId a = kNone, b = kNone;
      for (int k = 0; k < 4; ++k)
        if (k != f && k != fb) (a == kNone ? a : b) = nt.verts[k];
      if (a > b) std::swap(a, b);
      const Index here = mesh::pack_face(t, f);
      for (std::size_t h = (std::size_t{a} * 0x9E3779B1u ^ std::size_t{b} * 0x85EBCA77u) & mask;; h = (h + 1) & mask) {
        auto& slot = cav.edge_table_[h];
        if (slot[0] == kNone) {
          slot = {a, b, here};
          break;
        }
        if (slot[0] == a && slot[1] == b && slot[2] != kNone) {
          m.tet2adj[here] = slot[2];
          m.tet2adj[slot[2]] = here;
          slot[2] = kNone;  // matched; the key stays so probe chains hold
          break;
        }
      }
    }
  }
  for (VertId v : cav.verts_) {
    const TetId s = m.vert2tet[v];
    if (s != kNone && (ed.is_dead(s) || mesh::local_index(m, s, v) < 0)) m.vert2tet[v] = kNone;
  }
  if (ed.hook()) ed.hook()(m, cav.created_);
  return cav.created_;
}

}  // namespace cm::modify
