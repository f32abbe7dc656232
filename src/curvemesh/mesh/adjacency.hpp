#pragma once
// Face adjacency between tets, the vertex -> tet seed, and the two cavities
// every operator works on: the ball of a vertex and the shell of an edge.
#include <vector>

#include "curvemesh/mesh/tet_mesh.hpp"

namespace cm::mesh {

/// Rebuilds tet2adj and vert2tet from tet2verts. O(T log T) (a sort of the 4T
/// face keys). Faces shared by more than two tets are left unmatched and
/// counted in the return value (0 for a conforming mesh).
std::size_t build_adjacency(TetMesh& m);

/// Tets incident to vertex v, found by walking face adjacency from
/// m.vert2tet[v]. Visits each tet once; O(size of the ball). Requires valid
/// adjacency. `out` is cleared first.
void collect_ball(const TetMesh& m, VertId v, std::vector<TetId>& out);

/// The tets around edge (a,b) in cyclic order (the edge's shell), starting at
/// `start` (a tet containing both a and b). If the edge is on the hull the
/// walk starts at one hull face, so the order is still a contiguous fan;
/// `closed` reports whether the shell is a full cycle. O(size of the shell).
struct Shell {
  std::vector<TetId> tets;
  bool closed = false;
};
Shell collect_shell(const TetMesh& m, VertId a, VertId b, TetId start);

/// Iterates the ball of a vertex without allocating per call beyond the
/// reused buffers: for (TetId t : BallRange(m, v, scratch)).
class BallRange {
 public:
  BallRange(const TetMesh& m, VertId v, std::vector<TetId>& scratch) : tets_(scratch) {
    collect_ball(m, v, scratch);
  }
  auto begin() const { return tets_.begin(); }
  auto end() const { return tets_.end(); }
  std::size_t size() const { return tets_.size(); }

 private:
  const std::vector<TetId>& tets_;
};

/// Local index (0..3) of vertex v in tet t, or -1.
inline int local_index(const TetMesh& m, TetId t, VertId v) {
  const auto& tv = m.tet2verts[t];
  for (int k = 0; k < 4; ++k)
    if (tv[k] == v) return k;
  return -1;
}

}  // namespace cm::mesh
