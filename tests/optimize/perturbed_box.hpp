#pragma once
// Poor but valid test meshes: a classified Kuhn box whose interior vertices
// are moved at random (each move kept only if its ball stays positive) and
// some of them pushed almost onto a face of their ball, making flat tets.
#include <random>
#include <vector>

#include "curvemesh/core/predicates.hpp"
#include "curvemesh/mesh/adjacency.hpp"
#include "curvemesh/mesh/structured.hpp"

namespace cm::test {

inline bool ball_positive(const mesh::TetMesh& m, const std::vector<TetId>& ball) {
  for (TetId t : ball) {
    const auto& v = m.tet2verts[t];
    if (predicates::orient3d(m.coords[v[0]].data(), m.coords[v[1]].data(), m.coords[v[2]].data(),
                             m.coords[v[3]].data()) <= 0)
      return false;
  }
  return true;
}

/// n³ cells over [0,1]x[0,1]x[0,stretch]; interior vertices moved by up to
/// `jitter` cell sizes; `flatten` of them pushed to 99.9% of the way onto
/// the opposite face of one of their tets (kept only if still positive).
inline mesh::TetMesh perturbed_box(int n, unsigned seed, double jitter, int flatten, double stretch = 1) {
  auto m = mesh::make_box_mesh({n, n, n}, Vec3(0, 0, 0), Vec3(1, 1, stretch), true);
  std::mt19937 rng(seed);
  const Vec3 cell(1.0 / n, 1.0 / n, stretch / n);
  std::uniform_real_distribution<double> u(-jitter, jitter);
  std::vector<TetId> ball;
  std::vector<VertId> interior;
  for (VertId v = 0; v < m.num_verts(); ++v) {
    if (m.vert_class[v].dim != 3) continue;
    interior.push_back(v);
    mesh::collect_ball(m, v, ball);
    const Vec3 old = m.coords[v];
    for (double scale = 1; scale > 0.1; scale *= 0.5) {
      m.coords[v] = old + scale * Vec3(u(rng), u(rng), u(rng)).cwiseProduct(cell);
      if (ball_positive(m, ball)) break;
      m.coords[v] = old;
    }
  }
  std::shuffle(interior.begin(), interior.end(), rng);
  int done = 0;
  for (VertId v : interior) {
    if (done == flatten) break;
    mesh::collect_ball(m, v, ball);
    const TetId t = ball[rng() % ball.size()];
    Vec3 face[3];
    int k = 0;
    for (VertId w : m.tet2verts[t])
      if (w != v) face[k++] = m.coords[w];
    const Vec3 normal = (face[1] - face[0]).cross(face[2] - face[0]).normalized();
    const Vec3 old = m.coords[v];
    const Vec3 foot = old - normal * normal.dot(old - face[0]);
    for (double f : {0.999, 0.99, 0.95}) {
      m.coords[v] = old + f * (foot - old);
      if (ball_positive(m, ball)) {
        ++done;
        break;
      }
      m.coords[v] = old;
    }
  }
  return m;
}

}  // namespace cm::test
