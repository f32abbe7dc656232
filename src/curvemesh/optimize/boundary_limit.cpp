#include "curvemesh/optimize/boundary_limit.hpp"

#include <algorithm>
#include <cmath>
#include <unordered_map>
#include <unordered_set>
#include <vector>

#include "curvemesh/mesh/topology.hpp"
#include "curvemesh/quality/measures.hpp"

namespace cm::optimize {

namespace {

struct KeyHash {
  std::size_t operator()(const std::array<VertId, 3>& k) const {
    std::uint64_t h = k[0];
    h = h * 0x9E3779B97F4A7C15ull ^ k[1];
    h = h * 0x9E3779B97F4A7C15ull ^ k[2];
    return static_cast<std::size_t>(h ^ (h >> 29));
  }
};

std::array<VertId, 3> sorted(VertId a, VertId b, VertId c) {
  std::array<VertId, 3> k{a, b, c};
  std::sort(k.begin(), k.end());
  return k;
}

}  // namespace

const char* to_string(BoundaryLimit::Why why) {
  switch (why) {
    case BoundaryLimit::Why::kFree: return "free";
    case BoundaryLimit::Why::kTwoFaces: return "two boundary faces";
    case BoundaryLimit::Why::kWedge: return "boundary wedge";
  }
  return "?";
}

double best_mean_ratio_at_angle(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& side, double target) {
  const Vec3 g = (a + b + c) / 3;
  Vec3 n = (b - a).cross(c - a);
  const double area2 = n.norm();
  if (!(area2 > 0)) return 0;
  n /= area2;
  if (n.dot(side - g) < 0) n = -n;
  const Vec3 e1 = (b - a).normalized(), e2 = n.cross(e1);
  const double scale = std::sqrt(area2);  // about the triangle's size
  // One number to climb: below the target the angle (in [0, 1)), at it
  // 1 + the mean ratio, so an infeasible start climbs the angle first.
  auto score = [&](const Vec3& x) {
    const Vec3 d = g + scale * (x[0] * e1 + x[1] * e2 + x[2] * n);
    const double angle = quality::tet_min_dihedral(a, b, c, d);
    if (angle < target) return angle / target;
    return 1 + std::max(quality::tet_mean_ratio(a, b, c, d), quality::tet_mean_ratio(a, c, b, d));
  };
  // Starts: above the centroid at about a regular tet's height, and above
  // each corner and each edge's midpoint, low and high.
  std::vector<Vec3> starts{Vec3(0, 0, 0.8)};
  for (const Vec3& p : {a, b, c, Vec3((a + b) / 2), Vec3((b + c) / 2), Vec3((c + a) / 2)}) {
    const Vec3 local((p - g).dot(e1) / scale, (p - g).dot(e2) / scale, 0);
    for (double h : {0.3, 1.0}) starts.push_back(local + Vec3(0, 0, h));
  }
  double best = 0;
  for (Vec3 x : starts) {
    double cur = score(x);
    for (double step = 0.25; step > 1e-3; step /= 2) {
      for (bool moved = true; moved;) {
        moved = false;
        for (int k = 0; k < 6; ++k) {
          Vec3 y = x;
          y[k / 2] += k % 2 ? -step : step;
          if (!(y[2] > 0)) continue;
          if (const double s = score(y); s > cur + 1e-12) {
            x = y;
            cur = s;
            moved = true;
          }
        }
      }
    }
    if (cur >= 1) best = std::max(best, cur - 1);
  }
  return best;
}

BoundaryLimit classify_boundary_limit(const mesh::TetMesh& m, double target, std::size_t worst) {
  constexpr std::size_t kPriced = BoundaryLimit::kPriced;
  BoundaryLimit r;
  r.target = target;
  // Every tet face once: a face seen once is on the hull.
  std::unordered_map<std::array<VertId, 3>, int, KeyHash> faces;
  faces.reserve(3 * m.num_tets());
  for (const auto& tv : m.tet2verts)
    for (const auto& f : mesh::kFaceVerts) ++faces[sorted(tv[f[0]], tv[f[1]], tv[f[2]])];
  std::unordered_set<std::array<VertId, 3>, KeyHash> boundary;
  for (const auto& t : m.tris) boundary.insert(sorted(t.verts[0], t.verts[1], t.verts[2]));
  for (const auto& [k, n] : faces)
    if (n == 1) boundary.insert(k);
  std::unordered_set<std::array<VertId, 3>, KeyHash> boundary_edges;
  for (const auto& k : boundary)
    for (const auto& e : mesh::kTriEdges) boundary_edges.insert(sorted(k[e[0]], k[e[1]], kNone));

  using Why = BoundaryLimit::Why;
  std::vector<BoundaryLimit::Tet> bad;
  std::vector<char> is_bad(m.num_tets(), 0);
  for (TetId t = 0; t < m.num_tets(); ++t) {
    const auto& v = m.tet2verts[t];
    const Vec3 &p0 = m.coords[v[0]], &p1 = m.coords[v[1]], &p2 = m.coords[v[2]], &p3 = m.coords[v[3]];
    const double d = quality::tet_min_dihedral(p0, p1, p2, p3);
    if (d < target) {
      BoundaryLimit::Tet b;
      b.tet = t;
      b.centroid = (p0 + p1 + p2 + p3) / 4;
      b.dihedral = d;
      b.mean_ratio = quality::tet_mean_ratio(p0, p1, p2, p3);
      for (VertId x : v) b.boundary_verts += m.vert_class[x].dim < 3;
      bad.push_back(b);
      is_bad[t] = 1;
    }
  }
  // Wedges of the boundary edges of the bad tets: the sum of the dihedral
  // angles of all tets around each.
  std::unordered_map<std::array<VertId, 3>, double, KeyHash> wedge;
  for (const auto& b : bad) {
    const auto& tv = m.tet2verts[b.tet];
    for (const auto& e : mesh::kTetEdges) {
      const auto k = sorted(tv[e[0]], tv[e[1]], kNone);
      if (boundary_edges.count(k)) wedge.emplace(k, 0.0);
    }
  }
  if (!wedge.empty())
    for (const auto& tv : m.tet2verts) {
      std::array<double, 6> angles{};
      bool computed = false;
      for (int e = 0; e < 6; ++e) {
        const auto it = wedge.find(sorted(tv[mesh::kTetEdges[e][0]], tv[mesh::kTetEdges[e][1]], kNone));
        if (it == wedge.end()) continue;
        if (!computed) {
          angles = quality::tet_dihedral_angles(m.coords[tv[0]], m.coords[tv[1]], m.coords[tv[2]], m.coords[tv[3]]);
          computed = true;
        }
        it->second += angles[static_cast<std::size_t>(e)];
      }
    }
  // Worst first, so that the price search (which costs about a third of a
  // millisecond a tet) is spent on the worst kPriced of them.
  std::sort(bad.begin(), bad.end(), [](const auto& x, const auto& y) {
    return x.dihedral != y.dihedral ? x.dihedral < y.dihedral : x.tet < y.tet;
  });
  std::size_t priced = 0;
  for (auto& b : bad) {
    const auto& tv = m.tet2verts[b.tet];
    Why why = Why::kFree;
    for (const auto& f : mesh::kFaceVerts) b.boundary_faces += boundary.count(sorted(tv[f[0]], tv[f[1]], tv[f[2]])) > 0;
    if (b.boundary_faces >= 2) b.cap = b.dihedral, why = Why::kTwoFaces;
    for (const auto& e : mesh::kTetEdges) {
      const auto it = wedge.find(sorted(tv[e[0]], tv[e[1]], kNone));
      if (it != wedge.end() && it->second < b.cap) b.cap = it->second, why = Why::kWedge;
    }
    // A cap a hair above the target is no promise the target is reachable,
    // but counting those as free keeps "pinned" a claim about the boundary.
    if (b.cap < target) {
      b.why = why;
      ++r.pinned;
      ++(why == Why::kTwoFaces ? r.by_two_faces : r.by_wedge);
      r.pinned_min_dihedral = std::min(r.pinned_min_dihedral, b.dihedral);
      r.pinned_min_mean_ratio = std::min(r.pinned_min_mean_ratio, b.mean_ratio);
      r.pinned_min_cap = std::min(r.pinned_min_cap, b.cap);
      is_bad[b.tet] = 2;
    } else {
      ++r.free_below;
      if (b.boundary_faces == 1 && priced++ < kPriced)
        for (int f = 0; f < 4; ++f) {
          const auto& fv = mesh::kFaceVerts[static_cast<std::size_t>(f)];
          if (!boundary.count(sorted(tv[fv[0]], tv[fv[1]], tv[fv[2]]))) continue;
          b.price = best_mean_ratio_at_angle(m.coords[tv[fv[0]]], m.coords[tv[fv[1]]], m.coords[tv[fv[2]]],
                                             m.coords[tv[f]], target);
          if (b.price < b.mean_ratio) {
            ++r.held_by_thin_face;
            r.min_price = std::min(r.min_price, b.price);
          }
        }
    }
  }
  for (TetId t = 0; t < m.num_tets(); ++t) {
    if (is_bad[t] == 2) continue;
    const auto& v = m.tet2verts[t];
    const Vec3 &p0 = m.coords[v[0]], &p1 = m.coords[v[1]], &p2 = m.coords[v[2]], &p3 = m.coords[v[3]];
    r.free_min_mean_ratio = std::min(r.free_min_mean_ratio, quality::tet_mean_ratio(p0, p1, p2, p3));
    r.free_min_dihedral = std::min(r.free_min_dihedral, quality::tet_min_dihedral(p0, p1, p2, p3));
  }
  if (bad.size() > worst) bad.resize(worst);
  r.worst = std::move(bad);
  return r;
}

}  // namespace cm::optimize
