#include "curvemesh/generate/surface_intersection.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include "curvemesh/core/predicates.hpp"

namespace cm::generate {

namespace {

using predicates::orient3d;

// Segment (d, e) meets the closed triangle (a, b, c) at a point strictly
// between d and e. Non-coplanar only: a segment in the triangle's plane is
// left to the other triangle's edges.
bool segment_crosses(const Vec3& d, const Vec3& e, const Vec3& a, const Vec3& b, const Vec3& c) {
  const int sd = orient3d(a.data(), b.data(), c.data(), d.data());
  const int se = orient3d(a.data(), b.data(), c.data(), e.data());
  if (sd == 0 || se == 0 || sd == se) return false;
  const int t1 = orient3d(d.data(), e.data(), a.data(), b.data());
  const int t2 = orient3d(d.data(), e.data(), b.data(), c.data());
  const int t3 = orient3d(d.data(), e.data(), c.data(), a.data());
  return (t1 >= 0 && t2 >= 0 && t3 >= 0) || (t1 <= 0 && t2 <= 0 && t3 <= 0);
}

bool cross(std::span<const Vec3> x, const std::array<VertId, 3>& p, const std::array<VertId, 3>& q) {
  int shared = 0, sp = -1, sq = -1;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      if (p[i] == q[j]) {
        ++shared;
        sp = i;
        sq = j;
      }
  if (shared >= 2) return false;
  // Floating-point plane tests first (the exact predicates below cost a lot
  // on the many coplanar neighbours of a CAD surface mesh): a triangle with
  // all the other's vertices clearly on one side of its plane cannot cross
  // it, and two triangles within rounding of one plane are taken as touching
  // (a crossing at an angle below ~1e-10 is not something any mesh can fix).
  auto side_test = [&](const std::array<VertId, 3>& s, const std::array<VertId, 3>& t) {
    const Vec3 n = (x[s[1]] - x[s[0]]).cross(x[s[2]] - x[s[0]]);
    double len = 0;
    for (int i = 0; i < 3; ++i) len = std::max(len, (x[t[i]] - x[s[0]]).norm());
    const double tol = 1e-10 * n.norm() * len;
    int pos = 0, neg = 0;
    for (VertId v : t) {
      const double d = n.dot(x[v] - x[s[0]]);
      pos += d > tol;
      neg += d < -tol;
    }
    const bool shares = shared == 1;  // the shared vertex is on both planes
    if (pos == 3 - shares || neg == 3 - shares) return 1;  // one side: apart
    if (pos == 0 && neg == 0) return 0;                     // coplanar: touching at most
    return -1;                                              // undecided
  };
  const int sp_side = side_test(p, q);
  if (sp_side >= 0) return false;
  if (side_test(q, p) >= 0) return false;
  auto edge_hits = [&](const std::array<VertId, 3>& s, int i, const std::array<VertId, 3>& t) {
    return segment_crosses(x[s[i]], x[s[(i + 1) % 3]], x[t[0]], x[t[1]], x[t[2]]);
  };
  if (shared == 1) return edge_hits(p, (sp + 1) % 3, q) || edge_hits(q, (sq + 1) % 3, p);
  for (int i = 0; i < 3; ++i)
    if (edge_hits(p, i, q) || edge_hits(q, i, p)) return true;
  return false;
}

}  // namespace

std::vector<std::array<std::uint32_t, 2>> crossing_triangles(std::span<const Vec3> x,
                                                             std::span<const mesh::ClassifiedTri> tris,
                                                             std::span<const char> planar) {
  std::vector<std::array<std::uint32_t, 2>> out;
  const std::size_t n = tris.size();
  if (n < 2) return out;
  std::vector<std::array<Vec3, 2>> box(n);
  tbb::parallel_for(std::size_t{0}, n, [&](std::size_t i) {
    const auto& v = tris[i].verts;
    box[i] = {x[v[0]].cwiseMin(x[v[1]]).cwiseMin(x[v[2]]), x[v[0]].cwiseMax(x[v[1]]).cwiseMax(x[v[2]])};
  });
  Vec3 lo = Vec3::Constant(INFINITY), hi = Vec3::Constant(-INFINITY);
  double extent = 0;
  for (const auto& [tl, th] : box) {
    lo = lo.cwiseMin(tl);
    hi = hi.cwiseMax(th);
    extent += (th - tl).maxCoeff();
  }
  // Cells about the size of a mean triangle: each triangle overlaps a few
  // cells and each cell holds a few triangles. Only occupied cells count
  // (they are keys, not an array), so the grid's bound is on the entries: a
  // bound on all the box's cells made the cells of a long thin model many
  // triangles wide (917_fusee: 3.4 million candidate pairs for 65k triangles).
  const Vec3 span = (hi - lo).cwiseMax(1e-300);
  double cell = std::max(extent / static_cast<double>(n), 1e-300);
  const auto entries_at = [&](double c) {
    const Eigen::Array3d top = (span / c).array().floor();
    double total = 0;
    for (const auto& [tl, th] : box) {
      const Eigen::Array3d a = ((tl - lo) / c).array().floor().min(top).max(0.0);
      const Eigen::Array3d b = ((th - lo) / c).array().floor().min(top).max(0.0);
      total += (b - a + 1).prod();
    }
    return total;
  };
  // Keys must fit in 64 bits, and the entries stay proportional to the mesh.
  double entry_count = entries_at(cell);
  while ((span / cell).array().ceil().prod() > 1e18 || entry_count > 12.0 * static_cast<double>(n)) {
    cell *= 1.5;
    entry_count = entries_at(cell);
  }
  const auto dims = ((span / cell).array().floor() + 1).cast<std::int64_t>().eval();
  auto cell_of = [&](const Vec3& p) {
    Eigen::Array<std::int64_t, 3, 1> c = ((p - lo) / cell).array().floor().cast<std::int64_t>();
    return c.min(dims - 1).max(0).eval();
  };
  std::vector<std::pair<std::uint64_t, std::uint32_t>> entries;
  entries.reserve(static_cast<std::size_t>(entry_count));
  for (std::uint32_t i = 0; i < n; ++i) {
    const auto c0 = cell_of(box[i][0]), c1 = cell_of(box[i][1]);
    for (auto i0 = c0[0]; i0 <= c1[0]; ++i0)
      for (auto i1 = c0[1]; i1 <= c1[1]; ++i1)
        for (auto i2 = c0[2]; i2 <= c1[2]; ++i2)
          entries.emplace_back(static_cast<std::uint64_t>((i2 * dims[1] + i1) * dims[0] + i0), i);
  }
  tbb::parallel_sort(entries.begin(), entries.end());
  // Within a cell the entries are in triangle order: each pair is listed
  // with its first triangle, once per cell they share.
  std::vector<std::vector<std::uint32_t>> partners(n);
  for (std::size_t b = 0; b < entries.size();) {
    std::size_t e = b;
    while (e < entries.size() && entries[e].first == entries[b].first) ++e;
    for (std::size_t i = b; i < e; ++i)
      for (std::size_t j = i + 1; j < e; ++j) partners[entries[i].second].push_back(entries[j].second);
    b = e;
  }
  auto box_overlap = [&](std::uint32_t i, std::uint32_t j) {
    return (box[i][0].array() <= box[j][1].array()).all() && (box[j][0].array() <= box[i][1].array()).all();
  };
  // The exact tests, by first triangle in parallel: each keeps the partners
  // that cross it, read back in triangle order.
  tbb::parallel_for(tbb::blocked_range<std::uint32_t>(0, static_cast<std::uint32_t>(n), 256),
                    [&](const tbb::blocked_range<std::uint32_t>& r) {
                      for (std::uint32_t a = r.begin(); a != r.end(); ++a) {
                        std::vector<std::uint32_t>& with = partners[a];
                        std::sort(with.begin(), with.end());
                        with.erase(std::unique(with.begin(), with.end()), with.end());
                        const auto f = tris[a].face_tag;
                        const bool flat = f >= 0 && static_cast<std::size_t>(f) < planar.size() && planar[f];
                        std::erase_if(with, [&](std::uint32_t b) {
                          return (flat && tris[b].face_tag == f) || !box_overlap(a, b) ||
                                 !cross(x, tris[a].verts, tris[b].verts);
                        });
                      }
                    });
  for (std::uint32_t a = 0; a < n; ++a)
    for (const std::uint32_t b : partners[a]) out.push_back({a, b});
  return out;
}

}  // namespace cm::generate
