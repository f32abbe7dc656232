#pragma once
// Which poor tets the boundary holds where they are.
//
// With the surface fixed (no model), each boundary triangle stays the face
// of exactly one tet, and each boundary edge keeps its wedge (the domain's
// angle there, shared among the tets around the edge). So:
// - a tet holding two boundary triangles (they share an edge) is the only
//   tet around that edge and the only tet with those faces: its four
//   vertices are fixed and it cannot be replaced. Its shape is final.
// - a tet on a boundary edge has at most the edge's wedge angle.
// A single boundary triangle does not cap the angle: even a cap or a needle
// triangle is the face of a spindle-shaped tet with all dihedral angles
// near 60° (a poor mean ratio, but a fair angle), so a tet with one boundary
// face is free, whatever its vertices.
// That fair angle has a price, though: on a thin triangle every tet with
// all its angles at the target has a poor mean ratio. For a free tet with
// one boundary face the report gives the best mean ratio found for a tet on
// that face with its smallest angle at the target (a search over the apex):
// where the tet's own mean ratio is above it, bringing it to the target
// would lower the mesh's worst mean ratio, which the optimizer does not
// trade below kRescueFloor (measured_swap.hpp). Those are "held by a thin
// face".
// A tet whose smallest dihedral angle is below the target and whose cap (the
// least of these) is below the target too is "pinned by the boundary": no
// operator that keeps the surface can bring it to the target. The rest are
// "free": their angle is the optimizer's to answer for.
// With a model the surface may change, so the same count on an optimized
// mesh says what its final surface allows.
#include <array>
#include <cstddef>
#include <vector>

#include "curvemesh/mesh/tet_mesh.hpp"

namespace cm::optimize {

struct BoundaryLimit {
  double target = 10;  ///< degrees
  /// Tets below the target whose boundary caps them below it, and the rest
  /// of the tets below the target.
  std::size_t pinned = 0, free_below = 0;
  /// Of the pinned tets: the worst smallest dihedral (degrees) and mean
  /// ratio, and the smallest cap (what the boundary allows at best there).
  /// 180 / 1 / 180 when there are none.
  double pinned_min_dihedral = 180, pinned_min_mean_ratio = 1, pinned_min_cap = 180;
  /// Of all the other tets (free, whatever their angle).
  double free_min_dihedral = 180, free_min_mean_ratio = 1;
  /// Pinned tets by what pins them: two boundary faces, a boundary edge's
  /// wedge.
  std::size_t by_two_faces = 0, by_wedge = 0;
  /// Free tets below the target held by a thin face (see above), and the
  /// lowest price among them (1 when there are none). Only the kPriced
  /// worst free tets with one boundary face are priced.
  static constexpr std::size_t kPriced = 4096;
  std::size_t held_by_thin_face = 0;
  double min_price = 1;

  enum class Why { kFree, kTwoFaces, kWedge };
  /// A tet below the target: where it is, and what the boundary allows it.
  struct Tet {
    TetId tet = kNone;
    Vec3 centroid = Vec3::Zero();
    double dihedral = 0, mean_ratio = 0;
    double cap = 180;  ///< the boundary's cap on its smallest angle (180: none)
    Why why = Why::kFree;
    int boundary_verts = 0, boundary_faces = 0;  ///< vertices not in a region; faces in m.tris or the hull
    /// For a free tet with one boundary face: the best mean ratio found for
    /// a tet on that face with all its angles at the target (1: not asked).
    double price = 1;
  };
  /// The worst tets below the target, worst first (at most the count asked).
  std::vector<Tet> worst;
};
const char* to_string(BoundaryLimit::Why why);

/// The best mean ratio found for a tet on triangle (a, b, c) whose smallest
/// dihedral angle is at least `target_degrees`, its apex on the side of
/// `side` (a point off the triangle's plane); 0 if none was found. A
/// deterministic pattern search from several starts: a lower estimate of
/// the true optimum, within a few percent on the shared models' faces.
double best_mean_ratio_at_angle(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& side,
                                double target_degrees);

/// Classifies the tets of a compact, conforming mesh (adjacency not needed).
/// Boundary triangles are m.tris and the hull's faces. O(T) hashing, plus a
/// search of a few hundred trial apexes per free tet below the target with
/// one boundary face.
BoundaryLimit classify_boundary_limit(const mesh::TetMesh& m, double target_degrees = 10, std::size_t worst = 8);

}  // namespace cm::optimize
