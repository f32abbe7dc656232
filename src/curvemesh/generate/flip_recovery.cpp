#include "curvemesh/generate/flip_recovery.hpp"

#include <algorithm>
#include <utility>

#include "curvemesh/core/predicates.hpp"
#include "curvemesh/mesh/adjacency.hpp"
#include "curvemesh/mesh/topology.hpp"
#include "curvemesh/modify/measure.hpp"
#include "curvemesh/modify/swap.hpp"

namespace cm::generate {

namespace {

// Flips per recovery attempt. A missing simplex that flips can recover
// needs a few (one per crossed face or edge, a handful around a thin gap);
// more than this and splitting is the better way.
constexpr int kMaxSteps = 32;

int orient(const mesh::TetMesh& m, VertId a, VertId b, VertId c, VertId d) {
  return predicates::orient3d(m.coords[a].data(), m.coords[b].data(), m.coords[c].data(), m.coords[d].data());
}

// Sign of x against face f of tet t: < 0 on the tet's side (faces' normals
// point out of their tet).
int side_of_face(const mesh::TetMesh& m, TetId t, int f, VertId x) {
  const auto& tv = m.tet2verts[t];
  const auto& fv = mesh::kFaceVerts[f];
  return orient(m, tv[fv[0]], tv[fv[1]], tv[fv[2]], x);
}

// True if ring triangle (i, k, j) crosses the ring diagonal (x, y): it has
// a corner strictly between them and one strictly outside.
bool crosses_diagonal(const std::array<int, 3>& ikj, int x, int y) {
  if (x > y) std::swap(x, y);
  bool inside = false, outside = false;
  for (int v : ikj) {
    inside |= v > x && v < y;
    outside |= v < x || v > y;
  }
  return inside && outside;
}

}  // namespace

FlipRecovery::FlipRecovery(modify::MeshEditor& ed, std::function<bool(VertId, VertId)> is_boundary_edge)
    : ed_(ed), is_boundary_edge_(std::move(is_boundary_edge)) {}

bool FlipRecovery::protected_face(VertId a, VertId b, VertId c) const {
  return is_boundary_edge_(a, b) && is_boundary_edge_(b, c) && is_boundary_edge_(c, a);
}

bool FlipRecovery::face_swap(TetId t, int f) {
  const auto& m = ed_.mesh();
  const auto& tv = m.tet2verts[t];
  const auto& fv = mesh::kFaceVerts[f];
  if (protected_face(tv[fv[0]], tv[fv[1]], tv[fv[2]])) return false;
  const auto plan = modify::plan_face_swap(ed_, cavity_, t, f);
  // Any valid swap will do: recovery, not quality, is the aim.
  if (plan.refusal != modify::Refusal::kNone && plan.refusal != modify::Refusal::kNoImprovement) return false;
  modify::apply(ed_, cavity_, plan);
  ++stats_.face_swaps;
  return true;
}

bool FlipRecovery::remove_edge(VertId p, VertId q, TetId start, const std::array<VertId, 3>& wanted) {
  if (is_boundary_edge_(p, q)) return false;
  const auto& m = ed_.mesh();
  auto valid = [&m](const std::array<std::array<VertId, 4>, 2>& tets) {
    const double q0 = modify::tet_quality(m, tets[0]);
    if (q0 < 0) return -1.0;
    const double q1 = modify::tet_quality(m, tets[1]);
    if (q1 < 0) return -1.0;
    // Valid tets may be flat enough for a mean ratio of 0; they still count.
    return std::min(q0, q1) + 1e-300;
  };
  modify::Plan plan;
  if (wanted[0] != kNone) {
    // The triangulation of the ring must hold the wanted triangle: none of
    // its ring triangles may cross a diagonal between two wanted corners.
    plan = modify::plan_edge_removal(
        ed_, cavity_, p, q, start,
        [&](std::span<const VertId> ring, const std::array<int, 3>& ikj,
            const std::array<std::array<VertId, 4>, 2>& tets) {
          std::array<int, 3> at{-1, -1, -1};
          for (int w = 0; w < 3; ++w)
            for (std::size_t r = 0; r < ring.size(); ++r)
              if (ring[r] == wanted[static_cast<std::size_t>(w)]) at[static_cast<std::size_t>(w)] = static_cast<int>(r);
          if (at[0] >= 0 && at[1] >= 0 && at[2] >= 0)
            for (int w = 0; w < 3; ++w)
              if (crosses_diagonal(ikj, at[static_cast<std::size_t>(w)], at[static_cast<std::size_t>((w + 1) % 3)]))
                return -1.0;
          return valid(tets);
        });
  }
  if (wanted[0] == kNone || plan.refusal != modify::Refusal::kNone)
    plan = modify::plan_edge_removal(ed_, cavity_, p, q, start,
                                     [&](std::span<const VertId>, const std::array<int, 3>&,
                                         const std::array<std::array<VertId, 4>, 2>& tets) { return valid(tets); });
  if (plan.refusal != modify::Refusal::kNone) return false;
  modify::apply(ed_, cavity_, plan);
  ++stats_.edge_removals;
  return true;
}

bool FlipRecovery::recover_edge(VertId a, VertId b) {
  const auto& m = ed_.mesh();
  constexpr std::array<VertId, 3> kAny{kNone, kNone, kNone};
  for (int step = 0; step < kMaxSteps; ++step) {
    if (m.vert2tet[a] == kNone) return false;
    mesh::collect_ball(m, a, ball_);
    for (TetId t : ball_)
      if (mesh::local_index(m, t, b) >= 0) {
        stats_.edges_recovered += step > 0;
        return true;
      }
    // The tet at a whose cone holds the direction to b: b lies on the inner
    // side (or on the plane) of its three faces through a.
    bool moved = false;
    for (TetId t : ball_) {
      const int ia = mesh::local_index(m, t, a);
      int zeros = 0, zero_face = -1;
      bool outside = false;
      for (int f = 0; f < 4 && !outside; ++f) {
        if (f == ia) continue;
        const int s = side_of_face(m, t, f, b);
        outside = s > 0;
        if (s == 0) {
          ++zeros;
          zero_face = f;
        }
      }
      if (outside) continue;
      const auto& tv = m.tet2verts[t];
      if (zeros >= 2) return false;  // a vertex of t lies on the segment: only a split helps
      if (zeros == 1) {
        // The segment passes through the edge of t opposite a and tv[zero_face].
        VertId e[2];
        int n = 0;
        for (int k = 0; k < 4; ++k)
          if (k != ia && k != zero_face) e[n++] = tv[k];
        moved = remove_edge(e[0], e[1], t, kAny);
      } else {
        // The segment crosses face ia into the neighbour, apex x. The 2-3
        // swap is valid when x is strictly inside the cone too; else an edge
        // of the face whose plane through a x is beyond blocks it.
        const Index across = m.tet2adj[mesh::pack_face(t, ia)];
        if (across == kNone) return false;
        const VertId x = m.tet2verts[mesh::face_tet(across)][mesh::face_index(across)];
        int blocking = -1;
        for (int f = 0; f < 4 && blocking < 0; ++f)
          if (f != ia && side_of_face(m, t, f, x) >= 0) blocking = f;
        if (blocking < 0) {
          moved = face_swap(t, ia);
        } else {
          for (int f = 0; f < 4 && !moved; ++f) {
            if (f == ia || side_of_face(m, t, f, x) < 0) continue;
            VertId e[2];
            int n = 0;
            for (int k = 0; k < 4; ++k)
              if (k != ia && k != f) e[n++] = tv[k];
            moved = remove_edge(e[0], e[1], t, kAny);
          }
        }
      }
      break;
    }
    if (!moved) return false;
  }
  return false;
}

bool FlipRecovery::recover_triangle(VertId a, VertId b, VertId c) {
  const auto& m = ed_.mesh();
  for (int step = 0; step < kMaxSteps; ++step) {
    if (m.vert2tet[a] == kNone) return false;
    mesh::collect_ball(m, a, ball_);
    TetId start = kNone;
    for (TetId t : ball_)
      if (mesh::local_index(m, t, b) >= 0) {
        if (mesh::local_index(m, t, c) >= 0) {
          stats_.triangles_recovered += step > 0;
          return true;
        }
        start = t;
      }
    if (start == kNone) return false;  // edge (a, b) is missing
    const mesh::Shell shell = mesh::collect_shell(m, a, b, start);
    // The shell tet (a, b, p, q) whose wedge around (a, b) holds c: its
    // edge (p, q) crosses the triangle (edges of a triangulation do not
    // cross, and (a, c), (b, c) are edges, so (p, q) meets the triangle's
    // plane inside it).
    bool moved = false, found = false;
    for (TetId t : shell.tets) {
      VertId p = kNone, q = kNone;
      for (VertId v : m.tet2verts[t])
        if (v != a && v != b) (p == kNone ? p : q) = v;
      if (orient(m, a, b, p, q) < 0) std::swap(p, q);
      const int sp = orient(m, a, b, p, c), sq = orient(m, a, b, c, q);
      if (sp < 0 || sq < 0) continue;
      found = true;
      if (sp == 0 || sq == 0) return false;  // c on a face's plane through (a, b): degenerate
      moved = remove_edge(p, q, t, {a, b, c});
      break;
    }
    if (!found || !moved) return false;
  }
  return false;
}

}  // namespace cm::generate
