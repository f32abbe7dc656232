#pragma once
// The dynamic program behind edge removal (Klincsek): the triangulation of
// a polygon of n vertices 0..n-1 that maximizes the worst value of a
// measure over its triangles. Edge removal joins each triangle of the ring
// of a shell to the edge's two ends; a closed shell's ring is a closed
// polygon, an open one (a boundary edge swapped on the surface) has the new
// boundary edge (0, n-1) as its base side, and the same program serves both.
#include <algorithm>
#include <array>
#include <limits>
#include <type_traits>

namespace cm::modify {

/// Largest polygon the program takes (it is cubic in n).
inline constexpr int kMaxRing = 12;

struct RingTriangulation {
  double worst = -std::numeric_limits<double>::infinity();  ///< -inf: n < 3
  int count = 0;                                            ///< n - 2 triangles
  std::array<std::array<int, 3>, kMaxRing - 2> triangles{};  ///< (i, k, j), i < k < j
};

/// Maximizes min over triangles (i, k, j), i < k < j, of measure(i, k, j),
/// each triangle measured at most once. 3 <= n <= kMaxRing (else an empty
/// result). O(n³) measure calls at worst; pruned where a sub-polygon
/// already cannot beat the best.
/// A measure that takes a fourth argument, floor, is told the value it has
/// to beat: where the triangle's true value is <= floor it may return any
/// value <= floor (a measure that is a minimum over several tets can stop
/// at the first one at or below it). The result is the same.
template <class Measure>
RingTriangulation triangulate_ring(int n, Measure&& measure) {
  RingTriangulation out;
  if (n < 3 || n > kMaxRing) return out;
  constexpr double kInf = std::numeric_limits<double>::infinity();
  double best[kMaxRing][kMaxRing];
  int pick[kMaxRing][kMaxRing];
  for (int i = 0; i + 1 < n; ++i) best[i][i + 1] = kInf;
  // Triangle (i, k, j) belongs to sub-polygon (i, j) alone, so each one is
  // measured once without a table.
  for (int len = 2; len < n; ++len)
    for (int i = 0; i + len < n; ++i) {
      const int j = i + len;
      best[i][j] = -kInf;
      pick[i][j] = -1;
      for (int k = i + 1; k < j; ++k) {
        const double side = std::min(best[i][k], best[k][j]);
        if (side <= best[i][j]) continue;
        double t;
        if constexpr (std::is_invocable_v<Measure&, int, int, int, double>)
          t = measure(i, k, j, best[i][j]);
        else
          t = measure(i, k, j);
        const double q = std::min(side, t);
        if (q > best[i][j]) {
          best[i][j] = q;
          pick[i][j] = k;
        }
      }
    }
  out.worst = best[0][n - 1];
  std::array<std::pair<int, int>, kMaxRing> stack{};
  int top = 0;
  stack[top++] = {0, n - 1};
  while (top > 0) {
    const auto [i, j] = stack[--top];
    if (j - i < 2) continue;
    const int k = pick[i][j];
    if (k < 0) return RingTriangulation{};
    out.triangles[static_cast<std::size_t>(out.count++)] = {i, k, j};
    stack[top++] = {i, k};
    stack[top++] = {k, j};
  }
  return out;
}

}  // namespace cm::modify
