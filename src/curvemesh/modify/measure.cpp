#include "curvemesh/modify/measure.hpp"

#include <algorithm>
#include <cmath>
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
  return min_quality_above(m, tets, -INFINITY);
}

double min_quality_above(const mesh::TetMesh& m, std::span<const TetId> tets, double floor) {
  double q = 1;
  for (TetId t : tets) {
    const auto& v = m.tet2verts[t];
    const Vec3 &a = m.coords[v[0]], &b = m.coords[v[1]], &c = m.coords[v[2]], &d = m.coords[v[3]];
    if (predicates::orient3d(a.data(), b.data(), c.data(), d.data()) <= 0) {
      q = -1;
    } else if (!quality::tet_mean_ratio_at_least(a, b, c, d, q)) {  // else it cannot lower q
      q = std::min(q, std::max(quality::tet_mean_ratio(a, b, c, d), 0.0));
    }
    if (q <= floor) return q;
  }
  return q;
}

}  // namespace cm::modify
