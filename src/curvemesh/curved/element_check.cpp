#include "curvemesh/curved/element_check.hpp"

#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include "curvemesh/core/predicates.hpp"
#include "curvemesh/mesh/high_order.hpp"
#include "curvemesh/mesh/topology.hpp"
#include "curvemesh/quality/shape_measure.hpp"

namespace cm::curved {

namespace {

// Whether every node sits where the straight tet puts it (compared exactly:
// stored straight nodes are computed the same way).
const std::vector<std::array<int, 4>>& node_indices(int order) {
  static const std::array<std::vector<std::array<int, 4>>, mesh::kMaxOrder + 1> cache = [] {
    std::array<std::vector<std::array<int, 4>>, mesh::kMaxOrder + 1> c;
    for (int q = 1; q <= mesh::kMaxOrder; ++q) c[q] = mesh::tet_node_indices(q);
    return c;
  }();
  return cache[order];
}

bool is_straight(int order, std::span<const Vec3> nodes) {
  const auto& idx = node_indices(order);
  for (std::size_t n = 4; n < nodes.size(); ++n) {
    Vec3 linear = Vec3::Zero();
    for (int k = 0; k < 4; ++k) linear += (double(idx[n][k]) / order) * nodes[k];
    if ((nodes[n] - linear).squaredNorm() > 1e-28 * (nodes[1] - nodes[0]).squaredNorm()) return false;
  }
  return true;
}

// Whether any edge or face of the tet has stored nodes (interior edges are
// curved only by a repair's last resort, so this is rarely true).
bool has_any_node(const mesh::TetMesh& m, const std::array<VertId, 4>& v) {
  for (const auto& e : mesh::kTetEdges)
    if (m.high_order.has_edge(v[e[0]], v[e[1]])) return true;
  return false;
}

}  // namespace

ElementCheck check_element(int order, std::span<const Vec3> nodes, const Acceptance& acceptance,
                           bool exact_measure) {
  ElementCheck c;
  if (order == 1 || is_straight(order, nodes)) {
    if (predicates::orient3d(nodes[0].data(), nodes[1].data(), nodes[2].data(), nodes[3].data()) <= 0) {
      c.verdict = quality::Validity::kInvalid;
      c.scaled_jacobian = -1;
      c.measure = -1;
      c.where = {3, 0};
      c.acceptable = false;
    }
    return c;
  }
  quality::ValidityReport r = quality::certify_jacobian(order, nodes);
  // The first certified bound can be loose; where it decides whether the
  // element is acceptable, refine until it is within 1% of the minimum.
  if (r.verdict == quality::Validity::kValid && r.scaled_jacobian_lower < 2 * acceptance.min_scaled_jacobian) {
    quality::ValidityOptions tight;
    tight.bound_tolerance = 0.01;
    r = quality::certify_jacobian(order, nodes, tight);
  }
  c.verdict = r.verdict;
  c.scaled_jacobian = r.verdict == quality::Validity::kValid ? r.scaled_jacobian_lower
                                                             : std::min(0.0, r.scaled_jacobian_lower);
  c.where = r.where_entity;
  if (!exact_measure && c.verdict == quality::Validity::kValid && c.scaled_jacobian >= acceptance.min_measure) {
    c.measure = c.scaled_jacobian;
    c.measure_exact = false;
  } else {
    c.measure = quality::shape_measure(order, nodes).measure;
  }
  c.acceptable = c.verdict == quality::Validity::kValid && c.scaled_jacobian >= acceptance.min_scaled_jacobian &&
                 c.measure >= acceptance.min_measure;
  return c;
}

ElementCheck check_tet(const mesh::TetMesh& m, TetId t, const Acceptance& acceptance, bool exact_measure) {
  // Most tets have at most one vertex on the boundary, hence no boundary
  // edge and no nodes: straight, decided by orient3d alone.
  const auto& v = m.tet2verts[t];
  int on_boundary = 0;
  for (VertId x : v) on_boundary += x < m.vert_class.size() && m.vert_class[x].dim < 3;
  if (on_boundary < 2 && m.high_order.order() > 1) {
    const std::array<Vec3, 4> corners{m.coords[v[0]], m.coords[v[1]], m.coords[v[2]], m.coords[v[3]]};
    if (m.high_order.num_edges() == 0 || !has_any_node(m, v)) return check_element(1, corners, acceptance);
  }
  return check_element(m.high_order.order(), mesh::gather_tet_nodes(m, t), acceptance, exact_measure);
}

MeshCheck check_mesh(const mesh::TetMesh& m, const Acceptance& acceptance, bool exact_measures) {
  const std::size_t nt = m.num_tets();
  std::vector<ElementCheck> checks(nt);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nt, 256), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t t = r.begin(); t != r.end(); ++t)
      checks[t] = check_tet(m, static_cast<TetId>(t), acceptance, exact_measures);
  });
  MeshCheck out;
  double sum_sj = 0, sum_i = 0;
  for (std::size_t t = 0; t < nt; ++t) {
    const ElementCheck& c = checks[t];
    if (c.verdict != quality::Validity::kValid) out.invalid.push_back(static_cast<TetId>(t));
    out.undetermined += c.verdict == quality::Validity::kUndetermined;
    if (!c.acceptable) out.unacceptable.push_back(static_cast<TetId>(t));
    out.min_scaled_jacobian = std::min(out.min_scaled_jacobian, c.scaled_jacobian);
    out.min_measure = std::min(out.min_measure, c.measure);
    sum_sj += c.scaled_jacobian;
    sum_i += c.measure;
  }
  if (nt) {
    out.mean_scaled_jacobian = sum_sj / double(nt);
    out.mean_measure = sum_i / double(nt);
  }
  return out;
}

}  // namespace cm::curved
