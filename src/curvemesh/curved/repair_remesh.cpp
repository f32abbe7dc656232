#include "curvemesh/curved/detail/repairer.hpp"

#include <algorithm>
#include <vector>

#include "curvemesh/mesh/adjacency.hpp"

namespace cm::curved::detail {

// --- step 3: remeshing -----------------------------------------------------------

std::optional<Outcome> Repairer::judge_split(const modify::SplitPlan& plan, std::vector<TetId> shell,
                                             const Outcome& before) {
  const VertId a = plan.a, b = plan.b;
  const mesh::ModelRef on = edge_entity(a, b, shell.front());
  const ScratchVertex p(m_, plan.point, plan.classification, plan.param);
  NodeOverride nodes(m_.high_order);
  std::array<Vec3, mesh::kMaxOrder> buf;
  const std::span<const Vec3> out(buf.data(), order_ - 1);
  // The triangles of the model faces through (a, b): (a, b, c) becomes
  // (a, p, c) and (p, b, c), and (p, c) is a new edge on that face.
  std::vector<std::pair<VertId, int>> apexes;
  for (TetId s : shell)
    for (VertId c : m_.tet2verts[s])
      if (c != a && c != b)
        if (const Index i = boundary_.find_tri(a, b, c); i != kNone)
          if (std::find_if(apexes.begin(), apexes.end(), [&](const auto& x) { return x.first == c; }) ==
              apexes.end())
            apexes.push_back({c, m_.tris[i].face_tag});
  if (on.dim < 3) {
    placer_.edge_nodes(a, p.id(), on, buf.data());
    nodes.set_edge(a, p.id(), out);
    placer_.edge_nodes(p.id(), b, on, buf.data());
    nodes.set_edge(p.id(), b, out);
  }
  for (const auto& [c, face] : apexes) {
    placer_.edge_nodes(p.id(), c, {2, face}, buf.data());
    nodes.set_edge(p.id(), c, out);
  }
  if (order_ >= 3)
    for (const auto& [c, face] : apexes)
      for (const std::array<VertId, 3>& tri : {std::array<VertId, 3>{a, p.id(), c}, std::array<VertId, 3>{p.id(), b, c}}) {
        std::array<std::array<Vec3, 2>, 3> e{};
        for (int k = 0; k < 3; ++k) m_.high_order.get_edge(tri[k], tri[(k + 1) % 3], e[k].data());
        Vec3 centre;
        placer_.face_nodes(tri[0], tri[1], tri[2], face, e[0].data(), e[1].data(), e[2].data(), &centre);
        nodes.set_face(tri[0], tri[1], tri[2], std::span<const Vec3>(&centre, 1));
      }
  std::vector<Verts> fill;
  for (TetId s : shell) {
    Verts x = m_.tet2verts[s], y = x;
    for (int k = 0; k < 4; ++k) {
      if (x[k] == a) x[k] = p.id();
      if (y[k] == b) y[k] = p.id();
    }
    fill.push_back(x);
    fill.push_back(y);
  }
  return step_up(fill, before);
}

bool Repairer::keeps_chord_rule(VertId from, VertId to, std::span<const TetId> ball) const {
  // The triangles through `from` that survive, moved to `to`: their
  // centroids may not stray from the face more than the mesher's curvature
  // rule allows (alpha times the longest edge), unless no farther than the
  // triangles they come from. Collapsing boundary vertices coarsens the
  // surface, and the straight elements' geometric error with it.
  constexpr double kAlpha = 0.04;
  for (TetId s : ball) {
    const auto& tv = m_.tet2verts[s];
    for (const auto& f : mesh::kFaceVerts) {
      const std::array<VertId, 3> tri{tv[f[0]], tv[f[1]], tv[f[2]]};
      if (std::find(tri.begin(), tri.end(), from) == tri.end() || std::find(tri.begin(), tri.end(), to) != tri.end())
        continue;
      const Index i = boundary_.find_tri(tri[0], tri[1], tri[2]);
      if (i == kNone) continue;
      const int face = m_.tris[i].face_tag;
      std::array<VertId, 3> moved = tri;
      for (VertId& x : moved)
        if (x == from) x = to;
      auto deviation = [&](const std::array<VertId, 3>& v) {
        const Vec3 c = (m_.coords[v[0]] + m_.coords[v[1]] + m_.coords[v[2]]) / 3;
        return model_.closest_point({2, face}, c, modify::check_hint(m_, v, face)).distance;
      };
      double longest = 0;
      for (int k = 0; k < 3; ++k) longest = std::max(longest, (m_.coords[moved[k]] - m_.coords[moved[(k + 1) % 3]]).norm());
      const double after = deviation(moved);
      if (after > kAlpha * longest && after > deviation(tri)) return false;
    }
  }
  return true;
}

std::optional<Outcome> Repairer::judge_collapse(const modify::CollapsePlan& plan, std::vector<TetId> ball,
                                                const Outcome& before) {
  const VertId from = plan.from, to = plan.to;
  if (m_.vert_class[from].dim < 3 && !keeps_chord_rule(from, to, ball)) return std::nullopt;
  NodeOverride nodes(m_.high_order);
  std::array<Vec3, mesh::kMaxOrder> buf;
  const std::span<const Vec3> out(buf.data(), order_ - 1);
  std::vector<Verts> fill;
  std::vector<std::uint64_t> done;
  for (TetId s : ball) {
    Verts v = m_.tet2verts[s];
    if (mesh::local_index(m_, s, to) >= 0) continue;  // vanishes
    // Boundary edges (from, c) become (to, c) on the same entity.
    for (VertId c : v) {
      if (c == from || !m_.high_order.has_edge(from, c)) continue;
      if (std::find(done.begin(), done.end(), edge_key(to, c)) != done.end()) continue;
      done.push_back(edge_key(to, c));
      placer_.edge_nodes(to, c, edge_entity(from, c, s), buf.data());
      nodes.set_edge(to, c, out);
    }
    for (VertId& x : v)
      if (x == from) x = to;
    fill.push_back(v);
  }
  if (order_ >= 3)
    for (TetId s : ball) {
      const auto& v = m_.tet2verts[s];
      if (mesh::local_index(m_, s, to) >= 0) continue;
      for (const auto& f : mesh::kFaceVerts) {
        std::array<VertId, 3> tri{v[f[0]], v[f[1]], v[f[2]]};
        const Index i = boundary_.find_tri(tri[0], tri[1], tri[2]);
        if (i == kNone || std::find(tri.begin(), tri.end(), from) == tri.end()) continue;
        for (VertId& x : tri)
          if (x == from) x = to;
        std::array<std::array<Vec3, 2>, 3> e{};
        for (int k = 0; k < 3; ++k) m_.high_order.get_edge(tri[k], tri[(k + 1) % 3], e[k].data());
        Vec3 centre;
        placer_.face_nodes(tri[0], tri[1], tri[2], m_.tris[i].face_tag, e[0].data(), e[1].data(), e[2].data(),
                           &centre);
        nodes.set_face(tri[0], tri[1], tri[2], std::span<const Vec3>(&centre, 1));
      }
    }
  return step_up(fill, before);
}

bool Repairer::remesh(TetId t) {
  const Verts tv = m_.tet2verts[t];
  enum Kind { kSplit, kCollapse };
  struct Candidate {
    Kind kind;
    VertId a, b;  // split (a, b), or collapse a into b
    Outcome after;
  };
  std::vector<Candidate> candidates;
  for (const auto& e : mesh::kTetEdges) {
    const VertId a = tv[e[0]], b = tv[e[1]];
    // Curved boundary edges, and interior edges: a tet that holds two
    // boundary edges meeting at a vertex where they are tangent (model
    // edges through a smooth model vertex, face edges of a flat corner) is
    // singular there once curved, whatever its shape; the interior edge
    // joining their far ends, split, leaves each new tet one of them.
    if (is_curved(a, b) || !m_.high_order.has_edge(a, b)) {
      const modify::SplitPlan p = modify::plan_split(ed_, cav_, boundary_, a, b, t, &model_);
      if (p.refusal != modify::Refusal::kNone) continue;
      const std::vector<TetId> shell(cav_.tets().begin(), cav_.tets().end());
      // t, unacceptable, is in the shell: progress is what step_up judges.
      if (const std::optional<Outcome> after = judge_split(p, shell, evaluate_tets(shell)))
        candidates.push_back({kSplit, a, b, *after});
    }
    // An interior edge with one end on the boundary: its inner end goes onto
    // the boundary end (seed Fig. 3.7). And a boundary vertex along its own
    // model entity (the collapse's classification rules decide which): what
    // removes a boundary triangle with a corner near 180°, which no swap
    // can reach, by taking out its vertex next to the corner.
    for (int side = 0; side < 2; ++side) {
      const VertId from = side ? b : a, to = side ? a : b;
      if (m_.vert_class[from].dim == 3 && m_.vert_class[to].dim == 3) continue;
      const modify::CollapsePlan p = modify::plan_collapse(ed_, cav_, boundary_, from, to, &model_);
      if (p.refusal != modify::Refusal::kNone) continue;
      const std::vector<TetId> ball(cav_.tets().begin(), cav_.tets().end());
      // t holds `from`: it is in the ball.
      if (const std::optional<Outcome> after = judge_collapse(p, ball, evaluate_tets(ball)))
        candidates.push_back({kCollapse, from, to, *after});
    }
  }
  if (candidates.empty()) return false;
  const Candidate& c = *std::min_element(candidates.begin(), candidates.end(), [](const auto& x, const auto& y) {
    return ranks_above(x.after, y.after);
  });
  if (c.kind == kSplit) {
    const TetId start = find_tet_with(c.a, c.b);
    const modify::SplitPlan p = modify::plan_split(ed_, cav_, boundary_, c.a, c.b, start, &model_);
    before_edit(cav_.tets());
    modify::apply(ed_, cav_, boundary_, p);
    ++st_.splits;
  } else {
    const modify::CollapsePlan p = modify::plan_collapse(ed_, cav_, boundary_, c.a, c.b, &model_);
    before_edit(cav_.tets());
    modify::apply(ed_, cav_, boundary_, p);
    ++st_.collapses;
  }
  return true;
}

}  // namespace cm::curved::detail
