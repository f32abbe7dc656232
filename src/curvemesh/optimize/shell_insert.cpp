#include "curvemesh/optimize/shell_insert.hpp"

#include <algorithm>

#include "curvemesh/core/error.hpp"
#include "curvemesh/mesh/adjacency.hpp"
#include "curvemesh/modify/measure.hpp"
#include "curvemesh/modify/surface.hpp"

namespace cm::optimize {

namespace {

// Worst quality of the star of x over the cavity boundary. A boundary face
// lists its vertices with the normal out of the cavity, so the new tet has
// x behind it: (f1, f0, f2, x) is the positive order.
double star_quality(const mesh::TetMesh& m, std::span<const modify::CavityFace> faces, const Vec3& x) {
  double q = 1;
  for (const auto& f : faces) {
    q = std::min(q, modify::tet_quality_at(m.coords[f.verts[1]], m.coords[f.verts[0]], m.coords[f.verts[2]], x));
    if (q <= 0) return q;
  }
  return q;
}

// The mean of the star tets' centroids: a smoothing step for x.
Vec3 star_centroid(const mesh::TetMesh& m, std::span<const modify::CavityFace> faces, const Vec3& x) {
  Vec3 c = Vec3::Zero();
  for (const auto& f : faces) c += (m.coords[f.verts[0]] + m.coords[f.verts[1]] + m.coords[f.verts[2]] + x) / 4;
  return c / static_cast<double>(faces.size());
}

// Chooses the point for a cavity whose worst quality is plan.before: the
// given guess, the centroid of the boundary's vertices and their middle,
// each smoothed while that helps; sets after, point and the refusal.
void place_point(const mesh::TetMesh& m, std::span<const modify::CavityFace> faces, const Vec3& guess,
                 ShellInsertion& plan) {
  Vec3 centroid = Vec3::Zero();
  for (const auto& f : faces) centroid += m.coords[f.verts[0]] + m.coords[f.verts[1]] + m.coords[f.verts[2]];
  centroid /= 3.0 * static_cast<double>(faces.size());
  plan.after = -1;
  for (const Vec3& start : {guess, centroid, Vec3(0.5 * (guess + centroid))}) {
    Vec3 x = start;
    double q = star_quality(m, faces, x);
    for (int it = 0; it < 4; ++it) {
      const Vec3 y = star_centroid(m, faces, x);
      const double qy = star_quality(m, faces, y);
      if (!(qy > q)) break;
      x = y;
      q = qy;
    }
    if (q > plan.after) {
      plan.after = q;
      plan.point = x;
    }
  }
  if (!(plan.after > 0))
    plan.refusal = modify::Refusal::kNotStarShaped;
  else if (!(plan.after > plan.before + 1e-6))
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
  plan.before = modify::min_quality(m, shell.tets);
  place_point(m, cav.compute_boundary(ed), 0.5 * (m.coords[a] + m.coords[b]), plan);
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
  plan.before = modify::min_quality(m, cav.tets());
  Vec3 centroid = Vec3::Zero();
  for (VertId v : m.tet2verts[t]) centroid += m.coords[v] / 4;
  place_point(m, cav.boundary(), centroid, plan);
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
