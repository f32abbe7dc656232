#include "curvemesh/geom/cusps.hpp"

#include <algorithm>
#include <cmath>
#include <iterator>
#include <numbers>

namespace cm::geom {

namespace {

struct End {
  int edge, side;
  Vec3 direction;  // unit, leaving the vertex
};

// The non-degenerate edge ends at each vertex (index: vertex tag).
std::vector<std::vector<End>> ends_at_vertices(const Model& m) {
  std::vector<std::vector<End>> at(m.count(0) + 1);
  for (int e = 1; e <= m.count(1); ++e) {
    if (m.is_degenerate(e)) continue;
    const auto v = m.edge_vertices(e);
    const ParamRange r = m.param_range({1, e});
    for (int side = 0; side < 2; ++side) {
      if (v[side] <= 0) continue;
      const Vec3 d = m.edge_derivatives(e, side == 0 ? r.u0 : r.u1).d1 * (side == 0 ? 1.0 : -1.0);
      if (d.norm() > 0) at[v[side]].push_back({e, side, d.normalized()});
    }
  }
  return at;
}

bool is_cusp_pair(const End& a, const End& b) {
  return a.direction.dot(b.direction) > std::cos(kCuspDegrees * std::numbers::pi / 180);
}

double param_from_end(const ParamRange& r, int side, double t) {
  return side == 0 ? r.u0 + t * (r.u1 - r.u0) : r.u1 - t * (r.u1 - r.u0);
}

// Distance from the vertex, along edge a.edge, at which the strip between
// it and edge b is `width` wide. The strip widens as the square of that
// distance (or linearly for an angle), so the first half of the edge is
// searched with steps that are fine near the vertex, then bisected. If it
// never gets wide enough there, the half-way point: the caller's caps on R
// are then what decide.
double tip_length(const Model& m, const End& a, int other_edge, const Vec3& vertex,
                  const std::function<double(const Vec3&)>& width) {
  const ParamRange r = m.param_range({1, a.edge});
  const auto point = [&](double t) { return m.edge_point(a.edge, param_from_end(r, a.side, t)); };
  const auto wide = [&](double t) {
    const Vec3 x = point(t);
    return m.closest_point({1, other_edge}, x).distance >= width(x);
  };
  constexpr int kSteps = 32;
  double narrow = 0;
  for (int k = 1; k <= kSteps; ++k) {
    double t = 0.5 * double(k) / kSteps;
    t *= 2 * t;  // (k / kSteps)² / 2
    if (!wide(t)) {
      narrow = t;
      continue;
    }
    double lo = narrow, hi = t;
    for (int i = 0; i < 12; ++i) {
      const double mid = 0.5 * (lo + hi);
      (wide(mid) ? hi : lo) = mid;
    }
    return (point(hi) - vertex).norm();
  }
  return (point(0.5) - vertex).norm();
}

}  // namespace

std::vector<std::array<bool, 2>> cusp_ends(const Model& m) {
  std::vector<std::array<bool, 2>> out(m.count(1), {false, false});
  for (const auto& ends : ends_at_vertices(m))
    for (std::size_t i = 0; i < ends.size(); ++i)
      for (std::size_t j = i + 1; j < ends.size(); ++j)
        if (is_cusp_pair(ends[i], ends[j])) {
          out[ends[i].edge - 1][ends[i].side] = true;
          out[ends[j].edge - 1][ends[j].side] = true;
        }
  return out;
}

namespace {

// The cusp pairs at a vertex, as indices into its ends.
std::vector<std::array<std::size_t, 2>> pairs_at(const std::vector<End>& ends) {
  std::vector<std::array<std::size_t, 2>> out;
  for (std::size_t i = 0; i < ends.size(); ++i)
    for (std::size_t j = i + 1; j < ends.size(); ++j)
      if (ends[i].edge != ends[j].edge && is_cusp_pair(ends[i], ends[j])) out.push_back({i, j});
  return out;
}

// The distance at which a pair's strip is `width` wide (the nearer of the
// two edges' answers).
double pair_length(const Model& m, const std::vector<End>& ends, const std::array<std::size_t, 2>& pair,
                   const Vec3& p, const std::function<double(const Vec3&)>& width) {
  const End &a = ends[pair[0]], &b = ends[pair[1]];
  return std::min(tip_length(m, a, b.edge, p, width), tip_length(m, b, a.edge, p, width));
}

// What bounds a radius around vertex v: 0.4 times the length of every edge
// there and 0.8 times the distance to its point half-way by parameter (so
// each edge keeps nodes of its own beyond it; a closed edge comes back to
// the vertex, so its length alone would not do), and 0.8 times the distance
// to any face that does not touch the vertex.
double capped_radius(const Model& m, int v, const Vec3& p, double radius) {
  std::vector<int> touching;  // faces at the vertex
  for (const int e : m.upward({0, v})) {
    if (!m.is_degenerate(e)) {
      const ParamRange r = m.param_range({1, e});
      const double half_way = (m.edge_point(e, 0.5 * (r.u0 + r.u1)) - p).norm();
      radius = std::min({radius, 0.4 * m.length(e), 0.8 * half_way});
    }
    for (const int f : m.upward({1, e})) touching.push_back(f);
  }
  std::sort(touching.begin(), touching.end());
  for (int f = 1; f <= m.count(2); ++f) {
    if (std::binary_search(touching.begin(), touching.end(), f)) continue;
    const BoundingBox b = m.bounding_box({2, f});
    const Vec3 gap = (b.min - p).cwiseMax(p - b.max).cwiseMax(0.0);
    if (gap.norm() >= 1.25 * radius) continue;
    radius = std::min(radius, 0.8 * m.closest_point({2, f}, p).distance);
  }
  return radius;
}

// The radius of a wedge span at vertex v with these (two or more) cusp
// pairs, or 0 where none applies (see wedge_spans).
double span_radius(const Model& m, int v, const std::vector<End>& ends,
                   const std::vector<std::array<std::size_t, 2>>& pairs) {
  const double slope = std::tan(kCuspDegrees * std::numbers::pi / 180);
  const Vec3 p = m.vertex_point(v);
  const auto opened = [&](const Vec3& x) { return slope * (x - p).norm(); };
  double widest = 0;
  for (const auto& pair : pairs) widest = std::max(widest, pair_length(m, ends, pair, p, opened));
  const double radius = capped_radius(m, v, p, widest);
  if (!(radius > 0) || !std::isfinite(radius)) return 0;
  // A span that leaves a strip's triangle under half the cusp angle has not
  // opened it, and a long sliver between two nearly collinear segments is
  // what boundary recovery handles worst (a Steiner point splits it, at a
  // quarter of the angle).
  for (const auto& pair : pairs) {
    std::array<Vec3, 2> x;
    for (int k = 0; k < 2; ++k) {
      const End& end = ends[pair[k]];
      const std::optional<double> u = param_at_distance(m, end.edge, end.side, radius);
      if (!u) return 0;
      x[k] = m.edge_point(end.edge, *u);
    }
    if (2 * std::asin(std::min(1.0, 0.5 * (x[0] - x[1]).norm() / radius)) <
        0.5 * kCuspDegrees * std::numbers::pi / 180)
      return 0;
  }
  return radius;
}

}  // namespace

std::vector<CuspTip> cusp_tips(const Model& m, const std::function<double(const Vec3&)>& width) {
  std::vector<CuspTip> out;
  const auto at = ends_at_vertices(m);
  for (int v = 1; v < static_cast<int>(at.size()); ++v) {
    const auto pairs = pairs_at(at[v]);
    // Two faces tapering at one vertex are wedge_spans' business where a
    // span opens their strips. Where none does (two sharp corners of 4 deg
    // at one vertex, one on each side of a face between two regions; a
    // circle tangent to a line on both sides), a tip whose sphere reaches
    // where the slowest-opening strip is wide enough: without one, the tets
    // at the vertex were flat (0.4 to 3 deg on unseen models).
    if (pairs.empty() || (pairs.size() >= 2 && span_radius(m, v, at[v], pairs) > 0)) continue;
    const Vec3 p = m.vertex_point(v);
    double length = 0;
    for (const auto& pair : pairs) length = std::max(length, pair_length(m, at[v], pair, p, width));
    const double radius = capped_radius(m, v, p, length);
    CuspTip tip{v, p, radius, {}};
    for (const auto& pair : pairs) tip.pairs.push_back({at[v][pair[0]].edge, at[v][pair[1]].edge});
    if (radius > 0 && std::isfinite(radius)) out.push_back(std::move(tip));
  }
  return out;
}

std::vector<WedgeSpan> wedge_spans(const Model& m) {
  std::vector<WedgeSpan> out;
  const auto at = ends_at_vertices(m);
  for (int v = 1; v < static_cast<int>(at.size()); ++v) {
    const auto pairs = pairs_at(at[v]);
    if (pairs.size() < 2) continue;
    const double radius = span_radius(m, v, at[v], pairs);
    if (!(radius > 0)) continue;
    std::vector<int> strips;
    for (const auto& pair : pairs) {
      std::vector<int> a = m.upward({1, at[v][pair[0]].edge}), b = m.upward({1, at[v][pair[1]].edge});
      std::sort(a.begin(), a.end());
      std::sort(b.begin(), b.end());
      std::set_intersection(a.begin(), a.end(), b.begin(), b.end(), std::back_inserter(strips));
    }
    std::sort(strips.begin(), strips.end());
    strips.erase(std::unique(strips.begin(), strips.end()), strips.end());
    out.push_back({v, radius, std::move(strips)});
  }
  return out;
}

TipBalls::TipBalls(std::vector<CuspTip> tips) : tips_(std::move(tips)) {
  std::sort(tips_.begin(), tips_.end(), [](const CuspTip& a, const CuspTip& b) { return a.point.x() < b.point.x(); });
  for (const CuspTip& t : tips_) max_radius_ = std::max(max_radius_, t.radius);
}

const CuspTip* TipBalls::find(const Vec3& x) const {
  auto it = std::lower_bound(tips_.begin(), tips_.end(), x.x() - max_radius_,
                             [](const CuspTip& t, double value) { return t.point.x() < value; });
  for (; it != tips_.end() && it->point.x() <= x.x() + max_radius_; ++it)
    if ((x - it->point).norm() < it->radius) return &*it;
  return nullptr;
}

const CuspTip* TipBalls::sphere_of(const Vec3& x) const {
  constexpr double kTolerance = 1e-6;
  auto it = std::lower_bound(tips_.begin(), tips_.end(), x.x() - 2 * max_radius_,
                             [](const CuspTip& t, double value) { return t.point.x() < value; });
  for (; it != tips_.end() && it->point.x() <= x.x() + 2 * max_radius_; ++it)
    if (std::abs((x - it->point).norm() - it->radius) <= kTolerance * it->radius) return &*it;
  return nullptr;
}

Vec3 TipBalls::onto_sphere(const CuspTip& tip, const Vec3& x) {
  const Vec3 ray = x - tip.point;
  if (!(ray.squaredNorm() > 0)) return x;
  return tip.point + ray * (tip.radius * (1 + 1e-9) / ray.norm());
}

std::optional<double> param_at_distance(const Model& m, int edge, int side, double radius) {
  const ParamRange r = m.param_range({1, edge});
  const Vec3 end = m.edge_point(edge, side == 0 ? r.u0 : r.u1);
  const auto far = [&](double t) { return (m.edge_point(edge, param_from_end(r, side, t)) - end).norm() >= radius; };
  constexpr int kSteps = 64;
  for (int k = 1; k <= kSteps; ++k) {
    const double t = double(k) / kSteps;
    if (!far(t)) continue;
    double lo = double(k - 1) / kSteps, hi = t;
    for (int i = 0; i < 40 && hi - lo > 1e-14; ++i) {
      const double mid = 0.5 * (lo + hi);
      (far(mid) ? hi : lo) = mid;
    }
    return param_from_end(r, side, hi);
  }
  return std::nullopt;
}

}  // namespace cm::geom
