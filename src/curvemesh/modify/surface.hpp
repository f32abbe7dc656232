#pragma once
// The boundary surface as the point operators (split, collapse, model-aware
// relocation) see it: the classified triangles and edges found by their
// vertices, a cavity rebuild for operations that change the mesh's hull, and
// the small geometric predicates the three share.
//
// Swaps never touch m.tris or m.edges (they refuse marked faces), so only the
// point operators edit them — always through a BoundaryIndex, which must
// therefore be the only writer of m.tris / m.edges while it exists.
#include <array>
#include <optional>
#include <span>
#include <vector>

#include "curvemesh/geom/model.hpp"
#include "curvemesh/mesh/topology.hpp"
#include "curvemesh/modify/cavity.hpp"

namespace cm::modify {

/// Finds m.tris and m.edges entries by their vertices (any order) in O(1),
/// and edits those arrays keeping itself right. Construction is
/// O(#tris + #edges). Removing an entry moves the last one into its slot, so
/// indices into m.tris / m.edges are only stable until the next removal.
/// Holds a pointer to the mesh: the mesh must outlive it.
class BoundaryIndex {
 public:
  /// Indexes m.tris and m.edges. Throws std::invalid_argument if a triangle
  /// or an edge is listed twice.
  explicit BoundaryIndex(mesh::TetMesh& m);

  /// Index in m.tris of the triangle with these vertices, or kNone.
  Index find_tri(VertId a, VertId b, VertId c) const;
  /// Index in m.edges of the edge (a, b), or kNone.
  Index find_edge(VertId a, VertId b) const;

  Index add_tri(const mesh::ClassifiedTri& tri);
  /// Replaces the vertices of m.tris[i] (its tag stays).
  void set_tri(Index i, const std::array<VertId, 3>& verts);
  void remove_tri(Index i);
  Index add_edge(const mesh::ClassifiedEdge& edge);
  void set_edge(Index i, const std::array<VertId, 2>& verts);
  void remove_edge(Index i);

  std::size_t tri_count() const { return tris_.size; }
  std::size_t edge_count() const { return edges_.size; }

 private:
  // Open addressing with linear probing on sorted vertex triples (an edge is
  // (a, b, kNone)); erasure shifts the chain back, so there are no
  // tombstones to accumulate over millions of edits.
  struct Table {
    struct Slot {
      std::array<VertId, 3> key{kNone, kNone, kNone};
      Index value = kNone;
    };
    std::vector<Slot> slots;
    std::size_t size = 0;
    Index find(const std::array<VertId, 3>& key) const;
    bool insert(const std::array<VertId, 3>& key, Index value);  // false if present
    void erase(const std::array<VertId, 3>& key);
    void assign(const std::array<VertId, 3>& key, Index value);  // key must be present
    void grow();
  };
  mesh::TetMesh* m_;
  Table tris_, edges_;
};

/// Replaces the cavity's tets by `fill`, like rebuild(), for fills that
/// change the hull: a boundary face of the cavity may be left uncovered (a
/// hull face disappears, as the two hull faces of a split hull edge or the
/// degenerate ones of a collapse; a face with a tet outside becomes a hull
/// face of that tet, as when a collapse removes a tet against the hull), and
/// a face of a new tet that matches nothing becomes a hull face. A face
/// matched more than twice throws std::logic_error. The operator answers for
/// the new hull being right (its faces being classified triangles): this
/// function cannot tell a new hull face from a hole. Marks of matched
/// boundary faces carry over; new hull faces are left unmarked for the
/// operator to mark. Keeps vert2tet right (a vertex left in no tet gets
/// kNone), calls the editor's hook, and returns the created tets (valid until
/// the next call). Precondition: compute_boundary() was called.
std::span<const TetId> rebuild_open(MeshEditor& ed, Cavity& cavity, std::span<const NewTet> fill);

/// Parameter u of vertex v on model edge `edge`: its own when classified on
/// that edge; the end's parameter when it is an end vertex of the edge (for
/// a closed edge the end nearer `near`, needs the model); else nothing.
std::optional<double> param_on_edge(const mesh::TetMesh& m, const geom::Model* model, VertId v, int edge,
                                    std::optional<double> near = {});

/// (u, v) of vertex v on model face `face` when classified on it; for a
/// vertex on a bounding edge, its p-curve point (the forward side of a seam:
/// good as a hint only). Else nothing.
std::optional<Vec2> param_on_face(const mesh::TetMesh& m, const geom::Model* model, VertId v, int face);

/// The (u, v) hint generate::check_boundary projects triangle `verts` of
/// `face` with: the parameters of its last vertex classified on the face
/// (vertex `moved`, if given, read as having `moved_param`), or none. Fold
/// tests in the operators use it so that they judge a triangle exactly as the
/// boundary check will: on a closed, strongly curved face (a torus) the
/// projection of a coarse triangle's centroid depends on the hint.
std::optional<Vec2> check_hint(const mesh::TetMesh& m, const std::array<VertId, 3>& verts, int face,
                               VertId moved = kNone, std::optional<Vec2> moved_param = {});

/// Classified triangles through v (indices into m.tris, sorted, each once),
/// found among the faces of its ball.
void tris_through(const mesh::TetMesh& m, const BoundaryIndex& boundary, VertId v, std::span<const TetId> ball,
                  std::vector<Index>& out);

/// Whether the classified triangles `tris` lie exactly (orient3d) in one
/// plane per model face: each in the plane of the first of its face in the
/// list.
bool flat_per_face(const mesh::TetMesh& m, std::span<const Index> tris);

/// Whether p, q and r lie exactly on one line (orient2d in the three
/// coordinate planes).
bool collinear(const Vec3& p, const Vec3& q, const Vec3& r);

/// Where a boundary vertex may go without a model and leave the surface the
/// same point set: the plane of its triangles (a vertex on a model face) or
/// the line through its two neighbours along its model edge (both ends
/// found in m.edges), when that plane or line is exactly flat around it
/// (flat_per_face, collinear). Found once per vertex; then each candidate
/// position is a projection and an exact test.
class FlatBoundary {
 public:
  /// Nothing when v is not on a model edge or face or its surface is not
  /// exactly flat there. `tris` are v's triangles (tris_through), `ball` its
  /// tets.
  static std::optional<FlatBoundary> at(const mesh::TetMesh& m, const BoundaryIndex& boundary, VertId v,
                                        std::span<const Index> tris, std::span<const TetId> ball);
  /// The point nearest p on the plane (line), when it lies on it exactly
  /// once rounded. That holds for planes and lines parallel to the
  /// coordinate axes, whose fixed coordinates are copied exactly, and
  /// seldom otherwise.
  std::optional<Vec3> slide(const Vec3& p) const;

 private:
  bool plane_ = true;
  Vec3 a_, b_, c_;  // the plane's reference triangle, or the line's ends (a_, b_)
  std::array<bool, 3> fixed_{};  // coordinates every point of it shares (those of a_)
};

/// Face f of a tet with vertices tv, in the order of mesh::kFaceVerts
/// (its normal out of the tet).
inline std::array<VertId, 3> tet_face(const std::array<VertId, 4>& tv, int f) {
  const auto& fv = mesh::kFaceVerts[static_cast<std::size_t>(f)];
  return {tv[fv[0]], tv[fv[1]], tv[fv[2]]};
}

/// Whether two triangles on the same vertices list them in the same cyclic
/// order (the same orientation).
inline bool same_cycle(const std::array<VertId, 3>& x, const std::array<VertId, 3>& y) {
  for (int k = 0; k < 3; ++k)
    if (x[0] == y[k] && x[1] == y[(k + 1) % 3] && x[2] == y[(k + 2) % 3]) return true;
  return false;
}

/// Unnormalized normal of triangle (a, b, c) (right-hand rule).
inline Vec3 tri_normal(const Vec3& a, const Vec3& b, const Vec3& c) { return (b - a).cross(c - a); }

/// Whether triangle (a, b, c) of model face `face` agrees with the face's
/// normal at the closest point of its centroid (the test of
/// generate::check_boundary: m.tris follow face_normal). `hint` is a (u, v)
/// near the triangle.
bool agrees_with_model(const geom::Model& model, int face, const Vec3& a, const Vec3& b, const Vec3& c,
                       std::optional<Vec2> hint);

/// Mean ratio of the tet with these corners, or -1 unless strictly positive
/// by exact orient3d (tet_quality for points that are not mesh vertices yet).
double tet_quality_at(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d);

}  // namespace cm::modify
