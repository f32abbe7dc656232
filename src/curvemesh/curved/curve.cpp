#include "curvemesh/curved/curve.hpp"

#include <algorithm>
#include <stdexcept>

#include <fmt/format.h>
#include <tbb/parallel_for.h>

#include "curvemesh/core/timer.hpp"
#include "curvemesh/mesh/adjacency.hpp"
#include "curvemesh/mesh/high_order.hpp"
#include "curvemesh/modify/surface.hpp"

namespace cm::curved {

namespace {

// Value at barycentric l of the order-p Lagrange basis function of the
// triangle node with multi-index idx: a product of one-dimensional
// Lagrange factors in each barycentric coordinate.
double tri_basis(int p, const std::array<int, 3>& idx, const std::array<double, 3>& l) {
  double v = 1;
  for (int k = 0; k < 3; ++k)
    for (int s = 0; s < idx[k]; ++s) v *= (p * l[k] - s) / (s + 1);
  return v;
}

// Points per measure: closest points on CAD faces are some microseconds
// each, and the error is reported, not acted on.
constexpr std::size_t kTargetSamples = 40'000;

}  // namespace

GeometricError measure_geometric_error(const mesh::TetMesh& m, const geom::Model& model, bool straight) {
  GeometricError e;
  const std::size_t nt = m.tris.size();
  if (nt == 0) return e;
  const int p = straight ? 1 : m.high_order.order();
  const auto indices = mesh::tri_node_indices(std::max(p, 1));
  static constexpr std::array<std::array<double, 3>, 4> kPoints{
      {{1.0 / 3, 1.0 / 3, 1.0 / 3}, {0.5, 0.25, 0.25}, {0.25, 0.5, 0.25}, {0.25, 0.25, 0.5}}};
  // Every triangle at up to 4 points, or every stride-th triangle at its
  // centroid and 3 more points on a big mesh.
  const std::size_t per = std::clamp<std::size_t>(kTargetSamples / nt, 1, kPoints.size());
  const std::size_t stride = per > 1 ? 1 : std::max<std::size_t>(1, 4 * nt / kTargetSamples);
  const std::size_t points = per > 1 ? per : kPoints.size();
  const std::size_t picked = (nt + stride - 1) / stride;
  std::vector<double> worst(picked, 0), sum(picked, 0);
  tbb::parallel_for(std::size_t{0}, picked, [&](std::size_t k) {
    const std::size_t i = k * stride;
    const auto& t = m.tris[i];
    const std::vector<Vec3> nodes =
        p == 1 ? std::vector<Vec3>{m.coords[t.verts[0]], m.coords[t.verts[1]], m.coords[t.verts[2]]}
               : mesh::gather_tri_nodes(m, t.verts);
    const std::optional<Vec2> hint = modify::check_hint(m, t.verts, t.face_tag);
    for (std::size_t s = 0; s < points; ++s) {
      Vec3 x = Vec3::Zero();
      for (std::size_t n = 0; n < nodes.size(); ++n) x += tri_basis(p, indices[n], kPoints[s]) * nodes[n];
      const double d = model.closest_point({2, t.face_tag}, x, hint).distance;
      worst[k] = std::max(worst[k], d);
      sum[k] += d;
    }
  });
  double total = 0;
  for (std::size_t k = 0; k < picked; ++k) {
    e.max = std::max(e.max, worst[k]);
    total += sum[k];
  }
  e.samples = picked * points;
  e.mean = total / double(e.samples);
  return e;
}

CurveReport curve_mesh(mesh::TetMesh& m, const geom::Model& model, const CurveOptions& o) {
  if (o.order < 2 || o.order > 3)
    throw std::invalid_argument(fmt::format("curved elements of order {}: 2 or 3", o.order));
  CurveReport r;
  r.order = o.order;
  Timer step;
  r.placement = place_boundary_nodes(m, model, o.order);
  r.place_seconds = step.seconds();
  step.reset();
  // Before: what to repair, keeping every tet's result so that the report
  // after the repair redoes only the tets it changed.
  std::vector<ElementCheck> seen;
  const MeshCheck before = check_mesh(m, o.repair.acceptance, true, nullptr, nullptr, &seen);
  r.invalid_before = before.invalid.size();
  r.unacceptable_before = before.unacceptable.size();
  r.min_scaled_jacobian_before = before.min_scaled_jacobian;
  r.min_measure_before = before.min_measure;
  r.check_seconds = step.seconds();
  const bool repairs = o.repair_enabled && !before.unacceptable.empty();
  std::vector<TetId> origin;
  if (repairs) {
    r.repair = repair_curved_mesh(m, model, before.unacceptable, o.repair, &origin);
    // Tet adjacency does not change with the vertex numbers; vert2tet is
    // renumbered with them.
    mesh::drop_unused_vertices(m);
  }
  step.reset();
  // Untouched, the mesh checks as it did.
  r.after = repairs ? recheck_mesh(m, o.repair.acceptance, true, seen, origin) : before;
  r.check_seconds += step.seconds();
  step.reset();
  r.error_straight = measure_geometric_error(m, model, true);
  r.error_curved = measure_geometric_error(m, model, false);
  r.error_seconds = step.seconds();
  return r;
}

}  // namespace cm::curved
