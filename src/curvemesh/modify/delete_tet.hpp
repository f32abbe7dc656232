#pragma once
// Element deletion with reclassification (seed paper 1, §3, Fig. 3.4): a tet
// against the hull with two or three of its faces on one model face is
// removed; its other faces become boundary triangles of that face, so the
// interior entities they hold (the edge joining the two apexes, the faces)
// are reclassified onto the model face.
//
// - Two hull faces (a, b, c) and (a, b, d), sharing the face edge (a, b):
//   the tet goes with them and the edge (a, b); its faces (a, c, d) and
//   (b, c, d) become triangles, and (c, d) a face edge. On the surface this
//   is the 2D flip of (a, b) in the quad a c b d, with the tet between the
//   two triangulations taken out of the domain. No vertex changes.
// - Three hull faces around a vertex v: v is on the model face and this tet
//   is its whole ball (else it would be a pinched vertex): the tet and v go
//   (v stays in the vertex arrays with its classification but in no tet and
//   no triangle, vert2tet[v] == kNone, as after a collapse); the face
//   opposite v becomes a triangle. This is the removal of a valence-3
//   surface vertex.
// The enclosed volume shrinks by the tet's volume, and the surface moves
// with it, so the operator needs the model: the new triangles must agree
// with the model face (the fold test generate::check_boundary applies, with
// its projection hint) and stay as close to it as the chord rule of the
// mesher asks (see DeletionOptions). Without a model the surface is the
// user's and is refused (kConstrainedFace).
//
// Applying keeps adjacency, vert2tet (through rebuild_open, the cavity
// kernel for fills that change the hull), region tags, m.tris (the hull
// triangles through the tet removed, the new ones added with the
// orientation convention of the ones they replace), m.edges (untouched: no
// model edge is involved), and face marks (the new hull faces are marked).
#include <array>

#include "curvemesh/geom/model.hpp"
#include "curvemesh/modify/surface.hpp"

namespace cm::modify {

struct DeletionOptions {
  /// Chord rule for the new boundary: the distance of each new triangle's
  /// centroid and of the new face edge's midpoint to the model face may not
  /// exceed this times the triangle's longest edge, unless it is no more
  /// than the old triangles' own distance. 0.04 is the mesher's default
  /// curvature rule (deviation alpha times the edge length, --curv-alpha).
  double max_relative_deviation = 0.04;
};

struct TetDeletion {
  Refusal refusal = Refusal::kNone;
  TetId tet = kNone;
  /// The model face the hull faces lie on.
  std::int32_t face_tag = 0;
  /// Hull faces of the tet (2 or 3), all classified triangles of face_tag.
  int hull_faces = 0;
  /// The triangles that go and the ones that come (vertices in the
  /// orientation m.tris gives them).
  std::array<std::array<VertId, 3>, 3> removed{};
  std::array<std::array<VertId, 3>, 2> added{};
  int removed_count = 0, added_count = 0;
  /// The vertex that goes with three hull faces, else kNone.
  VertId removed_vertex = kNone;
  /// tet_quality of the deleted tet, and the worst of the tets across its
  /// inner faces (what the neighbourhood's worst becomes, as far as these
  /// tets tell; nothing is created).
  double before = 0, after = 0;
  /// Volume the domain loses (the tet's, > 0).
  double volume = 0;
  /// Worst triangle_mean_ratio of the triangles removed and added.
  double triangles_before = 0, triangles_after = 0;
  /// Largest distance to the model face of the new triangles' samples, and
  /// of the old ones' (same kind of samples).
  double deviation_after = 0, deviation_before = 0;
};

/// Plans deleting live tet t. Fills the cavity with {t}; changes nothing.
/// Refusals, checked in this order:
/// - kConstrainedFace: no model, or t has fewer than two or all four faces
///   on the hull, or a face across which a tet lies is a classified
///   triangle (an interface: deleting would open a hole between regions);
/// - kClassification: a hull face is not a triangle of m.tris, they lie on
///   different model faces or are oriented inconsistently, the shared edge
///   is on a model edge (two faces), or the lone vertex is not on the model
///   face (three faces);
/// - kNonManifold: the new face edge (c, d) is already on the boundary (a
///   hull face or a classified triangle or edge holds it), or the lone vertex
///   has other tets;
/// - kFoldedSurface: a new triangle turns against the ones it replaces or
///   against the model face (agrees_with_model with check_hint), or strays
///   from the model beyond DeletionOptions.
/// O(shell of (c, d)) plus a few closest-point queries.
TetDeletion plan_tet_deletion(MeshEditor& ed, Cavity& cavity, const BoundaryIndex& boundary, TetId t,
                              const geom::Model* model, const DeletionOptions& options = {});

/// Applies a plan made with this cavity (no other use of the cavity or edit
/// of the mesh in between). Precondition: plan.refusal == kNone. The
/// editor's hook is called with no created tets.
void apply(MeshEditor& ed, Cavity& cavity, BoundaryIndex& boundary, const TetDeletion& plan);

}  // namespace cm::modify
