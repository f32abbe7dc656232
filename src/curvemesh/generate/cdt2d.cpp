// Constrained Delaunay triangulation of (u, v) boundary loops, point location
// and constrained insertion, on top of the Triangulation2d primitives.
#include "curvemesh/generate/triangulation2d.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <queue>
#include <random>
#include <unordered_map>

#include <fmt/format.h>

#include "curvemesh/core/error.hpp"
#include "curvemesh/core/predicates.hpp"


namespace cm::generate {

namespace {

int orient(const Vec2& a, const Vec2& b, const Vec2& c) {
  return predicates::orient2d(a.data(), b.data(), c.data());
}
int incircle(const Vec2& a, const Vec2& b, const Vec2& c, const Vec2& d) {
  return predicates::incircle(a.data(), b.data(), c.data(), d.data());
}

std::uint64_t directed_key(int a, int b) {
  return (std::uint64_t(std::uint32_t(a)) << 32) | std::uint32_t(b);
}
std::uint64_t undirected_key(int a, int b) { return a < b ? directed_key(a, b) : directed_key(b, a); }

// Whether c, known to be collinear with a and b (and distinct from a), lies on
// the ray from a through b. Comparing coordinates is exact, unlike a dot product.
bool same_ray(const Vec2& a, const Vec2& c, const Vec2& b) {
  auto sgn = [](double p, double q) { return (p > q) - (p < q); };
  return sgn(c.x(), a.x()) == sgn(b.x(), a.x()) && sgn(c.y(), a.y()) == sgn(b.y(), a.y());
}

// Whether d is strictly inside the circumcircle of t.
bool in_circumcircle(const Triangulation2d& m, int t, int d) {
  const auto& v = m.tris[t];
  return incircle(m.points[v[0]], m.points[v[1]], m.points[v[2]], m.points[d]) > 0;
}

// Containment of p in the closed triangle t, with the number of edges p lies on.
Location classify(const Triangulation2d& m, int t, const Vec2& p) {
  int o[3];
  for (int i = 0; i < 3; ++i) {
    const auto [x1, x2] = m.edge(t, i);
    o[i] = orient(m.points[x1], m.points[x2], p);
    if (o[i] < 0) return {};
  }
  const int zeros = (o[0] == 0) + (o[1] == 0) + (o[2] == 0);
  if (zeros == 0) return {Location::kInside, t, -1};
  if (zeros == 1) return {Location::kOnEdge, t, o[0] == 0 ? 0 : o[1] == 0 ? 1 : 2};
  // Two edges through p meet at their common vertex, the one neither is opposite.
  const int i = o[0] != 0 ? 0 : o[1] != 0 ? 1 : 2;
  return {Location::kOnVertex, t, i};
}

// Fallback when the visibility walk hits the boundary: the domain may be
// concave or have holes, so explore triangles nearest to p first, then any
// component the search did not reach.
Location search(const Triangulation2d& m, const Vec2& p, int start) {
  std::vector<char> seen(m.tris.size(), 0);
  using Item = std::pair<double, int>;
  std::priority_queue<Item, std::vector<Item>, std::greater<>> queue;
  auto centroid_dist2 = [&](int t) {
    const auto& v = m.tris[t];
    return ((m.points[v[0]] + m.points[v[1]] + m.points[v[2]]) / 3.0 - p).squaredNorm();
  };
  seen[start] = 1;
  queue.push({centroid_dist2(start), start});
  while (!queue.empty()) {
    const int t = queue.top().second;
    queue.pop();
    const Location loc = classify(m, t, p);
    if (loc.kind != Location::kOutside) return loc;
    for (int n : m.adj[t]) {
      if (n >= 0 && !seen[n]) {
        seen[n] = 1;
        queue.push({centroid_dist2(n), n});
      }
    }
  }
  for (int t = 0; t < int(m.tris.size()); ++t) {
    if (seen[t] || !m.is_live(t)) continue;
    const Location loc = classify(m, t, p);
    if (loc.kind != Location::kOutside) return loc;
  }
  return {};
}

// Splits the triangle or unconstrained edge at `loc` with vertex v (already in
// m.points) and restores the constrained Delaunay property by flips around v.
void insert_at(Triangulation2d& m, int v, const Location& loc, std::vector<std::pair<int, int>>& stack) {
  stack.clear();
  if (loc.kind == Location::kInside) {
    const auto ts = m.split_triangle(loc.tri, v);
    for (int k = 0; k < 3; ++k) stack.push_back({ts[k], k});
  } else {
    CM_ASSERT(loc.kind == Location::kOnEdge);
    const auto ts = m.split_edge(loc.tri, loc.index, v);
    stack.push_back({ts[0], 2});
    stack.push_back({ts[1], 1});
    if (ts[2] >= 0) {
      stack.push_back({ts[2], 2});
      stack.push_back({ts[3], 1});
    }
  }
  // Every triangle on the stack holds v, so only edges opposite v can turn
  // non-Delaunay; a flip leaves v in both new triangles at known places.
  while (!stack.empty()) {
    const auto [t, i] = stack.back();
    stack.pop_back();
    CM_DEBUG_ASSERT(m.tris[t][i] == v);
    const int n = m.adj[t][i];
    if (n < 0 || m.is_constrained(t, i)) continue;
    if (!in_circumcircle(m, t, m.tris[n][m.mirror(t, i)])) continue;
    m.flip(t, i);  // t = (v, b, d), n = (d, c, v)
    stack.push_back({t, 0});
    stack.push_back({n, 2});
  }
}

// Hilbert index of a point of the 2^16 x 2^16 grid.
std::uint64_t hilbert_index(std::uint32_t x, std::uint32_t y) {
  constexpr std::uint32_t n = 1u << 16;
  std::uint64_t d = 0;
  for (std::uint32_t s = n / 2; s > 0; s /= 2) {
    const std::uint32_t rx = (x & s) ? 1 : 0;
    const std::uint32_t ry = (y & s) ? 1 : 0;
    d += std::uint64_t(s) * s * ((3 * rx) ^ ry);
    if (ry == 0) {  // rotate the quadrant so the sub-curve connects
      if (rx == 1) {
        x = n - 1 - x;
        y = n - 1 - y;
      }
      std::swap(x, y);
    }
  }
  return d;
}

// Biased randomized insertion order: random rounds of doubling size (which is
// what makes the expected cost O(n log n) whatever the input order), each
// sorted along a Hilbert curve so that consecutive points are close and the
// walk from the previous insertion is short.
std::vector<int> brio_order(const std::vector<Vec2>& pts, const Eigen::AlignedBox2d& box) {
  const std::size_t n = pts.size();
  const Vec2 lo = box.min();
  const Vec2 ext = box.sizes();
  auto grid = [](double t) { return std::uint32_t(std::clamp(t, 0.0, 1.0) * 65535.0); };
  // (Hilbert index, point) records: sorting them in place is much faster than
  // sorting indices that look their keys up all over memory.
  std::vector<std::pair<std::uint64_t, int>> rec(n);
  for (std::size_t i = 0; i < n; ++i) {
    const Vec2 q = pts[i] - lo;
    rec[i] = {hilbert_index(grid(ext.x() > 0 ? q.x() / ext.x() : 0), grid(ext.y() > 0 ? q.y() / ext.y() : 0)),
              int(i)};
  }
  std::mt19937_64 rng(0x5eed);
  std::shuffle(rec.begin(), rec.end(), rng);
  for (std::size_t end = n; end > 0;) {
    const std::size_t begin = end < 64 ? 0 : end / 2;
    std::sort(rec.begin() + begin, rec.begin() + end);
    end = begin;
  }
  std::vector<int> order(n);
  for (std::size_t i = 0; i < n; ++i) order[i] = rec[i].second;
  return order;
}

// Forces segments into a triangulation. A piece (a,e) of a segment that is not
// yet an edge is inserted by deleting the triangles it crosses and
// triangulating the two polygons on either side of it, each from the edge (a,e)
// by Anglada's rule: the apex is the polygon vertex whose circle through a and
// e holds no other polygon vertex. Those polygons may touch themselves (a
// vertex or an edge appearing twice along the side), but they are always seen
// whole from (a,e), which is what the rule needs: a vertex seen twice always
// has a polygon vertex strictly inside its circle, so it is never the apex.
class SegmentInserter {
 public:
  // With `owner`, the constrained edges are recorded against the input segment
  // being inserted (set seg), which names the segments in errors and makes a
  // shared edge an overlap; without it, error messages name mesh vertices.
  SegmentInserter(Triangulation2d& m, std::unordered_map<std::uint64_t, int>* owner,
                  const std::vector<std::array<int, 2>>* segments)
      : m_(m), owner_(owner), segments_(segments) {}

  int seg = -1;

  // Inserts (a,b); appends the vertices reached after a (up to b) to chain.
  void insert(int a, int b, std::vector<int>* chain) {
    begin_a_ = a;
    begin_b_ = b;
    while (a != b) {
      a = insert_piece(a, b);
      if (chain) chain->push_back(a);
    }
  }

 private:
  Triangulation2d& m_;
  std::unordered_map<std::uint64_t, int>* owner_;
  const std::vector<std::array<int, 2>>* segments_;
  int begin_a_ = -1, begin_b_ = -1;
  std::vector<int> fan_, crossed_, left_, right_, chain_;
  std::vector<std::uint8_t> crossed_mask_;
  struct OldEdge {
    std::uint64_t key;
    int tri;
    bool constrained;
  };
  std::vector<OldEdge> old_;
  struct HalfEdge {
    std::uint64_t key;
    int tri, i;
  };
  std::vector<HalfEdge> half_;
  std::vector<int> slots_, made_;
  struct Task {
    int p, q, lo, hi;
  };
  std::vector<Task> tasks_;
  std::vector<std::pair<int, int>> flips_;

  const Vec2& P(int v) const { return m_.points[v]; }

  std::string describe_segment(int s) const {
    const auto& sg = (*segments_)[s];
    return fmt::format("segment {} (points {}-{})", s, sg[0], sg[1]);
  }

  [[noreturn]] void fail_crossing(int t, int i) const {
    const auto [u, w] = m_.edge(t, i);
    if (owner_) {
      const auto it = owner_->find(undirected_key(u, w));
      CM_ASSERT(it != owner_->end());
      throw GeometryError(fmt::format("constrained triangulation: {} and {} cross", describe_segment(seg),
                                      describe_segment(it->second)));
    }
    throw GeometryError(fmt::format("insert_segment: segment {}-{} crosses the constrained edge {}-{}", begin_a_,
                                    begin_b_, u, w));
  }

  [[noreturn]] void fail_outside() const {
    // The enclosing triangle of constrained_delaunay() makes this unreachable there.
    CM_ASSERT(!owner_);
    throw GeometryError(
        fmt::format("insert_segment: segment {}-{} leaves the triangulated region", begin_a_, begin_b_));
  }

  // Marks the existing edge (t,i) as part of the segment.
  void constrain(int t, int i) {
    const auto [u, w] = m_.edge(t, i);
    if (owner_) {
      const auto [it, fresh] = owner_->try_emplace(undirected_key(u, w), seg);
      if (!fresh)
        throw GeometryError(fmt::format("constrained triangulation: {} and {} overlap between points {} and {}",
                                        describe_segment(it->second), describe_segment(seg), std::min(u, w),
                                        std::max(u, w)));
    }
    m_.set_constrained(t, i, true);
  }

  // Inserts the part of (a,b) from a to the first vertex on it; returns that vertex.
  int insert_piece(int a, int b) {
    const Vec2& pa = P(a);
    const Vec2& pb = P(b);
    m_.triangles_around(a, fan_);
    int start = -1, k = -1;
    for (int t : fan_) {
      k = m_.local_index(t, a);
      const int u = m_.tris[t][Triangulation2d::next(k)];
      const int w = m_.tris[t][Triangulation2d::prev(k)];
      // t = (a, u, w): edge (a,u) is edge prev(k), edge (w,a) is edge next(k).
      const int ou = u == b ? 0 : orient(pa, pb, P(u));
      if (ou == 0 && same_ray(pa, P(u), pb)) {  // (a,u) is an edge along the segment
        constrain(t, Triangulation2d::prev(k));
        return u;
      }
      const int ow = w == b ? 0 : orient(pa, pb, P(w));
      if (ow == 0 && same_ray(pa, P(w), pb)) {
        constrain(t, Triangulation2d::next(k));
        return w;
      }
      if (ou < 0 && ow > 0) {  // b's direction is strictly inside the angle of t at a
        start = t;
        break;
      }
    }
    if (start < 0) fail_outside();

    // Walk along (a,b) through the triangles it crosses. The crossed edge of
    // the current triangle is (right, left) in its counter-clockwise order.
    crossed_.assign(1, start);
    crossed_mask_.assign(1, std::uint8_t(1u << k));
    right_.assign(1, m_.tris[start][Triangulation2d::next(k)]);
    left_.assign(1, m_.tris[start][Triangulation2d::prev(k)]);
    int cur = start, ci = k, e = -1;
    for (;;) {
      if (m_.is_constrained(cur, ci)) fail_crossing(cur, ci);
      const int n = m_.adj[cur][ci];
      if (n < 0) fail_outside();
      const int j = m_.mirror(cur, ci);
      const int x = m_.tris[n][j];
      crossed_.push_back(n);
      crossed_mask_.push_back(std::uint8_t(1u << j));
      if (x == b) {
        e = b;
        break;
      }
      const int o = orient(pa, pb, P(x));
      // x lies on (a,b): it cannot be beyond b, which would then be inside n.
      if (o == 0) {
        e = x;
        break;
      }
      // n = (x, left, right).
      if (o > 0) {
        left_.push_back(x);
        ci = Triangulation2d::next(j);
      } else {
        right_.push_back(x);
        ci = Triangulation2d::prev(j);
      }
      crossed_mask_.back() |= std::uint8_t(1u << ci);
      cur = n;
    }

    // Remember the outer side of every edge of the crossed triangles that is
    // not crossed: the new triangles will be glued to it by vertex pair. An
    // edge with crossed triangles on both sides (the polygon touching itself
    // along it) is rebuilt from both sides and only its flag matters.
    old_.clear();
    for (std::size_t c = 0; c < crossed_.size(); ++c) {
      const int t = crossed_[c];
      for (int i = 0; i < 3; ++i) {
        if ((crossed_mask_[c] >> i) & 1u) continue;
        const auto [x1, x2] = m_.edge(t, i);
        old_.push_back({directed_key(x1, x2), m_.adj[t][i], m_.is_constrained(t, i)});
      }
    }
    std::sort(old_.begin(), old_.end(), [](const OldEdge& l, const OldEdge& r) { return l.key < r.key; });

    // As many triangles come out as go in (same region, same vertices), so the
    // crossed slots are reused.
    slots_ = crossed_;
    made_.clear();
    triangulate_side(a, e, left_);
    chain_.assign(right_.rbegin(), right_.rend());
    triangulate_side(e, a, chain_);
    CM_ASSERT_OP(made_.size(), ==, slots_.size());

    half_.clear();
    for (int t : made_)
      for (int i = 0; i < 3; ++i) {
        const auto [x1, x2] = m_.edge(t, i);
        half_.push_back({directed_key(x1, x2), t, i});
      }
    std::sort(half_.begin(), half_.end(), [](const HalfEdge& l, const HalfEdge& r) { return l.key < r.key; });
    auto find_old = [&](std::uint64_t key) -> const OldEdge* {
      const auto it = std::lower_bound(old_.begin(), old_.end(), key,
                                       [](const OldEdge& o, std::uint64_t x) { return o.key < x; });
      return it != old_.end() && it->key == key ? &*it : nullptr;
    };
    for (const HalfEdge& h : half_) {
      const int x1 = int(h.key >> 32), x2 = int(h.key & 0xffffffffu);
      const std::uint64_t rev = directed_key(x2, x1);
      const auto it = std::lower_bound(half_.begin(), half_.end(), rev,
                                       [](const HalfEdge& o, std::uint64_t x) { return o.key < x; });
      if (it != half_.end() && it->key == rev) {
        if (h.key > rev) continue;  // linked from the other side
        bool flag = (x1 == a && x2 == e) || (x1 == e && x2 == a);
        if (const OldEdge* o = find_old(h.key)) flag = flag || o->constrained;
        m_.set_neighbour(h.tri, h.i, it->tri, flag);
      } else {
        const OldEdge* o = find_old(h.key);
        CM_ASSERT(o != nullptr);
        m_.set_neighbour(h.tri, h.i, o->tri, o->constrained);
      }
    }
    for (int t : made_)
      for (int v : m_.tris[t]) m_.vert_tri[v] = t;
    if (owner_) {
      const auto [it, fresh] = owner_->try_emplace(undirected_key(a, e), seg);
      CM_ASSERT(fresh);
    }

    // Anglada's triangulations are constrained Delaunay already; this pass only
    // tests them (3 incircles per triangle) and would repair a stray edge.
    flips_.clear();
    for (int t : made_)
      for (int i = 0; i < 3; ++i) flips_.push_back({t, i});
    legalize(m_, flips_);
    return e;
  }

  // Triangulates the polygon p, chain..., q lying left of p->q, the chain
  // ordered from p to q, into the reserved slots.
  void triangulate_side(int p, int q, const std::vector<int>& chain) {
    tasks_.assign(1, {p, q, 0, int(chain.size())});
    while (!tasks_.empty()) {
      const Task k = tasks_.back();
      tasks_.pop_back();
      if (k.lo >= k.hi) continue;
      // Circles through p and q are nested on the left of p->q, so one pass
      // that moves to any vertex inside the current circle ends at the
      // smallest one, whose circle holds no chain vertex.
      int c = k.lo;
      for (int x = k.lo + 1; x < k.hi; ++x)
        if (incircle(P(k.p), P(k.q), P(chain[c]), P(chain[x])) > 0) c = x;
      const int apex = chain[c];
      CM_ASSERT(orient(P(k.p), P(k.q), P(apex)) > 0);
      CM_ASSERT(made_.size() < slots_.size());
      const int t = slots_[made_.size()];
      m_.tris[t] = {k.p, k.q, apex};
      m_.adj[t] = {-1, -1, -1};
      m_.constrained[t] = 0;
      made_.push_back(t);
      tasks_.push_back({k.p, apex, k.lo, c});
      tasks_.push_back({apex, k.q, c + 1, k.hi});
    }
  }
};

[[noreturn]] void fail_input(const std::string& what) {
  throw GeometryError("constrained triangulation: " + what);
}

void validate(const CdtInput& in) {
  const int n = int(in.points.size());
  if (n < 3) fail_input(fmt::format("needs at least 3 points, got {}", n));
  for (int i = 0; i < n; ++i)
    if (!in.points[i].allFinite()) fail_input(fmt::format("point {} has a non-finite coordinate", i));
  for (std::size_t s = 0; s < in.segments.size(); ++s) {
    const auto [a, b] = in.segments[s];
    if (a < 0 || a >= n || b < 0 || b >= n)
      fail_input(fmt::format("segment {} refers to point {}, but there are only {} points", s,
                             (a < 0 || a >= n) ? a : b, n));
    if (a == b) fail_input(fmt::format("segment {} starts and ends at point {}", s, a));
  }
  struct Rec {
    double x, y;
    int i;
    bool operator<(const Rec& o) const { return x != o.x ? x < o.x : y != o.y ? y < o.y : i < o.i; }
  };
  std::vector<Rec> rec(n);
  for (int i = 0; i < n; ++i) rec[i] = {in.points[i].x(), in.points[i].y(), i};
  std::sort(rec.begin(), rec.end());
  for (int k = 0; k + 1 < n; ++k)
    if (rec[k].x == rec[k + 1].x && rec[k].y == rec[k + 1].y)
      fail_input(fmt::format("points {} and {} are duplicates (both at ({}, {}))", rec[k].i, rec[k + 1].i,
                             rec[k].x, rec[k].y));
  const Vec2& lo = in.points[rec.front().i];
  const Vec2& hi = in.points[rec.back().i];
  bool flat = true;
  for (int i = 0; i < n && flat; ++i) flat = orient(lo, hi, in.points[i]) == 0;
  if (flat) fail_input(fmt::format("all {} points are collinear", n));
}

}  // namespace

// ---------------------------------------------------------------------------
// Free functions

void legalize(Triangulation2d& m, std::vector<std::pair<int, int>>& edges) {
  while (!edges.empty()) {
    const auto [t, i] = edges.back();
    edges.pop_back();
    const int n = m.adj[t][i];
    if (n < 0 || m.is_constrained(t, i)) continue;
    // A vertex strictly inside the circle across an edge makes the
    // quadrilateral strictly convex, so the flip is always valid.
    if (!in_circumcircle(m, t, m.tris[n][m.mirror(t, i)])) continue;
    m.flip(t, i);  // t = (a,b,d), n = (d,c,a); edge 1 of both is the new one
    edges.push_back({t, 0});
    edges.push_back({t, 2});
    edges.push_back({n, 0});
    edges.push_back({n, 2});
  }
}

Location locate_point(const Triangulation2d& m, const Vec2& p, int hint) {
  if (m.num_tris() == 0 || !p.allFinite()) return {};
  int t = hint;
  if (t < 0 || std::size_t(t) >= m.tris.size() || !m.is_live(t)) {
    t = int(m.tris.size()) - 1;
    while (!m.is_live(t)) --t;
  }
  // Visibility walk: step across any edge p lies strictly beyond. Trying the
  // edges from a random one keeps it from cycling in a non-Delaunay (e.g.
  // constrained) triangulation; the seed depends on p only, for determinism.
  std::uint32_t rng = 0x9e3779b9u ^ std::uint32_t(std::hash<double>{}(p.x()) * 31 + std::hash<double>{}(p.y()));
  int from = -1;
  const std::size_t max_steps = 4 * m.tris.size() + 64;
  for (std::size_t step = 0; step < max_steps; ++step) {
    rng ^= rng << 13;
    rng ^= rng >> 17;
    rng ^= rng << 5;
    const int r = int(rng % 3);
    int go = -1;
    bool blocked = false;
    for (int k = 0; k < 3 && go < 0; ++k) {
      const int i = (r + k) % 3;
      const int n = m.adj[t][i];
      if (n >= 0 && n == from) continue;  // p is strictly on our side of the edge we came through
      const auto [x1, x2] = m.edge(t, i);
      if (orient(m.points[x1], m.points[x2], p) >= 0) continue;
      if (n < 0)
        blocked = true;
      else
        go = n;
    }
    if (go >= 0) {
      from = t;
      t = go;
      continue;
    }
    if (blocked) return search(m, p, t);
    return classify(m, t, p);
  }
  return search(m, p, t);
}

int locate(const Triangulation2d& m, const Vec2& p, int hint) { return locate_point(m, p, hint).tri; }

int insert_point(Triangulation2d& m, const Vec2& p, int hint) {
  const Location loc = locate_point(m, p, hint);
  if (loc.kind == Location::kOutside || loc.kind == Location::kOnVertex) return -1;
  if (loc.kind == Location::kOnEdge && m.is_constrained(loc.tri, loc.index)) return -1;
  const int v = m.add_point(p);
  std::vector<std::pair<int, int>> stack;
  insert_at(m, v, loc, stack);
  return v;
}

void insert_segment(Triangulation2d& m, int a, int b) {
  CM_ASSERT(a >= 0 && std::size_t(a) < m.points.size() && m.vert_tri[a] >= 0);
  CM_ASSERT(b >= 0 && std::size_t(b) < m.points.size() && m.vert_tri[b] >= 0);
  CM_ASSERT(a != b);
  SegmentInserter inserter(m, nullptr, nullptr);
  inserter.insert(a, b, nullptr);
}

CdtResult constrained_delaunay(const CdtInput& in) {
  validate(in);
  const int n = int(in.points.size());
  CdtResult result;
  Triangulation2d& m = result.mesh;
  m.points = in.points;

  // An enclosing right triangle far enough that every input point is strictly
  // inside. Its corners see no triangle of the region once the segments are in:
  // the outer loop hides them, so they do not change the constrained Delaunay
  // triangles inside.
  Eigen::AlignedBox2d box;
  for (const Vec2& p : in.points) box.extend(p);
  const double size = box.sizes().maxCoeff();
  const Vec2 corner = box.min() - Vec2::Constant(size);
  const double leg = 8 * size;
  const int s0 = m.add_point(corner);
  const int s1 = m.add_point(corner + Vec2(leg, 0));
  const int s2 = m.add_point(corner + Vec2(0, leg));
  for (const Vec2& q : {box.corner(Eigen::AlignedBox2d::BottomLeft), box.corner(Eigen::AlignedBox2d::BottomRight),
                        box.corner(Eigen::AlignedBox2d::TopLeft), box.corner(Eigen::AlignedBox2d::TopRight)}) {
    CM_ASSERT(orient(m.points[s0], m.points[s1], q) > 0 && orient(m.points[s1], m.points[s2], q) > 0 &&
              orient(m.points[s2], m.points[s0], q) > 0);
  }
  m.tris.reserve(2 * std::size_t(n) + 8);
  m.adj.reserve(2 * std::size_t(n) + 8);
  m.constrained.reserve(2 * std::size_t(n) + 8);
  int hint = m.add_triangle(s0, s1, s2);

  std::vector<std::pair<int, int>> stack;
  for (int v : brio_order(in.points, box)) {
    const Location loc = locate_point(m, m.points[v], hint);
    // The enclosing triangle is convex and the points distinct (validated).
    CM_ASSERT(loc.kind == Location::kInside || loc.kind == Location::kOnEdge);
    insert_at(m, v, loc, stack);
    hint = m.vert_tri[v];
  }

  std::unordered_map<std::uint64_t, int> owner;
  owner.reserve(2 * in.segments.size());
  SegmentInserter inserter(m, &owner, &in.segments);
  result.segment_vertices.resize(in.segments.size());
  for (std::size_t s = 0; s < in.segments.size(); ++s) {
    const auto [a, b] = in.segments[s];
    auto& chain = result.segment_vertices[s];
    chain.assign(1, a);
    inserter.seg = int(s);
    inserter.insert(a, b, &chain);
  }

  // Even-odd flood fill from the enclosing triangle's corner, which is outside.
  std::vector<signed char> inside(m.tris.size(), -1);
  std::vector<int> todo{m.vert_tri[s0]};
  inside[todo[0]] = 0;
  while (!todo.empty()) {
    const int t = todo.back();
    todo.pop_back();
    for (int i = 0; i < 3; ++i) {
      const int nb = m.adj[t][i];
      if (nb < 0 || inside[nb] >= 0) continue;
      inside[nb] = static_cast<signed char>(inside[t] ^ int(m.is_constrained(t, i)));
      todo.push_back(nb);
    }
  }
  for (std::size_t t = 0; t < m.tris.size(); ++t) {
    const auto& v = m.tris[t];
    const bool super = v[0] >= n || v[1] >= n || v[2] >= n;
    if (inside[t] != 1 || super) m.tris[t] = {-1, -1, -1};  // compact() drops them and their adjacency
  }
  m.points.resize(n);
  m.compact();
  return result;
}

}  // namespace cm::generate
