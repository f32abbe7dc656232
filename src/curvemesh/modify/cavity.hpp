#pragma once
// The cavity kernel: the one place where tets are removed and replaced.
//
// Every local operator is "delete a cavity, fill it again": Delaunay insertion
// (the tets whose circumsphere holds the point, refilled as a star from it),
// edge split (the edge's shell, star from the new point), relocation (the
// ball, star from the moved vertex), collapse (the ball of the removed vertex,
// star from the kept one) and swaps (a shell or a face's two tets, refilled by
// a given triangulation). Operators first evaluate their fill — a refusal is
// returned as a value, nothing changes — and only then call rebuild(), which
// links adjacency, keeps vert2tet right and calls the editor's hook (where
// curving places high-order nodes on the new entities).
#include <array>
#include <cstdint>
#include <span>
#include <string_view>
#include <vector>

#include "curvemesh/mesh/topology.hpp"
#include "curvemesh/modify/mesh_editor.hpp"

namespace cm::modify {

/// Why an operator declined (kNone: it did not).
enum class Refusal : std::uint8_t {
  kNone,
  kNotStarShaped,     ///< some new tet would be flat or inverted
  kNoImprovement,     ///< valid, but not better for the measure asked
  kClassification,    ///< would break classification rules
  kConstrainedFace,   ///< would cross or delete a protected (boundary) face
  kDuplicatePoint,    ///< the point coincides with an existing vertex
  kOutsideDomain,     ///< the point is not inside the meshed domain
  kTooClose,          ///< the point is closer than allowed to a vertex
  kFoldedSurface,     ///< a boundary triangle would flip (or fold against its model face)
  kNonManifold,       ///< would duplicate a triangle or edge, or pinch the mesh (link condition)
};
std::string_view to_string(Refusal r);

/// A face on the cavity's boundary: its vertices in the order of kFaceVerts
/// of the cavity tet it belongs to (normal pointing out of the cavity), that
/// packed face, and the packed face across it (kNone on the hull).
struct CavityFace {
  std::array<VertId, 3> verts;
  Index inside = kNone;
  Index outside = kNone;
  bool marked = false;  ///< a protected face (see MeshEditor::face_marked)
};

/// A tet to create, with its region tag.
struct NewTet {
  std::array<VertId, 4> verts;
  std::int32_t region = 0;
};

/// A set of live tets being replaced, with its boundary. Reuse one object for
/// many operations: its buffers keep their capacity.
class Cavity {
 public:
  /// Starts an empty cavity (a new stamp epoch of the editor).
  void reset(MeshEditor& ed);
  /// Adds t (no effect if already in). Only between reset() and rebuild().
  void add(MeshEditor& ed, TetId t);
  bool contains(const MeshEditor& ed, TetId t) const { return ed.marked(t); }
  std::span<const TetId> tets() const { return tets_; }

  /// Faces of cavity tets whose neighbour is outside the cavity (or none).
  /// O(cavity size). Call after the last add().
  std::span<const CavityFace> compute_boundary(const MeshEditor& ed);
  std::span<const CavityFace> boundary() const { return boundary_; }

  /// Grows the cavity from `seed` (added first) face by face: each neighbour
  /// of a cavity tet is tested once with in_conflict(n) and joins when that
  /// is true (rejected ones are stamped, MeshEditor::mark_rejected). With
  /// `keep_marked_faces`, protected faces are never crossed. The boundary is
  /// recorded on the way, so boundary() is valid afterwards without
  /// compute_boundary(). Returns false if a protected face still ends up with
  /// both its tets in the cavity (reached around it): filling would delete
  /// it. Only right after reset().
  template <class InConflict>
  bool grow(MeshEditor& ed, TetId seed, InConflict&& in_conflict, bool keep_marked_faces);

 private:
  friend std::span<const TetId> rebuild(MeshEditor&, Cavity&, std::span<const NewTet>);
  friend std::span<const TetId> fill_star(MeshEditor&, Cavity&, VertId);
  std::vector<TetId> tets_;
  std::vector<CavityFace> boundary_;
  // Face matching during rebuild: open addressing on sorted vertex triples.
  struct Slot {
    std::array<VertId, 3> key{kNone, kNone, kNone};
    Index value = kNone;  // packed face of a new tet, or boundary index | kBoundaryBit
  };
  std::vector<Slot> table_;
  std::vector<TetId> created_;
  std::vector<VertId> verts_;
  std::vector<NewTet> star_;
  // Star fills (see fill_star): the new tets' faces through p, and the
  // matching of the boundary's directed edges, by local vertex numbers or by
  // hashing.
  friend bool link_star_by_local_edges(mesh::TetMesh&, Cavity&);
  friend void link_star_by_hashed_edges(mesh::TetMesh&, Cavity&);
  std::vector<Index> side_;
  std::vector<std::uint32_t> local_;  // per vertex: generation << 6 | number
  std::uint32_t local_generation_ = 0;
  std::vector<std::array<std::uint32_t, 3>> local_ids_;  // per boundary face
  std::vector<std::uint16_t> edge_cell_;
  struct EdgeEntry {
    VertId a, b;        // the edge a -> b
    std::int32_t next;  // next entry of the bucket, or -1
  };
  std::vector<std::int32_t> edge_heads_;
  std::vector<EdgeEntry> edge_entries_;
};

template <class InConflict>
bool Cavity::grow(MeshEditor& ed, TetId seed, InConflict&& in_conflict, bool keep_marked_faces) {
  const auto& m = ed.mesh();
  add(ed, seed);
  // The hot loop of Delaunay insertion: raw views of arrays that do not
  // change while it runs, and the stamps read directly (every tet has one).
  ed.grow_stamps();
  std::uint32_t* const stamp = ed.stamps_.data();
  const std::uint32_t member = ed.epoch_, rejected = ed.epoch_ + 1;
  const Index* const adj_all = m.tet2adj.data();
  const std::array<VertId, 4>* const verts = m.tet2verts.data();
  bool blocked = false;
  // Breadth first, tets_ being the queue: a tet's neighbours are examined a
  // while after it joined, so the loads prefetched then have landed.
  for (std::size_t next = tets_.size() - 1; next < tets_.size(); ++next) {
    const TetId t = tets_[next];
    const Index* const at = adj_all + 4 * std::size_t{t};
    const std::array<Index, 4> adj{at[0], at[1], at[2], at[3]};
    // The neighbours may be scattered in memory: start the loads of their
    // stamps and vertices before testing any, so that misses overlap.
    for (const Index a : adj)
      if (a != kNone) {
        __builtin_prefetch(&stamp[mesh::face_tet(a)]);
        __builtin_prefetch(&verts[mesh::face_tet(a)]);
      }
    const std::array<VertId, 4> tv = verts[t];
    for (int f = 0; f < 4; ++f) {
      const Index here = mesh::pack_face(t, f);
      const Index across = adj[f];
      if (across != kNone) {
        const TetId n = mesh::face_tet(across);
        const std::uint32_t s = stamp[n];
        if (s == member) continue;  // an inner face
        const bool stop = keep_marked_faces && ed.face_marked(here);
        blocked |= stop;
        if (!stop && s != rejected) {
          if (in_conflict(n)) {
            stamp[n] = member;
            tets_.push_back(n);
            // Read next (its neighbours) and by a fill (its region).
            __builtin_prefetch(&adj_all[mesh::pack_face(n, 0)]);
            __builtin_prefetch(&m.tet_region[n]);
            continue;
          }
          stamp[n] = rejected;
        }
        __builtin_prefetch(&adj_all[across], 1);  // a fill relinks it
      }
      // Face f of t holds the three vertices other than f, in kFaceVerts order.
      const auto& fv = mesh::kFaceVerts[f];
      boundary_.push_back({{tv[fv[0]], tv[fv[1]], tv[fv[2]]}, here, across, ed.face_marked(here)});
    }
  }
  if (!blocked) return true;
  // A protected face is on the boundary only if its far tet stayed out.
  std::size_t kept = 0;
  bool crossed = false;
  for (const CavityFace& bf : boundary_) {
    if (bf.outside != kNone && ed.marked(mesh::face_tet(bf.outside))) {
      crossed = true;
      continue;
    }
    boundary_[kept++] = bf;
  }
  boundary_.resize(kept);
  return !crossed;
}

/// Replaces the cavity's tets by `fill`. The fill must tile exactly the
/// cavity: every face of a new tet is either a boundary face of the cavity
/// (same vertex set; linked to the tet outside it) or shared with exactly one
/// other new tet, and every boundary face is covered. Violations are operator
/// bugs and throw std::logic_error (the mesh is then unusable). Returns the
/// created tets (valid until the cavity is reused) after calling the hook.
std::span<const TetId> rebuild(MeshEditor& ed, Cavity& cavity, std::span<const NewTet> fill);

/// Evaluates the star of vertex p over the cavity boundary: every boundary
/// face not containing p joined to p must make a positive tet (exact
/// orient3d). Returns kNotStarShaped if one does not, else kNone.
/// Precondition: compute_boundary() was called.
Refusal check_star(const mesh::TetMesh& m, const Cavity& cavity, VertId p);

/// Fills the cavity with the star of p (boundary faces containing p are
/// skipped: they are matched by the star's own faces, as in a collapse).
/// Each new tet takes the region of the cavity tet its face came from.
/// Precondition: check_star() returned kNone.
std::span<const TetId> fill_star(MeshEditor& ed, Cavity& cavity, VertId p);

}  // namespace cm::modify
