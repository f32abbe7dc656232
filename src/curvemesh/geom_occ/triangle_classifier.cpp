// TriangleClassifier: a bounding-volume hierarchy over the triangles (median
// split on the widest centroid axis), the "within a triangle's band" query
// and ray-parity point-in-solid.
#include "curvemesh/geom_occ/detail/triangle_classifier.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>

namespace cm::geom_occ::detail {

namespace {

constexpr std::uint32_t kLeafSize = 4;
// Median splits keep the depth within log2(T) + 1, and a depth-first walk
// holds at most one pending node per level plus one.
constexpr int kStackSize = 64;
// A crossing this close to a triangle's edge (in barycentric units) may be
// counted on both triangles that share the edge, or on neither.
constexpr double kGrazing = 1e-9;
// Fixed directions with no simple ratio between their components, so that
// CAD faces (axis-aligned, symmetric) are neither parallel nor edge-on to them.
const std::array<Vec3, 3> kRays = {Vec3(0.8234, 0.4471, 0.3497).normalized(),
                                   Vec3(-0.3123, 0.8817, -0.3536).normalized(),
                                   Vec3(0.2815, -0.4130, 0.8662).normalized()};

double squared_box_distance(const Vec3& x, const Vec3& lo, const Vec3& hi) {
  return (lo - x).cwiseMax(x - hi).cwiseMax(0.0).squaredNorm();
}

// Barycentric coordinates of the point of triangle abc closest to x, by the
// Voronoi regions of its vertices, edges and face (Ericson, "Real-Time
// Collision Detection", §5.1.5).
Vec3 closest_barycentric(const Vec3& x, const std::array<Vec3, 3>& t) {
  const Vec3 &a = t[0], &b = t[1], &c = t[2];
  const Vec3 ab = b - a, ac = c - a, ax = x - a;
  const double d1 = ab.dot(ax), d2 = ac.dot(ax);
  if (d1 <= 0 && d2 <= 0) return {1, 0, 0};
  const Vec3 bx = x - b;
  const double d3 = ab.dot(bx), d4 = ac.dot(bx);
  if (d3 >= 0 && d4 <= d3) return {0, 1, 0};
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) {
    const double v = d1 / (d1 - d3);
    return {1 - v, v, 0};
  }
  const Vec3 cx = x - c;
  const double d5 = ab.dot(cx), d6 = ac.dot(cx);
  if (d6 >= 0 && d5 <= d6) return {0, 0, 1};
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) {
    const double w = d2 / (d2 - d6);
    return {1 - w, 0, w};
  }
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && d4 - d3 >= 0 && d5 - d6 >= 0) {
    const double w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
    return {0, 1 - w, w};
  }
  const double denom = 1 / (va + vb + vc);
  return {1 - (vb + vc) * denom, vb * denom, vc * denom};
}

double squared_triangle_distance(const Vec3& x, const std::array<Vec3, 3>& t, Vec3* barycentric = nullptr) {
  const Vec3 w = closest_barycentric(x, t);
  if (barycentric) *barycentric = w;
  return (x - (w[0] * t[0] + w[1] * t[1] + w[2] * t[2])).squaredNorm();
}

bool ray_hits_box(const Vec3& x, const Vec3& inv_dir, const Vec3& lo, const Vec3& hi) {
  double t0 = 0, t1 = std::numeric_limits<double>::infinity();
  for (int a = 0; a < 3; ++a) {
    double near = (lo[a] - x[a]) * inv_dir[a], far = (hi[a] - x[a]) * inv_dir[a];
    if (near > far) std::swap(near, far);
    t0 = std::max(t0, near);
    t1 = std::min(t1, far);
  }
  return t0 <= t1;
}

}  // namespace

TriangleClassifier::TriangleClassifier(std::vector<Triangle> triangles) : triangles_(std::move(triangles)) {
  if (triangles_.empty()) return;
  std::vector<Vec3> centroids(triangles_.size());
  for (std::size_t i = 0; i < triangles_.size(); ++i) {
    const auto& c = triangles_[i].corners;
    centroids[i] = (c[0] + c[1] + c[2]) / 3;
  }
  nodes_.reserve(4 * triangles_.size() / kLeafSize + 1);
  nodes_.emplace_back();
  build(0, 0, static_cast<std::uint32_t>(triangles_.size()), centroids);
}

// Fills node `self` with the subtree of triangles [first, first + count),
// reordering them (and their centroids) so that every node's are contiguous.
void TriangleClassifier::build(std::uint32_t self, std::uint32_t first, std::uint32_t count,
                               std::vector<Vec3>& centroids) {
  Node node;
  node.lo = Vec3::Constant(std::numeric_limits<double>::infinity());
  node.hi = -node.lo;
  Vec3 clo = node.lo, chi = node.hi;
  for (std::uint32_t i = first; i < first + count; ++i) {
    for (const Vec3& p : triangles_[i].corners) {
      node.lo = node.lo.cwiseMin(p);
      node.hi = node.hi.cwiseMax(p);
    }
    node.band = std::max(node.band, triangles_[i].band);
    clo = clo.cwiseMin(centroids[i]);
    chi = chi.cwiseMax(centroids[i]);
  }
  if (count <= kLeafSize) {
    node.first = first;
    node.count = count;
    nodes_[self] = node;
    return;
  }
  int axis = 0;
  (chi - clo).maxCoeff(&axis);
  std::vector<std::uint32_t> order(count);
  std::iota(order.begin(), order.end(), first);
  const std::uint32_t half = count / 2;
  std::nth_element(order.begin(), order.begin() + half, order.end(),
                   [&](std::uint32_t a, std::uint32_t b) { return centroids[a][axis] < centroids[b][axis]; });
  std::vector<Triangle> tris(count);
  std::vector<Vec3> cents(count);
  for (std::uint32_t k = 0; k < count; ++k) {
    tris[k] = triangles_[order[k]];
    cents[k] = centroids[order[k]];
  }
  std::copy(tris.begin(), tris.end(), triangles_.begin() + first);
  std::copy(cents.begin(), cents.end(), centroids.begin() + first);
  node.first = static_cast<std::uint32_t>(nodes_.size());
  node.count = 0;
  nodes_[self] = node;
  nodes_.resize(nodes_.size() + 2);
  build(node.first, first, half, centroids);
  build(node.first + 1, first + half, count - half, centroids);
}

bool TriangleClassifier::in_band(const Vec3& x) const {
  if (nodes_.empty()) return false;
  std::uint32_t stack[kStackSize];
  int top = 0;
  stack[top++] = 0;
  while (top > 0) {
    const Node& n = nodes_[stack[--top]];
    if (squared_box_distance(x, n.lo, n.hi) > n.band * n.band) continue;
    if (n.count == 0) {
      stack[top++] = n.first;
      stack[top++] = n.first + 1;
      continue;
    }
    for (std::uint32_t i = n.first; i < n.first + n.count; ++i)
      if (squared_triangle_distance(x, triangles_[i].corners) <= triangles_[i].band * triangles_[i].band) return true;
  }
  return false;
}

std::optional<TriangleClassifier::Nearest> TriangleClassifier::nearest(const Vec3& x) const {
  if (nodes_.empty()) return std::nullopt;
  double best = std::numeric_limits<double>::infinity();
  std::uint32_t best_index = 0;
  Vec3 best_bary = Vec3::Zero();
  std::uint32_t stack[kStackSize];
  int top = 0;
  stack[top++] = 0;
  while (top > 0) {
    const Node& n = nodes_[stack[--top]];
    if (squared_box_distance(x, n.lo, n.hi) >= best) continue;
    if (n.count == 0) {
      // Nearer child last, so it is searched first and prunes the other.
      const Node &l = nodes_[n.first], &r = nodes_[n.first + 1];
      const bool left_first = squared_box_distance(x, l.lo, l.hi) <= squared_box_distance(x, r.lo, r.hi);
      stack[top++] = left_first ? n.first + 1 : n.first;
      stack[top++] = left_first ? n.first : n.first + 1;
      continue;
    }
    for (std::uint32_t i = n.first; i < n.first + n.count; ++i) {
      Vec3 bary;
      const double d2 = squared_triangle_distance(x, triangles_[i].corners, &bary);
      if (d2 < best) {
        best = d2;
        best_index = i;
        best_bary = bary;
      }
    }
  }
  return Nearest{&triangles_[best_index], std::sqrt(best), best_bary};
}

std::vector<TriangleClassifier::Nearest> TriangleClassifier::faces_within(const Vec3& x, double radius,
                                                                          std::size_t max_faces) const {
  std::vector<Nearest> found;
  if (nodes_.empty()) return found;
  std::uint32_t stack[kStackSize];
  int top = 0;
  stack[top++] = 0;
  while (top > 0) {
    const Node& n = nodes_[stack[--top]];
    const double reach = radius + n.band;
    if (squared_box_distance(x, n.lo, n.hi) > reach * reach) continue;
    if (n.count == 0) {
      stack[top++] = n.first;
      stack[top++] = n.first + 1;
      continue;
    }
    for (std::uint32_t i = n.first; i < n.first + n.count; ++i) {
      const Triangle& t = triangles_[i];
      Vec3 bary;
      const double d2 = squared_triangle_distance(x, t.corners, &bary);
      const double r = radius + t.band;
      if (d2 > r * r) continue;
      const double d = std::sqrt(d2);
      auto it = std::find_if(found.begin(), found.end(), [&](const Nearest& f) { return f.triangle->face == t.face; });
      if (it == found.end()) {
        found.push_back({&t, d, bary});
        if (found.size() > max_faces) return found;
      } else if (d < it->distance) {
        *it = {&t, d, bary};
      }
    }
  }
  std::sort(found.begin(), found.end(),
            [](const Nearest& a, const Nearest& b) { return a.triangle->face < b.triangle->face; });
  return found;
}

std::optional<int> TriangleClassifier::crossings(const Vec3& x, const Vec3& dir) const {
  const Vec3 inv_dir = dir.cwiseInverse();
  int hits = 0;
  std::uint32_t stack[kStackSize];
  int top = 0;
  stack[top++] = 0;
  while (top > 0) {
    const Node& n = nodes_[stack[--top]];
    if (!ray_hits_box(x, inv_dir, n.lo, n.hi)) continue;
    if (n.count == 0) {
      stack[top++] = n.first;
      stack[top++] = n.first + 1;
      continue;
    }
    for (std::uint32_t i = n.first; i < n.first + n.count; ++i) {
      // Möller–Trumbore.
      const std::array<Vec3, 3>& t = triangles_[i].corners;
      const Vec3 e1 = t[1] - t[0], e2 = t[2] - t[0];
      const Vec3 p = dir.cross(e2);
      const double det = e1.dot(p);
      if (e1.cross(e2).squaredNorm() == 0) continue;  // no area: nothing to cross
      // Edge-on, the ray may slide along the triangle: no count is reliable.
      if (std::abs(det) <= 1e-12 * e1.norm() * e2.norm()) return std::nullopt;
      const double inv = 1 / det;
      const Vec3 s = x - t[0];
      const double u = s.dot(p) * inv;
      if (u < -kGrazing || u > 1 + kGrazing) continue;
      const Vec3 q = s.cross(e1);
      const double v = dir.dot(q) * inv;
      if (v < -kGrazing || u + v > 1 + kGrazing) continue;
      if (e2.dot(q) * inv <= 0) continue;  // behind x
      if (u < kGrazing || v < kGrazing || u + v > 1 - kGrazing) return std::nullopt;
      ++hits;
    }
  }
  return hits;
}

std::optional<bool> TriangleClassifier::inside(const Vec3& x) const {
  if (nodes_.empty()) return std::nullopt;
  int odd = 0, even = 0;
  for (const Vec3& dir : kRays) {
    const std::optional<int> n = crossings(x, dir);
    if (!n) continue;
    (*n % 2 == 1 ? odd : even) += 1;
    if (odd == 2) return true;
    if (even == 2) return false;
  }
  return std::nullopt;
}

}  // namespace cm::geom_occ::detail
