#include "curvemesh/size/background_field.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <functional>
#include <limits>
#include <numeric>
#include <queue>
#include <stdexcept>
#include <tuple>
#include <type_traits>

#include <Eigen/Eigenvalues>
#include <fmt/format.h>

#include "curvemesh/core/error.hpp"
#include "curvemesh/mesh/topology.hpp"

namespace cm::size {

namespace {

// A point whose smallest barycentric is >= -kInsideTol counts as inside the
// tet (weights then clamped). Barycentrics are ratios of nearly equal-scale
// dot products, so their rounding error is ~1e-16 times the tet's aspect
// ratio; without slack a point on a shared face could fail the test in both
// tets and take the slower nearest-tet path. The value error this allows is
// 1e-10 of the variation across one tet.
constexpr double kInsideTol = 1e-10;
// Tets per BVH leaf: small leaves keep the number of barycentric tests low,
// the tree is then about T/2 nodes.
constexpr std::size_t kLeafSize = 4;
// Bound of the traversal stacks: the tree is split at the median, so its
// depth is <= ceil(log2(T / kLeafSize)) + 1 <= 32 for 32-bit tet ids, and a
// depth-first traversal keeps at most depth + 1 entries.
constexpr int kStackSize = 64;

void check_tets(const std::vector<Vec3>& coords, const std::vector<std::array<VertId, 4>>& tets) {
  if (tets.empty()) throw std::invalid_argument("background mesh has no tetrahedra");
  for (std::size_t t = 0; t < tets.size(); ++t)
    for (VertId v : tets[t])
      if (v >= coords.size())
        throw std::invalid_argument(fmt::format("background mesh: tetrahedron {} refers to vertex {}, but there are {} vertices",
                                                t + 1, std::uint64_t{v} + 1, coords.size()));
  for (std::size_t v = 0; v < coords.size(); ++v)
    if (!coords[v].allFinite())
      throw std::invalid_argument(fmt::format("background mesh: vertex {} has a non-finite coordinate", v + 1));
}

void check_count(std::size_t values, std::size_t verts, const char* what) {
  if (values != verts)
    throw std::invalid_argument(
        fmt::format("background field: {} {} given for {} mesh vertices (need one per vertex)", values, what, verts));
}

void check_sizes(const std::vector<double>& h, std::size_t verts) {
  check_count(h.size(), verts, "sizes");
  for (std::size_t v = 0; v < h.size(); ++v)
    if (!(h[v] > 0) || !std::isfinite(h[v]))
      throw std::invalid_argument(
          fmt::format("background size at vertex {} is {}; sizes must be finite and > 0", v + 1, h[v]));
}

void check_metrics(const std::vector<Metric>& m, std::size_t verts) {
  check_count(m.size(), verts, "metrics");
  for (std::size_t v = 0; v < m.size(); ++v) {
    if (is_metric(m[v])) continue;
    std::string reason;
    if (!m[v].allFinite()) {
      reason = "has a non-finite entry";
    } else if ((m[v] - m[v].transpose()).cwiseAbs().maxCoeff() > 1e-12 * m[v].cwiseAbs().maxCoeff()) {
      reason = "is not symmetric";
    } else {
      const Eigen::SelfAdjointEigenSolver<Metric> eig(m[v], Eigen::EigenvaluesOnly);
      reason = fmt::format("is not positive definite (smallest eigenvalue {})", eig.eigenvalues()[0]);
    }
    throw std::invalid_argument(fmt::format("background metric at vertex {} {}", v + 1, reason));
  }
}

void check_hgrad(double hgrad) {
  if (!(hgrad >= 1) || !std::isfinite(hgrad))
    throw std::invalid_argument(fmt::format("gradation hgrad must be finite and >= 1 (got {})", hgrad));
}

void check_point(const Vec3& x) {
  if (!x.allFinite())
    throw std::domain_error(
        fmt::format("background field queried at a non-finite point ({}, {}, {})", x.x(), x.y(), x.z()));
}

// log and exp of a symmetric matrix through its eigendecomposition.
Metric log_spd(const Metric& m) {
  const Eigen::SelfAdjointEigenSolver<Metric> eig(0.5 * (m + m.transpose()));
  const Vec3 l = eig.eigenvalues().array().log();
  return eig.eigenvectors() * l.asDiagonal() * eig.eigenvectors().transpose();
}

Metric exp_sym(const Metric& l) {
  const Eigen::SelfAdjointEigenSolver<Metric> eig(l);
  const Vec3 e = eig.eigenvalues().array().exp();
  return eig.eigenvectors() * e.asDiagonal() * eig.eigenvectors().transpose();
}

// Barycentric coordinates of x in the tet v[0..3] (weight of v[i] in b[i]),
// each as the ratio of x's and v[f]'s heights over the plane of face f, so a
// point on a shared face gets the same weights from both tets up to rounding
// and either orientation works. False for a flat tet.
bool barycentric(const std::array<const Vec3*, 4>& v, const Vec3& x, std::array<double, 4>& b) {
  for (int f = 0; f < 4; ++f) {
    const auto& fv = mesh::kFaceVerts[f];
    const Vec3& p = *v[fv[0]];
    const Vec3 n = (*v[fv[1]] - p).cross(*v[fv[2]] - p);
    const double den = n.dot(*v[f] - p);
    if (!(den != 0)) return false;
    b[f] = n.dot(x - p) / den;
  }
  return std::isfinite(b[0] + b[1] + b[2] + b[3]);
}

// The same weights, but giving up at the first face that has x outside by
// more than kInsideTol: most candidate tets of a query fail at once.
bool inside_weights(const std::array<const Vec3*, 4>& v, const Vec3& x, std::array<double, 4>& b) {
  for (int f = 0; f < 4; ++f) {
    const auto& fv = mesh::kFaceVerts[f];
    const Vec3& p = *v[fv[0]];
    const Vec3 n = (*v[fv[1]] - p).cross(*v[fv[2]] - p);
    b[f] = n.dot(x - p) / n.dot(*v[f] - p);
    if (!(b[f] >= -kInsideTol)) return false;  // also rejects NaN (flat tet)
  }
  return std::isfinite(b[0] + b[1] + b[2] + b[3]);
}

// Clamps weights that passed the inside test (>= -kInsideTol) to a convex
// combination.
void clamp_weights(std::array<double, 4>& b) {
  double sum = 0;
  for (double& w : b) sum += (w = std::max(w, 0.0));
  for (double& w : b) w /= sum;
}

// Closest point of segment ab to x as the weight of b (0 for a point segment).
double closest_on_segment(const Vec3& x, const Vec3& a, const Vec3& b) {
  const Vec3 ab = b - a;
  const double l2 = ab.squaredNorm();
  if (!(l2 > 0)) return 0;
  return std::clamp((x - a).dot(ab) / l2, 0.0, 1.0);
}

// Weights (of a, b, c) of the closest point of triangle abc to x: the
// Voronoi-region walk of Ericson, Real-Time Collision Detection §5.1.5, with
// a fallback to the three edges for a degenerate (needle or point) triangle
// where the region tests divide by zero.
std::array<double, 3> closest_on_triangle(const Vec3& x, const Vec3& a, const Vec3& b, const Vec3& c) {
  const Vec3 ab = b - a, ac = c - a;
  const double area2 = ab.cross(ac).squaredNorm();
  if (!(area2 > 1e-24 * ab.squaredNorm() * ac.squaredNorm())) {
    std::array<double, 3> best{1, 0, 0};
    double best_d2 = std::numeric_limits<double>::infinity();
    const std::array<std::array<int, 2>, 3> edges{{{0, 1}, {1, 2}, {2, 0}}};
    const std::array<const Vec3*, 3> p{&a, &b, &c};
    for (const auto& e : edges) {
      const double t = closest_on_segment(x, *p[e[0]], *p[e[1]]);
      const double d2 = (x - ((1 - t) * *p[e[0]] + t * *p[e[1]])).squaredNorm();
      if (d2 < best_d2) {
        best_d2 = d2;
        best = {0, 0, 0};
        best[e[0]] = 1 - t;
        best[e[1]] = t;
      }
    }
    return best;
  }
  const Vec3 ap = x - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0) return {1, 0, 0};
  const Vec3 bp = x - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) return {0, 1, 0};
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) {
    const double t = d1 / (d1 - d3);
    return {1 - t, t, 0};
  }
  const Vec3 cp = x - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) return {0, 0, 1};
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) {
    const double t = d2 / (d2 - d6);
    return {1 - t, 0, t};
  }
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && d4 - d3 >= 0 && d5 - d6 >= 0) {
    const double t = (d4 - d3) / ((d4 - d3) + (d5 - d6));
    return {0, 1 - t, t};
  }
  const double inv = 1 / (va + vb + vc);
  const double v = vb * inv, w = vc * inv;
  return {1 - v - w, v, w};
}

// Squared distance from x to the tet v[0..3] and the weights of its closest
// point. Only faces whose plane has x on its outer side can hold the closest
// point (x minus the closest point lies in the normal cone there, spanned by
// the outward normals of the faces through it), so the others are skipped;
// all four are tried for a flat tet.
double closest_on_tet(const std::array<const Vec3*, 4>& v, const Vec3& x, std::array<double, 4>& out) {
  std::array<double, 4> b;
  const bool solid = barycentric(v, x, b);
  if (solid && *std::min_element(b.begin(), b.end()) >= -kInsideTol) {
    clamp_weights(b);
    out = b;
    return 0;
  }
  double best = std::numeric_limits<double>::infinity();
  for (int f = 0; f < 4; ++f) {
    if (solid && b[f] >= 0) continue;
    const auto& fv = mesh::kFaceVerts[f];
    const auto w = closest_on_triangle(x, *v[fv[0]], *v[fv[1]], *v[fv[2]]);
    const Vec3 p = w[0] * *v[fv[0]] + w[1] * *v[fv[1]] + w[2] * *v[fv[2]];
    const double d2 = (x - p).squaredNorm();
    if (d2 < best) {
      best = d2;
      out = {0, 0, 0, 0};
      for (int k = 0; k < 3; ++k) out[fv[k]] = w[k];
    }
  }
  return best;
}

// Float bounds that contain [lo, hi]: rounded outwards.
float float_below(double v) {
  const auto f = static_cast<float>(v);
  return static_cast<double>(f) > v ? std::nextafter(f, -std::numeric_limits<float>::infinity()) : f;
}
float float_above(double v) {
  const auto f = static_cast<float>(v);
  return static_cast<double>(f) < v ? std::nextafter(f, std::numeric_limits<float>::infinity()) : f;
}

template <class Box>
bool box_contains(const Box& n, const Vec3& x) {
  return !(x[0] < n.lo[0] || x[0] > n.hi[0] || x[1] < n.lo[1] || x[1] > n.hi[1] || x[2] < n.lo[2] || x[2] > n.hi[2]);
}

double box_distance2(const std::array<float, 3>& lo, const std::array<float, 3>& hi, const Vec3& x) {
  double d2 = 0;
  for (int k = 0; k < 3; ++k) {
    const double d = std::max({lo[k] - x[k], 0.0, x[k] - hi[k]});
    d2 += d * d;
  }
  return d2;
}

// The vertex graph of the mesh edges in CSR form (neighbours of v at
// nbrs[offsets[v] .. offsets[v+1])).
struct EdgeGraph {
  std::vector<std::size_t> offsets;
  std::vector<VertId> nbrs;
};

EdgeGraph edge_graph(const mesh::TetMesh& m) {
  std::vector<std::uint64_t> keys;
  keys.reserve(6 * m.num_tets());
  for (const auto& tv : m.tet2verts)
    for (const auto& e : mesh::kTetEdges) {
      const VertId a = std::min(tv[e[0]], tv[e[1]]), b = std::max(tv[e[0]], tv[e[1]]);
      if (a != b) keys.push_back(std::uint64_t{a} << 32 | b);
    }
  std::sort(keys.begin(), keys.end());
  keys.erase(std::unique(keys.begin(), keys.end()), keys.end());
  EdgeGraph g;
  g.offsets.assign(m.num_verts() + 1, 0);
  for (std::uint64_t k : keys) {
    ++g.offsets[(k >> 32) + 1];
    ++g.offsets[(k & 0xffffffffu) + 1];
  }
  std::partial_sum(g.offsets.begin(), g.offsets.end(), g.offsets.begin());
  g.nbrs.resize(2 * keys.size());
  std::vector<std::size_t> fill(g.offsets.begin(), g.offsets.end() - 1);
  for (std::uint64_t k : keys) {
    const auto a = static_cast<VertId>(k >> 32), b = static_cast<VertId>(k & 0xffffffffu);
    g.nbrs[fill[a]++] = b;
    g.nbrs[fill[b]++] = a;
  }
  return g;
}

}  // namespace

BackgroundField::BackgroundField(mesh::TetMesh mesh, std::vector<double> sizes)
    : coords_(std::move(mesh.coords)), tets_(std::move(mesh.tet2verts)), sizes_(std::move(sizes)) {
  check_tets(coords_, tets_);
  check_sizes(sizes_, coords_.size());
  build_bvh();
}

BackgroundField::BackgroundField(mesh::TetMesh mesh, std::vector<Metric> metrics)
    : coords_(std::move(mesh.coords)), tets_(std::move(mesh.tet2verts)) {
  check_tets(coords_, tets_);
  check_metrics(metrics, coords_.size());
  // Log-Euclidean interpolation needs log(M) of the four corners at every
  // query; taking the logs once here leaves one eigensolve per query instead
  // of five, with the same result as size::interpolate.
  log_metrics_.resize(metrics.size());
  for (std::size_t v = 0; v < metrics.size(); ++v) log_metrics_[v] = log_spd(metrics[v]);
  build_bvh();
}

void BackgroundField::build_bvh() {
  const std::size_t nt = tets_.size();
  std::vector<std::array<double, 3>> lo(nt), hi(nt), centroid(nt);
  for (std::size_t t = 0; t < nt; ++t)
    for (int k = 0; k < 3; ++k) {
      double a = coords_[tets_[t][0]][k], b = a;
      for (int i = 1; i < 4; ++i) {
        a = std::min(a, coords_[tets_[t][i]][k]);
        b = std::max(b, coords_[tets_[t][i]][k]);
      }
      lo[t][k] = a;
      hi[t][k] = b;
      centroid[t][k] = 0.5 * (a + b);
    }
  order_.resize(nt);
  std::iota(order_.begin(), order_.end(), TetId{0});
  nodes_.clear();
  nodes_.reserve(2 * (nt / kLeafSize + 1));

  // Median split along the widest extent of the box centroids: balanced, so
  // the depth bound of kStackSize holds whatever the grading.
  auto build = [&](auto&& self, std::size_t begin, std::size_t end) -> void {
    const std::size_t id = nodes_.size();
    nodes_.emplace_back();
    std::array<double, 3> blo = lo[order_[begin]], bhi = hi[order_[begin]];
    std::array<double, 3> clo = centroid[order_[begin]], chi = clo;
    for (std::size_t i = begin + 1; i < end; ++i)
      for (int k = 0; k < 3; ++k) {
        const TetId t = order_[i];
        blo[k] = std::min(blo[k], lo[t][k]);
        bhi[k] = std::max(bhi[k], hi[t][k]);
        clo[k] = std::min(clo[k], centroid[t][k]);
        chi[k] = std::max(chi[k], centroid[t][k]);
      }
    Node node;
    for (int k = 0; k < 3; ++k) {
      node.lo[k] = float_below(blo[k]);
      node.hi[k] = float_above(bhi[k]);
    }
    if (end - begin <= kLeafSize) {
      node.first = static_cast<Index>(begin);
      node.count = static_cast<Index>(end - begin);
      nodes_[id] = node;
      return;
    }
    int axis = 0;
    for (int k = 1; k < 3; ++k)
      if (chi[k] - clo[k] > chi[axis] - clo[axis]) axis = k;
    const std::size_t mid = begin + (end - begin) / 2;
    std::nth_element(order_.begin() + static_cast<std::ptrdiff_t>(begin),
                     order_.begin() + static_cast<std::ptrdiff_t>(mid),
                     order_.begin() + static_cast<std::ptrdiff_t>(end),
                     [&](TetId a, TetId b) { return centroid[a][axis] < centroid[b][axis]; });
    self(self, begin, mid);
    node.first = static_cast<Index>(nodes_.size());
    node.count = 0;
    self(self, mid, end);
    nodes_[id] = node;
  };
  build(build, 0, nt);

  // Lay the tets out in leaf order and number the vertices by first use in
  // that order, so that the tets of a leaf and their corners are close in
  // memory: random queries are bound by cache misses, not by arithmetic.
  std::vector<std::array<VertId, 4>> tets(nt);
  std::vector<VertId> new_id(coords_.size(), kNone);
  VertId next = 0;
  for (std::size_t i = 0; i < nt; ++i)
    for (int k = 0; k < 4; ++k) {
      VertId& id = new_id[tets_[order_[i]][k]];
      if (id == kNone) id = next++;
      tets[i][k] = id;
    }
  for (VertId& id : new_id)
    if (id == kNone) id = next++;
  auto permute = [&new_id](auto& values) {
    std::remove_reference_t<decltype(values)> out(values.size());
    for (std::size_t v = 0; v < values.size(); ++v) out[new_id[v]] = values[v];
    values = std::move(out);
  };
  tets_ = std::move(tets);
  permute(coords_);
  permute(sizes_);
  permute(log_metrics_);
}

bool BackgroundField::find_containing(const Vec3& x, Location& loc) const {
  if (!box_contains(nodes_[0], x)) return false;
  // Depth first through the boxes that contain x; children are tested
  // before they are pushed so that only useful nodes go through the stack.
  std::array<Index, kStackSize> stack;
  int top = 0;
  stack[top++] = 0;
  while (top > 0) {
    const Index id = stack[--top];
    const Node& n = nodes_[id];
    if (n.count == 0) {
      CM_DEBUG_ASSERT(top + 2 <= kStackSize);
      if (box_contains(nodes_[n.first], x)) stack[top++] = n.first;
      if (box_contains(nodes_[id + 1], x)) stack[top++] = id + 1;
      continue;
    }
    for (Index i = n.first; i < n.first + n.count; ++i) {
      const auto& tv = tets_[i];
      std::array<double, 4> b;
      if (!inside_weights({&coords_[tv[0]], &coords_[tv[1]], &coords_[tv[2]], &coords_[tv[3]]}, x, b)) continue;
      clamp_weights(b);
      loc = {i, b, 0};
      return true;
    }
  }
  return false;
}

BackgroundField::Location BackgroundField::find_nearest(const Vec3& x) const {
  // Branch and bound, nearer child first; a box no closer than the best tet
  // so far cannot hold a better one.
  Location best;
  double best_d2 = std::numeric_limits<double>::infinity();
  std::array<std::pair<Index, double>, kStackSize> stack;
  int top = 0;
  stack[top++] = {0, box_distance2(nodes_[0].lo, nodes_[0].hi, x)};
  while (top > 0) {
    const auto [id, d2] = stack[--top];
    if (d2 >= best_d2) continue;
    const Node& n = nodes_[id];
    if (n.count == 0) {
      const Index left = id + 1, right = n.first;
      const double dl = box_distance2(nodes_[left].lo, nodes_[left].hi, x);
      const double dr = box_distance2(nodes_[right].lo, nodes_[right].hi, x);
      CM_DEBUG_ASSERT(top + 2 <= kStackSize);
      if (dl <= dr) {
        stack[top++] = {right, dr};
        stack[top++] = {left, dl};
      } else {
        stack[top++] = {left, dl};
        stack[top++] = {right, dr};
      }
      continue;
    }
    for (Index i = n.first; i < n.first + n.count; ++i) {
      const auto& tv = tets_[i];
      std::array<double, 4> b;
      const double td2 = closest_on_tet({&coords_[tv[0]], &coords_[tv[1]], &coords_[tv[2]], &coords_[tv[3]]}, x, b);
      if (td2 < best_d2) {
        best_d2 = td2;
        best.tet = i;
        best.bary = b;
      }
    }
  }
  CM_ASSERT(best.tet != kNone);
  best.distance = std::sqrt(best_d2);
  return best;
}

BackgroundField::Location BackgroundField::locate_slot(const Vec3& x) const {
  check_point(x);
  Location loc;
  if (find_containing(x, loc)) return loc;
  return find_nearest(x);
}

BackgroundField::Location BackgroundField::locate(const Vec3& x) const {
  Location loc = locate_slot(x);
  loc.tet = order_[loc.tet];
  return loc;
}

double BackgroundField::size(const Vec3& x, const SizeHint&) const {
  const Location loc = locate_slot(x);
  const auto& tv = tets_[loc.tet];
  if (log_metrics_.empty()) {
    double h = 0;
    for (int i = 0; i < 4; ++i) h += loc.bary[i] * sizes_[tv[i]];
    return h;
  }
  // min_size(exp L) = exp(-λmax(L) / 2): the eigenvalues suffice.
  Metric l = Metric::Zero();
  for (int i = 0; i < 4; ++i) l += loc.bary[i] * log_metrics_[tv[i]];
  const Eigen::SelfAdjointEigenSolver<Metric> eig(l, Eigen::EigenvaluesOnly);
  return std::exp(-0.5 * eig.eigenvalues()[2]);
}

Metric BackgroundField::metric(const Vec3& x, const SizeHint& hint) const {
  if (log_metrics_.empty()) return isotropic_metric(size(x, hint));
  const Location loc = locate_slot(x);
  const auto& tv = tets_[loc.tet];
  Metric l = Metric::Zero();
  for (int i = 0; i < 4; ++i) l += loc.bary[i] * log_metrics_[tv[i]];
  return exp_sym(l);
}

std::vector<double> grade_sizes(const mesh::TetMesh& mesh, std::vector<double> h, double hgrad) {
  check_hgrad(hgrad);
  check_tets(mesh.coords, mesh.tet2verts);
  check_sizes(h, mesh.num_verts());
  const EdgeGraph g = edge_graph(mesh);
  const double slope = hgrad - 1;
  // Multi-source Dijkstra with every vertex a source at its own size: a
  // vertex popped with its current size is final, and relaxing its edges
  // then enforces the bound towards every later vertex exactly.
  using Item = std::pair<double, VertId>;
  std::priority_queue<Item, std::vector<Item>, std::greater<>> queue;
  for (VertId v = 0; v < h.size(); ++v) queue.emplace(h[v], v);
  std::vector<char> done(h.size(), 0);
  while (!queue.empty()) {
    const auto [hp, p] = queue.top();
    queue.pop();
    if (done[p] || hp != h[p]) continue;
    done[p] = 1;
    for (std::size_t k = g.offsets[p]; k < g.offsets[p + 1]; ++k) {
      const VertId q = g.nbrs[k];
      if (done[q]) continue;
      const double cand = hp + slope * (mesh.coords[q] - mesh.coords[p]).norm();
      if (cand < h[q]) {
        h[q] = cand;
        queue.emplace(cand, q);
      }
    }
  }
  return h;
}

std::vector<Metric> grade_metrics(const mesh::TetMesh& mesh, std::vector<Metric> m, double hgrad) {
  check_hgrad(hgrad);
  check_tets(mesh.coords, mesh.tet2verts);
  check_metrics(m, mesh.num_verts());
  for (Metric& x : m) x = 0.5 * (x + x.transpose());
  const EdgeGraph g = edge_graph(mesh);
  const double slope = hgrad - 1;
  constexpr double kRelTol = 1e-9;
  // Finest vertex first, as in the scalar Dijkstra (to which this reduces for
  // isotropic metrics); a vertex is queued again whenever its metric grows.
  // `version` invalidates the older queue entries of a vertex.
  using Item = std::tuple<double, VertId, std::uint32_t>;
  std::priority_queue<Item, std::vector<Item>, std::greater<>> queue;
  std::vector<std::uint32_t> version(m.size(), 0);
  for (VertId v = 0; v < m.size(); ++v) queue.emplace(min_size(m[v]), v, 0);
  const std::size_t max_visits = 100 * m.size();
  std::size_t visits = 0;
  while (!queue.empty() && visits < max_visits) {
    const auto [key, p, ver] = queue.top();
    queue.pop();
    if (ver != version[p]) continue;
    ++visits;
    const Metric mp = m[p];
    for (std::size_t k = g.offsets[p]; k < g.offsets[p + 1]; ++k) {
      const VertId q = g.nbrs[k];
      const double eta = 1 + slope * metric_length(mp, mesh.coords[p], mesh.coords[q]);
      const Metric grown = mp / (eta * eta);
      // Largest λ with grown·u = λ·M_q·u: how much finer than M_q the grown
      // metric of p is along its worst direction (<= 1: the bound holds).
      const Eigen::GeneralizedSelfAdjointEigenSolver<Metric> ges(grown, m[q], Eigen::EigenvaluesOnly | Eigen::Ax_lBx);
      if (ges.eigenvalues()[2] <= 1 + kRelTol) continue;
      m[q] = intersect(m[q], grown);
      queue.emplace(min_size(m[q]), q, ++version[q]);
    }
  }
  return m;
}

}  // namespace cm::size
