#include "curvemesh/mesh/adjacency.hpp"

#include <algorithm>

#include <tbb/parallel_sort.h>

#include "curvemesh/core/error.hpp"

namespace cm::mesh {

namespace {
struct FaceRecord {
  VertId v[3];
  Index packed;
  bool same_face(const FaceRecord& o) const { return v[0] == o.v[0] && v[1] == o.v[1] && v[2] == o.v[2]; }
  bool operator<(const FaceRecord& o) const {
    if (v[0] != o.v[0]) return v[0] < o.v[0];
    if (v[1] != o.v[1]) return v[1] < o.v[1];
    if (v[2] != o.v[2]) return v[2] < o.v[2];
    return packed < o.packed;
  }
};
}  // namespace

std::size_t build_adjacency(TetMesh& m) {
  const std::size_t nt = m.num_tets();
  std::vector<FaceRecord> faces(4 * nt);
  for (std::size_t t = 0; t < nt; ++t) {
    const auto& tv = m.tet2verts[t];
    for (int f = 0; f < 4; ++f) {
      FaceRecord& r = faces[4 * t + f];
      for (int k = 0; k < 3; ++k) r.v[k] = tv[kFaceVerts[f][k]];
      std::sort(r.v, r.v + 3);
      r.packed = pack_face(static_cast<TetId>(t), f);
    }
  }
  tbb::parallel_sort(faces.begin(), faces.end());
  m.tet2adj.assign(4 * nt, kNone);
  std::size_t non_manifold = 0;
  for (std::size_t i = 0; i < faces.size();) {
    std::size_t j = i + 1;
    while (j < faces.size() && faces[j].same_face(faces[i])) ++j;
    if (j - i == 2) {
      m.tet2adj[faces[i].packed] = faces[i + 1].packed;
      m.tet2adj[faces[i + 1].packed] = faces[i].packed;
    } else if (j - i > 2) {
      non_manifold += j - i;
    }
    i = j;
  }
  m.vert2tet.assign(m.num_verts(), kNone);
  for (std::size_t t = 0; t < nt; ++t)
    for (VertId v : m.tet2verts[t])
      if (v < m.vert2tet.size()) m.vert2tet[v] = static_cast<TetId>(t);
  return non_manifold;
}

void collect_ball(const TetMesh& m, VertId v, std::vector<TetId>& out) {
  out.clear();
  const TetId seed = m.vert2tet[v];
  if (seed == kNone) return;
  out.push_back(seed);
  for (std::size_t i = 0; i < out.size(); ++i) {
    const TetId t = out[i];
    const int lv = local_index(m, t, v);
    CM_DEBUG_ASSERT(lv >= 0);
    for (int f = 0; f < 4; ++f) {
      if (f == lv) continue;  // the only face of t not containing v
      const Index adj = m.tet2adj[pack_face(t, f)];
      if (adj == kNone) continue;
      const TetId n = face_tet(adj);
      // Balls are small (tens of tets), so a linear scan beats a hash set.
      if (std::find(out.begin(), out.end(), n) == out.end()) out.push_back(n);
    }
  }
}

namespace {
// Walks the shell of (a,b) from `start`, leaving each tet through the face
// (a,b,w). Appends visited tets after start; returns true if it came back to
// start (closed shell), false if it reached the hull.
bool walk_shell(const TetMesh& m, VertId a, VertId b, TetId start, VertId w, std::vector<TetId>& out) {
  TetId t = start;
  const std::size_t limit = m.num_tets() + 1;
  for (std::size_t step = 0; step < limit; ++step) {
    const auto& tv = m.tet2verts[t];
    int opposite = -1;  // local index of the vertex not in {a, b, w}
    for (int k = 0; k < 4; ++k)
      if (tv[k] != a && tv[k] != b && tv[k] != w) opposite = k;
    CM_ASSERT(opposite >= 0);
    const Index adj = m.tet2adj[pack_face(t, opposite)];
    if (adj == kNone) return false;
    const TetId u = face_tet(adj);
    if (u == start) return true;
    out.push_back(u);
    // In u the entry face is (a,b,w); the exit face is (a,b,y) with y the
    // vertex of u opposite the entry face, so the next "w" is that vertex.
    w = m.tet2verts[u][face_index(adj)];
    t = u;
  }
  throw InternalError("edge shell walk did not terminate: corrupted adjacency");
}
}  // namespace

Shell collect_shell(const TetMesh& m, VertId a, VertId b, TetId start) {
  const auto& tv = m.tet2verts[start];
  VertId others[2];
  int n = 0;
  for (VertId v : tv)
    if (v != a && v != b) others[n++] = v;
  CM_ASSERT_OP(n, ==, 2);
  Shell shell;
  std::vector<TetId> forward;
  shell.closed = walk_shell(m, a, b, start, others[0], forward);
  if (shell.closed) {
    shell.tets.push_back(start);
    shell.tets.insert(shell.tets.end(), forward.begin(), forward.end());
    return shell;
  }
  std::vector<TetId> backward;
  walk_shell(m, a, b, start, others[1], backward);
  shell.tets.assign(backward.rbegin(), backward.rend());
  shell.tets.push_back(start);
  shell.tets.insert(shell.tets.end(), forward.begin(), forward.end());
  return shell;
}

}  // namespace cm::mesh
