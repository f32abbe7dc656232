#include "curvemesh/modify/boundary_swap.hpp"

#include <algorithm>

#include "curvemesh/core/predicates.hpp"
#include "curvemesh/mesh/adjacency.hpp"
#include "curvemesh/mesh/topology.hpp"
#include "curvemesh/modify/measure.hpp"
#include "curvemesh/modify/ring_triangulation.hpp"

namespace cm::modify {

namespace {

// The face of `tv` on these three vertices, in the tet's (outward) order.
std::array<VertId, 3> oriented_face(const std::array<VertId, 4>& tv, VertId x, VertId y, VertId z) {
  for (int f = 0; f < 4; ++f)
    if (tv[f] != x && tv[f] != y && tv[f] != z) return tet_face(tv, f);
  return {x, y, z};
}

BoundarySwap refuse(BoundarySwap plan, Refusal why) {
  plan.refusal = why;
  return plan;
}

double default_measure(const mesh::TetMesh& m, const std::array<VertId, 4>& v, const void*) {
  return tet_quality(m, v);
}

bool is_edge(const mesh::TetMesh& m, VertId x, VertId y) {
  if (x >= m.vert2tet.size() || m.vert2tet[x] == kNone) return false;
  thread_local std::vector<TetId> ball;
  mesh::collect_ball(m, x, ball);
  for (TetId t : ball)
    if (mesh::local_index(m, t, y) >= 0) return true;
  return false;
}

}  // namespace

BoundarySwap plan_boundary_edge_swap(MeshEditor& ed, Cavity& cav, const BoundaryIndex& surf, VertId a, VertId b,
                                     TetId start, const geom::Model* model, SwapMeasure measure,
                                     const void* context, const BoundarySwapOptions& o) {
  const auto& m = ed.mesh();
  if (!measure) measure = default_measure;
  BoundarySwap plan;
  plan.a = a;
  plan.b = b;
  if (!model) return refuse(plan, Refusal::kConstrainedFace);
  const mesh::Shell shell = mesh::collect_shell(m, a, b, start);
  if (shell.closed) return refuse(plan, Refusal::kConstrainedFace);
  if (surf.find_edge(a, b) != kNone) return refuse(plan, Refusal::kClassification);
  const int k = static_cast<int>(shell.tets.size());
  if (k < 2 || k + 1 > kMaxRing) return refuse(plan, Refusal::kConstrainedFace);
  cav.reset(ed);
  const std::int32_t region = m.tet_region[shell.tets[0]];
  plan.before = 1;
  for (TetId t : shell.tets) {
    if (m.tet_region[t] != region) return refuse(plan, Refusal::kClassification);
    cav.add(ed, t);
    plan.before = std::min(plan.before, measure(m, m.tet2verts[t], context));
  }
  // The ring from the first hull face's apex to the last one's: tet i of
  // the fan holds ring[i] and ring[i + 1].
  std::array<VertId, kMaxRing> ring{};
  auto others = [&](TetId t) {
    std::array<VertId, 2> out{kNone, kNone};
    int n = 0;
    for (VertId v : m.tet2verts[t])
      if (v != a && v != b) out[static_cast<std::size_t>(n++)] = v;
    return out;
  };
  {
    const TetId t0 = shell.tets.front();
    const auto o0 = others(t0);
    // The apex whose face with (a, b) is on the hull comes first.
    const int opposite = mesh::local_index(m, t0, o0[1]);
    const bool first_on_hull = m.tet2adj[mesh::pack_face(t0, opposite)] == kNone;
    ring[0] = first_on_hull ? o0[0] : o0[1];
    ring[1] = first_on_hull ? o0[1] : o0[0];
    for (int i = 1; i < k; ++i) {
      const auto oi = others(shell.tets[static_cast<std::size_t>(i)]);
      ring[static_cast<std::size_t>(i + 1)] = oi[0] == ring[static_cast<std::size_t>(i)] ? oi[1] : oi[0];
    }
  }
  const VertId c = ring[0], d = ring[static_cast<std::size_t>(k)];
  plan.c = c;
  plan.d = d;
  // The two hull faces: triangles of one model face; inner faces through
  // (a, b) are none (an interface would).
  const TetId first = shell.tets.front(), last = shell.tets.back();
  const Index ti = surf.find_tri(a, b, c), tj = surf.find_tri(a, b, d);
  if (ti == kNone || tj == kNone || m.tris[ti].face_tag != m.tris[tj].face_tag)
    return refuse(plan, Refusal::kClassification);
  for (int i = 1; i < k; ++i)
    if (surf.find_tri(a, b, ring[static_cast<std::size_t>(i)]) != kNone) return refuse(plan, Refusal::kConstrainedFace);
  plan.face_tag = m.tris[ti].face_tag;
  plan.removed = {m.tris[ti].verts, m.tris[tj].verts};
  if (is_edge(m, c, d)) return refuse(plan, Refusal::kNonManifold);

  // The ring's triangles joined to a and b, oriented as in edge removal.
  const bool ccw_from_a = predicates::orient3d(m.coords[a].data(), m.coords[b].data(), m.coords[ring[0]].data(),
                                               m.coords[ring[1]].data()) < 0;
  auto tets_of = [&](int i, int kk, int j) {
    const VertId ri = ring[static_cast<std::size_t>(i)], rk = ring[static_cast<std::size_t>(kk)],
                 rj = ring[static_cast<std::size_t>(j)];
    return ccw_from_a ? std::array<std::array<VertId, 4>, 2>{{{ri, rk, rj, a}, {rk, ri, rj, b}}}
                      : std::array<std::array<VertId, 4>, 2>{{{rk, ri, rj, a}, {ri, rk, rj, b}}};
  };
  const RingTriangulation best = triangulate_ring(k + 1, [&](int i, int kk, int j, double floor) {
    const auto tv = tets_of(i, kk, j);
    const double one = measure(m, tv[0], context);
    return one <= floor ? one : std::min(one, measure(m, tv[1], context));
  });
  if (!(best.worst > 0)) return refuse(plan, Refusal::kNotStarShaped);
  plan.after = best.worst;
  for (int n = 0; n < best.count; ++n) {
    const auto& t = best.triangles[static_cast<std::size_t>(n)];
    for (const auto& tv : tets_of(t[0], t[1], t[2])) plan.fill.push_back({tv, region});
  }

  // The new triangles take the orientation convention of the old ones
  // (m.tris listing its tet's outward face order, or the reverse).
  const bool tet_order = same_cycle(plan.removed[0], oriented_face(m.tet2verts[first], a, b, c));
  if (same_cycle(plan.removed[1], oriented_face(m.tet2verts[last], a, b, d)) != tet_order)
    return refuse(plan, Refusal::kClassification);
  for (int n = 0; n < 2; ++n) {
    const VertId apex = n == 0 ? a : b;
    for (const NewTet& nt : plan.fill) {
      if (std::count_if(nt.verts.begin(), nt.verts.end(), [&](VertId v) { return v == apex || v == c || v == d; }) <
          3)
        continue;
      auto f = oriented_face(nt.verts, apex, c, d);
      if (!tet_order) std::swap(f[1], f[2]);
      plan.added[static_cast<std::size_t>(n)] = f;
      break;
    }
  }

  // Geometry, judged as the boundary check judges it.
  const int tag = plan.face_tag;
  double longest = 0;
  for (const auto& v : plan.added) {
    const Vec3 &x = m.coords[v[0]], &y = m.coords[v[1]], &z = m.coords[v[2]];
    const Vec3 n = tri_normal(x, y, z);
    for (const auto& w : plan.removed)
      if (!(n.dot(tri_normal(m.coords[w[0]], m.coords[w[1]], m.coords[w[2]])) > 0))
        return refuse(plan, Refusal::kFoldedSurface);
    if (!agrees_with_model(*model, tag, x, y, z, check_hint(m, v, tag))) return refuse(plan, Refusal::kFoldedSurface);
    longest = std::max({longest, (y - x).norm(), (z - y).norm(), (x - z).norm()});
  }
  auto distance = [&](const Vec3& x, const std::array<VertId, 3>& tri) {
    return model->closest_point({2, tag}, x, check_hint(m, tri, tag)).distance;
  };
  auto deviation = [&](const std::array<std::array<VertId, 3>, 2>& tris, VertId e0, VertId e1) {
    double dev = distance(0.5 * (m.coords[e0] + m.coords[e1]), tris[0]);
    for (const auto& t : tris) dev = std::max(dev, distance((m.coords[t[0]] + m.coords[t[1]] + m.coords[t[2]]) / 3, t));
    return dev;
  };
  const double after = deviation(plan.added, c, d), before = deviation(plan.removed, a, b);
  if (after > std::max(before, o.max_relative_deviation * longest)) return refuse(plan, Refusal::kFoldedSurface);
  if (plan.after <= plan.before) plan.refusal = Refusal::kNoImprovement;
  return plan;
}

std::span<const TetId> apply(MeshEditor& ed, Cavity& cav, BoundaryIndex& surf, const BoundarySwap& plan) {
  // The hook runs once the new triangles are in m.tris.
  const MeshEditor::DeferredHook defer(ed);
  auto& m = ed.mesh();
  std::array<Index, 2> old{surf.find_tri(plan.removed[0][0], plan.removed[0][1], plan.removed[0][2]),
                           surf.find_tri(plan.removed[1][0], plan.removed[1][1], plan.removed[1][2])};
  if (old[0] < old[1]) std::swap(old[0], old[1]);  // removing the last moves nothing
  for (Index i : old) surf.remove_tri(i);
  cav.compute_boundary(ed);
  const auto created = rebuild_open(ed, cav, plan.fill);
  for (const auto& tri : plan.added) {
    surf.add_tri({tri, plan.face_tag});
    for (TetId t : created) {
      const int i0 = mesh::local_index(m, t, tri[0]), i1 = mesh::local_index(m, t, tri[1]),
                i2 = mesh::local_index(m, t, tri[2]);
      if (i0 < 0 || i1 < 0 || i2 < 0) continue;
      ed.mark_face(mesh::pack_face(t, 6 - i0 - i1 - i2));
      break;
    }
  }
  return created;
}

}  // namespace cm::modify
