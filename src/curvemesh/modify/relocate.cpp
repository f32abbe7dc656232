#include "curvemesh/modify/relocate.hpp"

#include <algorithm>

#include "curvemesh/mesh/adjacency.hpp"
#include "curvemesh/mesh/topology.hpp"
#include "curvemesh/modify/measure.hpp"

namespace cm::modify {

Relocation plan_relocation(MeshEditor& ed, Cavity& cav, VertId v) {
  auto& m = ed.mesh();
  Relocation r;
  if (v >= m.vert_class.size() || m.vert_class[v].dim != 3 || m.vert2tet[v] == kNone) {
    r.refusal = Refusal::kClassification;
    return r;
  }
  thread_local std::vector<TetId> ball;
  mesh::collect_ball(m, v, ball);
  cav.reset(ed);
  Vec3 centroid = Vec3::Zero();
  int count = 0;
  for (TetId t : ball) {
    cav.add(ed, t);
    for (VertId w : m.tet2verts[t])
      if (w != v) {
        centroid += m.coords[w];
        ++count;
      }
  }
  centroid /= count;
  r.before = min_quality(m, ball);
  r.after = r.before;
  const Vec3 old = m.coords[v];
  r.target = old;
  for (double w : {1.0, 0.5, 0.25}) {
    m.coords[v] = old + w * (centroid - old);
    const double q = min_quality_above(m, ball, r.after);
    if (q > r.after) {
      r.after = q;
      r.target = m.coords[v];
    }
  }
  m.coords[v] = old;
  if (!(r.after > r.before + 1e-6)) r.refusal = Refusal::kNoImprovement;
  return r;
}

namespace {

struct Candidate {
  Vec3 point;
  Vec2 param;
  double quality;
};

// A boundary triangle through the moving vertex, as it was.
struct TriBefore {
  Index tri;
  Vec3 normal;
  // With its model face: -1 until asked. A projection on the model each, the
  // planners' dearest step, so only for the triangles a candidate's check
  // reaches (most planned moves find no candidate or fail on the orientation).
  signed char agrees = -1;
};

// Whether x agreed with its model face before v moved from `old`.
bool agreed_before(const mesh::TetMesh& m, const geom::Model& model, TriBefore& x, VertId v, const Vec3& old) {
  if (x.agrees < 0) {
    const auto& tv = m.tris[x.tri].verts;
    std::array<Vec3, 3> p;
    for (std::size_t k = 0; k < 3; ++k) p[k] = tv[k] == v ? old : m.coords[tv[k]];
    const int f = m.tris[x.tri].face_tag;
    x.agrees = agrees_with_model(model, f, p[0], p[1], p[2], check_hint(m, tv, f)) ? 1 : 0;
  }
  return x.agrees == 1;
}

}  // namespace

Relocation plan_relocation(MeshEditor& ed, Cavity& cav, const BoundaryIndex& surf, VertId v, const geom::Model* model) {
  auto& m = ed.mesh();
  if (v < m.vert_class.size() && m.vert_class[v].dim == 3) return plan_relocation(ed, cav, v);
  Relocation r;
  const mesh::ModelRef c = v < m.vert_class.size() ? m.vert_class[v] : mesh::ModelRef{};
  if (!model || (c.dim != 1 && c.dim != 2) || m.vert2tet[v] == kNone) {
    r.refusal = Refusal::kClassification;
    return r;
  }
  const geom::EntityRef entity{c.dim, c.tag};
  thread_local std::vector<TetId> ball;
  thread_local std::vector<TriBefore> tris;
  thread_local std::vector<Candidate> candidates;
  mesh::collect_ball(m, v, ball);
  cav.reset(ed);
  Vec3 centroid = Vec3::Zero();
  int count = 0;
  tris.clear();
  for (TetId t : ball) {
    cav.add(ed, t);
    const auto& tv = m.tet2verts[t];
    for (VertId w : tv)
      if (w != v) {
        centroid += m.coords[w];
        ++count;
      }
    // The faces through v: the boundary triangles among them.
    const int iv = mesh::local_index(m, t, v);
    for (int f = 0; f < 4; ++f) {
      if (f == iv) continue;
      const auto& fv = mesh::kFaceVerts[static_cast<std::size_t>(f)];
      const Index i = surf.find_tri(tv[fv[0]], tv[fv[1]], tv[fv[2]]);
      if (i != kNone && std::none_of(tris.begin(), tris.end(), [i](const TriBefore& x) { return x.tri == i; }))
        tris.push_back({i, Vec3::Zero()});
    }
  }
  centroid /= count;
  // The neighbours along the entity: of v's triangles on a face, of v's
  // model-edge edges on an edge.
  Vec3 along = Vec3::Zero();
  int along_count = 0;
  if (c.dim == 2) {
    for (const TriBefore& x : tris)
      for (VertId w : m.tris[x.tri].verts)
        if (w != v) {
          along += m.coords[w];
          ++along_count;
        }
  } else {
    std::array<VertId, 2> seen{kNone, kNone};  // a vertex inside a model edge has two neighbours on it
    for (TetId t : ball)
      for (VertId w : m.tet2verts[t])
        if (w != v && w != seen[0] && w != seen[1] && along_count < 2)
          if (const Index e = surf.find_edge(v, w); e != kNone && m.edges[e].edge_tag == c.tag) {
            seen[static_cast<std::size_t>(along_count++)] = w;
            along += m.coords[w];
          }
  }
  r.before = min_quality(m, ball);
  r.after = r.before;
  const Vec3 old = m.coords[v];
  r.target = old;

  // Where v is on its entity, and the tangent space there.
  const mesh::Param& own = m.vert_param[v];
  Vec2 param;
  if (own.has_u() && (c.dim == 1 || !std::isnan(own.v))) {
    param = Vec2(own.u, c.dim == 1 ? 0.0 : own.v);
  } else {
    param = model->closest_point(entity, old).param;
  }
  const std::optional<Vec2> hint = param;
  auto tangential = [&](const Vec3& d) -> Vec3 {
    if (c.dim == 2) {
      const Vec3 n = model->face_normal(c.tag, param);
      return d - d.dot(n) * n;
    }
    const Vec3 t = model->edge_derivatives(c.tag, param.x()).d1;
    const double len2 = t.squaredNorm();
    return len2 > 0 ? Vec3(t * (d.dot(t) / len2)) : Vec3::Zero();
  };
  for (TriBefore& x : tris) {
    const auto& tv = m.tris[x.tri].verts;
    x.normal = tri_normal(m.coords[tv[0]], m.coords[tv[1]], m.coords[tv[2]]);
  }

  candidates.clear();
  std::array<Vec3, 2> goals{centroid, along_count ? Vec3(along / along_count) : centroid};
  for (const Vec3& goal : goals) {
    const Vec3 d = tangential(goal - old);
    if (!(d.squaredNorm() > 0)) continue;
    for (double w : {1.0, 0.5, 0.25}) {
      const geom::Projection p = model->closest_point(entity, old + w * d, hint);
      m.coords[v] = p.point;
      const double q = min_quality_above(m, ball, r.before + 1e-6);
      if (q > r.before + 1e-6) candidates.push_back({p.point, p.param, q});
    }
  }
  m.coords[v] = old;
  std::sort(candidates.begin(), candidates.end(),
            [](const Candidate& x, const Candidate& y) { return x.quality > y.quality; });
  r.refusal = Refusal::kNoImprovement;
  // The best candidate whose triangles keep their side; the model check is
  // the expensive one, so it runs on the winner only.
  for (const Candidate& cand : candidates) {
    m.coords[v] = cand.point;
    bool ok = true;
    for (TriBefore& x : tris) {
      const auto& tri = m.tris[x.tri];
      const Vec3 &a = m.coords[tri.verts[0]], &b = m.coords[tri.verts[1]], &d = m.coords[tri.verts[2]];
      if (!(tri_normal(a, b, d).dot(x.normal) > 0) ||
          (agreed_before(m, *model, x, v, old) &&
           !agrees_with_model(*model, tri.face_tag, a, b, d,
                              check_hint(m, tri.verts, tri.face_tag, v,
                                         c.dim == 2 ? std::optional<Vec2>(cand.param) : std::nullopt)))) {
        ok = false;
        break;
      }
    }
    m.coords[v] = old;
    if (!ok) {
      r.refusal = Refusal::kFoldedSurface;
      continue;
    }
    r.refusal = Refusal::kNone;
    r.target = cand.point;
    r.after = cand.quality;
    r.param.u = cand.param.x();
    if (c.dim == 2) r.param.v = cand.param.y();
    break;
  }
  return r;
}

Relocation plan_relocation_to(MeshEditor& ed, Cavity& cav, const BoundaryIndex* surf, VertId v,
                              const geom::Model* model, const Vec3& target, const mesh::Param& param) {
  auto& m = ed.mesh();
  Relocation r;
  const mesh::ModelRef c = v < m.vert_class.size() ? m.vert_class[v] : mesh::ModelRef{};
  const bool boundary = c.dim == 1 || c.dim == 2;
  if ((c.dim != 3 && !boundary) || m.vert2tet[v] == kNone || (boundary && (!model || !surf))) {
    r.refusal = Refusal::kClassification;
    return r;
  }
  thread_local std::vector<TetId> ball;
  thread_local std::vector<TriBefore> tris;
  mesh::collect_ball(m, v, ball);
  cav.reset(ed);
  tris.clear();
  for (TetId t : ball) {
    cav.add(ed, t);
    if (!boundary) continue;
    const auto& tv = m.tet2verts[t];
    const int iv = mesh::local_index(m, t, v);
    for (int f = 0; f < 4; ++f) {
      if (f == iv) continue;
      const auto& fv = mesh::kFaceVerts[static_cast<std::size_t>(f)];
      const Index i = surf->find_tri(tv[fv[0]], tv[fv[1]], tv[fv[2]]);
      if (i != kNone && std::none_of(tris.begin(), tris.end(), [i](const TriBefore& x) { return x.tri == i; }))
        tris.push_back({i, Vec3::Zero()});
    }
  }
  r.before = min_quality(m, ball);
  for (TriBefore& x : tris) {
    const auto& tv = m.tris[x.tri].verts;
    x.normal = tri_normal(m.coords[tv[0]], m.coords[tv[1]], m.coords[tv[2]]);
  }
  const Vec3 old = m.coords[v];
  m.coords[v] = target;
  r.after = min_quality(m, ball);
  r.target = target;
  if (!(r.after > 0)) r.refusal = Refusal::kNotStarShaped;
  const std::optional<Vec2> moved_param =
      c.dim == 2 ? std::optional<Vec2>(Vec2(param.u, param.v)) : std::optional<Vec2>();
  for (TriBefore& x : tris) {
    if (r.refusal != Refusal::kNone) break;
    const auto& tri = m.tris[x.tri];
    const Vec3 &a = m.coords[tri.verts[0]], &b = m.coords[tri.verts[1]], &d = m.coords[tri.verts[2]];
    if (!(tri_normal(a, b, d).dot(x.normal) > 0) ||
        (agreed_before(m, *model, x, v, old) && !agrees_with_model(*model, tri.face_tag, a, b, d,
                                        check_hint(m, tri.verts, tri.face_tag, v, moved_param))))
      r.refusal = Refusal::kFoldedSurface;
  }
  m.coords[v] = old;
  if (boundary) {
    r.param.u = param.u;
    if (c.dim == 2) r.param.v = param.v;
  }
  return r;
}

void apply(MeshEditor& ed, Cavity& cav, VertId v, const Relocation& plan) {
  auto& m = ed.mesh();
  // Marked faces through v inside the ball (an interface between regions, a
  // face embedded in one) are inner faces of the cavity: the kernel leaves
  // their new copies unmarked.
  thread_local std::vector<std::array<VertId, 3>> marked;
  marked.clear();
  for (TetId t : cav.tets()) {
    const auto& tv = m.tet2verts[t];
    const int iv = mesh::local_index(m, t, v);
    for (int f = 0; f < 4; ++f) {
      if (f == iv) continue;
      const Index packed = mesh::pack_face(t, f), across = m.tet2adj[packed];
      if (!ed.face_marked(packed) || across == kNone || !cav.contains(ed, mesh::face_tet(across))) continue;
      const auto& fv = mesh::kFaceVerts[static_cast<std::size_t>(f)];
      marked.push_back({tv[fv[0]], tv[fv[1]], tv[fv[2]]});
    }
  }
  m.coords[v] = plan.target;
  if (plan.param.has_u()) m.vert_param[v] = plan.param;
  cav.compute_boundary(ed);
  const auto created = fill_star(ed, cav, v);
  for (const auto& face : marked)
    for (TetId t : created) {
      const int i0 = mesh::local_index(m, t, face[0]), i1 = mesh::local_index(m, t, face[1]),
                i2 = mesh::local_index(m, t, face[2]);
      if (i0 < 0 || i1 < 0 || i2 < 0) continue;
      ed.mark_face(mesh::pack_face(t, 6 - i0 - i1 - i2));
      break;
    }
}

}  // namespace cm::modify
