// The mesh data structure: adjacency bookkeeping and the local primitives
// (flip, splits, removal) that the CDT and the local operators build on.
#include "curvemesh/generate/triangulation2d.hpp"

#include <algorithm>
#include <unordered_map>

#include <fmt/format.h>

#include "curvemesh/core/error.hpp"
#include "curvemesh/core/predicates.hpp"

namespace cm::generate {

namespace {

std::uint64_t directed_key(int a, int b) {
  return (std::uint64_t(std::uint32_t(a)) << 32) | std::uint32_t(b);
}

int tri_orient(const Triangulation2d& m, int t) {
  const auto& v = m.tris[t];
  return predicates::orient2d(m.points[v[0]].data(), m.points[v[1]].data(), m.points[v[2]].data());
}

}  // namespace

// ---------------------------------------------------------------------------
// Triangulation2d

void Triangulation2d::set_constrained(int t, int i, bool on) {
  auto set = [&](int tt, int ii) {
    if (on)
      constrained[tt] = std::uint8_t(constrained[tt] | (1u << ii));
    else
      constrained[tt] = std::uint8_t(constrained[tt] & ~(1u << ii));
  };
  set(t, i);
  if (adj[t][i] >= 0) set(adj[t][i], mirror(t, i));
}

Triangulation2d::Balls Triangulation2d::balls() const {
  const std::size_t nv = points.size();
  Balls b;
  b.start.assign(nv + 1, 0);
  for (std::size_t t = 0; t < tris.size(); ++t)
    if (is_live(static_cast<int>(t)))
      for (const int v : tris[t]) ++b.start[static_cast<std::size_t>(v) + 1];
  for (std::size_t v = 0; v < nv; ++v) b.start[v + 1] += b.start[v];
  b.tris_of.resize(static_cast<std::size_t>(b.start[nv]));
  std::vector<int> fill(b.start.begin(), b.start.end() - 1);
  for (std::size_t t = 0; t < tris.size(); ++t)
    if (is_live(static_cast<int>(t)))
      for (const int v : tris[t]) b.tris_of[static_cast<std::size_t>(fill[static_cast<std::size_t>(v)]++)] = static_cast<int>(t);
  return b;
}

void Triangulation2d::triangles_around(int v, std::vector<int>& out) const {
  out.clear();
  const int t0 = vert_tri[v];
  if (t0 < 0) return;
  // Rotate counter-clockwise (across the edge (v, tris[t][k+2])); if the fan is
  // open, restart from its clockwise end so the output is in order.
  int t = t0;
  do {
    out.push_back(t);
    t = adj[t][next(local_index(t, v))];
  } while (t >= 0 && t != t0);
  if (t == t0) return;
  t = t0;
  for (;;) {
    const int n = adj[t][prev(local_index(t, v))];
    if (n < 0) break;
    t = n;
  }
  out.clear();
  for (; t >= 0; t = adj[t][next(local_index(t, v))]) out.push_back(t);
}

std::pair<int, int> Triangulation2d::find_edge(int a, int b) const {
  const int t0 = vert_tri[a];
  if (t0 < 0) return {-1, -1};
  std::pair<int, int> reversed{-1, -1};
  // One pass each way from vert_tri[a] covers an open fan; a closed one ends early.
  for (int dir = 0; dir < 2; ++dir) {
    int t = t0;
    do {
      const int k = local_index(t, a);
      if (tris[t][next(k)] == b) return {t, prev(k)};
      if (tris[t][prev(k)] == b) reversed = {t, next(k)};
      t = adj[t][dir == 0 ? next(k) : prev(k)];
    } while (t >= 0 && t != t0);
    if (t == t0) break;
  }
  return reversed;
}

int Triangulation2d::add_point(const Vec2& p) {
  points.push_back(p);
  vert_tri.resize(points.size(), -1);
  return int(points.size()) - 1;
}

int Triangulation2d::add_triangle(int a, int b, int c) {
  int t;
  if (!free_tris.empty()) {
    t = free_tris.back();
    free_tris.pop_back();
    tris[t] = {a, b, c};
    adj[t] = {-1, -1, -1};
    constrained[t] = 0;
  } else {
    t = int(tris.size());
    tris.push_back({a, b, c});
    adj.push_back({-1, -1, -1});
    constrained.push_back(0);
  }
  if (vert_tri.size() < points.size()) vert_tri.resize(points.size(), -1);
  vert_tri[a] = vert_tri[b] = vert_tri[c] = t;
  return t;
}

void Triangulation2d::remove_triangle(int t) {
  for (int k = 0; k < 3; ++k) {
    const int v = tris[t][k];
    if (vert_tri[v] != t) continue;
    const int n1 = adj[t][next(k)], n2 = adj[t][prev(k)];
    vert_tri[v] = n1 >= 0 ? n1 : n2;
  }
  for (int i = 0; i < 3; ++i) {
    const int n = adj[t][i];
    if (n >= 0) adj[n][mirror(t, i)] = -1;
  }
  tris[t] = {-1, -1, -1};
  adj[t] = {-1, -1, -1};
  constrained[t] = 0;
  free_tris.push_back(t);
}

void Triangulation2d::set_neighbour(int t, int i, int n, bool constrained_edge) {
  adj[t][i] = n;
  const std::uint8_t bit = std::uint8_t(1u << i);
  constrained[t] = std::uint8_t(constrained_edge ? constrained[t] | bit : constrained[t] & ~bit);
  if (n < 0) return;
  const int j = prev(local_index(n, tris[t][prev(i)]));
  CM_DEBUG_ASSERT(tris[n][next(j)] == tris[t][prev(i)] && tris[n][prev(j)] == tris[t][next(i)]);
  adj[n][j] = t;
  const std::uint8_t nbit = std::uint8_t(1u << j);
  constrained[n] = std::uint8_t(constrained_edge ? constrained[n] | nbit : constrained[n] & ~nbit);
}

void Triangulation2d::flip(int t, int i) {
  const int u = adj[t][i];
  const int j = mirror(t, i);
  const int a = tris[t][i], b = tris[t][next(i)], c = tris[t][prev(i)];
  const int d = tris[u][j];
  // t = (a,b,c), u = (d,c,b); the outer edges keep their neighbours and flags.
  const int n_ca = adj[t][next(i)], n_ab = adj[t][prev(i)];
  const int n_bd = adj[u][next(j)], n_dc = adj[u][prev(j)];
  const bool f_ca = is_constrained(t, next(i)), f_ab = is_constrained(t, prev(i));
  const bool f_bd = is_constrained(u, next(j)), f_dc = is_constrained(u, prev(j));
  tris[t] = {a, b, d};
  tris[u] = {d, c, a};
  adj[t] = adj[u] = {-1, -1, -1};
  constrained[t] = constrained[u] = 0;
  set_neighbour(t, 0, n_bd, f_bd);
  set_neighbour(t, 2, n_ab, f_ab);
  set_neighbour(u, 0, n_ca, f_ca);
  set_neighbour(u, 2, n_dc, f_dc);
  set_neighbour(t, 1, u, false);
  vert_tri[a] = vert_tri[b] = t;
  vert_tri[c] = vert_tri[d] = u;
}

std::array<int, 3> Triangulation2d::split_triangle(int t, int v) {
  const auto [a, b, c] = tris[t];
  const std::array<int, 3> n = adj[t];
  const std::uint8_t f = constrained[t];
  const int t1 = add_triangle(a, v, c);
  const int t2 = add_triangle(a, b, v);
  tris[t] = {v, b, c};
  adj[t] = {-1, -1, -1};
  constrained[t] = 0;
  set_neighbour(t, 0, n[0], f & 1u);
  set_neighbour(t1, 1, n[1], f & 2u);
  set_neighbour(t2, 2, n[2], f & 4u);
  set_neighbour(t, 1, t1, false);
  set_neighbour(t, 2, t2, false);
  set_neighbour(t1, 2, t2, false);
  vert_tri[v] = vert_tri[b] = vert_tri[c] = t;
  vert_tri[a] = t1;
  return {t, t1, t2};
}

std::array<int, 4> Triangulation2d::split_edge(int t, int i, int v) {
  const int a = tris[t][i], b = tris[t][next(i)], c = tris[t][prev(i)];
  const int u = adj[t][i];
  const bool f_bc = is_constrained(t, i);
  const int n_ca = adj[t][next(i)], n_ab = adj[t][prev(i)];
  const bool f_ca = is_constrained(t, next(i)), f_ab = is_constrained(t, prev(i));
  int d = -1, n_bd = -1, n_dc = -1;
  bool f_bd = false, f_dc = false;
  if (u >= 0) {
    // u = (d, c, b)
    const int j = mirror(t, i);
    d = tris[u][j];
    n_bd = adj[u][next(j)];
    n_dc = adj[u][prev(j)];
    f_bd = is_constrained(u, next(j));
    f_dc = is_constrained(u, prev(j));
  }
  tris[t] = {a, b, v};
  adj[t] = {-1, -1, -1};
  constrained[t] = 0;
  const int t1 = add_triangle(a, v, c);
  set_neighbour(t, 2, n_ab, f_ab);
  set_neighbour(t1, 1, n_ca, f_ca);
  set_neighbour(t, 1, t1, false);
  int u1 = -1;
  if (u >= 0) {
    tris[u] = {d, c, v};
    adj[u] = {-1, -1, -1};
    constrained[u] = 0;
    u1 = add_triangle(d, v, b);
    set_neighbour(u, 2, n_dc, f_dc);
    set_neighbour(u1, 1, n_bd, f_bd);
    set_neighbour(u, 1, u1, false);
    set_neighbour(t, 0, u1, f_bc);
    set_neighbour(t1, 0, u, f_bc);
    vert_tri[d] = u;
  } else {
    set_neighbour(t, 0, -1, f_bc);
    set_neighbour(t1, 0, -1, f_bc);
  }
  vert_tri[a] = vert_tri[b] = vert_tri[v] = t;
  vert_tri[c] = t1;
  return {t, t1, u, u1};
}

int Triangulation2d::insert_in_cavity(const Vec2& p, const std::vector<int>& cavity, std::vector<int>* fan) {
  if (cavity.empty() || !p.allFinite()) return -1;
  std::vector<int> sorted = cavity;
  std::sort(sorted.begin(), sorted.end());
  if (std::adjacent_find(sorted.begin(), sorted.end()) != sorted.end()) return -1;
  for (const int t : sorted)
    if (t < 0 || std::size_t(t) >= tris.size() || !is_live(t)) return -1;
  const auto in_cavity = [&](int t) { return t >= 0 && std::binary_search(sorted.begin(), sorted.end(), t); };
  struct Side {
    int a, b, outer;
    bool constrained;
  };
  std::vector<Side> sides;
  for (const int t : cavity)
    for (int i = 0; i < 3; ++i) {
      const int n = adj[t][i];
      if (in_cavity(n)) {
        if (is_constrained(t, i)) return -1;
        continue;
      }
      const auto [a, b] = edge(t, i);
      if (predicates::orient2d(points[a].data(), points[b].data(), p.data()) <= 0) return -1;
      sides.push_back({a, b, n, is_constrained(t, i)});
    }
  // One cycle through distinct vertices: each vertex starts exactly one side,
  // and following the sides from the first one visits them all.
  std::sort(sides.begin(), sides.end(), [](const Side& x, const Side& y) { return x.a < y.a; });
  for (std::size_t k = 0; k + 1 < sides.size(); ++k)
    if (sides[k].a == sides[k + 1].a) return -1;
  const auto side_from = [&](int a) {
    const auto it = std::lower_bound(sides.begin(), sides.end(), a, [](const Side& s, int x) { return s.a < x; });
    return it != sides.end() && it->a == a ? int(it - sides.begin()) : -1;
  };
  std::size_t walked = 0;
  for (int k = 0;;) {
    ++walked;
    k = side_from(sides[k].b);
    if (k < 0) return -1;
    if (k == 0) break;
    if (walked > sides.size()) return -1;
  }
  if (walked != sides.size()) return -1;
  // A simple cycle, all of whose edges p sees from the left, winds once
  // around p, so it bounds the cavity; a vertex inside it would be lost.
  for (const int t : cavity)
    for (const int v : tris[t])
      if (side_from(v) < 0) return -1;

  for (const int t : cavity) remove_triangle(t);
  const int v = add_point(p);
  std::vector<int> made(sides.size());
  for (std::size_t k = 0; k < sides.size(); ++k) {
    made[k] = add_triangle(sides[k].a, sides[k].b, v);
    set_neighbour(made[k], 2, sides[k].outer, sides[k].constrained);
  }
  // Fan triangle (a, b, v): its edge 0 (b, v) is edge 1 of the triangle starting at b.
  for (std::size_t k = 0; k < sides.size(); ++k) set_neighbour(made[k], 0, made[side_from(sides[k].b)], false);
  if (fan) *fan = std::move(made);
  return v;
}

void Triangulation2d::compact() {
  std::vector<int> remap(tris.size(), -1);
  int k = 0;
  for (std::size_t t = 0; t < tris.size(); ++t)
    if (is_live(int(t))) remap[t] = k++;
  for (std::size_t t = 0; t < tris.size(); ++t) {
    const int nt = remap[t];
    if (nt < 0) continue;
    tris[nt] = tris[t];
    constrained[nt] = constrained[t];
    for (int i = 0; i < 3; ++i) adj[nt][i] = adj[t][i] >= 0 ? remap[adj[t][i]] : -1;
  }
  tris.resize(k);
  adj.resize(k);
  constrained.resize(k);
  free_tris.clear();
  rebuild_vert_tri();
}

void Triangulation2d::rebuild_vert_tri() {
  vert_tri.assign(points.size(), -1);
  for (std::size_t t = 0; t < tris.size(); ++t)
    if (is_live(int(t)))
      for (int v : tris[t]) vert_tri[v] = int(t);
}

std::string Triangulation2d::check() const {
  const std::size_t nt = tris.size();
  const int nv = int(points.size());
  if (adj.size() != nt || constrained.size() != nt)
    return fmt::format("array sizes differ: {} tris, {} adj, {} constrained", nt, adj.size(), constrained.size());
  if (vert_tri.size() != points.size())
    return fmt::format("vert_tri has {} entries for {} points", vert_tri.size(), points.size());
  std::vector<char> is_free(nt, 0);
  for (int t : free_tris) {
    if (t < 0 || std::size_t(t) >= nt) return fmt::format("free list entry {} out of range", t);
    if (is_free[t]) return fmt::format("triangle {} is twice in the free list", t);
    if (tris[t] != std::array<int, 3>{-1, -1, -1}) return fmt::format("free triangle {} is not cleared", t);
    is_free[t] = 1;
  }
  std::vector<char> used(points.size(), 0);
  std::vector<std::uint64_t> keys;
  keys.reserve(3 * nt);
  for (std::size_t ut = 0; ut < nt; ++ut) {
    const int t = int(ut);
    if (!is_live(t)) {
      if (!is_free[t]) return fmt::format("deleted triangle {} is not in the free list", t);
      continue;
    }
    const auto& v = tris[t];
    for (int k = 0; k < 3; ++k)
      if (v[k] < 0 || v[k] >= nv) return fmt::format("triangle {} has vertex {} out of range", t, v[k]);
    if (v[0] == v[1] || v[1] == v[2] || v[0] == v[2])
      return fmt::format("triangle {} repeats a vertex ({}, {}, {})", t, v[0], v[1], v[2]);
    if (tri_orient(*this, t) <= 0)
      return fmt::format("triangle {} ({}, {}, {}) is not counter-clockwise", t, v[0], v[1], v[2]);
    for (int k = 0; k < 3; ++k) used[v[k]] = 1;
    for (int i = 0; i < 3; ++i) {
      const auto [x1, x2] = edge(t, i);
      keys.push_back(directed_key(x1, x2));
      const int n = adj[t][i];
      if (n < 0) continue;
      if (std::size_t(n) >= nt || !is_live(n))
        return fmt::format("triangle {} edge {} has neighbour {}, not a live triangle", t, i, n);
      const int k2 = local_index(n, x2);
      const int j = k2 < 0 ? -1 : prev(k2);
      if (j < 0 || tris[n][prev(j)] != x1)
        return fmt::format("triangle {} edge {} ({}-{}) is not an edge of its neighbour {}", t, i, x1, x2, n);
      if (adj[n][j] != t)
        return fmt::format("adjacency is not symmetric: {} -> {} across {}-{}, but back to {}", t, n, x1, x2,
                           adj[n][j]);
      if (is_constrained(t, i) != is_constrained(n, j))
        return fmt::format("constraint flag of edge {}-{} differs between triangles {} and {}", x1, x2, t, n);
    }
  }
  std::sort(keys.begin(), keys.end());
  for (std::size_t k = 0; k + 1 < keys.size(); ++k)
    if (keys[k] == keys[k + 1])
      return fmt::format("directed edge {}-{} is used by two triangles (they overlap)", keys[k] >> 32,
                         keys[k] & 0xffffffffu);
  for (std::size_t ut = 0; ut < nt; ++ut) {
    const int t = int(ut);
    if (!is_live(t)) continue;
    for (int i = 0; i < 3; ++i) {
      if (adj[t][i] >= 0) continue;
      const auto [x1, x2] = edge(t, i);
      if (std::binary_search(keys.begin(), keys.end(), directed_key(x2, x1)))
        return fmt::format("boundary edge {}-{} of triangle {} has a triangle on its other side", x1, x2, t);
    }
  }
  for (int v = 0; v < nv; ++v) {
    const int t = vert_tri[v];
    if (t < 0) {
      if (used[v]) return fmt::format("vertex {} is used but has no vert_tri", v);
      continue;
    }
    if (std::size_t(t) >= nt || !is_live(t) || local_index(t, v) < 0)
      return fmt::format("vert_tri of vertex {} is {}, which does not contain it", v, t);
  }
  return {};
}

}  // namespace cm::generate
