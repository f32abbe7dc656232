#pragma once
// Invariant checks shared by the operator tests.
#include <gtest/gtest.h>

#include <algorithm>
#include <map>

#include "curvemesh/core/predicates.hpp"
#include "curvemesh/mesh/adjacency.hpp"
#include "curvemesh/mesh/topology.hpp"
#include "curvemesh/modify/mesh_editor.hpp"

namespace cm::test {

using modify::MeshEditor;

// Every invariant the editor promises, checked from scratch.
inline void expect_invariants(const MeshEditor& ed, double volume) {
  const auto& m = ed.mesh();
  double vol = 0;
  std::map<std::array<VertId, 3>, int> faces;
  for (TetId t = 0; t < m.tet2verts.size(); ++t) {
    if (ed.is_dead(t)) continue;
    const auto& tv = m.tet2verts[t];
    ASSERT_GT(predicates::orient3d(m.coords[tv[0]].data(), m.coords[tv[1]].data(), m.coords[tv[2]].data(),
                                   m.coords[tv[3]].data()),
              0)
        << "tet " << t;
    vol += mesh::tet_volume(m, t);
    for (int f = 0; f < 4; ++f) {
      const Index a = m.tet2adj[4 * t + f];
      const auto& fv = mesh::kFaceVerts[f];
      std::array<VertId, 3> key{tv[fv[0]], tv[fv[1]], tv[fv[2]]};
      std::sort(key.begin(), key.end());
      ++faces[key];
      if (a == kNone) continue;
      const TetId n = mesh::face_tet(a);
      ASSERT_FALSE(ed.is_dead(n)) << "tet " << t << " points to a dead tet";
      ASSERT_EQ(m.tet2adj[a], mesh::pack_face(t, f)) << "adjacency not symmetric at tet " << t;
      const auto& nv = m.tet2verts[n];
      const auto& nfv = mesh::kFaceVerts[mesh::face_index(a)];
      std::array<VertId, 3> nkey{nv[nfv[0]], nv[nfv[1]], nv[nfv[2]]};
      std::sort(nkey.begin(), nkey.end());
      ASSERT_EQ(key, nkey) << "neighbours do not share the face";
    }
  }
  for (const auto& [k, c] : faces) ASSERT_LE(c, 2);
  EXPECT_NEAR(vol, volume, 1e-9 * volume);
  for (VertId v = 0; v < m.coords.size(); ++v) {
    const TetId s = m.vert2tet[v];
    if (s == kNone) continue;
    ASSERT_FALSE(ed.is_dead(s)) << "vertex " << v;
    ASSERT_GE(mesh::local_index(m, s, v), 0) << "vertex " << v;
  }
}

}  // namespace cm::test
