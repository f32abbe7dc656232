#include "curvemesh/optimize/shell_insert.hpp"

#include <algorithm>
#include <cmath>
#include <utility>

#include "curvemesh/core/error.hpp"
#include "curvemesh/mesh/adjacency.hpp"
#include "curvemesh/modify/surface.hpp"
#include "curvemesh/optimize/measured_swap.hpp"
#include "curvemesh/optimize/vertex_search.hpp"

namespace cm::optimize {

namespace {

// Worst mean ratio and worst angle-aware quality of the star of x over the
// cavity boundary; {-1, -1} as soon as a tet is invalid or the worst
// angle-aware quality is at most `unless_above` (a smoothing step that does
// not beat the point it started from). A boundary face lists its vertices
// with the normal out of the cavity, so the new tet has x behind it:
// (f1, f0, f2, x) is the positive order.
std::pair<double, double> star_quality(const mesh::TetMesh& m, std::span<const modify::CavityFace> faces,
                                       const Vec3& x, double unless_above = -INFINITY) {
  std::pair<double, double> q{1, 1};
  for (const auto& f : faces) {
    fold_mean_ratio_and_shape(q, m.coords[f.verts[1]], m.coords[f.verts[0]], m.coords[f.verts[2]], x);
    if (q.second <= 0 || q.second <= unless_above) return {-1, -1};
  }
  return q;
}

std::pair<double, double> worst_shape(const mesh::TetMesh& m, std::span<const TetId> tets) {
  std::pair<double, double> q{1, 1};
  for (TetId t : tets) {
    const auto& v = m.tet2verts[t];
    fold_mean_ratio_and_shape(q, m.coords[v[0]], m.coords[v[1]], m.coords[v[2]], m.coords[v[3]]);
  }
  return q;
}

// The mean of the star tets' centroids: a smoothing step for x.
Vec3 star_centroid(const mesh::TetMesh& m, std::span<const modify::CavityFace> faces, const Vec3& x) {
  Vec3 c = Vec3::Zero();
  for (const auto& f : faces) c += (m.coords[f.verts[0]] + m.coords[f.verts[1]] + m.coords[f.verts[2]] + x) / 4;
  return c / static_cast<double>(faces.size());
}

// Chooses the point for a cavity whose worst (mean ratio, angle-aware
// quality) is `before`: the given guess, the centroid of the boundary's
// vertices and their middle, each smoothed while its angle-aware quality
// rises; the best that is progress (is_progress) wins. Sets after (the
// angle-aware quality), point and the refusal.
// The angle-aware quality of a tet whose smallest dihedral angle is 12
// degrees: the point search stops short of it (vertex_search.hpp).
constexpr double kSearchBelow = 12.0 / kRegularDihedral;

void place_point(const mesh::TetMesh& m, std::span<const modify::CavityFace> faces, const Vec3& guess,
                 std::pair<double, double> before, ShellInsertion& plan) {
  Vec3 centroid = Vec3::Zero();
  for (const auto& f : faces) centroid += m.coords[f.verts[0]] + m.coords[f.verts[1]] + m.coords[f.verts[2]];
  centroid /= 3.0 * static_cast<double>(faces.size());
  plan.before = before.second;
  plan.after = -1;
  bool positive = false;
  Vec3 best = guess;
  std::pair<double, double> best_q{-1, -1};
  auto consider = [&](const Vec3& x, const std::pair<double, double>& q) {
    positive |= q.second > 0;
    if (q.second > best_q.second) best = x, best_q = q;
    if (q.second > plan.after && is_progress(before.first, before.second, q.first, q.second)) {
      plan.after = q.second;
      plan.point = x;
    }
  };
  for (const Vec3& start : {guess, centroid, Vec3(0.5 * (guess + centroid))}) {
    Vec3 x = start;
    auto q = star_quality(m, faces, x);
    for (int it = 0; it < 4; ++it) {
      const Vec3 y = star_centroid(m, faces, x);
      const auto qy = star_quality(m, faces, y, q.second);
      if (!(qy.second > q.second)) break;
      x = y;
      q = qy;
    }
    consider(x, q);
  }
  // Smoothing finds the middle of a fair cavity; a flat one (a sliver's
  // four boundary vertices) needs the point where its worst tet is best:
  // searched for from the best smoothed point, when that is not good enough.
  if (best_q.second > 0 && best_q.second < kSearchBelow) {
    const Vec3 y = search_star_point(m, faces, best, mean_ratio_floor(before.first, before.second));
    consider(y, star_quality(m, faces, y));
  }
  if (!positive)
    plan.refusal = modify::Refusal::kNotStarShaped;
  else if (!(plan.after > 0))
    plan.refusal = modify::Refusal::kNoImprovement;
}

}  // namespace

ShellInsertion plan_shell_insertion(modify::MeshEditor& ed, modify::Cavity& cav, VertId a, VertId b, TetId start) {
  const auto& m = ed.mesh();
  ShellInsertion plan;
  plan.a = a;
  plan.b = b;
  thread_local mesh::Shell shell;
  shell = mesh::collect_shell(m, a, b, start);
  if (!shell.closed) {
    plan.refusal = modify::Refusal::kConstrainedFace;
    return plan;
  }
  const std::int32_t region = m.tet_region[shell.tets[0]];
  cav.reset(ed);
  for (TetId t : shell.tets) {
    if (m.tet_region[t] != region) {
      plan.refusal = modify::Refusal::kClassification;
      return plan;
    }
    const int ia = mesh::local_index(m, t, a), ib = mesh::local_index(m, t, b);
    for (int f = 0; f < 4; ++f)
      if (f != ia && f != ib && ed.face_marked(mesh::pack_face(t, f))) {
        plan.refusal = modify::Refusal::kConstrainedFace;
        return plan;
      }
    cav.add(ed, t);
  }
  place_point(m, cav.compute_boundary(ed), 0.5 * (m.coords[a] + m.coords[b]), worst_shape(m, shell.tets), plan);
  return plan;
}

ShellInsertion plan_ball_insertion(modify::MeshEditor& ed, modify::Cavity& cav, TetId t, int depth) {
  const auto& m = ed.mesh();
  ShellInsertion plan;
  const std::int32_t region = m.tet_region[t];
  // The tets within `depth` unmarked face steps of t.
  thread_local std::vector<TetId> near;
  near.assign(1, t);
  for (int d = 0, begin = 0; d < depth; ++d) {
    const int end = static_cast<int>(near.size());
    for (int i = begin; i < end; ++i)
      for (int f = 0; f < 4; ++f) {
        const Index packed = mesh::pack_face(near[static_cast<std::size_t>(i)], f);
        const Index across = m.tet2adj[packed];
        if (across == kNone || ed.face_marked(packed)) continue;
        const TetId n = mesh::face_tet(across);
        if (m.tet_region[n] == region && std::find(near.begin(), near.end(), n) == near.end()) near.push_back(n);
      }
    begin = end;
  }
  cav.reset(ed);
  const bool closed = cav.grow(
      ed, t, [&](TetId n) { return std::find(near.begin(), near.end(), n) != near.end(); }, true);
  if (!closed) {
    plan.refusal = modify::Refusal::kConstrainedFace;
    return plan;
  }
  Vec3 centroid = Vec3::Zero();
  for (VertId v : m.tet2verts[t]) centroid += m.coords[v] / 4;
  place_point(m, cav.boundary(), centroid, worst_shape(m, cav.tets()), plan);
  return plan;
}

VertId apply(modify::MeshEditor& ed, modify::Cavity& cav, const ShellInsertion& plan) {
  auto& m = ed.mesh();
  const std::int32_t region = m.tet_region[cav.tets()[0]];
  const VertId p = m.add_vert(plan.point);
  m.resize_vertex_arrays();
  m.vert_class[p] = {3, region};
  CM_ASSERT(modify::check_star(m, cav, p) == modify::Refusal::kNone);
  modify::fill_star(ed, cav, p);
  return p;
}

}  // namespace cm::optimize
