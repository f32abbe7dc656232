#include "curvemesh/curved/detail/repairer.hpp"

#include <algorithm>
#include <vector>

#include "curvemesh/mesh/adjacency.hpp"
#include "curvemesh/modify/relocate.hpp"

namespace cm::curved::detail {

// --- step 4: repositioning ---------------------------------------------------------

bool Repairer::reposition(TetId t) {
  const Verts tv = m_.tet2verts[t];
  std::vector<TetId> ball;
  for (VertId v : tv) {
    if (m_.vert_class[v].dim != 3) continue;
    mesh::collect_ball(m_, v, ball);
    sort_worst_first(ball);
    const Vec3 start = m_.coords[v];
    const Outcome before = evaluate_tets(ball);
    // Pattern search on the worst curved quality of the ball: axis moves
    // and the move to the ball's centroid, halving the step down to 1/64 of
    // the ball's mean edge length.
    double mean = 0;
    Vec3 centroid = Vec3::Zero();
    int n = 0;
    for (TetId s : ball)
      for (VertId w : m_.tet2verts[s])
        if (w != v) {
          mean += (m_.coords[w] - start).norm();
          centroid += m_.coords[w];
          ++n;
        }
    mean /= n;
    centroid /= n;
    Vec3 x = start;
    Outcome current = before;
    for (double step = 0.25 * mean; step > mean / 64; step /= 2) {
      bool moved = true;
      while (moved) {
        moved = false;
        const std::array<Vec3, 7> moves{Vec3(step, 0, 0), Vec3(-step, 0, 0), Vec3(0, step, 0), Vec3(0, -step, 0),
                                        Vec3(0, 0, step), Vec3(0, 0, -step), (centroid - x).normalized() * step};
        for (const Vec3& d : moves) {
          m_.coords[v] = x + d;
          if (const std::optional<Outcome> o = step_up(ball, current)) {
            current = *o;
            x = x + d;
            moved = true;
          }
        }
      }
    }
    m_.coords[v] = start;
    if (!improves(current, before)) continue;
    cav_.reset(ed_);
    for (TetId s : ball) cav_.add(ed_, s);
    modify::Relocation plan;
    plan.target = x;
    before_edit(cav_.tets());
    modify::apply(ed_, cav_, v, plan);
    ++st_.relocations;
    return true;
  }
  return false;
}

// --- step 5: curving interior edges ------------------------------------------------

void Repairer::curve_interior(TetId t) {
  const Verts tv = m_.tet2verts[t];
  for (const auto& e : mesh::kTetEdges) {
    const VertId a = tv[e[0]], b = tv[e[1]];
    if (m_.high_order.has_edge(a, b)) continue;  // boundary (or done)
    // det J at a corner depends only on the nodes of the three edges there:
    // where the tet is invalid at a corner, no other edge can change that.
    if (const ElementCheck c = check(tv); c.verdict != quality::Validity::kValid && c.where.dim == 0) {
      const VertId corner = tv[c.where.index];
      if (a != corner && b != corner) continue;
    }
    std::vector<TetId> shell = mesh::collect_shell(m_, a, b, t).tets;
    sort_worst_first(shell);
    const Outcome before = evaluate_tets(shell);
    if (before.bad == 0) continue;
    const Vec3 xa = m_.coords[a], xb = m_.coords[b];
    const double len = (xb - xa).norm();
    std::array<Vec3, mesh::kMaxOrder> straight;
    for (int s = 1; s < order_; ++s) straight[s - 1] = xa + (xb - xa) * (double(s) / order_);
    // The edge's nodes move together (a bow of the whole edge), searched on
    // the axes with a shrinking step.
    Vec3 offset = Vec3::Zero();
    Outcome current = before;
    auto set = [&](const Vec3& d) {
      std::array<Vec3, mesh::kMaxOrder> nodes;
      for (int s = 1; s < order_; ++s) {
        const double w = 4.0 * s * (order_ - s) / (order_ * order_);  // 1 at the middle
        nodes[s - 1] = straight[s - 1] + w * d;
      }
      m_.high_order.set_edge(a, b, std::span<const Vec3>(nodes.data(), order_ - 1));
    };
    for (double step = 0.2 * len; step > len / 256; step /= 2) {
      bool moved = true;
      while (moved) {
        moved = false;
        for (int axis = 0; axis < 6; ++axis) {
          Vec3 d = Vec3::Zero();
          d[axis / 2] = axis % 2 ? -step : step;
          set(offset + d);
          if (const std::optional<Outcome> o = step_up(shell, current)) {
            current = *o;
            offset += d;
            moved = true;
          }
        }
      }
    }
    if (improves(current, before)) {
      set(offset);
      interior_curved_.insert(edge_key(a, b));
      touched_.insert(touched_.end(), shell.begin(), shell.end());
    } else {
      m_.high_order.erase_edge(a, b);
    }
    if (acceptable(t)) return;
  }
}

// --- step 6: straightening ----------------------------------------------------------

void Repairer::straighten(std::vector<TetId> queue) {
  std::vector<TetId> ball;
  while (!queue.empty()) {
    const TetId t = queue.back();
    queue.pop_back();
    if (ed_.is_dead(t) || acceptable(t)) continue;
    const Verts v = m_.tet2verts[t];
    for (const auto& e : mesh::kTetEdges) {
      const VertId a = v[e[0]], b = v[e[1]];
      if (!is_curved(a, b)) continue;
      std::array<Vec3, mesh::kMaxOrder> nodes;
      for (int s = 1; s < order_; ++s) nodes[s - 1] = m_.coords[a] + (m_.coords[b] - m_.coords[a]) * (double(s) / order_);
      if (interior_curved_.erase(edge_key(a, b)))
        m_.high_order.erase_edge(a, b);
      else {
        m_.high_order.set_edge(a, b, std::span<const Vec3>(nodes.data(), order_ - 1));
        ++st_.edges_straightened;
      }
      const mesh::Shell shell = mesh::collect_shell(m_, a, b, t);
      for (TetId s : shell.tets)
        if (s != t) queue.push_back(s);
    }
    if (order_ >= 3)
      for (const auto& f : mesh::kFaceVerts) {
        const std::array<VertId, 3> tri{v[f[0]], v[f[1]], v[f[2]]};
        Vec3 centre;
        if (!m_.high_order.get_face(tri[0], tri[1], tri[2], &centre)) continue;
        const Vec3 flat = (m_.coords[tri[0]] + m_.coords[tri[1]] + m_.coords[tri[2]]) / 3;
        if (centre == flat) continue;
        m_.high_order.set_face(tri[0], tri[1], tri[2], std::span<const Vec3>(&flat, 1));
        ++st_.faces_straightened;
      }
  }
}

}  // namespace cm::curved::detail
