#include "curvemesh/modify/marks.hpp"

#include <algorithm>
#include <unordered_map>
#include <vector>

#include "curvemesh/mesh/topology.hpp"

namespace cm::modify {

namespace {
struct KeyHash {
  std::size_t operator()(const std::array<VertId, 3>& k) const {
    return (std::size_t{k[0]} * 0x9E3779B97F4A7C15ull) ^ (std::size_t{k[1]} * 0xC2B2AE3D27D4EB4Full) ^
           (std::size_t{k[2]} * 0x165667B19E3779F9ull);
  }
};
}  // namespace

std::size_t mark_boundary_faces(MeshEditor& ed) {
  const auto& m = ed.mesh();
  std::unordered_map<std::array<VertId, 3>, char, KeyHash> tris;
  tris.reserve(m.tris.size());
  for (const auto& t : m.tris) {
    auto k = t.verts;
    std::sort(k.begin(), k.end());
    tris.emplace(k, 0);
  }
  // Only a face whose three vertices are on boundary triangles can be one:
  // most tets have none there and skip the table.
  std::vector<char> on_tri(m.coords.size(), 0);
  for (const auto& t : m.tris)
    for (VertId v : t.verts) on_tri[v] = 1;
  for (TetId t = 0; t < m.tet2verts.size(); ++t) {
    if (ed.is_dead(t)) continue;
    const auto& tv = m.tet2verts[t];
    for (int f = 0; f < 4; ++f) {
      const Index packed = mesh::pack_face(t, f);
      const auto& fv = mesh::kFaceVerts[f];
      std::array<VertId, 3> k{tv[fv[0]], tv[fv[1]], tv[fv[2]]};
      bool listed = false;
      if (on_tri[k[0]] && on_tri[k[1]] && on_tri[k[2]]) {
        std::sort(k.begin(), k.end());
        const auto it = tris.find(k);
        if (it != tris.end()) it->second = 1;
        listed = it != tris.end();
      }
      if (listed || m.tet2adj[packed] == kNone) ed.set_face_mark_one_side(packed, true);
    }
  }
  std::size_t missing = 0;
  for (const auto& [k, found] : tris) missing += !found;
  return missing;
}

}  // namespace cm::modify
