#include "curvemesh/optimize/boundary_limit.hpp"

#include <algorithm>
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

BoundaryLimit classify_boundary_limit(const mesh::TetMesh& m, double target, std::size_t worst) {
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
    const double d = quality::tet_dihedral_range(p0, p1, p2, p3).min;
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
    }
  }
  for (TetId t = 0; t < m.num_tets(); ++t) {
    if (is_bad[t] == 2) continue;
    const auto& v = m.tet2verts[t];
    const Vec3 &p0 = m.coords[v[0]], &p1 = m.coords[v[1]], &p2 = m.coords[v[2]], &p3 = m.coords[v[3]];
    r.free_min_mean_ratio = std::min(r.free_min_mean_ratio, quality::tet_mean_ratio(p0, p1, p2, p3));
    r.free_min_dihedral = std::min(r.free_min_dihedral, quality::tet_dihedral_range(p0, p1, p2, p3).min);
  }
  std::sort(bad.begin(), bad.end(), [](const auto& x, const auto& y) {
    return x.dihedral != y.dihedral ? x.dihedral < y.dihedral : x.tet < y.tet;
  });
  if (bad.size() > worst) bad.resize(worst);
  r.worst = std::move(bad);
  return r;
}

}  // namespace cm::optimize
