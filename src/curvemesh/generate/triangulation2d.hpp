#pragma once
// A compact triangle mesh of the plane and its constrained Delaunay
// triangulation (CDT): the first step of the surface mesher, which meshes
// each CAD face in its (u,v) parameter plane starting from the CDT of the
// face's boundary loops, then refines it with local operators.
//
// Every topological decision (which triangle holds a point, whether a point
// lies on a segment, whether an edge is Delaunay) uses the exact predicates of
// core/predicates.hpp, never a tolerance: orientations of stored triangles are
// exactly positive, and "on an edge" means exactly collinear.
#include <array>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "curvemesh/core/types.hpp"

namespace cm::generate {

/// Triangles with edge adjacency and per-edge constraint flags, in flat arrays.
///
/// Conventions (the invariants check() verifies):
/// - tris[t] lists three distinct vertex indices counter-clockwise:
///   orient2d(points[tris[t][0]], points[tris[t][1]], points[tris[t][2]]) > 0.
/// - Edge i of t is the edge opposite vertex tris[t][i]; edge(t, i) returns its
///   ends in the counter-clockwise order of t: (tris[t][i+1], tris[t][i+2]).
/// - adj[t][i] is the triangle across edge i, -1 on the boundary. Adjacency is
///   symmetric, and two triangles share at most one edge.
/// - Bit i of constrained[t] marks edge i as a constraint (a piece of an input
///   segment); both triangles of an edge carry the same bit. Constrained edges
///   are never flipped by the functions here.
/// - vert_tri[v] is one live triangle containing v, -1 for a vertex no triangle
///   uses. Where the domain pinches at a vertex (two loops touching at a point)
///   the vertex has several fans and vert_tri names one of them.
/// - A deleted triangle has tris[t] == {-1,-1,-1} and is listed in free_tris;
///   add_triangle() reuses those slots and compact() removes them.
struct Triangulation2d {
  std::vector<Vec2> points;
  std::vector<std::array<int, 3>> tris;
  std::vector<std::array<int, 3>> adj;
  std::vector<std::uint8_t> constrained;
  std::vector<int> vert_tri;
  std::vector<int> free_tris;

  static int next(int i) { return i == 2 ? 0 : i + 1; }
  static int prev(int i) { return i == 0 ? 2 : i - 1; }

  /// Live triangles (slots minus deleted ones).
  std::size_t num_tris() const { return tris.size() - free_tris.size(); }
  std::size_t num_slots() const { return tris.size(); }
  bool is_live(int t) const { return tris[t][0] >= 0; }

  /// Ends of edge i of t, counter-clockwise in t.
  std::array<int, 2> edge(int t, int i) const { return {tris[t][next(i)], tris[t][prev(i)]}; }
  /// Local index (0..2) of vertex v in t, or -1.
  int local_index(int t, int v) const {
    const auto& tv = tris[t];
    return tv[0] == v ? 0 : tv[1] == v ? 1 : tv[2] == v ? 2 : -1;
  }
  /// Index of edge (t, i) inside its neighbour adj[t][i] (which must exist).
  int mirror(int t, int i) const { return prev(local_index(adj[t][i], tris[t][prev(i)])); }
  bool is_constrained(int t, int i) const { return (constrained[t] >> i) & 1u; }
  /// Sets or clears the constraint flag of edge (t, i) on both of its sides.
  void set_constrained(int t, int i, bool on);

  /// The triangles around vertex v, counter-clockwise, starting from the
  /// first one after the boundary if v is on the boundary. Only the fan of
  /// vert_tri[v]. `out` is cleared first.
  void triangles_around(int v, std::vector<int>& out) const;
  /// Every vertex's live triangles, all fans, as flat arrays: those of v are
  /// tris_of[start[v]] .. tris_of[start[v + 1]], in slot order.
  struct Balls {
    std::vector<int> start, tris_of;
  };
  Balls balls() const;
  /// An edge {a,b}: (t, i) with edge(t, i) == (a, b) if such a triangle
  /// exists, else the triangle holding it as (b, a); {-1,-1} if a and b are not
  /// joined (in the fan of vert_tri[a]). O(degree of a).
  std::pair<int, int> find_edge(int a, int b) const;

  /// Appends a point with no triangle yet; returns its index.
  int add_point(const Vec2& p);
  /// New triangle (a,b,c), which must be counter-clockwise, in a free slot or
  /// at the end: no neighbours, no constraint flags; vert_tri of a, b, c point
  /// to it. Returns its index.
  int add_triangle(int a, int b, int c);
  /// Deletes t: its neighbours' adjacency to it becomes -1 (their constraint
  /// flags stay), vert_tri of its vertices moves to a neighbour containing
  /// them when there is one (else -1), and the slot joins free_tris.
  void remove_triangle(int t);
  /// Makes n the neighbour of t across edge i and t the neighbour of n across
  /// the same edge (n == -1 makes it a boundary edge), with the given flag on
  /// both sides. tris[n] must already hold the edge reversed.
  void set_neighbour(int t, int i, int n, bool constrained_edge);

  /// Flips edge i of t. With (a,b,c) = (tris[t][i], tris[t][i+1], tris[t][i+2])
  /// and d the vertex of u = adj[t][i] opposite the edge, afterwards
  /// tris[t] == {a,b,d} and tris[u] == {d,c,a}, so the new edge (a,d) is edge 1
  /// of both. Precondition: the edge has a neighbour, is not constrained and
  /// the quadrilateral a,b,d,c is strictly convex (not checked).
  void flip(int t, int i);
  /// Splits t into three triangles around vertex v, which must lie strictly
  /// inside it. Returns them; the k-th has v as local vertex k, so its edge k is
  /// one of t's former edges. The first one reuses slot t.
  std::array<int, 3> split_triangle(int t, int v);
  /// Splits edge i of t (and the neighbour across it, if any) at vertex v,
  /// which must lie strictly inside the edge. Returns {t, t', u, u'} (u, u' are
  /// -1 on the boundary): v is local vertex 2 of t and u and local vertex 1 of
  /// t' and u', and the opposite edges are the former outer edges. The two
  /// halves keep the edge's constraint flag, so splitting a constrained edge
  /// yields two constrained edges.
  std::array<int, 4> split_edge(int t, int i, int v);
  /// Bowyer–Watson step with a cavity chosen by the caller (e.g. by an
  /// anisotropic in-circle test that the exact kernel does not offer):
  /// replaces the live triangles `cavity` by the fan joining a new vertex at
  /// p to the cavity's boundary, keeping the boundary edges' neighbours and
  /// constraint flags. Checked exactly first, leaving the mesh unchanged and
  /// returning -1 when the fan would not be a valid triangulation of the
  /// cavity: a repeated or dead triangle, a constrained edge between two
  /// cavity triangles, a boundary that is not one cycle through distinct
  /// vertices, a cavity vertex not on that boundary, or p not strictly on
  /// the left of every boundary edge (exact orient2d > 0; together these make
  /// the cavity a disk that is star-shaped from p). Returns the new vertex
  /// index; `fan`, if given, receives the new triangles. O(k log k) for k
  /// cavity triangles.
  int insert_in_cavity(const Vec2& p, const std::vector<int>& cavity, std::vector<int>* fan = nullptr);

  /// Drops deleted slots, renumbering triangles in their order (neighbours
  /// that were deleted become -1), and rebuilds vert_tri.
  void compact();
  /// Recomputes vert_tri from tris (size points.size()).
  void rebuild_vert_tri();

  /// Checks every invariant above: array sizes, vertex indices, exact positive
  /// orientation, symmetric adjacency with matching edges and flags, no
  /// directed edge used twice, no boundary edge whose reverse is used by
  /// another triangle, vert_tri, and the free list. Returns "" if the mesh is
  /// valid, else a description of the first problem found. O(T log T).
  std::string check() const;
};

/// Boundary loops of a face in its parameter plane.
struct CdtInput {
  std::vector<Vec2> points;
  /// Constraint segments as pairs of point indices. They should form closed
  /// loops (an outer loop and hole loops, in any orientation and order).
  std::vector<std::array<int, 2>> segments;
};

struct CdtResult {
  /// The triangles of the region enclosed by the loops, compact (no free
  /// slots). mesh.points == input points with the same indices: no Steiner
  /// point is ever added (crossing segments are an error instead). Points
  /// outside the region keep their index with vert_tri -1.
  Triangulation2d mesh;
  /// For each input segment, the mesh vertices along it from segments[s][0] to
  /// segments[s][1]: its two ends, plus the input points lying exactly on it.
  /// Consecutive entries are constrained mesh edges.
  std::vector<std::vector<int>> segment_vertices;
};

/// Constrained Delaunay triangulation of the region enclosed by the segments.
///
/// A triangle is kept iff it is inside by the even-odd rule: a ray from it
/// crosses the segments an odd number of times (computed by a flood fill from
/// the outside that toggles at every constrained edge). Every segment appears as
/// a chain of constrained mesh edges, split at the input points lying exactly
/// on it (orient2d == 0 and between its ends); segments may touch at points
/// (T-junctions are fine). Every unconstrained interior edge is locally
/// Delaunay: exact incircle <= 0 against the opposite vertex. With unclosed
/// loops the inside/outside labelling is unspecified but the mesh stays valid.
///
/// Throws cm::GeometryError, naming the point or segment indices, for fewer
/// than 3 points, a non-finite coordinate, two points with exactly equal
/// coordinates, all points collinear, a segment whose end is not a point index
/// or whose two ends are the same point, two segments crossing at a point
/// interior to both, and two segments overlapping along a stretch (including
/// the same segment given twice).
///
/// Algorithm: points in biased randomized insertion order (random rounds of
/// doubling size, each sorted along a Hilbert curve) inserted by walking from
/// the last insertion and Lawson flips inside an enclosing triangle; segments
/// inserted by deleting the triangles they cross and retriangulating the two
/// polygons on either side (Anglada's recursive Delaunay choice), then a flood
/// fill. Expected O(n log n) for n points, plus O(k²) per segment crossing k
/// triangles. Deterministic: the same input gives the same mesh.
CdtResult constrained_delaunay(const CdtInput& in);

/// Forces edge (a,b) into m as a constraint (a chain of constrained edges,
/// split at the vertices lying exactly on it), keeping the triangulation
/// constrained Delaunay: crossed triangles are replaced as in
/// constrained_delaunay(). Inserting an existing constraint does nothing.
/// Throws cm::GeometryError if the segment crosses a constrained edge or leaves
/// the triangulated region (m is then unchanged except for the pieces already
/// inserted, at vertices lying on the segment). a and b must be vertices used by
/// m.
void insert_segment(Triangulation2d& m, int a, int b);

/// Lawson flips: pops edges (t, i) from `edges` (consumed) and flips each one
/// that is unconstrained, interior and not locally Delaunay (its opposite
/// vertex strictly inside the circumcircle, exactly), pushing the four outer
/// edges of every flipped quadrilateral. Terminates; afterwards every edge that
/// was given or touched by a flip is locally Delaunay or constrained. For local
/// operators: after split_edge() or split_triangle(), pass the edges opposite
/// the new vertex.
void legalize(Triangulation2d& m, std::vector<std::pair<int, int>>& edges);

/// Where a point lies relative to a triangulation.
struct Location {
  enum Kind { kOutside, kInside, kOnEdge, kOnVertex };
  Kind kind = kOutside;
  int tri = -1;    ///< a triangle containing the point (closed), -1 if outside
  int index = -1;  ///< the edge (kOnEdge) or the local vertex (kOnVertex) of tri
};

/// Finds the triangle containing p by a visibility walk from `hint` (any
/// triangle if hint is not a live triangle): O(√T) steps from a random start,
/// O(1) from a nearby hint. When the walk is stopped by the boundary (a hole or
/// a concave part of the domain lies between hint and p) it continues with a
/// best-first search over triangles, so a point outside the domain costs
/// O(T log T).
Location locate_point(const Triangulation2d& m, const Vec2& p, int hint = -1);
/// locate_point(m, p, hint).tri.
int locate(const Triangulation2d& m, const Vec2& p, int hint = -1);

/// Inserts p into m, already constrained Delaunay, keeping it so: the cavity of
/// triangles whose circumcircle contains p, seen from p without crossing a
/// constrained edge, is replaced by the fan around p (done by splitting the
/// triangle or edge holding p and Lawson flips that never cross a constraint).
/// Returns the new vertex index (points.size() before the call), or -1 leaving
/// m unchanged if p is outside the triangulated region, coincides with a
/// vertex, lies exactly on a constrained edge (refinement splits such edges
/// itself, with split_edge() and legalize(), as it tracks the boundary) or has
/// a non-finite coordinate. A point on an unconstrained boundary edge splits it.
int insert_point(Triangulation2d& m, const Vec2& p, int hint = -1);

}  // namespace cm::generate
