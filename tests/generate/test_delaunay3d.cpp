// The 3D Delaunay kernel: random, grid (maximally cospherical), coplanar and
// duplicate point sets; every result checked tet by tet — positive
// orientation, symmetric adjacency, the local Delaunay property with the
// perturbed insphere on every interior face, all points used, the enclosing
// volume tiled exactly — plus protected faces and the Hilbert order.
#include <gtest/gtest.h>

#include <random>
#include <set>

#include "../common/delaunay_support.hpp"
#include "curvemesh/core/predicates.hpp"
#include "curvemesh/generate/delaunay3d.hpp"
#include "curvemesh/generate/spatial_sort.hpp"
#include "curvemesh/mesh/topology.hpp"

using namespace cm;
using namespace cm::generate;

namespace {

struct Built {
  mesh::TetMesh m;
  std::vector<VertId> dup;
};

Built triangulate(const std::vector<Vec3>& pts) {
  Built b;
  test::triangulate_points(b.m, pts, &b.dup)->editor().compact();
  return b;
}

double far_volume(const mesh::TetMesh& m, std::size_t n) {
  const auto& c = m.coords;
  return std::abs((c[n + 1] - c[n]).dot((c[n + 2] - c[n]).cross(c[n + 3] - c[n]))) / 6;
}

// Checks a compacted Delaunay mesh of n input points (+4 far vertices).
void expect_delaunay(const Built& b, std::size_t n) {
  const auto& m = b.m;
  double vol = 0;
  for (TetId t = 0; t < m.tet2verts.size(); ++t) {
    const auto& tv = m.tet2verts[t];
    ASSERT_GT(predicates::orient3d(m.coords[tv[0]].data(), m.coords[tv[1]].data(), m.coords[tv[2]].data(),
                                   m.coords[tv[3]].data()),
              0);
    vol += mesh::tet_volume(m, t);
    for (int f = 0; f < 4; ++f) {
      const Index a = m.tet2adj[4 * t + f];
      if (a == kNone) continue;
      ASSERT_EQ(m.tet2adj[a], mesh::pack_face(t, f));
      const VertId opp = m.tet2verts[mesh::face_tet(a)][mesh::face_index(a)];
      ASSERT_LT(insphere_perturbed(m, tv, opp), 0) << "face " << f << " of tet " << t << " is not locally Delaunay";
    }
  }
  const double big = far_volume(m, n);
  EXPECT_NEAR(vol, big, 1e-9 * big);
  for (VertId v = 0; v < n + 4; ++v) {
    const bool expected = v >= n || b.dup[v] == kNone;
    if (expected) {
      EXPECT_NE(m.vert2tet[v], kNone) << "vertex " << v << " unused";
    }
  }
}

}  // namespace

TEST(Delaunay3d, RandomPoints) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-1, 1);
  std::vector<Vec3> pts(20000);
  for (auto& p : pts) p = Vec3(u(rng), u(rng), u(rng));
  const auto b = triangulate(pts);
  expect_delaunay(b, pts.size());
  // A Delaunay triangulation of random points has about 6.7 tets per point.
  EXPECT_GT(b.m.tet2verts.size(), 6 * pts.size());
  EXPECT_LT(b.m.tet2verts.size(), 7 * pts.size());
}

TEST(Delaunay3d, GridIsMaximallyDegenerate) {
  std::vector<Vec3> pts;
  for (int i = 0; i < 12; ++i)
    for (int j = 0; j < 12; ++j)
      for (int k = 0; k < 12; ++k) pts.emplace_back(i, j, k);
  const auto b = triangulate(pts);
  expect_delaunay(b, pts.size());
  // Tets with no far vertex tile the grid's box exactly.
  double inner = 0;
  for (TetId t = 0; t < b.m.tet2verts.size(); ++t) {
    bool far = false;
    for (VertId v : b.m.tet2verts[t]) far |= v >= pts.size();
    if (!far) inner += mesh::tet_volume(b.m, t);
  }
  EXPECT_NEAR(inner, 11.0 * 11 * 11, 1e-9);
}

TEST(Delaunay3d, CosphericalAndCoplanarPoints) {
  std::vector<Vec3> pts;
  // Points on a sphere at rational coordinates (Pythagorean quadruples) plus a plane of points.
  const int q[][3] = {{1, 2, 2}, {2, 3, 6}, {1, 4, 8}, {4, 4, 7}, {2, 6, 9}, {6, 6, 7}, {3, 4, 12}};
  const double r[] = {3, 7, 9, 9, 11, 11, 13};
  for (int k = 0; k < 7; ++k)
    for (int sx = -1; sx <= 1; sx += 2)
      for (int sy = -1; sy <= 1; sy += 2)
        for (int sz = -1; sz <= 1; sz += 2)
          pts.emplace_back(sx * q[k][0] / r[k], sy * q[k][1] / r[k], sz * q[k][2] / r[k]);
  for (int i = 0; i < 10; ++i)
    for (int j = 0; j < 10; ++j) pts.emplace_back(0.2 * i - 1, 0.2 * j - 1, 0.0);
  const auto b = triangulate(pts);
  expect_delaunay(b, pts.size());
}

TEST(Delaunay3d, DuplicatesAreReportedNotInserted) {
  std::vector<Vec3> pts;
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(0, 1);
  for (int i = 0; i < 500; ++i) pts.emplace_back(u(rng), u(rng), u(rng));
  for (int i = 0; i < 50; ++i) pts.push_back(pts[static_cast<std::size_t>(i) * 7]);
  const auto b = triangulate(pts);
  int dups = 0;
  for (std::size_t i = 0; i < pts.size(); ++i)
    if (b.dup[i] != kNone) {
      ++dups;
      EXPECT_EQ(b.m.coords[b.dup[i]], pts[i]);
      EXPECT_EQ(b.m.vert2tet[i], kNone);
    }
  EXPECT_EQ(dups, 50);
}

TEST(Delaunay3d, ProtectedFacesAreNeverCrossed) {
  // Two points and a triangle between them that the second insertion would
  // normally destroy: protect it and insert a point whose cavity needs it.
  std::vector<Vec3> pts{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0.2, 0.2, 1}, {0.2, 0.2, -1}};
  mesh::TetMesh m;
  for (const auto& p : pts) m.add_vert(p);
  m.resize_vertex_arrays();
  Delaunay3d dt(m, Vec3(-1, -1, -1), Vec3(1, 1, 1));
  for (VertId v = 0; v < 5; ++v) ASSERT_EQ(dt.insert(v).refusal, modify::Refusal::kNone);
  // Triangle (0,1,2) is present (it separates 3 from 4 at these positions).
  ASSERT_TRUE(dt.protect({0, 1, 2}));
  EXPECT_FALSE(dt.protect({0, 3, 4}));  // not a face: 3 and 4 are on opposite sides
  EXPECT_TRUE(dt.is_protected({2, 0, 1}));
  const VertId p = m.add_vert(Vec3(0.25, 0.25, 0.01));
  m.resize_vertex_arrays();
  const auto r = dt.insert(p);
  if (r.refusal == modify::Refusal::kNone) {
    // Inserted: the protected triangle must still be a face of the mesh.
    bool found = false;
    for (TetId t = 0; t < m.tet2verts.size(); ++t) {
      if (dt.editor().is_dead(t)) continue;
      int c = 0;
      for (VertId v : m.tet2verts[t]) c += v <= 2;
      found |= c == 3;
    }
    EXPECT_TRUE(found);
    EXPECT_TRUE(dt.is_protected({0, 1, 2}));  // the mark followed the face
  } else {
    EXPECT_EQ(r.refusal, modify::Refusal::kNotStarShaped);
  }
}

TEST(SpatialSort, HilbertCurveVisitsNeighbouringCells) {
  // bits = 3: the 512 cells get 512 distinct keys and consecutive keys are
  // face neighbours (the defining property of the Hilbert curve).
  std::vector<std::array<int, 3>> cell(512);
  std::set<std::uint64_t> seen;
  for (int x = 0; x < 8; ++x)
    for (int y = 0; y < 8; ++y)
      for (int z = 0; z < 8; ++z) {
        const auto k = hilbert_key(x, y, z, 3);
        ASSERT_LT(k, 512u);
        seen.insert(k);
        cell[k] = {x, y, z};
      }
  EXPECT_EQ(seen.size(), 512u);
  for (int k = 1; k < 512; ++k) {
    const int d = std::abs(cell[k][0] - cell[k - 1][0]) + std::abs(cell[k][1] - cell[k - 1][1]) +
                  std::abs(cell[k][2] - cell[k - 1][2]);
    EXPECT_EQ(d, 1) << "keys " << k - 1 << ", " << k;
  }
}
