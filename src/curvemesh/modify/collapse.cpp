#include "curvemesh/modify/collapse.hpp"

#include <algorithm>

#include "curvemesh/core/error.hpp"
#include "curvemesh/mesh/adjacency.hpp"
#include "curvemesh/mesh/topology.hpp"
#include "curvemesh/modify/measure.hpp"

namespace cm::modify {

namespace {

std::uint64_t pair_key(VertId x, VertId y) {
  return x < y ? (std::uint64_t{x} << 32 | y) : (std::uint64_t{y} << 32 | x);
}

template <class T>
void sort_unique(std::vector<T>& v) {
  std::sort(v.begin(), v.end());
  v.erase(std::unique(v.begin(), v.end()), v.end());
}

template <class T>
bool contains(const std::vector<T>& sorted, const T& x) {
  return std::binary_search(sorted.begin(), sorted.end(), x);
}

bool has(const std::array<VertId, 4>& tv, VertId v) { return std::find(tv.begin(), tv.end(), v) != tv.end(); }

// Scratch reused across calls: balls are tens of tets.
struct Scratch {
  std::vector<TetId> ball_a, ball_b;
  std::vector<VertId> ring, near_a, near_b, surf_a, surf_b, apexes;
  std::vector<std::uint64_t> link_b, link_ab;
  std::vector<Index> tris_a, tris_b;
};

// Surface neighbours of v: the other vertices of its triangles.
void surface_neighbours(const mesh::TetMesh& m, VertId v, const std::vector<Index>& tris, std::vector<VertId>& out) {
  out.clear();
  for (Index i : tris)
    for (VertId x : m.tris[i].verts)
      if (x != v) out.push_back(x);
  sort_unique(out);
}

std::array<VertId, 3> moved(std::array<VertId, 3> t, VertId from, VertId to) {
  for (VertId& v : t)
    if (v == from) v = to;
  return t;
}

// Whether removing a into b leaves the surface as it is (see
// CollapsePlan::keeps_surface). `tris` are the classified triangles through
// a.
bool keeps_surface(const mesh::TetMesh& m, const BoundaryIndex& surf, VertId a, VertId b,
                   const std::vector<Index>& tris, const std::vector<VertId>& near_a) {
  if (!flat_per_face(m, tris)) return false;
  if (m.vert_class[a].dim != 1) return true;
  for (VertId x : near_a)
    if (x != b)
      if (const Index e = surf.find_edge(a, x); e != kNone && !collinear(m.coords[x], m.coords[a], m.coords[b]))
        return false;
  return true;
}

bool classification_allows(const mesh::TetMesh& m, const BoundaryIndex& surf, VertId a, VertId b,
                           const std::vector<TetId>& ball_a) {
  const mesh::ModelRef ca = m.vert_class[a], cb = m.vert_class[b];
  const Index edge = surf.find_edge(a, b);
  switch (ca.dim) {
    case 1:
      // Along the model edge, onto a vertex of it or an end vertex.
      return edge != kNone && m.edges[edge].edge_tag == ca.tag && (cb == ca || cb.dim == 0);
    case 2: {
      if (edge != kNone || cb.dim > 2 || (cb.dim == 2 && cb != ca)) return false;
      // The edge must be a side of a triangle of a's face.
      for (TetId t : ball_a) {
        if (mesh::local_index(m, t, b) < 0) continue;
        for (VertId r : m.tet2verts[t]) {
          if (r == a || r == b) continue;
          const Index i = surf.find_tri(a, b, r);
          if (i != kNone && m.tris[i].face_tag == ca.tag) return true;
        }
      }
      return false;
    }
    case 3: return true;
    default: return false;  // model vertices stay; unclassified vertices are not understood
  }
}

}  // namespace

CollapsePlan plan_collapse(MeshEditor& ed, Cavity& cav, const BoundaryIndex& surf, VertId a, VertId b,
                           const geom::Model* model) {
  const auto& m = ed.mesh();
  CollapsePlan plan;
  plan.from = a;
  plan.to = b;
  CM_ASSERT(a != b && m.vert2tet[a] != kNone && m.vert2tet[b] != kNone);
  thread_local Scratch s;
  mesh::collect_ball(m, a, s.ball_a);
  bool joined = false;
  for (TetId t : s.ball_a) joined |= mesh::local_index(m, t, b) >= 0;
  CM_ASSERT(joined);

  if (!classification_allows(m, surf, a, b, s.ball_a)) {
    plan.refusal = Refusal::kClassification;
    return plan;
  }

  cav.reset(ed);
  for (TetId t : s.ball_a) {
    cav.add(ed, t);
    const int ia = mesh::local_index(m, t, a);
    for (int f = 0; f < 4; ++f)
      if (f != ia && m.tet2adj[mesh::pack_face(t, f)] == kNone) plan.on_hull = true;
  }
  plan.before = min_quality(m, s.ball_a);

  // Link condition. Ring: the link of (a, b), as vertices and as edges.
  mesh::collect_ball(m, b, s.ball_b);
  s.ring.clear();
  s.near_a.clear();
  s.near_b.clear();
  s.link_ab.clear();
  s.link_b.clear();
  for (TetId t : s.ball_a) {
    const auto& tv = m.tet2verts[t];
    const bool shell = has(tv, b);
    std::array<VertId, 3> o{};
    int k = 0;
    for (VertId v : tv)
      if (v != a) {
        s.near_a.push_back(v);
        o[static_cast<std::size_t>(k++)] = v;
      }
    if (!shell) continue;
    for (VertId v : o)
      if (v != b) s.ring.push_back(v);
    const std::array<VertId, 2> e = o[0] == b ? std::array{o[1], o[2]} : o[1] == b ? std::array{o[0], o[2]} : std::array{o[0], o[1]};
    s.link_ab.push_back(pair_key(e[0], e[1]));
  }
  for (TetId t : s.ball_b) {
    const auto& tv = m.tet2verts[t];
    std::array<VertId, 3> o{};
    int k = 0;
    for (VertId v : tv)
      if (v != b) {
        s.near_b.push_back(v);
        o[static_cast<std::size_t>(k++)] = v;
      }
    for (int i = 0; i < 3; ++i) s.link_b.push_back(pair_key(o[static_cast<std::size_t>(i)], o[static_cast<std::size_t>((i + 1) % 3)]));
  }
  sort_unique(s.ring);
  sort_unique(s.near_a);
  sort_unique(s.near_b);
  sort_unique(s.link_ab);
  sort_unique(s.link_b);
  for (VertId x : s.near_a)
    if (x != b && contains(s.near_b, x) && !contains(s.ring, x)) {
      plan.refusal = Refusal::kNonManifold;
      return plan;
    }
  for (TetId t : s.ball_a) {
    const auto& tv = m.tet2verts[t];
    if (has(tv, b)) continue;
    const int ia = mesh::local_index(m, t, a);
    for (int i = 1; i < 4; ++i)
      for (int j = i + 1; j < 4; ++j) {
        const std::uint64_t e = pair_key(tv[static_cast<std::size_t>((ia + i) % 4)], tv[static_cast<std::size_t>((ia + j) % 4)]);
        if (contains(s.link_b, e) && !contains(s.link_ab, e)) {
          plan.refusal = Refusal::kNonManifold;
          return plan;
        }
      }
  }
  // On the surface: neighbours shared by a and b must be apexes of the
  // triangles through (a, b); nothing may come out twice.
  tris_through(m, surf, a, s.ball_a, s.tris_a);
  if (!s.tris_a.empty()) {
    tris_through(m, surf, b, s.ball_b, s.tris_b);
    surface_neighbours(m, a, s.tris_a, s.surf_a);
    surface_neighbours(m, b, s.tris_b, s.surf_b);
    s.apexes.clear();
    for (Index i : s.tris_a) {
      const auto& tv = m.tris[i].verts;
      if (std::find(tv.begin(), tv.end(), b) == tv.end()) continue;
      for (VertId x : tv)
        if (x != a && x != b) s.apexes.push_back(x);
    }
    sort_unique(s.apexes);
    for (VertId x : s.surf_a)
      if (x != b && contains(s.surf_b, x) && !contains(s.apexes, x)) {
        plan.refusal = Refusal::kNonManifold;
        return plan;
      }
    for (Index i : s.tris_a) {
      const auto& tv = m.tris[i].verts;
      if (std::find(tv.begin(), tv.end(), b) != tv.end()) continue;
      const auto nv = moved(tv, a, b);
      if (surf.find_tri(nv[0], nv[1], nv[2]) != kNone) {
        plan.refusal = Refusal::kNonManifold;
        return plan;
      }
    }
  }
  for (VertId x : s.near_a)
    if (const Index e = surf.find_edge(a, x); e != kNone && x != b && surf.find_edge(b, x) != kNone) {
      plan.refusal = Refusal::kNonManifold;
      return plan;
    }

  // Validity of what survives.
  plan.after = 1;
  for (TetId t : s.ball_a) {
    auto tv = m.tet2verts[t];
    if (has(tv, b)) continue;
    for (VertId& v : tv)
      if (v == a) v = b;
    plan.after = std::min(plan.after, tet_quality(m, tv));
  }
  if (!(plan.after > 0)) {
    plan.refusal = Refusal::kNotStarShaped;
    return plan;
  }

  // The moved triangles keep their side.
  for (Index i : s.tris_a) {
    const auto& tri = m.tris[i];
    if (std::find(tri.verts.begin(), tri.verts.end(), b) != tri.verts.end()) continue;
    const auto nv = moved(tri.verts, a, b);
    const Vec3 &x0 = m.coords[tri.verts[0]], &x1 = m.coords[tri.verts[1]], &x2 = m.coords[tri.verts[2]];
    const Vec3 &y0 = m.coords[nv[0]], &y1 = m.coords[nv[1]], &y2 = m.coords[nv[2]];
    if (!(tri_normal(y0, y1, y2).dot(tri_normal(x0, x1, x2)) > 0)) {
      plan.refusal = Refusal::kFoldedSurface;
      return plan;
    }
    if (model) {
      // Judged as the boundary check will judge it, whatever the triangle
      // did before.
      if (!agrees_with_model(*model, tri.face_tag, y0, y1, y2, check_hint(m, nv, tri.face_tag))) {
        plan.refusal = Refusal::kFoldedSurface;
        return plan;
      }
    }
  }
  plan.keeps_surface = s.tris_a.empty() || keeps_surface(m, surf, a, b, s.tris_a, s.near_a);
  return plan;
}

std::span<const TetId> apply(MeshEditor& ed, Cavity& cav, BoundaryIndex& surf, const CollapsePlan& plan) {
  // The hook runs once m.tris and m.edges follow the collapse too.
  const MeshEditor::DeferredHook defer(ed);
  auto& m = ed.mesh();
  const VertId a = plan.from, b = plan.to;
  thread_local std::vector<NewTet> fill;
  thread_local std::vector<std::array<VertId, 3>> marked;  // faces through b to mark afterwards
  thread_local std::vector<TetId> ball;
  thread_local std::vector<Index> tris, edges;
  fill.clear();
  marked.clear();
  for (TetId t : cav.tets()) {
    const auto& tv = m.tet2verts[t];
    const int ia = mesh::local_index(m, t, a);
    for (int f = 0; f < 4; ++f) {
      if (f == ia || !ed.face_marked(mesh::pack_face(t, f))) continue;
      const auto& fv = mesh::kFaceVerts[static_cast<std::size_t>(f)];
      const std::array<VertId, 3> face{tv[fv[0]], tv[fv[1]], tv[fv[2]]};
      if (std::find(face.begin(), face.end(), b) == face.end()) marked.push_back(moved(face, a, b));
    }
    if (has(tv, b)) continue;
    NewTet nt{tv, m.tet_region[t]};
    for (VertId& v : nt.verts)
      if (v == a) v = b;
    fill.push_back(nt);
  }

  // The boundary entities through a, found before the ball goes.
  ball.assign(cav.tets().begin(), cav.tets().end());
  tris_through(m, surf, a, ball, tris);
  edges.clear();
  for (TetId t : ball)
    for (VertId x : m.tet2verts[t])
      if (x != a)
        if (const Index e = surf.find_edge(a, x); e != kNone) edges.push_back(e);
  sort_unique(edges);

  cav.compute_boundary(ed);
  const auto created = plan.on_hull ? rebuild_open(ed, cav, fill) : rebuild(ed, cav, fill);

  // Moves before removals, and removals from the highest index down: a
  // removal moves the last entry into the hole.
  for (Index i : tris) {
    const auto& tv = m.tris[i].verts;
    if (std::find(tv.begin(), tv.end(), b) == tv.end()) surf.set_tri(i, moved(tv, a, b));
  }
  for (auto it = tris.rbegin(); it != tris.rend(); ++it) {
    const auto& tv = m.tris[*it].verts;
    if (std::find(tv.begin(), tv.end(), a) != tv.end()) surf.remove_tri(*it);
  }
  for (Index i : edges) {
    const auto& ev = m.edges[i].verts;
    if (ev[0] != b && ev[1] != b) surf.set_edge(i, {ev[0] == a ? b : ev[0], ev[1] == a ? b : ev[1]});
  }
  for (auto it = edges.rbegin(); it != edges.rend(); ++it) {
    const auto& ev = m.edges[*it].verts;
    if (ev[0] == a || ev[1] == a) surf.remove_edge(*it);
  }

  // Marked faces through a are now faces through b, inside the new fill or
  // (when a tet against the hull went) faces of tets outside it.
  if (!marked.empty()) {
    mesh::collect_ball(m, b, ball);
    for (const auto& face : marked)
      for (TetId t : ball) {
        const int i0 = mesh::local_index(m, t, face[0]), i1 = mesh::local_index(m, t, face[1]),
                  i2 = mesh::local_index(m, t, face[2]);
        if (i0 < 0 || i1 < 0 || i2 < 0) continue;
        ed.mark_face(mesh::pack_face(t, 6 - i0 - i1 - i2));
        break;
      }
  }
  return created;
}

}  // namespace cm::modify
