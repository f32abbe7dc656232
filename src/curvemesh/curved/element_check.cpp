#include "curvemesh/curved/element_check.hpp"

#include <algorithm>
#include <bit>
#include <stdexcept>

#include <fmt/format.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include "curvemesh/core/predicates.hpp"
#include "curvemesh/mesh/high_order.hpp"
#include "curvemesh/mesh/topology.hpp"
#include "curvemesh/quality/shape_measure.hpp"

namespace cm::curved {

namespace {

// The least quick bound check_element takes. A mesh check certifies again
// in full the quick tets whose bound is under the least scaled Jacobian it
// reports; on a mesh whose least is high, a lower floor would send most of
// them through both checks (the bound is looser than the Bezier one by 0.05
// to 0.35 on the shared models' coarse P3 meshes).
constexpr double kQuickFloor = 0.5;

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
                           bool exact_measure, bool locate_minimum, bool quick) {
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
  if (quick && !exact_measure) {
    const quality::NearStraightBounds bound = quality::near_straight_bounds(order, nodes);
    if (bound.ratio >= std::max({kQuickFloor, 2 * acceptance.min_scaled_jacobian, acceptance.min_measure})) {
      c.scaled_jacobian = bound.ratio;
      c.measure = bound.mean_ratio;
      c.measure_exact = false;
      c.quick = true;
      return c;
    }
  }
  std::array<double, quality::simplex_count(quality::kMaxJacobianDegree)> coefs;
  const std::span<double> jacobian(coefs.data(), std::size_t(quality::simplex_count(3 * (order - 1))));
  // The first certified bound can be loose; where it decides whether the
  // element is acceptable, it is refined until within 1% of the minimum.
  quality::ValidityOptions options;
  if (!locate_minimum) options.locate_splits = 0;
  options.bound_tolerance = 0.01;
  options.refine_below = 2 * acceptance.min_scaled_jacobian;
  const quality::ValidityReport r = quality::certify_jacobian(order, nodes, options, jacobian);
  c.verdict = r.verdict;
  c.scaled_jacobian = r.verdict == quality::Validity::kValid ? r.scaled_jacobian_lower
                                                             : std::min(0.0, r.scaled_jacobian_lower);
  c.where = r.where_entity;
  // I is the least det J at the rule's points over the mean of det J, which
  // is the mean of the coefficients: at least min det J over that mean (and
  // at least the scaled Jacobian, which divides by the larger max det J).
  double measure_lower = c.scaled_jacobian;
  if (c.verdict == quality::Validity::kValid) {
    double sum = 0;
    for (double x : jacobian) sum += x;
    const double mean = sum / static_cast<double>(jacobian.size());
    measure_lower = std::max(measure_lower, (r.min_lower - r.rounding_bound) / (mean + r.rounding_bound));
  }
  if (!exact_measure && c.verdict == quality::Validity::kValid && measure_lower >= acceptance.min_measure) {
    c.measure = measure_lower;
    c.measure_exact = false;
  } else {
    c.measure = quality::shape_measure_from_bezier(order, jacobian).measure;
  }
  c.acceptable = c.verdict == quality::Validity::kValid && c.scaled_jacobian >= acceptance.min_scaled_jacobian &&
                 c.measure >= acceptance.min_measure;
  return c;
}

namespace {

std::uint64_t hash_nodes(std::span<const Vec3> nodes) {
  std::uint64_t h = 0xcbf29ce484222325ull;
  for (const Vec3& p : nodes)
    for (int i = 0; i < 3; ++i) {
      h ^= std::bit_cast<std::uint64_t>(p[i]);
      h *= 0x100000001b3ull;
      h ^= h >> 29;
    }
  return h;
}

}  // namespace

CheckCache::CheckCache(int order) : order_(order), per_tet_(mesh::tet_node_count(order)) {}

const ElementCheck* CheckCache::find(std::span<const Vec3> tet_nodes) const {
  if (tet_nodes.size() != per_tet_ || by_hash_.empty()) return nullptr;
  const std::uint64_t hash = hash_nodes(tet_nodes);
  const std::size_t mask = by_hash_.size() - 1;
  for (std::size_t i = hash & mask;; i = (i + 1) & mask) {
    const Slot& slot = by_hash_[i];
    if (slot.entry == kNoEntry) return nullptr;
    if (slot.hash != hash) continue;
    const Vec3* stored = &nodes_[std::size_t(slot.entry) * per_tet_];
    return std::equal(tet_nodes.begin(), tet_nodes.end(), stored) ? &checks_[slot.entry] : nullptr;
  }
}

void CheckCache::insert(std::uint64_t hash, std::uint32_t entry) {
  if (2 * (checks_.size() + 1) > by_hash_.size()) {
    // Grown, then every entry so far indexed again (entry is the newest).
    by_hash_.assign(std::max<std::size_t>(64, std::bit_ceil(4 * (checks_.size() + 1))), Slot{});
    for (std::uint32_t k = 0; k < entry; ++k)
      insert(hash_nodes(std::span<const Vec3>(&nodes_[std::size_t(k) * per_tet_], per_tet_)), k);
  }
  const std::size_t mask = by_hash_.size() - 1;
  for (std::size_t i = hash & mask;; i = (i + 1) & mask) {
    Slot& slot = by_hash_[i];
    if (slot.entry == kNoEntry) {
      slot = {hash, entry};
      return;
    }
    if (slot.hash == hash) return;  // the first entry with a hash stays
  }
}

void CheckCache::add(std::span<const Vec3> tet_nodes, const ElementCheck& c) {
  if (tet_nodes.size() != per_tet_) return;
  nodes_.insert(nodes_.end(), tet_nodes.begin(), tet_nodes.end());
  checks_.push_back(c);
  insert(hash_nodes(tet_nodes), static_cast<std::uint32_t>(checks_.size() - 1));
}

void CheckCache::clear() {
  nodes_.clear();
  checks_.clear();
  by_hash_.clear();
}

void CheckCache::index_all() {
  by_hash_.assign(std::max<std::size_t>(64, std::bit_ceil(2 * checks_.size() + 1)), Slot{});
  for (std::uint32_t k = 0; k < checks_.size(); ++k)
    insert(hash_nodes(std::span<const Vec3>(&nodes_[std::size_t(k) * per_tet_], per_tet_)), k);
}

namespace {

// Most tets have at most one vertex on the boundary, hence no boundary
// edge and no nodes: straight, decided by orient3d alone.
bool plainly_straight(const mesh::TetMesh& m, TetId t) {
  if (m.high_order.order() <= 1) return true;
  const auto& v = m.tet2verts[t];
  int on_boundary = 0;
  for (VertId x : v) on_boundary += x < m.vert_class.size() && m.vert_class[x].dim < 3;
  return on_boundary < 2 && (m.high_order.num_edges() == 0 || !has_any_node(m, v));
}

ElementCheck check_straight(const mesh::TetMesh& m, TetId t, const Acceptance& acceptance) {
  const auto& v = m.tet2verts[t];
  const std::array<Vec3, 4> corners{m.coords[v[0]], m.coords[v[1]], m.coords[v[2]], m.coords[v[3]]};
  return check_element(1, corners, acceptance);
}

}  // namespace

ElementCheck check_tet(const mesh::TetMesh& m, TetId t, const Acceptance& acceptance, bool exact_measure) {
  if (plainly_straight(m, t)) return check_straight(m, t, acceptance);
  return check_element(m.high_order.order(), mesh::tet_nodes(m, m.tet2verts[t]).view(), acceptance, exact_measure);
}

namespace {

// What check_mesh and recheck_mesh share once each tet has its first-pass
// result: the exact minima (see check_mesh) and the summary.
MeshCheck summarize(const mesh::TetMesh& m, const Acceptance& acceptance, bool exact_minima,
                    std::vector<ElementCheck>& checks) {
  const std::size_t nt = checks.size();
  const int order = m.high_order.order();
  MeshCheck out;
  // Certified in full, lowest bound first, the tets whose bound is under
  // the least exact value found so far (`exact` tells a tet already has
  // it, `bound` reads the value or its lower bound). A check that reuses
  // first-pass results then makes the same full certifications here and
  // gives what a fresh one gives (a few tets; the first pass is the cost).
  const auto settle_least = [&](auto exact, auto bound, bool exact_measure) {
    double least = 1;
    std::vector<std::pair<double, TetId>> open;
    for (std::size_t t = 0; t < nt; ++t) {
      if (exact(checks[t]))
        least = std::min(least, bound(checks[t]));
      else
        open.emplace_back(bound(checks[t]), static_cast<TetId>(t));
    }
    std::sort(open.begin(), open.end());
    for (const auto& [value, t] : open) {
      if (value >= least) break;
      checks[t] = check_element(order, mesh::tet_nodes(m, m.tet2verts[t]).view(), acceptance, exact_measure);
      least = std::min(least, bound(checks[t]));
    }
  };
  if (exact_minima) {
    // The least scaled Jacobian: a quick bound is a lower bound of the
    // Bezier one only up to looseness, so those under the least Bezier
    // bound found are certified. The least I: a measure that is not exact
    // is a lower bound of I (the certified scaled Jacobian).
    settle_least([](const ElementCheck& c) { return !c.quick; },
                 [](const ElementCheck& c) { return c.scaled_jacobian; }, false);
    settle_least([](const ElementCheck& c) { return c.measure_exact; },
                 [](const ElementCheck& c) { return c.measure; }, true);
  }
  double sum_sj = 0;
  for (std::size_t t = 0; t < nt; ++t) {
    const ElementCheck& c = checks[t];
    if (c.verdict != quality::Validity::kValid) out.invalid.push_back(static_cast<TetId>(t));
    out.undetermined += c.verdict == quality::Validity::kUndetermined;
    if (!c.acceptable) out.unacceptable.push_back(static_cast<TetId>(t));
    out.min_scaled_jacobian = std::min(out.min_scaled_jacobian, c.scaled_jacobian);
    out.min_measure = std::min(out.min_measure, c.measure);
    out.quick += c.quick;
    sum_sj += c.scaled_jacobian;
  }
  if (nt) out.mean_scaled_jacobian = sum_sj / double(nt);
  return out;
}

// The first-pass result of tet t, given its nodes.
ElementCheck first_pass(int order, std::span<const Vec3> nodes, const Acceptance& acceptance) {
  return check_element(order, nodes, acceptance, false, true, true);
}

}  // namespace

MeshCheck check_mesh(const mesh::TetMesh& m, const Acceptance& acceptance, bool exact_minima,
                     const CheckCache* reuse, CheckCache* keep, std::vector<ElementCheck>* first_results) {
  const std::size_t nt = m.num_tets();
  const int order = m.high_order.order();
  const std::size_t per_tet = mesh::tet_node_count(order);
  if (reuse && reuse->order() != order) reuse = nullptr;
  // Curved tets get consecutive entries in `keep`, in tet order.
  std::vector<std::uint32_t> entry(nt + 1, 0);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nt, 1024), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t t = r.begin(); t != r.end(); ++t) entry[t + 1] = !plainly_straight(m, static_cast<TetId>(t));
  });
  for (std::size_t t = 0; t < nt; ++t) entry[t + 1] += entry[t];
  if (keep) {
    // Filled in place by the parallel loop, indexed after it.
    *keep = CheckCache(order);
    keep->nodes_.resize(std::size_t(entry[nt]) * per_tet);
    keep->checks_.resize(entry[nt]);
  }
  std::vector<ElementCheck> checks(nt);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nt, 256), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t t = r.begin(); t != r.end(); ++t) {
      const auto tet = static_cast<TetId>(t);
      if (entry[t + 1] == entry[t]) {
        checks[t] = check_straight(m, tet, acceptance);
        continue;
      }
      const mesh::TetNodes gathered = mesh::tet_nodes(m, m.tet2verts[tet]);
      const std::span<const Vec3> nodes = gathered.view();
      const ElementCheck* known = reuse ? reuse->find(nodes) : nullptr;
      checks[t] = known ? *known : first_pass(order, nodes, acceptance);
      if (keep) {
        std::copy(nodes.begin(), nodes.end(), keep->nodes_.begin() + std::ptrdiff_t(std::size_t(entry[t]) * per_tet));
        keep->checks_[entry[t]] = checks[t];
      }
    }
  });
  if (first_results) *first_results = checks;
  MeshCheck out = summarize(m, acceptance, exact_minima, checks);
  if (keep) keep->index_all();
  return out;
}

MeshCheck recheck_mesh(const mesh::TetMesh& m, const Acceptance& acceptance, bool exact_minima,
                       std::span<const ElementCheck> previous, std::span<const TetId> origin) {
  const std::size_t nt = m.num_tets();
  if (origin.size() != nt)
    throw std::invalid_argument(fmt::format("recheck_mesh: {} origins for {} tets", origin.size(), nt));
  const int order = m.high_order.order();
  std::vector<ElementCheck> checks(nt);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nt, 256), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t t = r.begin(); t != r.end(); ++t) {
      const auto tet = static_cast<TetId>(t);
      if (origin[t] != kNone && origin[t] < previous.size())
        checks[t] = previous[origin[t]];
      else if (plainly_straight(m, tet))
        checks[t] = check_straight(m, tet, acceptance);
      else
        checks[t] = first_pass(order, mesh::tet_nodes(m, m.tet2verts[tet]).view(), acceptance);
    }
  });
  return summarize(m, acceptance, exact_minima, checks);
}

}  // namespace cm::curved
