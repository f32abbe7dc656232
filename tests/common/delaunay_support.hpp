#pragma once
// Delaunay tetrahedralizations of given points for the tests of the kernel
// and of what works on its output.
#include <memory>
#include <vector>

#include "curvemesh/generate/delaunay3d.hpp"

namespace cm::test {

/// Appends `pts` to m (vertices 0..n-1 if m was empty) and inserts them all
/// in the tetrahedralization of their bounding box; `dup`, if given, gets
/// per point the vertex it duplicates or kNone.
inline std::unique_ptr<generate::Delaunay3d> triangulate_points(mesh::TetMesh& m, const std::vector<Vec3>& pts,
                                                                std::vector<VertId>* dup = nullptr) {
  Vec3 lo = pts[0], hi = pts[0];
  std::vector<VertId> ids;
  for (const Vec3& p : pts) {
    ids.push_back(m.add_vert(p));
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  m.resize_vertex_arrays();
  auto dt = std::make_unique<generate::Delaunay3d>(m, lo, hi);
  auto d = dt->insert_all(ids);
  if (dup) *dup = std::move(d);
  return dt;
}

}  // namespace cm::test
