// The constrained Delaunay kernel of the surface mesher: triangle counts by
// Euler's formula, exact areas, segments present as constrained edges, the
// constrained Delaunay property checked with exact incircle, degenerate inputs
// (cocircular grids, points on segments, slivers, self-touching cavities), the
// input errors, point insertion, and a timing.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <numbers>
#include <random>
#include <string>

#include "curvemesh/core/error.hpp"
#include "curvemesh/core/predicates.hpp"
#include "curvemesh/core/timer.hpp"
#include "curvemesh/generate/triangulation2d.hpp"

using namespace cm;
using namespace cm::generate;

namespace {

constexpr double kPi = std::numbers::pi;

int orient(const Vec2& a, const Vec2& b, const Vec2& c) { return predicates::orient2d(a.data(), b.data(), c.data()); }

// Appends a closed loop through pts (in that order) to the input; returns the
// index of its first point.
int add_loop(CdtInput& in, const std::vector<Vec2>& pts) {
  const int first = int(in.points.size());
  const int n = int(pts.size());
  for (const Vec2& p : pts) in.points.push_back(p);
  for (int i = 0; i < n; ++i) in.segments.push_back({first + i, first + (i + 1) % n});
  return first;
}

std::vector<Vec2> circle(Vec2 c, double r, int n, bool ccw = true) {
  std::vector<Vec2> pts;
  for (int i = 0; i < n; ++i) {
    const double t = 2 * kPi * i / n * (ccw ? 1 : -1);
    pts.push_back(c + r * Vec2(std::cos(t), std::sin(t)));
  }
  return pts;
}

// Points on the boundary of the axis-aligned square [lo, hi]^2, k per side.
std::vector<Vec2> square(double lo, double hi, int k, bool ccw = true) {
  std::vector<Vec2> pts;
  const Vec2 c[4] = {{lo, lo}, {hi, lo}, {hi, hi}, {lo, hi}};
  for (int s = 0; s < 4; ++s)
    for (int i = 0; i < k; ++i) pts.push_back(c[s] + (c[(s + 1) % 4] - c[s]) * (double(i) / k));
  if (!ccw) std::reverse(pts.begin(), pts.end());
  return pts;
}

long double shoelace(const std::vector<Vec2>& pts) {
  long double a = 0;
  for (std::size_t i = 0; i < pts.size(); ++i) {
    const Vec2& p = pts[i];
    const Vec2& q = pts[(i + 1) % pts.size()];
    a += (long double)p.x() * q.y() - (long double)q.x() * p.y();
  }
  return std::abs(a) / 2;
}

long double mesh_area(const Triangulation2d& m) {
  long double a = 0;
  for (std::size_t t = 0; t < m.tris.size(); ++t) {
    if (!m.is_live(int(t))) continue;
    const Vec2& p = m.points[m.tris[t][0]];
    const Vec2& q = m.points[m.tris[t][1]];
    const Vec2& r = m.points[m.tris[t][2]];
    a += ((long double)(q.x() - p.x()) * (r.y() - p.y()) - (long double)(r.x() - p.x()) * (q.y() - p.y())) / 2;
  }
  return a;
}

// The first unconstrained interior edge that is not locally Delaunay, or "".
std::string delaunay_violation(const Triangulation2d& m) {
  for (std::size_t ut = 0; ut < m.tris.size(); ++ut) {
    const int t = int(ut);
    if (!m.is_live(t)) continue;
    for (int i = 0; i < 3; ++i) {
      const int n = m.adj[t][i];
      if (n < t || m.is_constrained(t, i)) continue;
      const int d = m.tris[n][m.mirror(t, i)];
      const auto& v = m.tris[t];
      if (predicates::incircle(m.points[v[0]].data(), m.points[v[1]].data(), m.points[v[2]].data(),
                               m.points[d].data()) > 0)
        return "edge " + std::to_string(m.edge(t, i)[0]) + "-" + std::to_string(m.edge(t, i)[1]) +
               " is not locally Delaunay";
    }
  }
  return {};
}

// Every chain starts and ends at its segment's ends, its inner vertices lie
// exactly on the segment, and consecutive vertices are constrained edges.
void expect_segments_present(const Triangulation2d& m, const CdtInput& in,
                             const std::vector<std::vector<int>>& chains) {
  ASSERT_EQ(chains.size(), in.segments.size());
  for (std::size_t s = 0; s < chains.size(); ++s) {
    const auto& c = chains[s];
    ASSERT_GE(c.size(), 2u);
    EXPECT_EQ(c.front(), in.segments[s][0]);
    EXPECT_EQ(c.back(), in.segments[s][1]);
    for (std::size_t k = 0; k + 1 < c.size(); ++k) {
      if (k > 0) {
        EXPECT_EQ(orient(m.points[c.front()], m.points[c.back()], m.points[c[k]]), 0);
      }
      const auto [t, i] = m.find_edge(c[k], c[k + 1]);
      ASSERT_GE(t, 0) << "segment " << s << " piece " << c[k] << "-" << c[k + 1] << " is not an edge";
      EXPECT_TRUE(m.is_constrained(t, i)) << "segment " << s << " piece " << c[k] << "-" << c[k + 1];
    }
  }
}

int used_vertices(const Triangulation2d& m) {
  int n = 0;
  for (int t : m.vert_tri) n += t >= 0;
  return n;
}

// Euler for a triangulated polygon with H holes, B boundary and V vertices.
int euler_tris(int v, int b, int h) { return 2 * v - b - 2 + 2 * h; }

// The standard battery for a result whose region is the loops' even-odd inside.
void expect_valid_cdt(const CdtInput& in, const CdtResult& r, int boundary_vertices, int holes,
                      long double area) {
  const Triangulation2d& m = r.mesh;
  EXPECT_EQ(m.check(), "");
  EXPECT_EQ(delaunay_violation(m), "");
  EXPECT_TRUE(m.free_tris.empty());
  EXPECT_EQ(m.points.size(), in.points.size());
  for (std::size_t v = 0; v < in.points.size(); ++v) ASSERT_EQ(m.points[v], in.points[v]);
  EXPECT_EQ(int(m.num_tris()), euler_tris(used_vertices(m), boundary_vertices, holes));
  EXPECT_NEAR(double(mesh_area(m) / area), 1.0, 1e-12);
  expect_segments_present(m, in, r.segment_vertices);
}

std::string error_of(const CdtInput& in) {
  try {
    constrained_delaunay(in);
  } catch (const GeometryError& e) {
    return e.what();
  }
  return "<no error>";
}

bool contains(const std::string& s, const std::string& part) { return s.find(part) != std::string::npos; }

}  // namespace

TEST(Triangulation2dCdt, SquareWithSquareHole) {
  for (bool hole_ccw : {true, false}) {
    CdtInput in;
    add_loop(in, square(0, 1, 5));
    add_loop(in, square(0.25, 0.5, 3, hole_ccw));
    // Interior points: a grid, some of them in the hole (dropped).
    int inside = 0;
    for (int i = 1; i < 8; ++i)
      for (int j = 1; j < 8; ++j) {
        const Vec2 p(i / 8.0 + 1.0 / 64, j / 8.0 + 1.0 / 64);
        in.points.push_back(p);
        const bool in_hole = p.x() > 0.25 && p.x() < 0.5 && p.y() > 0.25 && p.y() < 0.5;
        inside += !in_hole;
      }
    const CdtResult r = constrained_delaunay(in);
    expect_valid_cdt(in, r, 20 + 12, 1, 1.0L - 0.0625L);
    EXPECT_EQ(used_vertices(r.mesh), 32 + inside);
    EXPECT_EQ(int(r.mesh.num_tris()), 2 * (32 + inside) - 32 - 2 + 2);
  }
}

TEST(Triangulation2dCdt, GridPointsSplitCornerSegments) {
  // An n x n integer grid (every interior edge has cocircular neighbours) with
  // an outer loop and a hole loop given by their corners only: every segment
  // passes through grid points and must be split at each of them.
  const int n = 40;
  CdtInput in;
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) in.points.push_back(Vec2(i, j));
  auto id = [&](int i, int j) { return j * n + i; };
  in.segments = {{id(0, 0), id(n - 1, 0)},
                 {id(n - 1, 0), id(n - 1, n - 1)},
                 {id(n - 1, n - 1), id(0, n - 1)},
                 {id(0, n - 1), id(0, 0)},
                 {id(10, 10), id(10, 20)},
                 {id(10, 20), id(20, 20)},
                 {id(20, 20), id(20, 10)},
                 {id(20, 10), id(10, 10)}};
  const CdtResult r = constrained_delaunay(in);
  const int b = 4 * (n - 1) + 40;
  expect_valid_cdt(in, r, b, 1, (long double)(n - 1) * (n - 1) - 100);
  EXPECT_EQ(used_vertices(r.mesh), n * n - 81);
  for (int s = 0; s < 4; ++s) EXPECT_EQ(r.segment_vertices[s].size(), std::size_t(n));
  for (int s = 4; s < 8; ++s) EXPECT_EQ(r.segment_vertices[s].size(), 11u);
}

TEST(Triangulation2dCdt, CollinearPointsOnSlantedSegments) {
  // A triangle whose slanted sides hold exactly collinear points (binary
  // fractions), given in shuffled order, plus points one ulp off a side that
  // must not be taken as lying on it.
  CdtInput in;
  in.points = {{0, 0}, {3, 1}, {1, 3}};
  in.segments = {{0, 1}, {1, 2}, {2, 0}};
  std::vector<Vec2> extra;
  for (int k = 1; k < 8; ++k) {
    extra.push_back(Vec2(3.0 * k / 8, 1.0 * k / 8));                // on 0-1
    extra.push_back(Vec2(3 - 2.0 * k / 8, 1 + 2.0 * k / 8));        // on 1-2
  }
  std::mt19937 rng(7);
  std::shuffle(extra.begin(), extra.end(), rng);
  for (const Vec2& p : extra) in.points.push_back(p);
  const int off_in = int(in.points.size());
  in.points.push_back(Vec2(1.5, std::nextafter(0.5, 1.0)));  // just inside side 0-1
  const int off_out = int(in.points.size());
  in.points.push_back(Vec2(1.5, std::nextafter(0.5, 0.0)));  // just outside it
  const CdtResult r = constrained_delaunay(in);
  // Boundary: 3 corners + 14 points on the sides; the outside point is dropped.
  expect_valid_cdt(in, r, 17, 0, shoelace({{0, 0}, {3, 1}, {1, 3}}));
  EXPECT_EQ(r.segment_vertices[0].size(), 9u);
  EXPECT_EQ(r.segment_vertices[1].size(), 9u);
  EXPECT_EQ(r.segment_vertices[2].size(), 2u);
  for (std::size_t k = 1; k + 1 < r.segment_vertices[0].size(); ++k) {
    const Vec2& p = r.mesh.points[r.segment_vertices[0][k]];
    EXPECT_EQ(p.x(), 3 * p.y());
    EXPECT_GT(p.x(), r.mesh.points[r.segment_vertices[0][k - 1]].x());  // ordered from 0 to 1
  }
  EXPECT_GE(r.mesh.vert_tri[off_in], 0);
  EXPECT_EQ(r.mesh.vert_tri[off_out], -1);
}

TEST(Triangulation2dCdt, CircleWithTenThousandPointsAndHoles) {
  CdtInput in;
  const auto outer = circle({0, 0}, 1, 10000);
  add_loop(in, outer);
  long double area = shoelace(outer);
  const Vec2 centres[] = {{0.4, 0}, {-0.4, 0.1}, {0, 0.5}, {0.1, -0.5}, {-0.3, -0.45}};
  int boundary = 10000;
  for (int h = 0; h < 5; ++h) {
    const auto hole = circle(centres[h], 0.15, 300 + 100 * h, h % 2 == 0);
    add_loop(in, hole);
    area -= shoelace(hole);
    boundary += int(hole.size());
  }
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> u(-1, 1);
  for (int k = 0; k < 5000; ++k) in.points.push_back(Vec2(u(rng), u(rng)));
  const CdtResult r = constrained_delaunay(in);
  expect_valid_cdt(in, r, boundary, 5, area);
}

TEST(Triangulation2dCdt, ThinSliverRectangle) {
  const int k = 1000;
  const double w = 1e-6;
  std::vector<Vec2> pts;
  for (int i = 0; i < k; ++i) pts.push_back(Vec2(double(i) / (k - 1), 0));
  for (int i = k - 1; i >= 0; --i) pts.push_back(Vec2(double(i) / (k - 1), w));
  CdtInput in;
  add_loop(in, pts);
  const CdtResult r = constrained_delaunay(in);
  expect_valid_cdt(in, r, 2 * k, 0, shoelace(pts));
  EXPECT_EQ(int(r.mesh.num_tris()), 2 * k - 2);
}

TEST(Triangulation2dCdt, RandomPolygonsWithManyHoles) {
  for (unsigned seed = 1; seed <= 6; ++seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u(0, 1);
    CdtInput in;
    // Star-shaped outer loop: radius in [0.8, 1.3].
    std::vector<Vec2> outer;
    const int no = 150 + int(100 * u(rng));
    for (int i = 0; i < no; ++i) {
      const double t = 2 * kPi * i / no;
      const double rad = 1.05 + 0.15 * std::sin(5 * t) + 0.1 * (u(rng) - 0.5);
      outer.push_back(rad * Vec2(std::cos(t), std::sin(t)));
    }
    if (seed % 2) std::reverse(outer.begin(), outer.end());
    add_loop(in, outer);
    long double area = shoelace(outer);
    int boundary = no, holes = 0;
    // Star-shaped holes in the cells of a grid, each within its cell's disc.
    const int g = 7;
    const double cell = 1.3 / g;
    for (int i = 0; i < g; ++i)
      for (int j = 0; j < g; ++j) {
        if (u(rng) < 0.25) continue;
        const Vec2 c(-0.65 + (i + 0.5) * cell, -0.65 + (j + 0.5) * cell);
        if (c.norm() > 0.6) continue;
        std::vector<Vec2> hole;
        const int nh = 3 + int(25 * u(rng));
        for (int k = 0; k < nh; ++k) {
          const double t = 2 * kPi * (k + 0.8 * u(rng)) / nh;
          const double rad = cell * (0.15 + 0.3 * u(rng));
          hole.push_back(c + rad * Vec2(std::cos(t), std::sin(t)));
        }
        if (u(rng) < 0.5) std::reverse(hole.begin(), hole.end());
        add_loop(in, hole);
        area -= shoelace(hole);
        boundary += nh;
        ++holes;
      }
    for (int k = 0; k < 3000; ++k) in.points.push_back(Vec2(2.6 * u(rng) - 1.3, 2.6 * u(rng) - 1.3));
    // Shuffle the segments: the result must not depend on loop order.
    std::shuffle(in.segments.begin(), in.segments.end(), rng);
    const CdtResult r = constrained_delaunay(in);
    SCOPED_TRACE("seed " + std::to_string(seed));
    expect_valid_cdt(in, r, boundary, holes, area);
  }
}

TEST(Triangulation2dCdt, SelfTouchingCavityWhenInsertingASegment) {
  // The triangles crossed by segment a-b surround the triangle (v, z1, z2)
  // without crossing it: the polygon above the segment touches itself at v.
  CdtInput in;
  add_loop(in, square(-1000, 1000, 1));
  const int v = int(in.points.size());
  in.points.insert(in.points.end(), {{0, 100}, {-49.9, 0.1}, {49.9, 0.1}, {-100, -100}, {100, -100}, {0, -30}});
  const int a = int(in.points.size());
  in.points.insert(in.points.end(), {{-300, 0.05}, {300, 0.05}});
  CdtResult r = constrained_delaunay(in);
  Triangulation2d& m = r.mesh;
  ASSERT_EQ(m.check(), "");
  // The configuration exists: triangle (v, z1, z2) with all three neighbours
  // crossing the line y = 0.05 while it stays above it.
  const auto [t, i] = m.find_edge(v + 1, v + 2);
  ASSERT_GE(t, 0);
  ASSERT_EQ(m.tris[t][i], v);
  for (int n : m.adj[t]) {
    ASSERT_GE(n, 0);
    int above = 0, below = 0;
    for (int x : m.tris[n]) (m.points[x].y() > 0.05 ? above : below)++;
    EXPECT_TRUE(above > 0 && below > 0) << "neighbour " << n << " does not cross the segment";
  }
  insert_segment(m, a, a + 1);
  EXPECT_EQ(m.check(), "");
  EXPECT_EQ(delaunay_violation(m), "");
  const auto [ta, ia] = m.find_edge(a, a + 1);
  ASSERT_GE(ta, 0);
  EXPECT_TRUE(m.is_constrained(ta, ia));
  EXPECT_EQ(int(m.num_tris()), euler_tris(used_vertices(m), 4, 0));
  EXPECT_NEAR(double(mesh_area(m)), 2000.0 * 2000.0, 1e-6);
  // Inserting it again changes nothing.
  insert_segment(m, a + 1, a);
  EXPECT_EQ(m.check(), "");
}

TEST(Triangulation2dCdt, LatticeWithDiamondHoles) {
  // Every lattice point of a square, diamond-shaped holes whose slanted sides
  // pass through lattice points (split exactly), and a slanted segment chain
  // from corner to corner of a hole-free strip: collinear and cocircular
  // everywhere.
  const int n = 41;
  CdtInput in;
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) in.points.push_back(Vec2(i, j));
  auto id = [&](int i, int j) { return j * n + i; };
  in.segments = {{id(0, 0), id(n - 1, 0)},
                 {id(n - 1, 0), id(n - 1, n - 1)},
                 {id(n - 1, n - 1), id(0, n - 1)},
                 {id(0, n - 1), id(0, 0)}};
  int boundary = 4 * (n - 1), holes = 0, hole_lattice_inside = 0;
  long double area = (long double)(n - 1) * (n - 1);
  for (int cx : {8, 20, 32})
    for (int cy : {8, 20, 32}) {
      const int r = 3 + (cx + cy) % 3;
      const int c[4] = {id(cx + r, cy), id(cx, cy + r), id(cx - r, cy), id(cx, cy - r)};
      for (int k = 0; k < 4; ++k)
        in.segments.push_back((cx + cy) % 8 ? std::array<int, 2>{c[k], c[(k + 1) % 4]}
                                            : std::array<int, 2>{c[(k + 1) % 4], c[k]});
      boundary += 4 * r;
      hole_lattice_inside += 2 * r * r - 2 * r + 1;  // lattice points strictly inside |x|+|y| < r
      area -= 2 * r * r;
      ++holes;
    }
  const CdtResult r = constrained_delaunay(in);
  expect_valid_cdt(in, r, boundary, holes, area);
  EXPECT_EQ(used_vertices(r.mesh), n * n - hole_lattice_inside);
}

TEST(Triangulation2dCdt, InsertSegmentErrors) {
  CdtInput in;
  add_loop(in, square(0, 4, 4));  // points 0..15 on the boundary of [0,4]^2
  add_loop(in, square(1, 2, 1));  // hole, points 16..19
  in.points.push_back(Vec2(3, 3));  // 20
  in.points.push_back(Vec2(3, 1));  // 21
  CdtResult r = constrained_delaunay(in);
  Triangulation2d& m = r.mesh;
  // (3,3) -> (1,1) passes through the hole's corner (2,2) = 18, then into the
  // hole, which has no triangles. The piece up to 18 stays inserted.
  try {
    insert_segment(m, 20, 16);
    ADD_FAILURE() << "no error";
  } catch (const GeometryError& e) {
    EXPECT_TRUE(contains(e.what(), "segment 20-16 leaves the triangulated region")) << e.what();
  }
  {
    const auto [t, i] = m.find_edge(20, 18);
    ASSERT_GE(t, 0);
    EXPECT_TRUE(m.is_constrained(t, i));
  }
  // A segment between the vertices (3,3) and (3,1) is fine, and so is one
  // along the boundary, split at the boundary vertex in between.
  insert_segment(m, 20, 21);
  insert_segment(m, 0, 2);
  EXPECT_EQ(m.check(), "");
  EXPECT_EQ(delaunay_violation(m), "");
  const auto [t, i] = m.find_edge(20, 21);
  ASSERT_GE(t, 0);
  EXPECT_TRUE(m.is_constrained(t, i));
  // (4,2) -> (2,2) crosses it at (3,2).
  try {
    insert_segment(m, 6, 18);
    ADD_FAILURE() << "no error";
  } catch (const GeometryError& e) {
    EXPECT_TRUE(contains(e.what(), "segment 6-18 crosses the constrained edge 2")) << e.what();
  }
  EXPECT_EQ(m.check(), "");
  // Leaving the region through a concave corner: an L-shaped domain.
  CdtInput l;
  add_loop(l, {{0, 0}, {2, 0}, {2, 1}, {1, 1}, {1, 2}, {0, 2}});
  CdtResult rl = constrained_delaunay(l);
  try {
    insert_segment(rl.mesh, 2, 4);
    ADD_FAILURE() << "no error";
  } catch (const GeometryError& e) {
    EXPECT_TRUE(contains(e.what(), "leaves the triangulated region")) << e.what();
  }
  EXPECT_EQ(rl.mesh.check(), "");
}

TEST(Triangulation2dCdt, ErrorsNameTheIndices) {
  CdtInput base;
  add_loop(base, square(0, 1, 2));  // 8 points, segments 0..7

  {
    CdtInput in = base;
    in.points[5] = in.points[2];
    const std::string e = error_of(in);
    EXPECT_TRUE(contains(e, "points 2 and 5 are duplicates")) << e;
  }
  {
    CdtInput in;  // bow tie: segments 0 (0-1) and 2 (2-3) cross
    in.points = {{0, 0}, {1, 1}, {1, 0}, {0, 1}};
    in.segments = {{0, 1}, {1, 2}, {2, 3}, {3, 0}};
    const std::string e = error_of(in);
    EXPECT_TRUE(contains(e, "segment 0 (points 0-1)") && contains(e, "segment 2 (points 2-3)") &&
                contains(e, "cross"))
        << e;
  }
  {
    CdtInput in = base;
    in.segments.push_back({3, 12});
    const std::string e = error_of(in);
    EXPECT_TRUE(contains(e, "segment 8 refers to point 12")) << e;
  }
  {
    CdtInput in;
    in.points = {{0, 0}, {1, 0}};
    const std::string e = error_of(in);
    EXPECT_TRUE(contains(e, "at least 3 points")) << e;
  }
  {
    CdtInput in;
    for (int k = 0; k < 6; ++k) in.points.push_back(Vec2(k, 3 * k));  // exactly collinear
    in.segments = {{0, 5}, {5, 0}};
    const std::string e = error_of(in);
    EXPECT_TRUE(contains(e, "collinear")) << e;
  }
  {
    CdtInput in = base;
    in.segments.push_back({4, 3});  // segment 3 again, reversed
    const std::string e = error_of(in);
    EXPECT_TRUE(contains(e, "segment 3 (points 3-4)") && contains(e, "segment 8 (points 4-3)") &&
                contains(e, "overlap"))
        << e;
  }
  {
    CdtInput in = base;  // points 0,1,2 are collinear (bottom side): 0-2 overlaps 0-1 and 1-2
    in.segments.push_back({2, 0});
    const std::string e = error_of(in);
    EXPECT_TRUE(contains(e, "segment 8 (points 2-0)") && contains(e, "overlap")) << e;
  }
  {
    CdtInput in = base;
    in.segments.push_back({6, 6});
    const std::string e = error_of(in);
    EXPECT_TRUE(contains(e, "segment 8 starts and ends at point 6")) << e;
  }
  {
    CdtInput in = base;
    in.points[3].y() = std::nan("");
    const std::string e = error_of(in);
    EXPECT_TRUE(contains(e, "point 3 has a non-finite coordinate")) << e;
  }
  {
    // A segment from a hole's corner through the hole and out of its left side.
    CdtInput in = base;
    const int h = add_loop(in, square(0.3, 0.6, 1));
    in.segments.push_back({h + 2, 7});
    const std::string e = error_of(in);
    EXPECT_TRUE(contains(e, fmt::format("segment 12 (points {}-7)", h + 2)) &&
                contains(e, fmt::format("segment 11 (points {}-{})", h + 3, h)) && contains(e, "cross"))
        << e;
  }
}

TEST(Triangulation2dInsert, PointsOnEdgesAndVertices) {
  CdtInput in;
  add_loop(in, square(0, 1, 1));
  CdtResult r = constrained_delaunay(in);
  Triangulation2d& m = r.mesh;
  ASSERT_EQ(m.num_tris(), 2u);
  EXPECT_EQ(insert_point(m, Vec2(0.5, 0), -1), -1);  // on a constrained edge
  EXPECT_EQ(insert_point(m, Vec2(1, 1), -1), -1);    // on a vertex
  EXPECT_EQ(insert_point(m, Vec2(1.5, 0.5), -1), -1);  // outside
  EXPECT_EQ(m.num_tris(), 2u);
  EXPECT_EQ(m.points.size(), 4u);
  // The diagonal is unconstrained: a point on it splits both triangles.
  const int v = insert_point(m, Vec2(0.5, 0.5), 0);
  EXPECT_EQ(v, 4);
  EXPECT_EQ(m.num_tris(), 4u);
  EXPECT_EQ(m.check(), "");
  EXPECT_EQ(locate_point(m, Vec2(0.5, 0.5), 0).kind, Location::kOnVertex);
  EXPECT_EQ(locate_point(m, Vec2(0.25, 0.25), 0).kind, Location::kOnEdge);
  EXPECT_EQ(locate_point(m, Vec2(0.25, 0.2), 0).kind, Location::kInside);
  EXPECT_EQ(locate(m, Vec2(-0.25, 0.2), 0), -1);
}

TEST(Triangulation2dInsert, TenThousandRandomPointsInDomainWithHoles) {
  CdtInput in;
  const int no = 400, nh = 60;
  const double ro = 1, rh = 0.12;
  add_loop(in, circle({0, 0}, ro, no));
  std::vector<Vec2> centres;
  for (int k = 0; k < 8; ++k) centres.push_back(0.55 * Vec2(std::cos(k * kPi / 4), std::sin(k * kPi / 4)));
  centres.push_back({0, 0});
  for (const Vec2& c : centres) add_loop(in, circle(c, rh, nh, false));
  const int boundary = no + nh * int(centres.size());
  const int holes = int(centres.size());
  CdtResult r = constrained_delaunay(in);
  Triangulation2d& m = r.mesh;
  ASSERT_EQ(m.check(), "");

  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-1.05, 1.05);
  int inserted = 0, refused = 0, hint = 0;
  const double inscribed = ro * std::cos(kPi / no), hole_inscribed = rh * std::cos(kPi / nh);
  while (inserted < 10000) {
    const Vec2 p(u(rng), u(rng));
    double hole_dist = 1e9;
    for (const Vec2& c : centres) hole_dist = std::min(hole_dist, (p - c).norm());
    const bool surely_in = p.norm() < inscribed - 1e-9 && hole_dist > rh + 1e-9;
    const bool surely_out = p.norm() > ro + 1e-9 || hole_dist < hole_inscribed - 1e-9;
    if (!surely_in && !surely_out) continue;
    if (surely_out && refused >= 200) continue;  // a few suffice: each one searches the whole mesh
    const std::size_t before = m.num_tris();
    const int v = insert_point(m, p, hint);
    if (surely_in) {
      ASSERT_GE(v, 0) << p.transpose();
      EXPECT_EQ(m.num_tris(), before + 2);
      hint = m.vert_tri[v];
      ++inserted;
    } else {
      ASSERT_EQ(v, -1) << p.transpose();
      EXPECT_EQ(m.num_tris(), before);
      ++refused;
    }
  }
  EXPECT_EQ(m.check(), "");
  EXPECT_EQ(delaunay_violation(m), "");
  expect_segments_present(m, in, r.segment_vertices);
  EXPECT_EQ(int(m.num_tris()), euler_tris(used_vertices(m), boundary, holes));
  long double area = shoelace(circle({0, 0}, ro, no));
  for (const Vec2& c : centres) area -= shoelace(circle(c, rh, nh, false));
  EXPECT_NEAR(double(mesh_area(m) / area), 1.0, 1e-12);
}

TEST(Triangulation2dMesh, PrimitivesKeepInvariants) {
  CdtInput in;
  add_loop(in, square(0, 1, 4));  // points 0..15, bottom side 0 (0,0), 1 (0.25,0), ...
  in.points.push_back(Vec2(0.5, 0.5));
  CdtResult r = constrained_delaunay(in);
  Triangulation2d m = r.mesh;
  ASSERT_EQ(m.check(), "");

  // Split the constrained boundary edge 0-1 at its midpoint: two constrained halves.
  const auto [t, i] = m.find_edge(0, 1);
  ASSERT_GE(t, 0);
  const int v = m.add_point(Vec2(0.125, 0));
  const auto ts = m.split_edge(t, i, v);
  EXPECT_EQ(ts[2], -1);  // boundary edge: no triangle on the other side
  std::vector<std::pair<int, int>> edges{{ts[0], 2}, {ts[1], 1}};
  legalize(m, edges);
  EXPECT_EQ(m.check(), "");
  EXPECT_EQ(delaunay_violation(m), "");
  for (const auto& [x, y] : {std::pair{0, v}, std::pair{v, 1}}) {
    const auto [te, ie] = m.find_edge(x, y);
    ASSERT_GE(te, 0);
    EXPECT_TRUE(m.is_constrained(te, ie));
  }
  std::vector<int> fan;
  m.triangles_around(v, fan);
  EXPECT_EQ(fan.size(), 2u);
  m.triangles_around(16, fan);  // the interior vertex: a closed fan
  for (int f : fan) EXPECT_GE(m.local_index(f, 16), 0);

  // Delete a triangle: the mesh stays valid with a hole; the slot is reused.
  const std::size_t before = m.num_tris();
  const int gone = fan[0];
  const auto verts = m.tris[gone];
  const auto nbrs = m.adj[gone];
  const auto flags = m.constrained[gone];
  m.remove_triangle(gone);
  EXPECT_EQ(m.num_tris(), before - 1);
  EXPECT_EQ(m.check(), "");
  // Balls list every live triangle at each of its vertices, never a deleted slot.
  const Triangulation2d::Balls balls = m.balls();
  ASSERT_EQ(balls.start.size(), m.points.size() + 1);
  EXPECT_EQ(balls.tris_of.size(), 3 * m.num_tris());
  for (std::size_t w = 0; w < m.points.size(); ++w)
    for (int k = balls.start[w]; k < balls.start[w + 1]; ++k) {
      const int f = balls.tris_of[static_cast<std::size_t>(k)];
      EXPECT_TRUE(m.is_live(f));
      EXPECT_GE(m.local_index(f, static_cast<int>(w)), 0);
    }
  EXPECT_EQ(balls.start[17] - balls.start[16], static_cast<int>(fan.size()) - 1);  // the fan, less the deleted one
  EXPECT_EQ(locate(m, (m.points[verts[0]] + m.points[verts[1]] + m.points[verts[2]]) / 3, 0), -1);
  EXPECT_EQ(m.add_triangle(verts[0], verts[1], verts[2]), gone);
  for (int k = 0; k < 3; ++k) m.set_neighbour(gone, k, nbrs[k], (flags >> k) & 1);
  EXPECT_EQ(m.check(), "");
  EXPECT_EQ(m.num_tris(), before);

  // Compacting after a deletion renumbers densely and keeps everything valid.
  m.remove_triangle(0);
  m.compact();
  EXPECT_TRUE(m.free_tris.empty());
  EXPECT_EQ(m.num_tris(), before - 1);
  EXPECT_EQ(m.tris.size(), before - 1);
  EXPECT_EQ(m.check(), "");
}

// Bowyer–Watson with a caller's cavity: valid cavities become fans around the
// new vertex; every invalid one is refused with the mesh untouched.
TEST(Triangulation2dMesh, InsertInCavityChecksTheCavity) {
  CdtInput in;
  add_loop(in, square(0, 1, 4));  // points 0..15 on the boundary
  in.points.push_back(Vec2(0.5, 0.5));  // 16
  const Triangulation2d base = constrained_delaunay(in).mesh;
  ASSERT_EQ(base.check(), "");
  const auto live = [](const Triangulation2d& m) {
    std::vector<int> ts;
    for (int t = 0; t < int(m.tris.size()); ++t)
      if (m.is_live(t)) ts.push_back(t);
    return ts;
  };
  const auto expect_refused = [&](const Vec2& p, const std::vector<int>& cavity, const char* why) {
    Triangulation2d m = base;
    EXPECT_EQ(m.insert_in_cavity(p, cavity), -1) << why;
    EXPECT_EQ(m.tris, base.tris) << why;
    EXPECT_EQ(m.adj, base.adj) << why;
    EXPECT_EQ(m.points.size(), base.points.size()) << why;
  };

  // The triangles whose circumcircle holds p: the Delaunay cavity, a fan
  // with one triangle per boundary side, exact counts by Euler.
  {
    Triangulation2d m = base;
    const Vec2 p(0.3, 0.6);
    std::vector<int> cavity;
    for (const int t : live(m)) {
      const auto& v = m.tris[t];
      if (predicates::incircle(m.points[v[0]].data(), m.points[v[1]].data(), m.points[v[2]].data(), p.data()) > 0)
        cavity.push_back(t);
    }
    ASSERT_FALSE(cavity.empty());
    std::vector<int> fan;
    const int v = m.insert_in_cavity(p, cavity, &fan);
    ASSERT_EQ(v, 17);
    EXPECT_EQ(m.check(), "");
    EXPECT_EQ(fan.size(), cavity.size() + 2);
    for (const int f : fan) EXPECT_GE(m.local_index(f, v), 0);
    EXPECT_EQ(int(m.num_tris()), euler_tris(used_vertices(m), 16, 0));
    EXPECT_EQ(delaunay_violation(m), "");
    EXPECT_NEAR(double(mesh_area(m)), 1.0, 1e-12);
  }

  std::vector<int> around_centre;
  base.triangles_around(16, around_centre);
  const int holder = locate(base, Vec2(0.3, 0.6));
  ASSERT_GE(holder, 0);
  // The whole ball of vertex 16: it would vanish.
  expect_refused(Vec2(0.52, 0.51), around_centre, "cavity vertex inside the cavity");
  // p outside the cavity: not star-shaped from p.
  expect_refused(Vec2(0.05, 0.95), {holder}, "p outside the cavity");
  expect_refused(Vec2(0.3, 0.6), {holder, holder}, "repeated triangle");
  expect_refused(Vec2(0.3, 0.6), {}, "empty cavity");
  // Two triangles that share no edge: the boundary is two cycles.
  {
    int far = -1;
    for (const int t : live(base)) {
      bool touches = t == holder;
      for (const int v : base.tris[t])
        if (base.local_index(holder, v) >= 0) touches = true;
      if (!touches) far = t;
    }
    ASSERT_GE(far, 0);
    expect_refused(Vec2(0.3, 0.6), {holder, far}, "disconnected cavity");
  }
  // A constrained edge between two cavity triangles would be lost: the same
  // cavity that takes the point without the flag refuses it with the flag.
  {
    const Vec2 p = (base.points[base.tris[holder][0]] + base.points[base.tris[holder][1]] +
                    base.points[base.tris[holder][2]]) / 3;
    int n = 0;
    while (base.adj[holder][n] < 0) ++n;
    const std::vector<int> cavity{holder, base.adj[holder][n]};
    Triangulation2d free_mesh = base;
    EXPECT_EQ(free_mesh.insert_in_cavity(p, cavity), 17);
    EXPECT_EQ(free_mesh.check(), "");
    Triangulation2d m = base;
    m.set_constrained(holder, n, true);
    const auto tris = m.tris;
    EXPECT_EQ(m.insert_in_cavity(p, cavity), -1);
    EXPECT_EQ(m.tris, tris);
  }
}

TEST(Triangulation2dPerf, MillionPointsThousandSegments) {
  const int n = 1000000, ns = 1000;
  CdtInput in;
  add_loop(in, circle({0.5, 0.5}, 0.45, ns));
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(0, 1);
  for (int k = 0; k < n; ++k) in.points.push_back(Vec2(u(rng), u(rng)));
  Timer timer;
  const CdtResult r = constrained_delaunay(in);
  const double s = timer.seconds();
  std::printf("[ perf     ] constrained_delaunay: %zu points, %zu segments: %.3f s, %.3g points/s, %zu triangles\n",
              in.points.size(), in.segments.size(), s, in.points.size() / s, r.mesh.num_tris());
  EXPECT_EQ(r.mesh.check(), "");
  EXPECT_EQ(delaunay_violation(r.mesh), "");
  EXPECT_EQ(int(r.mesh.num_tris()), euler_tris(used_vertices(r.mesh), ns, 0));
}
