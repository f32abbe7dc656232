#pragma once
// Cusps: model vertices where two edges leave in (nearly) the same
// direction, so the face between them tapers to a point.
//
// Near such a vertex the face is a strip whose width w(x) grows slowly with
// the distance x from the vertex (as x² where the edges are tangent). Where
// the strip is narrower than the local size, any triangulation of it has
// either caps (nodes of one side between two of the other) or cross edges
// of length w among edges of the size, and the tets on them have dihedral
// angles of about w / size: this is where the worst elements of a model with
// a cusp come from (0.16° before optimization on SampleCrankshaft4A).
//
// The way out is a *tip*: a ball of radius R around the vertex, where the
// strip reaches a usable width, that holds no mesh point but the vertex.
// Every edge at the vertex gets its first node on the ball's sphere, the
// faces and the volume get no point inside it, so the tets at the vertex are
// needles from the vertex to a triangulated cap of the sphere: long, but
// their dihedral angles are those of the cap's triangles. Outside the ball
// the size along the strip follows its width (size/build.cpp), so the
// triangles there have cross edges of about the size.
#include <array>
#include <functional>
#include <vector>

#include "curvemesh/geom/model.hpp"

namespace cm::geom {

/// Two edges leaving a vertex at less than this angle form a cusp.
inline constexpr double kCuspDegrees = 10;

/// Per edge (index edge - 1), which of its ends (at u0, at u1) are cusps.
std::vector<std::array<bool, 2>> cusp_ends(const Model& model);

/// A vertex's tip ball: no mesh point but the vertex lies closer than
/// `radius` to `point`.
struct CuspTip {
  int vertex = 0;
  Vec3 point;
  double radius = 0;
  std::vector<std::array<int, 2>> pairs;  ///< the edges (tags) that leave it tangent, two by two
};

/// Whether a point lies inside any of a set of tip balls: sorted along x, so
/// a query looks only at the balls whose x-extent can hold it.
class TipBalls {
 public:
  TipBalls() = default;
  explicit TipBalls(std::vector<CuspTip> tips);
  bool contains(const Vec3& x) const { return find(x) != nullptr; }
  /// The tip whose ball holds x, or null.
  const CuspTip* find(const Vec3& x) const;
  bool empty() const { return tips_.empty(); }

 private:
  std::vector<CuspTip> tips_;  // by point.x()
  double max_radius_ = 0;
};

/// The tips of the model's cusp vertices, by vertex tag. At each, R is the
/// least distance from the vertex, along either edge of a cusp pair, at
/// which the strip between the two edges is at least `width(x)` wide (x the
/// point on the edge), over all pairs at the vertex; then at most 0.4 times
/// the length of every edge at the vertex and 0.8 times the distance to its
/// point half-way by parameter (so each edge keeps nodes of its own beyond
/// the ball), and at most 0.8 times the distance to any face that does not
/// touch the vertex. A vertex whose R would be 0 gets no tip, nor one where
/// two pairs meet (two faces tapering there: the solid itself is a thin
/// wedge, which a ball with no point inside cannot mesh).
std::vector<CuspTip> cusp_tips(const Model& model, const std::function<double(const Vec3&)>& width);

/// The parameter on `edge` at chord distance `radius` from the edge's end
/// `side` (0: u0, 1: u1), nearest that end; nullopt if the edge never gets
/// that far from it.
std::optional<double> param_at_distance(const Model& model, int edge, int side, double radius);

}  // namespace cm::geom
