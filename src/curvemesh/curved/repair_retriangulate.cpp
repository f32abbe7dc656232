#include "curvemesh/curved/detail/repairer.hpp"

#include <algorithm>
#include <limits>
#include <optional>
#include <vector>

#include "curvemesh/mesh/adjacency.hpp"
#include "curvemesh/modify/delete_tet.hpp"
#include "curvemesh/modify/swap.hpp"
#include "curvemesh/optimize/measured_swap.hpp"

namespace cm::curved::detail {

// --- step 1: retriangulation -----------------------------------------------------

modify::Plan Repairer::plan_retriangulation(TetId t, const Retriangulation& r, optimize::TetMeasure measure,
                                            const void* context) {
  const Verts& tv = m_.tet2verts[t];
  if (r.kind == 0) {
    const auto& e = mesh::kTetEdges[r.local];
    return optimize::plan_measured_edge_removal(ed_, cav_, tv[e[0]], tv[e[1]], t, measure, context);
  }
  return optimize::plan_measured_face_swap(ed_, cav_, t, r.local, measure, context);
}

Repairer::Retriangulation Repairer::best_retriangulation(TetId t, optimize::TetMeasure measure, const void* context,
                                                         bool resolving_only) {
  const Verts tv = m_.tet2verts[t];
  Retriangulation best;
  Outcome none_bad;
  none_bad.worst = -std::numeric_limits<double>::infinity();
  for (int kind = 0; kind < 2; ++kind)
    for (int local = 0; local < (kind == 0 ? 6 : 4); ++local) {
      if (kind == 0) {
        const auto& e = mesh::kTetEdges[local];
        if (m_.high_order.has_edge(tv[e[0]], tv[e[1]])) continue;  // a boundary edge stays
      }
      const modify::Plan p = plan_retriangulation(t, {kind, local, {}}, measure, context);
      if (p.fill.empty() || (p.refusal != modify::Refusal::kNone && p.refusal != modify::Refusal::kNoImprovement))
        continue;
      std::vector<Verts> fill;
      for (const auto& nt : p.fill) fill.push_back(nt.verts);
      // t, unacceptable, is in the cavity: progress is fewer unacceptable
      // tets, or as many and a better worst one, which step_up judges.
      const std::optional<Outcome> after = step_up(fill, resolving_only ? none_bad : evaluate_tets(cav_.tets()));
      if (!after) continue;
      if (best.kind < 0 || ranks_above(*after, best.after)) best = {kind, local, *after};
    }
  return best;
}

bool Repairer::retriangulate(TetId t) {
  // First the retriangulations that are best for the straight tets, judged
  // curved: where one leaves every new tet acceptable (two thirds of the
  // time on the crankshaft at order 3, and as good a mesh) the dynamic
  // programs on the curved measure, each a few dozen certifications, are
  // not needed.
  if (const Retriangulation quick = best_retriangulation(t, &optimize::angle_aware_measure, nullptr, true);
      quick.kind >= 0)
    return apply_retriangulation(t, quick, &optimize::angle_aware_measure, nullptr);
  const Verts tv = m_.tet2verts[t];
  const Retriangulation found = best_retriangulation(t, &Repairer::curved_measure, this, false);
  Outcome best = found.after;
  // The boundary's own retriangulation: a curved face edge of the tet
  // swapped on its model face (the quad's other diagonal, the open shell
  // retriangulated). What fixes a boundary triangle whose corner is near
  // 180°, where two model edges tangent at a model vertex meet: curved, its
  // edges there line up and det J vanishes.
  int best_swap_edge = -1;
  for (int local = 0; local < 6; ++local) {
    const auto& e = mesh::kTetEdges[local];
    const VertId a = tv[e[0]], b = tv[e[1]];
    if (!is_curved(a, b)) continue;
    const Outcome candidate = judge_boundary_swap(a, b, t);
    if (candidate.bad < 0) continue;
    const Outcome before = evaluate_tets(cav_.tets());
    if (!improves(candidate, before)) continue;
    if ((found.kind < 0 && best_swap_edge < 0) || ranks_above(candidate, best)) {
      best = candidate;
      best_swap_edge = local;
    }
  }
  if (best_swap_edge >= 0) {
    const auto& e = mesh::kTetEdges[best_swap_edge];
    const modify::BoundarySwap p =
        modify::plan_boundary_edge_swap(ed_, cav_, boundary_, tv[e[0]], tv[e[1]], t, &model_);
    before_edit(cav_.tets());
    modify::apply(ed_, cav_, boundary_, p);
    ++st_.boundary_swaps;
    return true;
  }
  return found.kind >= 0 && apply_retriangulation(t, found, &Repairer::curved_measure, this);
}

bool Repairer::apply_retriangulation(TetId t, const Retriangulation& r, optimize::TetMeasure measure,
                                     const void* context) {
  // Planned again: judging the other candidates refilled the cavity.
  const modify::Plan p = plan_retriangulation(t, r, measure, context);
  before_edit(cav_.tets());
  modify::apply(ed_, cav_, p);
  ++(r.kind == 0 ? st_.edge_removals : st_.face_swaps);
  return true;
}

Outcome Repairer::judge_boundary_swap(VertId a, VertId b, TetId t) {
  Outcome none;
  none.bad = -1;
  // First for the new edge's ends, then judged with it curved on the face.
  const modify::BoundarySwap first = modify::plan_boundary_edge_swap(ed_, cav_, boundary_, a, b, t, &model_);
  if (first.refusal != modify::Refusal::kNone && first.refusal != modify::Refusal::kNoImprovement) return none;
  NodeOverride nodes(m_.high_order);
  std::array<Vec3, mesh::kMaxOrder> buf;
  placer_.edge_nodes(first.c, first.d, {2, first.face_tag}, buf.data());
  nodes.set_edge(first.c, first.d, std::span<const Vec3>(buf.data(), order_ - 1));
  if (order_ >= 3)
    for (const auto& tri : first.added) {
      std::array<std::array<Vec3, 2>, 3> e{};
      for (int k = 0; k < 3; ++k) m_.high_order.get_edge(tri[k], tri[(k + 1) % 3], e[k].data());
      Vec3 centre;
      placer_.face_nodes(tri[0], tri[1], tri[2], first.face_tag, e[0].data(), e[1].data(), e[2].data(), &centre);
      nodes.set_face(tri[0], tri[1], tri[2], std::span<const Vec3>(&centre, 1));
    }
  const modify::BoundarySwap p =
      modify::plan_boundary_edge_swap(ed_, cav_, boundary_, a, b, t, &model_, &Repairer::curved_measure, this);
  if (p.refusal != modify::Refusal::kNone && p.refusal != modify::Refusal::kNoImprovement) return none;
  std::vector<Verts> fill;
  for (const auto& nt : p.fill) fill.push_back(nt.verts);
  return evaluate(fill);
}

// --- step 2: element deletion ------------------------------------------------------

// A tet with two or three faces on one model face (curved, det J vanishes
// where its boundary edges meet tangent to the face) is taken out; the tets
// around its new face edge get that edge curved on the face.
bool Repairer::delete_element(TetId t) {
  const modify::TetDeletion plan = modify::plan_tet_deletion(ed_, cav_, boundary_, t, &model_);
  if (plan.refusal != modify::Refusal::kNone) return false;
  // The new face edge: the one of the added triangles that is not on the
  // boundary yet (none when a lone vertex goes with three faces).
  VertId c = kNone, d = kNone;
  for (int i = 0; i < plan.added_count && c == kNone; ++i)
    for (int k = 0; k < 3; ++k) {
      const VertId x = plan.added[i][k], y = plan.added[i][(k + 1) % 3];
      if (!m_.high_order.has_edge(x, y)) {
        c = x;
        d = y;
        break;
      }
    }
  std::vector<TetId> affected;
  if (c != kNone) {
    affected = mesh::collect_shell(m_, c, d, find_tet_with(c, d)).tets;
  } else {
    for (int f = 0; f < 4; ++f)
      if (const Index across = m_.tet2adj[mesh::pack_face(t, f)]; across != kNone)
        affected.push_back(mesh::face_tet(across));
  }
  const Outcome before = evaluate_tets(affected);
  std::erase(affected, t);
  Outcome after;
  {
    NodeOverride nodes(m_.high_order);
    std::array<Vec3, mesh::kMaxOrder> buf;
    if (c != kNone) {
      placer_.edge_nodes(c, d, {2, plan.face_tag}, buf.data());
      nodes.set_edge(c, d, std::span<const Vec3>(buf.data(), order_ - 1));
    }
    if (order_ >= 3)
      for (int i = 0; i < plan.added_count; ++i) {
        const auto& tri = plan.added[i];
        std::array<std::array<Vec3, 2>, 3> e{};
        for (int k = 0; k < 3; ++k) m_.high_order.get_edge(tri[k], tri[(k + 1) % 3], e[k].data());
        Vec3 centre;
        placer_.face_nodes(tri[0], tri[1], tri[2], plan.face_tag, e[0].data(), e[1].data(), e[2].data(), &centre);
        nodes.set_face(tri[0], tri[1], tri[2], std::span<const Vec3>(&centre, 1));
      }
    after = evaluate_tets(affected);
  }
  if (!improves(after, before)) return false;
  // Planned again: judging used the cavity's tets only, but be exact.
  const modify::TetDeletion p = modify::plan_tet_deletion(ed_, cav_, boundary_, t, &model_);
  const std::array<TetId, 1> gone{t};
  before_edit(gone);
  // The operator creates no tet: its hook call, empty, settles the deleted
  // tet's entities (the new face edge gets its nodes, the old shared edge
  // loses them); the tets around it are re-listed here.
  modify::apply(ed_, cav_, boundary_, p);
  created_.insert(created_.end(), affected.begin(), affected.end());
  ++st_.deletions;
  return true;
}

}  // namespace cm::curved::detail
