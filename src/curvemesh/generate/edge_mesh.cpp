#include "curvemesh/generate/edge_mesh.hpp"

#include <algorithm>
#include <cmath>
#include <map>

#include <tbb/parallel_for.h>

namespace cm::generate {

namespace {

// Metric length density |γ'(u)|_M at u.
double density(const geom::Model& m, int edge, const size::SizeField& size, double u) {
  const geom::CurveDerivatives d = m.edge_derivatives(edge, u);
  const size::SizeHint hint{{1, edge}, Vec2(u, 0)};
  if (size.anisotropic()) return std::sqrt(std::max(0.0, d.d1.dot(size.metric(d.point, hint) * d.d1)));
  return d.d1.norm() / size.size(d.point, hint);
}

struct Table {
  std::vector<double> u;    // increasing
  std::vector<double> cum;  // metric length from u.front()
};

// Simpson on each interval, bisected until an interval holds at most `tol`
// of metric length and its halves agree with it.
Table integrate(const geom::Model& m, int edge, const size::SizeField& size, double u0, double u1,
                const EdgeMeshOptions& o) {
  struct Interval {
    double a, b, fa, fm, fb;
    int depth;
  };
  const auto simpson = [](const Interval& i) { return (i.b - i.a) * (i.fa + 4 * i.fm + i.fb) / 6; };
  constexpr int kStart = 16;
  std::vector<Interval> stack;
  std::vector<double> f(kStart + 1);
  for (int k = 0; k <= kStart; ++k) f[k] = density(m, edge, size, u0 + (u1 - u0) * k / kStart);
  for (int k = kStart - 1; k >= 0; --k) {
    const double a = u0 + (u1 - u0) * k / kStart, b = u0 + (u1 - u0) * (k + 1) / kStart;
    stack.push_back({a, b, f[k], density(m, edge, size, 0.5 * (a + b)), f[k + 1], 0});
  }
  Table t{{u0}, {0.0}};
  while (!stack.empty()) {
    const Interval i = stack.back();
    stack.pop_back();
    const double whole = simpson(i);
    if (i.depth < o.max_table_depth) {
      const double mid = 0.5 * (i.a + i.b);
      const Interval left{i.a, mid, i.fa, density(m, edge, size, 0.5 * (i.a + mid)), i.fm, i.depth + 1};
      const Interval right{mid, i.b, i.fm, density(m, edge, size, 0.5 * (mid + i.b)), i.fb, i.depth + 1};
      const double halves = simpson(left) + simpson(right);
      if (whole > o.table_tolerance || std::abs(halves - whole) > 1e-3 * std::max(halves, 1e-12)) {
        stack.push_back(right);
        stack.push_back(left);
        continue;
      }
    }
    t.u.push_back(i.b);
    t.cum.push_back(t.cum.back() + whole);
  }
  return t;
}

EdgeMesh place_nodes(const geom::Model& m, int edge, const size::SizeField& size, const EdgeMeshOptions& o,
                     int min_segments, std::array<double, 2> tip_radius) {
  EdgeMesh out;
  out.edge = edge;
  out.vertices = m.edge_vertices(edge);
  out.degenerate = m.is_degenerate(edge);
  const geom::ParamRange r = m.param_range({1, edge});
  if (out.degenerate) {
    // All at the pole; the faces decide how many (u,v) points they need.
    out.params = {r.u0, r.u1};
    const Vec3 p = out.vertices[0] > 0 ? m.vertex_point(out.vertices[0]) : m.edge_point(edge, r.u0);
    out.points = {p, p};
    return out;
  }
  // A tip's sphere takes the first node; the metric places the others
  // between the two (or the edge's own) ends.
  double ua = r.u0, ub = r.u1;
  for (int side = 0; side < 2; ++side) {
    if (!(tip_radius[side] > 0)) continue;
    if (const auto u = geom::param_at_distance(m, edge, side, tip_radius[side])) (side == 0 ? ua : ub) = *u;
  }
  if (!(ua < ub)) {
    ua = r.u0;
    ub = r.u1;
  }
  const bool tip0 = ua > r.u0, tip1 = ub < r.u1;
  const Table t = integrate(m, edge, size, ua, ub, o);
  out.metric_length = t.cum.back();
  int n = static_cast<int>(std::lround(out.metric_length));
  if (m.length(edge) < o.hmin) n = 1;
  n = std::max({n, min_segments - int(tip0) - int(tip1), 1});
  std::vector<double> inner(n + 1);
  inner.front() = ua;
  inner.back() = ub;
  std::size_t k = 1;
  for (int i = 1; i < n; ++i) {
    const double target = out.metric_length * i / n;
    while (k + 1 < t.cum.size() && t.cum[k] < target) ++k;
    // Linear in the table interval [k-1, k].
    const double c0 = t.cum[k - 1], c1 = t.cum[k];
    const double w = c1 > c0 ? std::clamp((target - c0) / (c1 - c0), 0.0, 1.0) : 0.5;
    inner[i] = t.u[k - 1] + w * (t.u[k] - t.u[k - 1]);
  }
  if (tip0) out.params.push_back(r.u0);
  out.params.insert(out.params.end(), inner.begin(), inner.end());
  if (tip1) out.params.push_back(r.u1);
  out.points.resize(out.params.size());
  for (std::size_t i = 0; i < out.params.size(); ++i) out.points[i] = m.edge_point(edge, out.params[i]);
  // End points are the model vertices themselves, not the curve's ends.
  if (out.vertices[0] > 0) out.points.front() = m.vertex_point(out.vertices[0]);
  if (out.vertices[1] > 0) out.points.back() = m.vertex_point(out.vertices[1]);
  return out;
}

}  // namespace

EdgeMesh discretize_edge(const geom::Model& m, int edge, const size::SizeField& size, const EdgeMeshOptions& o,
                         int min_segments, std::array<double, 2> tip_radius, std::array<double, 2> min_first) {
  EdgeMesh out = place_nodes(m, edge, size, o, min_segments, tip_radius);
  const std::size_t n = out.points.size();
  if (out.degenerate || n < 3) return out;
  bool again = false;
  for (int side = 0; side < 2; ++side) {
    const Vec3& end = side == 0 ? out.points.front() : out.points.back();
    const Vec3& first = side == 0 ? out.points[1] : out.points[n - 2];
    if (tip_radius[side] > 0 || !(min_first[side] > (first - end).norm())) continue;
    tip_radius[side] = min_first[side];
    again = true;
  }
  return again ? place_nodes(m, edge, size, o, min_segments, tip_radius) : out;
}

std::vector<geom::CuspTip> cusp_tips(const geom::Model& m, const size::SizeField& size) {
  return geom::cusp_tips(m, [&](const Vec3& x) { return kTipWidth * size.size(x); });
}

std::vector<EdgeMesh> discretize_edges(const geom::Model& m, const size::SizeField& size, const EdgeMeshOptions& o,
                                       const std::vector<geom::CuspTip>& tips,
                                       const std::vector<geom::WedgeSpan>& spans) {
  const int ne = m.count(1);
  // Edges joining the same two vertices need two segments each so that no
  // two mesh edges coincide.
  std::map<std::pair<int, int>, int> joining;
  for (int e = 1; e <= ne; ++e) {
    if (m.is_degenerate(e)) continue;
    const auto v = m.edge_vertices(e);
    ++joining[{std::min(v[0], v[1]), std::max(v[0], v[1])}];
  }
  std::vector<double> tip_of(m.count(0) + 1, 0.0);
  for (const geom::CuspTip& tip : tips) tip_of[tip.vertex] = tip.radius;
  std::vector<double> span_of(m.count(0) + 1, 0.0);
  for (const geom::WedgeSpan& s : spans) span_of[s.vertex] = s.radius;
  std::vector<EdgeMesh> out(ne);
  tbb::parallel_for(1, ne + 1, [&](int e) {
    const auto v = m.edge_vertices(e);
    int min_segments = 1;
    if (v[0] == v[1]) {
      min_segments = 3;
    } else if (const auto it = joining.find({std::min(v[0], v[1]), std::max(v[0], v[1])});
               it != joining.end() && it->second > 1) {
      min_segments = 2;
    }
    out[e - 1] = discretize_edge(m, e, size, o, min_segments,
                                 {v[0] > 0 ? tip_of[v[0]] : 0.0, v[1] > 0 ? tip_of[v[1]] : 0.0},
                                 {v[0] > 0 ? span_of[v[0]] : 0.0, v[1] > 0 ? span_of[v[1]] : 0.0});
  });
  return out;
}

}  // namespace cm::generate
