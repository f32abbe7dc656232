#include "curvemesh/modify/measure.hpp"

#include <algorithm>
#include <span>

#include "curvemesh/core/predicates.hpp"
#include "curvemesh/quality/measures.hpp"

namespace cm::modify {

double tet_quality(const mesh::TetMesh& m, const std::array<VertId, 4>& v) {
  const Vec3 &a = m.coords[v[0]], &b = m.coords[v[1]], &c = m.coords[v[2]], &d = m.coords[v[3]];
  if (predicates::orient3d(a.data(), b.data(), c.data(), d.data()) <= 0) return -1;
  return std::max(quality::tet_mean_ratio(a, b, c, d), 0.0);
}

double min_quality(const mesh::TetMesh& m, std::span<const TetId> tets) {
  double q = 1;
  for (TetId t : tets) q = std::min(q, tet_quality(m, m.tet2verts[t]));
  return q;
}

}  // namespace cm::modify
