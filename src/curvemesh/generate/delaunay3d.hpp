#pragma once
// Incremental 3D Delaunay tetrahedralization (Bowyer–Watson) built on the
// cavity kernel of modify/.
//
// - Starts from one enclosing tetrahedron whose four "far" vertices are
//   appended to the mesh; every later point must lie strictly inside it.
// - Point location: visibility walk with exact orient3d from a hint (the last
//   created tet by default), the face order varied so the walk cannot cycle.
// - Cavity: the tets whose circumsphere strictly contains the point, grown
//   face by face from the located tet. Cospherical ties are broken by a
//   symbolic perturbation of the lifting (each point lifted by ε^(rank), rank
//   = vertex id), so the triangulation is the unique Delaunay triangulation of
//   the perturbed points: no flat tets, every cavity star-shaped, whatever the
//   degeneracy (grids, cospherical or coplanar sets).
// - Constrained insertion: faces registered with protect() are never crossed
//   by a cavity (interior points never cut a recovered boundary face); such a
//   cavity may not be star-shaped, and the point is then refused
//   (kNotStarShaped), as it is when the cavity reaches around a protected
//   face and would delete it (kConstrainedFace).
// - Duplicate points are refused and reported with the vertex they repeat.
#include <array>
#include <span>
#include <vector>

#include "curvemesh/mesh/tet_mesh.hpp"
#include "curvemesh/modify/cavity.hpp"
#include "curvemesh/modify/mesh_editor.hpp"

namespace cm::generate {

/// insphere with the symbolic perturbation described above: never 0 for a
/// positive tet `t` and a point e that is not one of its vertices.
int insphere_perturbed(const mesh::TetMesh& m, const std::array<VertId, 4>& t, VertId e);

class Delaunay3d {
 public:
  /// `m` holds the points to insert later (any vertices; may have no tets).
  /// Appends the 4 far vertices around the box [lo, hi] and the enclosing tet.
  Delaunay3d(mesh::TetMesh& m, const Vec3& lo, const Vec3& hi);

  modify::MeshEditor& editor() { return editor_; }
  mesh::TetMesh& mesh() { return editor_.mesh(); }
  const std::array<VertId, 4>& far_vertices() const { return far_; }
  bool is_far(VertId v) const { return v >= far_[0] && v <= far_[3]; }

  /// The live tet containing x (closed), walking from `hint` (or the last
  /// created tet). Throws std::domain_error if x is outside the enclosing tet.
  TetId locate(const Vec3& x, TetId hint = kNone);

  struct Result {
    modify::Refusal refusal = modify::Refusal::kNone;
    VertId duplicate_of = kNone;  ///< for kDuplicatePoint
    std::size_t cavity_size = 0;
  };
  /// Inserts vertex v (already in the mesh's coords, in no tet).
  Result insert(VertId v, TetId hint = kNone);
  /// Inserts many vertices in BRIO + Hilbert order; returns, per input
  /// position, the vertex it duplicates or kNone. vert2tet is rebuilt at the
  /// end (MeshEditor::defer_seeds): a rebuild hook must not read it meanwhile.
  std::vector<VertId> insert_all(std::span<const VertId> verts);

  /// Marks a face of the mesh (vertex triple, any order) that cavities must
  /// not cross; the mark follows the face through later insertions. Returns
  /// false if the triple is not a face of the mesh.
  bool protect(const std::array<VertId, 3>& face);
  /// Protects many faces in one pass over the tets (no ball walks, so also
  /// faces at a vertex whose tets are not connected through faces, as at a
  /// pinched point of a domain). Returns how many of them are no face.
  std::size_t protect_all(std::span<const mesh::ClassifiedTri> faces);
  bool is_protected(const std::array<VertId, 3>& face) const;
  std::size_t protected_faces() const { return protected_count_; }

  /// Tells insert() that the mesh was changed by other operations than
  /// insertion (flips of boundary recovery) and may no longer be Delaunay.
  /// A cavity of tets whose circumspheres hold the point may then not be
  /// star-shaped from it; unconstrained insertion shrinks it until it is
  /// (dropping tets that hide the point, never one containing it) instead
  /// of assuming it. Cannot be undone.
  void set_non_delaunay() { non_delaunay_ = true; }
  /// Insertions whose cavity had to be shrunk (see set_non_delaunay).
  std::size_t shrunk_cavities() const { return shrunk_; }

  /// Tet created by the last successful insertion (a good walk start).
  TetId last_tet() const { return last_; }
  std::size_t exact_walk_steps() const { return walk_steps_; }

 private:
  /// The packed face with these vertices, or kNone.
  Index find_face(const std::array<VertId, 3>& face) const;

  modify::MeshEditor editor_;
  modify::Cavity cavity_;
  std::array<VertId, 4> far_{};
  TetId last_ = 0;
  std::uint64_t rng_ = 0x9E3779B97F4A7C15ull;
  // While insert_all renumbers the mesh: original id of each vertex (the
  // rank of the symbolic perturbation), else null.
  const VertId* rank_ = nullptr;
  std::size_t walk_steps_ = 0;
  std::size_t protected_count_ = 0;
  bool non_delaunay_ = false;
  std::size_t shrunk_ = 0;
  std::vector<TetId> keep_;
  /// Shrinks cavity_ (grown from t0) until it is star-shaped from v;
  /// false if a tet containing v hides it.
  bool shrink_to_star(VertId v, TetId t0);
  mutable std::vector<TetId> ball_;
};

}  // namespace cm::generate
