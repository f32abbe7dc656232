#pragma once
// Editing a TetMesh in place: the bookkeeping every cavity operation shares.
//
// Operators delete a cavity of tets and fill it with new ones many millions of
// times, so tets are never erased from the arrays: a deleted tet becomes a
// "dead" slot (its first vertex is kNone) that the next allocation reuses, and
// compact() squeezes the arrays once at the end. Per-tet stamps let operators
// mark cavity membership in O(1) without clearing a set per call.
//
// Contract:
// - The mesh must have valid adjacency (build_adjacency) when the editor is
//   made; the editor keeps tet2adj and vert2tet valid for live tets through
//   every rebuild (vert2tet[v] always names a live tet containing v, or kNone
//   when v has no tet).
// - While an editor exists, code that walks tet2verts must skip dead tets
//   (is_dead) — validate.hpp and the writers expect compact() first.
// - Not thread-safe: one editor, one thread.
#include <array>
#include <cstdint>
#include <functional>
#include <span>
#include <vector>

#include "curvemesh/mesh/tet_mesh.hpp"

namespace cm::modify {

/// Called after every cavity rebuild with the tets it created (already linked
/// into adjacency). This is where curving places high-order nodes on new
/// entities and where drivers queue new tets for inspection.
using RebuildHook = std::function<void(const mesh::TetMesh&, std::span<const TetId> created)>;

class MeshEditor {
 public:
  explicit MeshEditor(mesh::TetMesh& m);

  mesh::TetMesh& mesh() { return *m_; }
  const mesh::TetMesh& mesh() const { return *m_; }

  bool is_dead(TetId t) const { return m_->tet2verts[t][0] == kNone; }
  std::size_t live_tets() const { return m_->tet2verts.size() - free_.size(); }

  /// A slot for a new tet (reusing a dead one when possible, the last
  /// released first). Adjacency of the new tet is all kNone; the caller links
  /// it. Inline: Delaunay insertion calls it some 30 times per point.
  TetId allocate(const std::array<VertId, 4>& v, std::int32_t region) {
    auto& m = *m_;
    TetId t;
    if (!free_.empty()) [[likely]] {
      t = free_.back();
      free_.pop_back();
      m.tet2verts[t] = v;
      m.tet_region[t] = region;
      for (int f = 0; f < 4; ++f) m.tet2adj[4 * std::size_t{t} + f] = kNone;
    } else {
      t = append(v, region);
    }
    if (!seeds_deferred_) {
      if (m.vert2tet.size() < m.coords.size()) [[unlikely]]
        m.vert2tet.resize(m.coords.size(), kNone);
      for (VertId x : v) m.vert2tet[x] = t;
    }
    return t;
  }
  /// Marks t dead. Its adjacency entries are left for the caller to rewire.
  void release(TetId t) {
    m_->tet2verts[t][0] = kNone;
    if (t < face_marks_.size()) face_marks_[t] = 0;
    free_.push_back(t);
  }
  /// Reserves room for `tets` tets in the mesh's per-tet arrays (and the
  /// stamps), so that a bulk construction does not reallocate (each
  /// reallocation copies everything and briefly holds both copies).
  void reserve(std::size_t tets);

  /// Bulk construction: while seeds are deferred, vert2tet is not kept (the
  /// editor's contract on it is suspended; nothing may read it), which spares
  /// a scattered write per vertex of every new tet. Turning deferral off
  /// rebuilds vert2tet from the live tets in one pass.
  void defer_seeds(bool on);
  bool seeds_deferred() const { return seeds_deferred_; }

  /// Stamps: stamp(t) == epoch() means "marked in the current operation".
  /// next_epoch() invalidates every mark in O(1).
  std::uint32_t next_epoch();
  std::uint32_t epoch() const { return epoch_; }
  void mark(TetId t) { grow_stamps(); stamps_[t] = epoch_; }
  bool marked(TetId t) const { return t < stamps_.size() && stamps_[t] == epoch_; }
  /// A second mark of the same epoch, exclusive with mark(): "examined by the
  /// current operation and left out" (the neighbours a Delaunay cavity
  /// rejected, so that none is tested twice).
  void mark_rejected(TetId t) { grow_stamps(); stamps_[t] = epoch_ + 1; }
  bool rejected(TetId t) const { return t < stamps_.size() && stamps_[t] == epoch_ + 1; }

  /// Face marks: a protected face (a boundary triangle a cavity must not
  /// cross or remove). Stored on both tets sharing the face; cavity rebuilds
  /// carry marks of the cavity's boundary faces over to the new tets.
  bool face_marked(Index packed) const {
    const TetId t = mesh::face_tet(packed);
    return t < face_marks_.size() && (face_marks_[t] >> mesh::face_index(packed) & 1u);
  }
  /// Marks the face on both sides.
  void mark_face(Index packed);
  /// Sets or clears the mark on this side only (used by rebuild).
  void set_face_mark_one_side(Index packed, bool on);

  void set_hook(RebuildHook hook) { hook_ = std::move(hook); }
  const RebuildHook& hook() const { return hook_; }

  /// Removes dead tets (renumbering the rest in order), rebuilds vert2tet;
  /// returns old id -> new id (kNone for dead). Invalidates stamps.
  std::vector<TetId> compact();

 private:
  // The cavity kernel's hot loop (Cavity::grow) reads and writes the stamps
  // directly.
  friend class Cavity;

  void grow_stamps() {
    if (stamps_.size() < m_->tet2verts.size()) stamps_.resize(m_->tet2verts.size() + m_->tet2verts.size() / 2 + 16, 0);
  }
  // A new slot at the end, adjacency kNone. The per-tet arrays grow by half
  // rather than doubling: past a reserve() that fell short, the last
  // reallocation of a big mesh then over-allocates and transiently holds less.
  TetId append(const std::array<VertId, 4>& v, std::int32_t region);

  mesh::TetMesh* m_;
  std::vector<TetId> free_;
  std::vector<std::uint32_t> stamps_;
  std::vector<std::uint8_t> face_marks_;
  // Odd: epoch_ marks a member, epoch_ + 1 a rejected tet (see next_epoch).
  std::uint32_t epoch_ = 1;
  bool seeds_deferred_ = false;
  RebuildHook hook_;
};

/// Drops the vertices no tet uses (those collapses and element deletions
/// left behind): renumbers tets, m.tris, m.edges and the per-vertex arrays,
/// keeping the order of the rest. Precondition: no dead tets (compact()
/// first) and no high-order nodes. Returns old id -> new id (kNone for a
/// dropped vertex), empty when none was dropped. O(V + T).
std::vector<VertId> drop_unused_vertices(mesh::TetMesh& m);

}  // namespace cm::modify
