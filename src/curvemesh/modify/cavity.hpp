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
  std::vector<std::array<VertId, 3>> edge_table_;  // (a, b, packed face) for star fills
  std::vector<NewTet> star_;
};

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
