#include "curvemesh/mesh/classification.hpp"

#include <algorithm>
#include <map>
#include <numeric>
#include <set>

#include "curvemesh/core/error.hpp"

namespace cm::mesh {

namespace {

using TriKey = std::array<VertId, 3>;
using EdgeKey = std::pair<VertId, VertId>;

TriKey sorted_key(const std::array<VertId, 3>& v) {
  TriKey k = v;
  std::sort(k.begin(), k.end());
  return k;
}

std::int32_t max_tag(const std::vector<std::int32_t>& tags, std::int32_t floor) {
  std::int32_t best = floor;
  for (auto t : tags) best = std::max(best, t);
  return best;
}

// Adds the hull faces and region interfaces that m.tris does not classify.
// New tags are given per pair of regions (outside = none), in order of first
// appearance over the tets, so the result is deterministic.
void add_missing_boundary_faces(TetMesh& m) {
  std::set<TriKey> known;
  std::vector<std::int32_t> tags;
  for (const auto& tr : m.tris) {
    known.insert(sorted_key(tr.verts));
    tags.push_back(tr.face_tag);
  }
  std::int32_t next_tag = max_tag(tags, 0) + 1;
  std::map<std::pair<std::int32_t, std::int64_t>, std::int32_t> tag_of_pair;
  for (TetId t = 0; t < m.num_tets(); ++t)
    for (int f = 0; f < 4; ++f) {
      const Index adj = m.tet2adj[pack_face(t, f)];
      const std::int32_t r = m.tet_region[t];
      std::int64_t other = INT64_MIN;  // outside the mesh
      if (adj != kNone) {
        const TetId u = face_tet(adj);
        if (m.tet_region[u] == r) continue;
        // An interface face is owned by the tet with the smaller region tag.
        if (m.tet_region[u] < r) continue;
        other = m.tet_region[u];
      }
      const auto& tv = m.tet2verts[t];
      const std::array<VertId, 3> tri{tv[kFaceVerts[f][0]], tv[kFaceVerts[f][1]], tv[kFaceVerts[f][2]]};
      if (known.count(sorted_key(tri))) continue;
      auto [it, inserted] = tag_of_pair.try_emplace({r, other}, next_tag);
      if (inserted) ++next_tag;
      m.tris.push_back({tri, it->second});
    }
}

struct UnionFind {
  std::vector<std::size_t> parent;
  explicit UnionFind(std::size_t n) : parent(n) { std::iota(parent.begin(), parent.end(), 0); }
  std::size_t find(std::size_t x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  }
  void unite(std::size_t a, std::size_t b) {
    a = find(a);
    b = find(b);
    if (a != b) parent[std::max(a, b)] = std::min(a, b);
  }
};

// Feature edges: where triangles of different model faces meet or where the
// surface is not a 2-manifold. Those not yet in m.edges are grouped into new
// model edges: connected chains through vertices of feature degree 2 whose
// edges see the same set of model faces.
void add_missing_feature_edges(TetMesh& m) {
  std::vector<std::pair<EdgeKey, std::int32_t>> tri_edges;
  tri_edges.reserve(3 * m.tris.size());
  for (const auto& tr : m.tris)
    for (const auto& e : kTriEdges)
      tri_edges.push_back({std::minmax(tr.verts[e[0]], tr.verts[e[1]]), tr.face_tag});
  std::sort(tri_edges.begin(), tri_edges.end());

  std::map<EdgeKey, std::int32_t> known;
  std::vector<std::int32_t> tags;
  for (const auto& e : m.edges) {
    known[std::minmax(e.verts[0], e.verts[1])] = e.edge_tag;
    tags.push_back(e.edge_tag);
  }
  struct Candidate {
    EdgeKey key;
    std::vector<std::int32_t> faces;
  };
  std::vector<Candidate> cands;
  for (std::size_t i = 0; i < tri_edges.size();) {
    std::size_t j = i;
    std::vector<std::int32_t> faces;
    while (j < tri_edges.size() && tri_edges[j].first == tri_edges[i].first) faces.push_back(tri_edges[j++].second);
    const std::size_t uses = j - i;
    faces.erase(std::unique(faces.begin(), faces.end()), faces.end());
    if ((uses != 2 || faces.size() > 1) && !known.count(tri_edges[i].first))
      cands.push_back({tri_edges[i].first, std::move(faces)});
    i = j;
  }
  if (cands.empty()) return;

  std::map<VertId, int> degree;
  for (const auto& [key, tag] : known) ++degree[key.first], ++degree[key.second];
  for (const auto& c : cands) ++degree[c.key.first], ++degree[c.key.second];
  // Join candidates that share a degree-2 vertex and see the same faces.
  std::map<VertId, std::vector<std::size_t>> at_vertex;
  for (std::size_t i = 0; i < cands.size(); ++i) {
    at_vertex[cands[i].key.first].push_back(i);
    at_vertex[cands[i].key.second].push_back(i);
  }
  UnionFind uf(cands.size());
  for (const auto& [v, list] : at_vertex)
    if (degree[v] == 2 && list.size() == 2 && cands[list[0]].faces == cands[list[1]].faces) uf.unite(list[0], list[1]);

  std::int32_t next_tag = max_tag(tags, 0) + 1;
  std::map<std::size_t, std::int32_t> tag_of_root;
  for (std::size_t i = 0; i < cands.size(); ++i) {
    auto [it, inserted] = tag_of_root.try_emplace(uf.find(i), next_tag);
    if (inserted) ++next_tag;
    m.edges.push_back({{cands[i].key.first, cands[i].key.second}, it->second});
  }
}

void classify_vertices(TetMesh& m) {
  const std::size_t nv = m.num_verts();
  std::vector<std::vector<std::int32_t>> edge_tags(nv);
  for (const auto& e : m.edges)
    for (VertId v : e.verts) edge_tags[v].push_back(e.edge_tag);
  std::vector<std::int32_t> face_tag(nv, INT32_MIN);
  std::vector<char> multi_face(nv, 0);
  for (const auto& tr : m.tris)
    for (VertId v : tr.verts) {
      if (face_tag[v] != INT32_MIN && face_tag[v] != tr.face_tag) multi_face[v] = 1;
      face_tag[v] = tr.face_tag;
    }
  std::int32_t next_point = 1;
  for (VertId v = 0; v < nv; ++v) {
    auto& et = edge_tags[v];
    ModelRef c;
    if (!et.empty()) {
      if (et.size() == 2 && et[0] == et[1])
        c = {1, et[0]};
      else
        c = {0, next_point++};
    } else if (face_tag[v] != INT32_MIN) {
      c = multi_face[v] ? ModelRef{0, next_point++} : ModelRef{2, face_tag[v]};
    } else {
      // Interior vertex, or one used by no tet at all (tag 0 then).
      c = {3, m.vert2tet[v] != kNone ? m.tet_region[m.vert2tet[v]] : 0};
    }
    // Parameters belong to the entity they were given on.
    if (c != m.vert_class[v]) m.vert_param[v] = Param{};
    m.vert_class[v] = c;
  }
}

void rebuild_entities(TetMesh& m) {
  std::map<ModelRef, std::set<std::int32_t>> bounding;
  std::map<ModelRef, EntityInfo> previous;
  for (auto& e : m.entities) previous[{e.dim, e.tag}] = e;
  for (VertId v = 0; v < m.num_verts(); ++v)
    if (m.vert_class[v].dim == 0) bounding[m.vert_class[v]];
  for (const auto& e : m.edges) {
    auto& b = bounding[{1, e.edge_tag}];
    for (VertId v : e.verts)
      if (m.vert_class[v].dim == 0) b.insert(m.vert_class[v].tag);
  }
  std::map<EdgeKey, std::int32_t> edge_tag;
  for (const auto& e : m.edges) edge_tag[std::minmax(e.verts[0], e.verts[1])] = e.edge_tag;
  std::map<TriKey, std::int32_t> tri_tag;
  for (const auto& tr : m.tris) {
    auto& b = bounding[{2, tr.face_tag}];
    tri_tag[sorted_key(tr.verts)] = tr.face_tag;
    for (const auto& te : kTriEdges) {
      auto it = edge_tag.find(std::minmax(tr.verts[te[0]], tr.verts[te[1]]));
      if (it != edge_tag.end()) b.insert(it->second);
    }
  }
  for (TetId t = 0; t < m.num_tets(); ++t) {
    auto& b = bounding[{3, m.tet_region[t]}];
    const auto& tv = m.tet2verts[t];
    for (int f = 0; f < 4; ++f) {
      const Index adj = m.tet2adj[pack_face(t, f)];
      if (adj != kNone && m.tet_region[face_tet(adj)] == m.tet_region[t]) continue;
      auto it = tri_tag.find(sorted_key({tv[kFaceVerts[f][0]], tv[kFaceVerts[f][1]], tv[kFaceVerts[f][2]]}));
      if (it != tri_tag.end()) b.insert(it->second);
    }
  }
  m.entities.clear();
  for (const auto& [ref, tags] : bounding) {
    EntityInfo info;
    auto it = previous.find(ref);
    if (it != previous.end()) info = it->second;
    info.dim = ref.dim;
    info.tag = ref.tag;
    // Keep signed bounding lists from the file when they cover what the mesh shows.
    std::set<std::int32_t> old;
    for (auto b : info.bounding) old.insert(b < 0 ? -b : b);
    if (!std::includes(old.begin(), old.end(), tags.begin(), tags.end())) info.bounding.assign(tags.begin(), tags.end());
    m.entities.push_back(std::move(info));
  }
}

}  // namespace

bool is_fully_classified(const TetMesh& m) {
  if (m.vert_class.size() != m.num_verts()) return false;
  return std::all_of(m.vert_class.begin(), m.vert_class.end(), [](const ModelRef& r) { return r.valid(); });
}

void derive_classification(TetMesh& m) {
  CM_ASSERT_OP(m.tet2adj.size(), ==, 4 * m.num_tets());
  m.resize_vertex_arrays();
  const std::size_t tris_before = m.tris.size();
  const std::size_t edges_before = m.edges.size();
  add_missing_boundary_faces(m);
  add_missing_feature_edges(m);
  const bool changed = m.tris.size() != tris_before || m.edges.size() != edges_before;
  if (changed || !is_fully_classified(m)) classify_vertices(m);
  rebuild_entities(m);
}

}  // namespace cm::mesh
