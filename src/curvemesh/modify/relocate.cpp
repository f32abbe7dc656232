#include "curvemesh/modify/relocate.hpp"

#include <algorithm>

#include "curvemesh/mesh/adjacency.hpp"
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
    const double q = min_quality(m, ball);
    if (q > r.after) {
      r.after = q;
      r.target = m.coords[v];
    }
  }
  m.coords[v] = old;
  if (!(r.after > r.before + 1e-6)) r.refusal = Refusal::kNoImprovement;
  return r;
}

void apply(MeshEditor& ed, Cavity& cav, VertId v, const Relocation& plan) {
  ed.mesh().coords[v] = plan.target;
  cav.compute_boundary(ed);
  fill_star(ed, cav, v);
}

}  // namespace cm::modify
