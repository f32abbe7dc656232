#include "curvemesh/mesh/structured.hpp"

#include <algorithm>

#include "curvemesh/core/error.hpp"
#include "curvemesh/mesh/adjacency.hpp"
#include "curvemesh/mesh/classification.hpp"

namespace cm::mesh {

TetMesh make_box_mesh(const std::array<int, 3>& n, const Vec3& lo, const Vec3& hi, bool classify) {
  CM_ASSERT(n[0] > 0 && n[1] > 0 && n[2] > 0);
  TetMesh m;
  const auto nx = static_cast<std::size_t>(n[0] + 1), ny = static_cast<std::size_t>(n[1] + 1),
             nz = static_cast<std::size_t>(n[2] + 1);
  m.coords.reserve(nx * ny * nz);
  for (std::size_t k = 0; k < nz; ++k)
    for (std::size_t j = 0; j < ny; ++j)
      for (std::size_t i = 0; i < nx; ++i)
        m.coords.push_back({lo.x() + (hi.x() - lo.x()) * static_cast<double>(i) / n[0],
                            lo.y() + (hi.y() - lo.y()) * static_cast<double>(j) / n[1],
                            lo.z() + (hi.z() - lo.z()) * static_cast<double>(k) / n[2]});
  m.resize_vertex_arrays();
  auto vid = [&](std::size_t i, std::size_t j, std::size_t k) { return static_cast<VertId>(i + nx * (j + ny * k)); };
  // The 6 Kuhn tets: a path 0 -> e_a -> e_a+e_b -> (1,1,1) for each axis order.
  static constexpr std::array<std::array<int, 3>, 6> kAxisOrders{{{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}}};
  // Odd permutations give negative tets; swapping two vertices fixes that.
  static constexpr std::array<bool, 6> kOdd{false, true, true, false, false, true};
  m.tet2verts.reserve(6 * static_cast<std::size_t>(n[0]) * n[1] * n[2]);
  for (std::size_t k = 0; k + 1 < nz; ++k)
    for (std::size_t j = 0; j + 1 < ny; ++j)
      for (std::size_t i = 0; i + 1 < nx; ++i)
        for (int p = 0; p < 6; ++p) {
          std::array<std::size_t, 3> c{i, j, k};
          std::array<VertId, 4> tv;
          tv[0] = vid(c[0], c[1], c[2]);
          for (int s = 0; s < 3; ++s) {
            ++c[kAxisOrders[p][s]];
            tv[s + 1] = vid(c[0], c[1], c[2]);
          }
          if (kOdd[p]) std::swap(tv[1], tv[2]);
          m.add_tet(tv, 1);
        }
  if (!classify) return m;
  build_adjacency(m);
  // Model face of a hull face: the box side all three vertices lie on.
  auto side_of = [&](const std::array<VertId, 3>& tri) {
    for (int axis = 0; axis < 3; ++axis)
      for (int s = 0; s < 2; ++s) {
        const double plane = s == 0 ? lo[axis] : hi[axis];
        if (std::all_of(tri.begin(), tri.end(), [&](VertId v) { return m.coords[v][axis] == plane; }))
          return 2 * axis + s + 1;
      }
    return 0;
  };
  for (TetId t = 0; t < m.num_tets(); ++t)
    for (int f = 0; f < 4; ++f)
      if (m.tet2adj[pack_face(t, f)] == kNone) {
        const auto& tv = m.tet2verts[t];
        const std::array<VertId, 3> tri{tv[kFaceVerts[f][0]], tv[kFaceVerts[f][1]], tv[kFaceVerts[f][2]]};
        m.tris.push_back({tri, side_of(tri)});
      }
  derive_classification(m);
  return m;
}

}  // namespace cm::mesh
