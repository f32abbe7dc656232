#include "curvemesh/modify/split.hpp"

#include <algorithm>

#include "curvemesh/mesh/adjacency.hpp"
#include "curvemesh/mesh/topology.hpp"
#include "curvemesh/modify/measure.hpp"

namespace cm::modify {

namespace {

struct Placement {
  Vec3 point;
  mesh::Param param;
};

Placement place_on_model_edge(const geom::Model& g, const mesh::TetMesh& m, VertId a, VertId b, int edge) {
  const Vec3 mid = 0.5 * (m.coords[a] + m.coords[b]);
  const double half = 0.5 * (m.coords[b] - m.coords[a]).norm();
  auto ua = param_on_edge(m, &g, a, edge);
  const auto ub = param_on_edge(m, &g, b, edge, ua);
  // A model vertex closing the edge takes the end near its neighbour.
  if (!ua && ub) ua = param_on_edge(m, &g, a, edge, ub);
  else if (ua && ub && m.vert_class[a].dim == 0) ua = param_on_edge(m, &g, a, edge, ub);
  Placement p;
  if (ua && ub) {
    const auto range = g.param_range({1, edge});
    const bool straddles = range.periodic_u && std::abs(*ua - *ub) > 0.5 * range.period_u;
    if (!straddles) {
      // The mid-parameter keeps the points of a curve spread evenly in its
      // parameter; a badly parametrized curve can put it far from the
      // chord, and then the closest point serves better.
      const double u = 0.5 * (*ua + *ub);
      const Vec3 x = g.edge_point(edge, u);
      if ((x - mid).norm() <= half) {
        p.point = x;
        p.param.u = u;
        return p;
      }
    }
  }
  std::optional<Vec2> hint;
  if (ua) hint = Vec2(*ua, 0);
  else if (ub) hint = Vec2(*ub, 0);
  const geom::Projection pr = g.closest_point({1, edge}, mid, hint);
  p.point = pr.point;
  p.param.u = pr.param.x();
  return p;
}

Placement place_on_model_face(const geom::Model& g, const mesh::TetMesh& m, VertId a, VertId b, int face) {
  const Vec3 mid = 0.5 * (m.coords[a] + m.coords[b]);
  const auto pa = param_on_face(m, &g, a, face), pb = param_on_face(m, &g, b, face);
  std::optional<Vec2> hint = pa ? pa : pb;
  // Own (u, v) of both ends (not p-curve points, which may sit on the other
  // side of a seam): their midpoint is the best hint unless the pair
  // straddles a period.
  if (pa && pb && m.vert_class[a].dim == 2 && m.vert_class[b].dim == 2) {
    const auto range = g.param_range({2, face});
    const Vec2 d = *pa - *pb;
    const bool straddles = (range.periodic_u && std::abs(d.x()) > 0.5 * range.period_u) ||
                           (range.periodic_v && std::abs(d.y()) > 0.5 * range.period_v);
    if (!straddles) hint = 0.5 * (*pa + *pb);
  }
  const geom::Projection pr = g.closest_point({2, face}, mid, hint);
  Placement p;
  p.point = pr.point;
  p.param.u = pr.param.x();
  p.param.v = pr.param.y();
  return p;
}

// The other two vertices of tet t (not a, not b), in the tet's order.
std::array<VertId, 2> others(const mesh::TetMesh& m, TetId t, VertId a, VertId b) {
  std::array<VertId, 2> o{kNone, kNone};
  int k = 0;
  for (VertId v : m.tet2verts[t])
    if (v != a && v != b) o[static_cast<std::size_t>(k++)] = v;
  return o;
}

// Triangle verts rotated to (x, y, c) with {x, y} = {a, b}: the halves are
// then (x, p, c) and (p, y, c), with the orientation of the original.
std::array<VertId, 3> rotate_to_edge(std::array<VertId, 3> t, VertId a, VertId b) {
  for (int k = 0; k < 3; ++k) {
    const VertId x = t[0], y = t[1];
    if ((x == a && y == b) || (x == b && y == a)) return t;
    std::rotate(t.begin(), t.begin() + 1, t.end());
  }
  return t;
}

}  // namespace

SplitPlan plan_split(MeshEditor& ed, Cavity& cav, const BoundaryIndex& surf, VertId a, VertId b, TetId start,
                     const geom::Model* model) {
  const auto& m = ed.mesh();
  SplitPlan plan;
  plan.a = a;
  plan.b = b;
  const mesh::Shell shell = mesh::collect_shell(m, a, b, start);
  plan.on_hull = !shell.closed;
  cav.reset(ed);
  for (TetId t : shell.tets) cav.add(ed, t);
  plan.before = min_quality(m, shell.tets);

  // Classification of the edge, hence of p.
  thread_local std::vector<Index> tris;
  tris.clear();
  for (TetId t : shell.tets)
    for (VertId r : others(m, t, a, b)) {
      const Index i = surf.find_tri(a, b, r);
      if (i != kNone && std::find(tris.begin(), tris.end(), i) == tris.end()) tris.push_back(i);
    }
  const Index edge = surf.find_edge(a, b);
  if (edge != kNone) {
    plan.classification = {1, m.edges[edge].edge_tag};
  } else if (!tris.empty()) {
    const std::int32_t face = m.tris[tris.front()].face_tag;
    for (Index i : tris)
      if (m.tris[i].face_tag != face) {
        plan.refusal = Refusal::kClassification;
        return plan;
      }
    plan.classification = {2, face};
  } else {
    const std::int32_t region = m.tet_region[shell.tets.front()];
    for (TetId t : shell.tets)
      if (m.tet_region[t] != region) {
        plan.refusal = Refusal::kClassification;
        return plan;
      }
    if (plan.on_hull) {
      plan.refusal = Refusal::kClassification;
      return plan;
    }
    plan.classification = {3, region};
  }

  const Vec3 &xa = m.coords[a], &xb = m.coords[b];
  plan.point = 0.5 * (xa + xb);
  if (model && plan.classification.dim < 3) {
    const Placement p = plan.classification.dim == 1
                            ? place_on_model_edge(*model, m, a, b, plan.classification.tag)
                            : place_on_model_face(*model, m, a, b, plan.classification.tag);
    if (!((p.point - plan.point).norm() <= 0.5 * (xb - xa).norm())) {
      plan.refusal = Refusal::kNotStarShaped;
      return plan;
    }
    plan.point = p.point;
    plan.param = p.param;
  }

  // The new tets: each shell tet with b, then a, moved to p.
  plan.after = 1;
  for (TetId t : shell.tets) {
    for (VertId moved : {b, a}) {
      std::array<Vec3, 4> x;
      for (int k = 0; k < 4; ++k) {
        const VertId v = m.tet2verts[t][static_cast<std::size_t>(k)];
        x[static_cast<std::size_t>(k)] = v == moved ? plan.point : m.coords[v];
      }
      plan.after = std::min(plan.after, tet_quality_at(x[0], x[1], x[2], x[3]));
    }
  }
  if (!(plan.after > 0)) {
    plan.refusal = Refusal::kNotStarShaped;
    return plan;
  }

  // The halves of each split triangle keep its side, on the mesh and on the
  // model.
  for (Index i : tris) {
    const auto& tri = m.tris[i];
    const auto t = rotate_to_edge(tri.verts, a, b);
    const Vec3 &x = m.coords[t[0]], &y = m.coords[t[1]], &c = m.coords[t[2]];
    const Vec3 n = tri_normal(x, y, c);
    if (!(tri_normal(x, plan.point, c).dot(n) > 0) || !(tri_normal(plan.point, y, c).dot(n) > 0)) {
      plan.refusal = Refusal::kFoldedSurface;
      return plan;
    }
    if (model) {
      // Judged as the boundary check will judge the two halves, (x, p, c)
      // and (p, y, c): projected with the parameters of their last vertex
      // on the face (the new point's own when it lies on the face).
      const int f = tri.face_tag;
      std::optional<Vec2> pp;
      if (plan.classification == mesh::ModelRef{2, f}) pp = Vec2(plan.param.u, plan.param.v);
      // The hint of a vertex alone: its parameters if it is on the face.
      auto own = [&](VertId v) { return check_hint(m, {v, v, v}, f); };
      auto later = [](std::optional<Vec2> h, std::optional<Vec2> next) { return next ? next : h; };
      const auto first_half = later(later(own(t[0]), pp), own(t[2]));   // (x, p, c)
      const auto second_half = later(later(pp, own(t[1])), own(t[2]));  // (p, y, c)
      if (!agrees_with_model(*model, f, x, plan.point, c, first_half) ||
          !agrees_with_model(*model, f, plan.point, y, c, second_half)) {
        plan.refusal = Refusal::kFoldedSurface;
        return plan;
      }
    }
  }
  return plan;
}

VertId apply(MeshEditor& ed, Cavity& cav, BoundaryIndex& surf, const SplitPlan& plan) {
  // The hook runs once m.tris and m.edges are split too.
  const MeshEditor::DeferredHook defer(ed);
  auto& m = ed.mesh();
  const VertId a = plan.a, b = plan.b;
  const VertId p = m.add_vert(plan.point);
  m.vert_class[p] = plan.classification;
  m.vert_param[p] = plan.param;

  thread_local std::vector<NewTet> fill;
  thread_local std::vector<VertId> marked;  // third vertices of marked faces through (a, b)
  thread_local std::vector<Index> tris;
  fill.clear();
  marked.clear();
  tris.clear();
  for (TetId t : cav.tets()) {
    const auto tv = m.tet2verts[t];
    for (VertId moved : {b, a}) {
      NewTet nt{tv, m.tet_region[t]};
      for (VertId& v : nt.verts)
        if (v == moved) v = p;
      fill.push_back(nt);
    }
    const int ia = mesh::local_index(m, t, a), ib = mesh::local_index(m, t, b);
    for (int f = 0; f < 4; ++f) {
      if (f == ia || f == ib) continue;
      const VertId r = tv[static_cast<std::size_t>(6 - ia - ib - f)];
      if (ed.face_marked(mesh::pack_face(t, f)) && std::find(marked.begin(), marked.end(), r) == marked.end())
        marked.push_back(r);
      const Index i = surf.find_tri(a, b, r);
      if (i != kNone && std::find(tris.begin(), tris.end(), i) == tris.end()) tris.push_back(i);
    }
  }
  cav.compute_boundary(ed);
  const auto created = plan.on_hull ? rebuild_open(ed, cav, fill) : rebuild(ed, cav, fill);

  for (Index i : tris) {
    const auto t = rotate_to_edge(m.tris[i].verts, a, b);
    surf.set_tri(i, {t[0], p, t[2]});
    surf.add_tri({{p, t[1], t[2]}, m.tris[i].face_tag});
  }
  if (const Index e = surf.find_edge(a, b); e != kNone) {
    surf.set_edge(e, {a, p});
    surf.add_edge({{p, b}, m.edges[e].edge_tag});
  }
  // A marked face through (a, b) was inside the shell or on the hull: its
  // halves are new faces, which the kernel leaves unmarked.
  for (VertId r : marked)
    for (const std::array<VertId, 2> half : {std::array<VertId, 2>{a, p}, std::array<VertId, 2>{p, b}})
      for (TetId t : created) {
        const int i0 = mesh::local_index(m, t, half[0]), i1 = mesh::local_index(m, t, half[1]),
                  i2 = mesh::local_index(m, t, r);
        if (i0 < 0 || i1 < 0 || i2 < 0) continue;
        ed.mark_face(mesh::pack_face(t, 6 - i0 - i1 - i2));
        break;
      }
  return p;
}

}  // namespace cm::modify
