#include "curvemesh/generate/delaunay3d.hpp"

#include <algorithm>
#include <iterator>
#include <stdexcept>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "curvemesh/core/error.hpp"
#include "curvemesh/core/predicates.hpp"
#include "curvemesh/generate/spatial_sort.hpp"
#include "curvemesh/mesh/adjacency.hpp"
#include "curvemesh/mesh/topology.hpp"

namespace cm::generate {

namespace {

// The tie-break of insphere_perturbed, after an exact insphere returned 0
// (out of line: the cavity loop keeps only the inline filter).
// Lift point i by ε^(rank): the derivative of insphere with respect to the
// lift of tet vertex k is the sign of the barycentric coordinate of e in the
// tet (e put in place of vertex k); for e itself it is -1 (lifting e moves it
// outside). The most perturbed point whose term is nonzero wins. The rank is
// the vertex id, through `rank` when the mesh is temporarily renumbered
// (Delaunay3d::insert_all).
[[gnu::noinline]] int perturbed_tie(const double* const p[5], const std::array<VertId, 4>& t,
                                    VertId e, const VertId* rank) {
  auto r = [rank](VertId v) { return rank ? rank[v] : v; };
  std::array<std::pair<VertId, int>, 5> order{
      {{r(t[0]), 0}, {r(t[1]), 1}, {r(t[2]), 2}, {r(t[3]), 3}, {r(e), 4}}};
  std::sort(order.begin(), order.end(),
            [](const auto& a, const auto& b) { return a.first > b.first; });
  for (const auto& [id, slot] : order) {
    if (slot == 4) return -1;
    const double* q[4] = {p[0], p[1], p[2], p[3]};
    q[slot] = p[4];
    const int o = predicates::orient3d(q[0], q[1], q[2], q[3]);
    if (o != 0) return o;
  }
  return -1;  // unreachable for a positive tet
}

inline int insphere_perturbed_fast(const mesh::TetMesh& m, const std::array<VertId, 4>& t, VertId e,
                                   const VertId* rank) {
  const double* p[5] = {m.coords[t[0]].data(), m.coords[t[1]].data(), m.coords[t[2]].data(),
                        m.coords[t[3]].data(), m.coords[e].data()};
  const int s = predicates::insphere_inline(p[0], p[1], p[2], p[3], p[4]);
  return s != 0 ? s : perturbed_tie(p, t, e, rank);
}

}  // namespace

int insphere_perturbed(const mesh::TetMesh& m, const std::array<VertId, 4>& t, VertId e) {
  return insphere_perturbed_fast(m, t, e, nullptr);
}

Delaunay3d::Delaunay3d(mesh::TetMesh& m, const Vec3& lo, const Vec3& hi) : editor_(m) {
  const Vec3 c = 0.5 * (lo + hi);
  const double r = std::max(0.5 * (hi - lo).norm(), 1e-300);
  // A regular tet with inradius 10 r: every box point is well inside, and the
  // far vertices stay within the predicates' exact range.
  const double s = 10.0 * r * std::sqrt(3.0);
  const Vec3 dirs[4] = {{1, 1, 1}, {1, -1, -1}, {-1, 1, -1}, {-1, -1, 1}};
  for (int k = 0; k < 4; ++k) far_[k] = m.add_vert(c + s * dirs[k]);
  m.resize_vertex_arrays();
  m.vert2tet.resize(m.coords.size(), kNone);
  std::array<VertId, 4> t = far_;
  if (predicates::orient3d(m.coords[t[0]].data(), m.coords[t[1]].data(), m.coords[t[2]].data(),
                           m.coords[t[3]].data()) < 0)
    std::swap(t[2], t[3]);
  last_ = editor_.allocate(t, 0);
}

TetId Delaunay3d::locate(const Vec3& x, TetId hint) {
  const auto& m = editor_.mesh();
  TetId t = hint;
  if (t == kNone || t >= m.tet2verts.size() || editor_.is_dead(t)) t = last_;
  if (editor_.is_dead(t)) {
    for (t = 0; editor_.is_dead(t); ++t) {
    }
  }
  const double* xp = x.data();
  int from = -1;  // the face we entered through: x is known to be behind it
  for (std::size_t steps = 0;; ++steps) {
    const auto& tv = m.tet2verts[t];
    // The face order varies so the walk cannot cycle; xorshift, 2 bits a step.
    rng_ ^= rng_ << 13;
    rng_ ^= rng_ >> 7;
    rng_ ^= rng_ << 17;
    const int start = static_cast<int>(rng_ & 3u);
    int exit = -1;
    for (int k = 0; k < 4; ++k) {
      const int f = (start + k) & 3;
      if (f == from) continue;
      const auto& fv = mesh::kFaceVerts[f];
      const double* a = m.coords[tv[fv[0]]].data();
      const double* b = m.coords[tv[fv[1]]].data();
      const double* c = m.coords[tv[fv[2]]].data();
      if (predicates::orient3d_inline(a, b, c, xp) > 0) {
        exit = f;
        break;
      }
    }
    if (exit < 0) {
      walk_steps_ += steps;
      return t;
    }
    const Index across = m.tet2adj[4 * t + exit];
    if (across == kNone) throw std::domain_error("Delaunay3d: point outside the enclosing tetrahedron");
    t = mesh::face_tet(across);
    from = mesh::face_index(across);
  }
}

Index Delaunay3d::find_face(const std::array<VertId, 3>& face) const {
  const auto& m = editor_.mesh();
  if (face[0] >= m.vert2tet.size() || m.vert2tet[face[0]] == kNone) return kNone;
  mesh::collect_ball(m, face[0], ball_);
  for (TetId t : ball_) {
    const int i1 = mesh::local_index(m, t, face[1]), i2 = mesh::local_index(m, t, face[2]);
    if (i1 < 0 || i2 < 0) continue;
    const int i0 = mesh::local_index(m, t, face[0]);
    return mesh::pack_face(t, 6 - i0 - i1 - i2);  // the local face opposite the fourth vertex
  }
  return kNone;
}

bool Delaunay3d::protect(const std::array<VertId, 3>& face) {
  const Index f = find_face(face);
  if (f == kNone) return false;
  if (!editor_.face_marked(f)) ++protected_count_;
  editor_.mark_face(f);
  return true;
}

std::size_t Delaunay3d::protect_all(std::span<const mesh::ClassifiedTri> faces) {
  auto& m = editor_.mesh();
  auto sorted = [](std::array<VertId, 3> k) {
    std::sort(k.begin(), k.end());
    return k;
  };
  std::vector<std::array<VertId, 3>> keys;
  keys.reserve(faces.size());
  for (const auto& f : faces) keys.push_back(sorted(f.verts));
  std::sort(keys.begin(), keys.end());
  keys.erase(std::unique(keys.begin(), keys.end()), keys.end());
  // Every tet face is looked up, in parallel; the marking, which edits,
  // follows in tet order.
  const std::size_t nt = m.tet2verts.size();
  std::vector<std::uint32_t> hit(4 * nt, kNone);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nt, 4096), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t t = r.begin(); t != r.end(); ++t) {
      if (editor_.is_dead(static_cast<TetId>(t))) continue;
      const auto& tv = m.tet2verts[t];
      for (int f = 0; f < 4; ++f) {
        const auto& fv = mesh::kFaceVerts[f];
        const auto key = sorted({tv[fv[0]], tv[fv[1]], tv[fv[2]]});
        const auto it = std::lower_bound(keys.begin(), keys.end(), key);
        if (it != keys.end() && *it == key) hit[4 * t + static_cast<std::size_t>(f)] = static_cast<std::uint32_t>(it - keys.begin());
      }
    }
  });
  std::vector<char> found(keys.size(), 0);
  for (std::size_t k = 0; k < hit.size(); ++k) {
    if (hit[k] == kNone) continue;
    const Index packed = mesh::pack_face(static_cast<TetId>(k / 4), static_cast<int>(k % 4));
    if (!editor_.face_marked(packed)) {
      // mark_face marks both sides: count the face once.
      ++protected_count_;
      editor_.mark_face(packed);
    }
    found[hit[k]] = 1;
  }
  return static_cast<std::size_t>(std::count(found.begin(), found.end(), 0));
}

bool Delaunay3d::is_protected(const std::array<VertId, 3>& face) const {
  const Index f = find_face(face);
  return f != kNone && editor_.face_marked(f);
}

Delaunay3d::Result Delaunay3d::insert(VertId v, TetId hint) {
  auto& m = editor_.mesh();
  if (m.vert2tet.size() < m.coords.size()) m.vert2tet.resize(m.coords.size(), kNone);
  Result res;
  const Vec3 x = m.coords[v];
  const TetId t0 = locate(x, hint);
  for (VertId w : m.tet2verts[t0])
    if (m.coords[w] == x) {
      res.refusal = modify::Refusal::kDuplicatePoint;
      res.duplicate_of = rank_ ? rank_[w] : w;
      return res;
    }
  // The cavity: t0 (x is in it, so strictly inside its circumsphere unless x
  // is a vertex, refused above) and every tet reached from it whose
  // circumsphere holds x, each neighbour tested once.
  const bool constrained = protected_count_ != 0;
  cavity_.reset(editor_);
  auto in_conflict = [&](TetId n) {
    return insphere_perturbed_fast(m, m.tet2verts[n], v, rank_) > 0;
  };
  const bool kept = cavity_.grow(editor_, t0, in_conflict, constrained);
  res.cavity_size = cavity_.tets().size();
  if (!kept) {
    res.refusal = modify::Refusal::kConstrainedFace;
    return res;
  }
  if (constrained) {
    if (const auto r = modify::check_star(m, cavity_, v); r != modify::Refusal::kNone) {
      res.refusal = r;
      return res;
    }
  } else if (non_delaunay_) {
    if (modify::check_star(m, cavity_, v) != modify::Refusal::kNone) {
      if (!shrink_to_star(v, t0)) {
        res.refusal = modify::Refusal::kNotStarShaped;
        return res;
      }
      ++shrunk_;
      res.cavity_size = cavity_.tets().size();
    }
  } else {
    // Unconstrained cavities are star-shaped by construction (see header);
    // checking costs one orient3d per boundary face, so debug builds only.
    CM_DEBUG_ASSERT(modify::check_star(m, cavity_, v) == modify::Refusal::kNone);
  }
  const auto created = modify::fill_star(editor_, cavity_, v);
  last_ = created.front();
  return res;
}

bool Delaunay3d::shrink_to_star(VertId v, TetId t0) {
  auto& m = editor_.mesh();
  const double* x = m.coords[v].data();
  auto contains_v = [&](TetId t) {
    const auto& tv = m.tet2verts[t];
    for (const auto& fv : mesh::kFaceVerts)
      if (predicates::orient3d(m.coords[tv[fv[0]]].data(), m.coords[tv[fv[1]]].data(), m.coords[tv[fv[2]]].data(),
                               x) > 0)
        return false;
    return true;
  };
  keep_.assign(cavity_.tets().begin(), cavity_.tets().end());
  std::sort(keep_.begin(), keep_.end());
  // Each pass drops every tet behind a face that hides v, then regrows from
  // t0 through what is left (dropping may disconnect the cavity; a star
  // fill needs it connected). The cavity only shrinks, and t0 always stays.
  for (;;) {
    std::vector<TetId> drop;
    for (const modify::CavityFace& f : cavity_.boundary()) {
      if (f.verts[0] == v || f.verts[1] == v || f.verts[2] == v) continue;
      if (predicates::orient3d(m.coords[f.verts[0]].data(), m.coords[f.verts[1]].data(), m.coords[f.verts[2]].data(),
                               x) < 0)
        continue;
      const TetId t = mesh::face_tet(f.inside);
      if (contains_v(t)) return false;
      drop.push_back(t);
    }
    if (drop.empty()) return true;
    std::sort(drop.begin(), drop.end());
    std::vector<TetId> left;
    std::set_difference(keep_.begin(), keep_.end(), drop.begin(), drop.end(), std::back_inserter(left));
    keep_.swap(left);
    cavity_.reset(editor_);
    cavity_.grow(editor_, t0,
                 [&](TetId n) { return std::binary_search(keep_.begin(), keep_.end(), n); }, false);
  }
}

std::vector<VertId> Delaunay3d::insert_all(std::span<const VertId> verts) {
  auto& m = editor_.mesh();
  std::vector<std::uint32_t> order;
  {
    std::vector<Vec3> pts(verts.size());
    for (std::size_t i = 0; i < verts.size(); ++i) pts[i] = m.coords[verts[i]];
    order = brio_order(pts);
  }
  // A Delaunay tetrahedralization of n points in general position has about
  // 6.7 n tets (fewer for grids and surfaces): reserving that much up front
  // spares the copies of repeated growth; untouched capacity costs no memory.
  editor_.reserve(editor_.live_tets() + 7 * verts.size() + 64);
  if (m.vert2tet.size() < m.coords.size()) m.vert2tet.resize(m.coords.size(), kNone);
  // Insertion never reads vert2tet: rebuild it once at the end rather than
  // rewriting scattered seeds for every new tet (restored even on a throw).
  struct SeedsRestored {
    modify::MeshEditor& ed;
    bool was;
    ~SeedsRestored() { ed.defer_seeds(was); }
  } seeds{editor_, editor_.seeds_deferred()};
  editor_.defer_seeds(true);

  // Vertex ids follow the input, which is in no spatial order: every
  // coordinate read would be a cache (and TLB) miss. Unless a rebuild hook
  // watches, the mesh is renumbered for the duration so that vertices come in
  // insertion order (a copy of the coordinates, tets relabelled), and back at
  // the end (even on a throw). Ties are still broken by the original ids
  // (rank_), so the result is exactly that of inserting in place.
  std::vector<VertId> new2old;
  std::vector<Vec3> saved_coords;
  struct Renumbered {
    Delaunay3d& dt;
    std::vector<VertId>& new2old;
    std::vector<Vec3>& saved_coords;
    ~Renumbered() {
      if (new2old.empty()) return;
      auto& mm = dt.editor_.mesh();
      mm.coords.swap(saved_coords);
      for (TetId t = 0; t < mm.tet2verts.size(); ++t)
        if (!dt.editor_.is_dead(t))
          for (VertId& v : mm.tet2verts[t]) v = new2old[v];
      dt.rank_ = nullptr;
    }
  } renumbered{*this, new2old, saved_coords};
  // The vertex to insert k-th, in the numbering in force.
  std::vector<VertId> sequence(order.size());
  for (std::size_t k = 0; k < order.size(); ++k) sequence[k] = verts[order[k]];
  if (!editor_.hook() && rank_ == nullptr) {
    const std::size_t nv = m.coords.size();
    std::vector<VertId> old2new(nv, kNone);
    new2old.reserve(nv);
    // (A short loop of independent scattered accesses: their misses overlap,
    // where one per insertion would stall it.)
    for (VertId& v : sequence) {
      if (old2new[v] == kNone) {
        old2new[v] = static_cast<VertId>(new2old.size());
        new2old.push_back(v);
      }
      v = old2new[v];
    }
    for (VertId v = 0; v < nv; ++v)
      if (old2new[v] == kNone) {
        old2new[v] = static_cast<VertId>(new2old.size());
        new2old.push_back(v);
      }
    std::vector<Vec3> local(nv);
    for (VertId l = 0; l < nv; ++l) local[l] = m.coords[new2old[l]];
    saved_coords.swap(m.coords);
    m.coords.swap(local);
    for (TetId t = 0; t < m.tet2verts.size(); ++t)
      if (!editor_.is_dead(t))
        for (VertId& v : m.tet2verts[t]) v = old2new[v];
    rank_ = new2old.data();
  }

  std::vector<VertId> dup(verts.size(), kNone);
  for (std::size_t k = 0; k < order.size(); ++k) {
    // Without renumbering the next point's coordinates are a sure cache miss
    // unless loaded ahead.
    if (rank_ == nullptr && k + 1 < order.size()) __builtin_prefetch(&m.coords[sequence[k + 1]]);
    const Result r = insert(sequence[k]);
    if (r.refusal == modify::Refusal::kDuplicatePoint) dup[order[k]] = r.duplicate_of;
  }
  return dup;
}

}  // namespace cm::generate
