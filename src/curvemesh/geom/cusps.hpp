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
  /// The tip whose sphere x lies on (within 1e-6 of its radius), or null:
  /// the points of a tip's cap, which must stay on it.
  const CuspTip* sphere_of(const Vec3& x) const;
  /// x taken along the ray from the tip's vertex to just outside its sphere
  /// (the sphere itself counts as outside the ball); x itself at the vertex.
  static Vec3 onto_sphere(const CuspTip& tip, const Vec3& x);
  bool empty() const { return tips_.empty(); }

 private:
  std::vector<CuspTip> tips_;  // by point.x()
  double max_radius_ = 0;
};

/// The tips of the model's cusp vertices, by vertex tag. At each, R is the
/// least distance from the vertex, along either edge of its cusp pair, at
/// which the strip between the two edges is at least `width(x)` wide (x the
/// point on the edge); then at most 0.4 times the length of every edge at
/// the vertex and 0.8 times the distance to its point half-way by parameter
/// (so each edge keeps nodes of its own beyond the ball), and at most 0.8
/// times the distance to any face that does not touch the vertex. A vertex
/// whose R would be 0 gets no tip, nor one with two pairs or more that a
/// wedge span opens (see wedge_spans); with several pairs and no span, R is
/// the largest of the pairs' distances.
std::vector<CuspTip> cusp_tips(const Model& model, const std::function<double(const Vec3&)>& width);

/// Where two faces taper at one vertex (two cusp pairs: on t20_data.step,
/// two chamfers that die out where a circle touches a flat side, on both
/// sides of the point of contact) a tip is the wrong remedy: both strips stay
/// narrower than the size over their whole length, so sizing them by their
/// width refines all of it (twice the tets at hmax 1.2) and the ball leaves
/// the volume between them to interior points alone (3.3 deg there). The
/// faces are meshed as any face instead, and what is left to fix is the
/// sliver triangle at the vertex between a pair's first nodes: its angle
/// there is the angle the strip has opened to, which grows with the distance
/// from the vertex where the edges are tangent, and so do the dihedral angles
/// of the tet on it (7.8 deg at hmax 1.2 with first nodes 1.6 away, 14 deg
/// at 3.7). So every edge at such a vertex gets its first node at least
/// `radius` from it: the least distance at which every pair's strip has
/// opened to kCuspDegrees, within the same caps as a tip's radius. No span
/// where a strip is still under half that angle at the radius.
/// The strips (the faces between a pair's two edges) get no interior point
/// within the radius: there the strip is the one triangle on the vertex and
/// the two first nodes, and a point inside would split it into caps.
struct WedgeSpan {
  int vertex = 0;
  double radius = 0;
  std::vector<int> strips;  ///< face tags, sorted
};
std::vector<WedgeSpan> wedge_spans(const Model& model);

/// The parameter on `edge` at chord distance `radius` from the edge's end
/// `side` (0: u0, 1: u1), nearest that end; nullopt if the edge never gets
/// that far from it.
std::optional<double> param_at_distance(const Model& model, int edge, int side, double radius);

}  // namespace cm::geom
