#pragma once
// "Has anything around here changed since?" for the adaptation's retry rules.
// Each edit ticks the clock and stamps the vertices of the tets it created
// (feed it the editor's hook), so the question is a comparison of stamps:
// any edit of a tet, a vertex moved in it included, re-creates it and
// stamps all four of its vertices; a tet within two face steps of t shares
// at least two of t's vertices, so an edit there stamps t's too.
#include <cstdint>
#include <span>
#include <vector>

#include "curvemesh/mesh/tet_mesh.hpp"

namespace cm::optimize::detail {

struct EditClock {
  std::uint64_t now = 1;
  std::vector<std::uint64_t> vert;  ///< last edit that created a tet through each vertex

  explicit EditClock(std::size_t num_verts) : vert(num_verts, now) {}
  void tick(const mesh::TetMesh& m, std::span<const TetId> created) {
    ++now;
    if (vert.size() < m.num_verts()) vert.resize(m.num_verts(), now);
    for (TetId t : created)
      for (VertId v : m.tet2verts[t]) vert[v] = now;
  }
  /// No edit since `when` created a tet through any of these vertices.
  template <class... V>
  bool unchanged_since(std::uint64_t when, V... v) const {
    return ((v < vert.size() && vert[v] <= when) && ...);
  }
  bool tet_unchanged_since(std::uint64_t when, const std::array<VertId, 4>& v) const {
    return unchanged_since(when, v[0], v[1], v[2], v[3]);
  }
};

}  // namespace cm::optimize::detail
