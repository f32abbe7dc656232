#include "curvemesh/modify/swap.hpp"

#include <array>
#include <limits>

#include "curvemesh/core/predicates.hpp"
#include "curvemesh/mesh/adjacency.hpp"
#include "curvemesh/mesh/topology.hpp"
#include "curvemesh/modify/measure.hpp"
#include "curvemesh/modify/ring_triangulation.hpp"

namespace cm::modify {

namespace {

// Edge removal with `value(tri, tets, floor)` rating a ring triangle (ring
// vertices) by the two tets it makes; see triangulate_ring for the floor.
template <class Value>
Plan plan_ring_fill(MeshEditor& ed, Cavity& cav, VertId a, VertId b, TetId start, Value&& value) {
  const auto& m = ed.mesh();
  Plan plan;
  const mesh::Shell shell = mesh::collect_shell(m, a, b, start);
  const int n = static_cast<int>(shell.tets.size());
  if (!shell.closed) {
    plan.refusal = Refusal::kConstrainedFace;  // a hull edge: its faces would go
    return plan;
  }
  if (n < 3 || n > kMaxShell) {
    plan.refusal = Refusal::kNoImprovement;
    return plan;
  }
  const std::int32_t region = m.tet_region[shell.tets[0]];
  cav.reset(ed);
  for (TetId t : shell.tets) {
    if (m.tet_region[t] != region) {
      plan.refusal = Refusal::kClassification;
      return plan;
    }
    // The faces through (a, b) disappear: none may be a boundary triangle.
    const int ia = mesh::local_index(m, t, a), ib = mesh::local_index(m, t, b);
    for (int f = 0; f < 4; ++f)
      if (f != ia && f != ib && ed.face_marked(mesh::pack_face(t, f))) {
        plan.refusal = Refusal::kConstrainedFace;
        return plan;
      }
    cav.add(ed, t);
  }
  // Ring: r[k] is shared by shell tets k-1 and k.
  std::array<VertId, kMaxShell> ring{};
  auto others = [&](TetId t) {
    std::array<VertId, 2> o{kNone, kNone};
    int k = 0;
    for (VertId v : m.tet2verts[t])
      if (v != a && v != b) o[k++] = v;
    return o;
  };
  for (int k = 0; k < n; ++k) {
    const auto p = others(shell.tets[static_cast<std::size_t>(k)]);
    const auto q = others(shell.tets[static_cast<std::size_t>((k + n - 1) % n)]);
    ring[static_cast<std::size_t>(k)] = (p[0] == q[0] || p[0] == q[1]) ? p[0] : p[1];
  }
  plan.before = min_quality(m, shell.tets);
  // With the ring turning positively seen from a, (r_i, r_j, r_k, a) is
  // positive for i < j < k; orient3d(a, b, r0, r1) < 0 tells that it does.
  const bool ccw_from_a = predicates::orient3d(m.coords[a].data(), m.coords[b].data(), m.coords[ring[0]].data(),
                                               m.coords[ring[1]].data()) < 0;
  auto tets_of = [&](int i, int j, int k) {
    const VertId ri = ring[static_cast<std::size_t>(i)], rj = ring[static_cast<std::size_t>(j)],
                 rk = ring[static_cast<std::size_t>(k)];
    return ccw_from_a ? std::array<std::array<VertId, 4>, 2>{{{ri, rj, rk, a}, {rj, ri, rk, b}}}
                      : std::array<std::array<VertId, 4>, 2>{{{rj, ri, rk, a}, {ri, rj, rk, b}}};
  };
  const RingTriangulation best = triangulate_ring(n, [&](int i, int k, int j, double floor) {
    return value(std::span<const VertId>(ring.data(), static_cast<std::size_t>(n)), std::array<int, 3>{i, k, j},
                 tets_of(i, k, j), floor);
  });
  plan.after = best.worst;
  if (!(plan.after > 0)) {
    plan.refusal = Refusal::kNotStarShaped;
    return plan;
  }
  for (int t = 0; t < best.count; ++t) {
    const auto& tri = best.triangles[static_cast<std::size_t>(t)];
    for (const auto& tv : tets_of(tri[0], tri[1], tri[2])) plan.fill.push_back({tv, region});
  }
  if (plan.after <= plan.before) plan.refusal = Refusal::kNoImprovement;
  return plan;
}

}  // namespace

Plan plan_edge_removal(MeshEditor& ed, Cavity& cav, VertId a, VertId b, TetId start) {
  const auto& m = ed.mesh();
  return plan_ring_fill(ed, cav, a, b, start,
                        [&m](std::span<const VertId>, const std::array<int, 3>&,
                             const std::array<std::array<VertId, 4>, 2>& tv, double floor) {
                          const double first = tet_quality(m, tv[0]);
                          return first <= floor ? first : std::min(first, tet_quality(m, tv[1]));
                        });
}

Plan plan_edge_removal(MeshEditor& ed, Cavity& cav, VertId a, VertId b, TetId start, const RingTriangleValue& value) {
  Plan plan = plan_ring_fill(ed, cav, a, b, start,
                             [&value](std::span<const VertId> ring, const std::array<int, 3>& ikj,
                                      const std::array<std::array<VertId, 4>, 2>& tv,
                                      double) { return value(ring, ikj, tv); });
  // The caller's values are not qualities: "before" means nothing here.
  if (plan.refusal == Refusal::kNoImprovement && !plan.fill.empty()) plan.refusal = Refusal::kNone;
  return plan;
}

Plan plan_face_swap(MeshEditor& ed, Cavity& cav, TetId t, int f) {
  const auto& m = ed.mesh();
  Plan plan;
  const Index across = m.tet2adj[mesh::pack_face(t, f)];
  if (across == kNone || ed.face_marked(mesh::pack_face(t, f))) {
    plan.refusal = Refusal::kConstrainedFace;
    return plan;
  }
  const TetId u = mesh::face_tet(across);
  if (m.tet_region[u] != m.tet_region[t]) {
    plan.refusal = Refusal::kClassification;
    return plan;
  }
  const auto& tv = m.tet2verts[t];
  const auto& fv = mesh::kFaceVerts[f];
  const VertId x = tv[fv[0]], y = tv[fv[1]], z = tv[fv[2]];
  const VertId d = tv[f], e = m.tet2verts[u][mesh::face_index(across)];
  cav.reset(ed);
  cav.add(ed, t);
  cav.add(ed, u);
  const std::array<TetId, 2> old{t, u};
  plan.before = min_quality(m, old);
  // (x, y, z) faces e: replacing z by d in (x, y, z, e) keeps it positive
  // exactly when the segment (d, e) crosses the triangle.
  const std::int32_t region = m.tet_region[t];
  plan.fill = {{{x, y, d, e}, region}, {{y, z, d, e}, region}, {{z, x, d, e}, region}};
  plan.after = 1;
  for (const auto& nt : plan.fill) plan.after = std::min(plan.after, tet_quality(m, nt.verts));
  if (!(plan.after > 0))
    plan.refusal = Refusal::kNotStarShaped;
  else if (plan.after <= plan.before)
    plan.refusal = Refusal::kNoImprovement;
  return plan;
}

std::span<const TetId> apply(MeshEditor& ed, Cavity& cav, const Plan& plan) {
  cav.compute_boundary(ed);
  return rebuild(ed, cav, plan.fill);
}

}  // namespace cm::modify
