#include "curvemesh/optimize/measured_swap.hpp"

#include <algorithm>
#include <limits>

#include "curvemesh/core/predicates.hpp"
#include "curvemesh/mesh/adjacency.hpp"
#include "curvemesh/mesh/topology.hpp"
#include "curvemesh/modify/ring_triangulation.hpp"
#include "curvemesh/quality/measures.hpp"

namespace cm::optimize {

double angle_aware_quality(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) {
  return mean_ratio_and_shape(a, b, c, d).second;
}

std::pair<double, double> mean_ratio_and_shape(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) {
  if (predicates::orient3d(a.data(), b.data(), c.data(), d.data()) <= 0) return {-1, -1};
  const double mr = std::max(quality::tet_mean_ratio(a, b, c, d), 0.0);
  return {mr, std::min(mr, quality::tet_min_dihedral(a, b, c, d) / kRegularDihedral)};
}

namespace {

// For a strictly positive tet: whether, by the cheap bounds, its mean ratio
// (clamped at 0) is at least mr and its scaled angle at least shape.
bool bounded_below(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d, double mr, double shape) {
  return (mr <= 0 || quality::tet_mean_ratio_at_least(a, b, c, d, mr)) &&
         quality::tet_min_dihedral_at_least(a, b, c, d, shape * kRegularDihedral);
}

}  // namespace

bool angle_aware_quality_at_least(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d, double q) {
  return predicates::orient3d(a.data(), b.data(), c.data(), d.data()) > 0 && bounded_below(a, b, c, d, q, q);
}

void fold_mean_ratio_and_shape(std::pair<double, double>& worst, const Vec3& a, const Vec3& b, const Vec3& c,
                               const Vec3& d) {
  if (predicates::orient3d(a.data(), b.data(), c.data(), d.data()) <= 0) {
    worst = {std::min(worst.first, -1.0), std::min(worst.second, -1.0)};
    return;
  }
  // The tet lowers neither minimum when its mean ratio is at least both
  // (its shape is at most its mean ratio) and its angle at least the shape's.
  if (bounded_below(a, b, c, d, std::max(worst.first, worst.second), worst.second)) return;
  const double mr = std::max(quality::tet_mean_ratio(a, b, c, d), 0.0);
  worst.first = std::min(worst.first, mr);
  worst.second = std::min(worst.second, std::min(mr, quality::tet_min_dihedral(a, b, c, d) / kRegularDihedral));
}

TetShape tet_shape(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) {
  const double angle = quality::tet_min_dihedral(a, b, c, d);
  if (predicates::orient3d(a.data(), b.data(), c.data(), d.data()) <= 0) return {-1, -1, angle};
  const double mr = std::max(quality::tet_mean_ratio(a, b, c, d), 0.0);
  return {mr, std::min(mr, angle / kRegularDihedral), angle};
}

double mean_ratio_floor(double mr_before, double shape_before) {
  constexpr double kTenDegrees = 10.0 / kRegularDihedral;  // angle-aware quality of a 10 degree tet
  return std::min(mr_before, shape_before < kTenDegrees ? kRescueFloor : kProgressFloor);
}

bool is_progress(double mr_before, double shape_before, double mr_after, double shape_after) {
  constexpr double kFloor = kProgressFloor, kMargin = 1e-6;
  if (!(mr_after > 0) || !(shape_after > 0)) return false;
  return (shape_after > shape_before + kMargin && mr_after >= mean_ratio_floor(mr_before, shape_before)) ||
         (mr_after > mr_before + kMargin && shape_after >= std::min(shape_before, kFloor));
}

double angle_aware_measure(const mesh::TetMesh& m, const std::array<VertId, 4>& v, const void*) {
  return angle_aware_quality(m.coords[v[0]], m.coords[v[1]], m.coords[v[2]], m.coords[v[3]]);
}

modify::Plan plan_measured_edge_removal(modify::MeshEditor& ed, modify::Cavity& cav, VertId a, VertId b, TetId start,
                                        TetMeasure measure, const void* context) {
  using modify::Refusal;
  constexpr int kMax = modify::kMaxShell;
  const auto& m = ed.mesh();
  modify::Plan plan;
  thread_local mesh::Shell shell;
  shell = mesh::collect_shell(m, a, b, start);
  const int n = static_cast<int>(shell.tets.size());
  if (!shell.closed) {
    plan.refusal = Refusal::kConstrainedFace;
    return plan;
  }
  if (n < 3 || n > kMax) {
    plan.refusal = Refusal::kNoImprovement;
    return plan;
  }
  const std::int32_t region = m.tet_region[shell.tets[0]];
  cav.reset(ed);
  plan.before = 1;
  for (TetId t : shell.tets) {
    if (m.tet_region[t] != region) {
      plan.refusal = Refusal::kClassification;
      return plan;
    }
    const int ia = mesh::local_index(m, t, a), ib = mesh::local_index(m, t, b);
    for (int f = 0; f < 4; ++f)
      if (f != ia && f != ib && ed.face_marked(mesh::pack_face(t, f))) {
        plan.refusal = Refusal::kConstrainedFace;
        return plan;
      }
    cav.add(ed, t);
    plan.before = std::min(plan.before, measure(m, m.tet2verts[t], context));
  }
  // ring[k] is shared by shell tets k-1 and k.
  std::array<VertId, kMax> ring{};
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
  // Seen from a the ring turns positively when orient3d(a, b, r0, r1) < 0;
  // then (ri, rj, rk, a) is positive for i < j < k.
  const bool ccw_from_a = predicates::orient3d(m.coords[a].data(), m.coords[b].data(), m.coords[ring[0]].data(),
                                               m.coords[ring[1]].data()) < 0;
  auto tets_of = [&](int i, int j, int k) {
    const VertId ri = ring[static_cast<std::size_t>(i)], rj = ring[static_cast<std::size_t>(j)],
                 rk = ring[static_cast<std::size_t>(k)];
    return ccw_from_a ? std::array<std::array<VertId, 4>, 2>{{{ri, rj, rk, a}, {rj, ri, rk, b}}}
                      : std::array<std::array<VertId, 4>, 2>{{{rj, ri, rk, a}, {ri, rj, rk, b}}};
  };
  // The ring's best triangulation; each triangle (i, k, j) of the ring is
  // measured once, through its two tets.
  const modify::RingTriangulation best = modify::triangulate_ring(n, [&](int i, int k, int j, double floor) {
    const auto tv = tets_of(i, k, j);
    const double first = measure(m, tv[0], context);
    return first <= floor ? first : std::min(first, measure(m, tv[1], context));
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

modify::Plan plan_measured_face_swap(modify::MeshEditor& ed, modify::Cavity& cav, TetId t, int f, TetMeasure measure,
                                     const void* context) {
  const auto& m = ed.mesh();
  modify::Plan plan = modify::plan_face_swap(ed, cav, t, f);
  // Refused for the isotropic measure may still be better in this one;
  // refused for validity or constraints is final.
  if (plan.fill.empty() || plan.refusal == modify::Refusal::kNotStarShaped) return plan;
  plan.refusal = modify::Refusal::kNone;
  plan.before = 1;
  for (TetId u : cav.tets()) plan.before = std::min(plan.before, measure(m, m.tet2verts[u], context));
  plan.after = 1;
  for (const auto& nt : plan.fill) plan.after = std::min(plan.after, measure(m, nt.verts, context));
  if (!(plan.after > 0))
    plan.refusal = modify::Refusal::kNotStarShaped;
  else if (plan.after <= plan.before)
    plan.refusal = modify::Refusal::kNoImprovement;
  return plan;
}

}  // namespace cm::optimize
