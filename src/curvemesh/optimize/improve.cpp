#include "curvemesh/optimize/improve.hpp"

#include <algorithm>
#include <memory>
#include <span>
#include <utility>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "curvemesh/core/timer.hpp"
#include "curvemesh/mesh/adjacency.hpp"
#include "curvemesh/mesh/topology.hpp"
#include "curvemesh/modify/collapse.hpp"
#include "curvemesh/modify/delete_tet.hpp"
#include "curvemesh/modify/marks.hpp"
#include "curvemesh/modify/measure.hpp"
#include "curvemesh/modify/relocate.hpp"
#include "curvemesh/modify/surface.hpp"
#include "curvemesh/modify/swap.hpp"
#include "curvemesh/optimize/detail/edit_clock.hpp"
#include "curvemesh/optimize/measured_swap.hpp"
#include "curvemesh/optimize/shell_insert.hpp"
#include "curvemesh/optimize/vertex_search.hpp"
#include "curvemesh/quality/measures.hpp"

namespace cm::optimize {

namespace {

struct Summary {
  double min = 1, mean = 0, min_dihedral = 180;
  std::size_t below = 0;
};

double min_dihedral(const mesh::TetMesh& m, TetId t) {
  const auto& v = m.tet2verts[t];
  return quality::tet_min_dihedral(m.coords[v[0]], m.coords[v[1]], m.coords[v[2]], m.coords[v[3]]);
}

// The measures in parallel, the sums in tet order (the same result for any
// number of threads).
Summary summarize(const modify::MeshEditor& ed, double threshold) {
  const auto& m = ed.mesh();
  const std::size_t nt = m.tet2verts.size();
  std::vector<double> q(nt), angle(nt);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nt, 4096), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t t = r.begin(); t != r.end(); ++t) {
      if (ed.is_dead(static_cast<TetId>(t))) continue;
      q[t] = modify::tet_quality(m, m.tet2verts[t]);
      angle[t] = min_dihedral(m, static_cast<TetId>(t));
    }
  });
  Summary s;
  std::size_t n = 0;
  for (std::size_t t = 0; t < nt; ++t) {
    if (ed.is_dead(static_cast<TetId>(t))) continue;
    s.min = std::min(s.min, q[t]);
    s.min_dihedral = std::min(s.min_dihedral, angle[t]);
    s.mean += q[t];
    s.below += q[t] < threshold;
    ++n;
  }
  s.mean = n ? s.mean / static_cast<double>(n) : 0;
  return s;
}

// A needle of a cusp tip's fan (a corner at the tip's vertex) has a low
// mean ratio by design: it is judged by its angles only.
bool needs_work(const mesh::TetMesh& m, TetId t, double q, const ImproveOptions& o, const std::vector<char>& tip_vertex) {
  if (!tip_vertex.empty())
    for (const VertId v : m.tet2verts[t])
      if (v < tip_vertex.size() && tip_vertex[v]) return min_dihedral(m, t) < o.dihedral_threshold;
  return q < o.threshold || min_dihedral(m, t) < o.dihedral_threshold;
}

double shape(const mesh::TetMesh& m, TetId t) { return angle_aware_measure(m, m.tet2verts[t], nullptr); }

// Worst mean ratio and worst angle-aware quality of a set of tets (the
// first is modify::tet_quality's).
void take_worst(const mesh::TetMesh& m, const std::array<VertId, 4>& v, std::pair<double, double>& w) {
  const auto q = mean_ratio_and_shape(m.coords[v[0]], m.coords[v[1]], m.coords[v[2]], m.coords[v[3]]);
  w.first = std::min(w.first, q.first);
  w.second = std::min(w.second, q.second);
}
std::pair<double, double> worst_of(const mesh::TetMesh& m, std::span<const TetId> tets) {
  std::pair<double, double> w{1, 1};
  for (TetId t : tets) take_worst(m, m.tet2verts[t], w);
  return w;
}

// Mean ratio and angle-aware quality (mean_ratio_and_shape) of would-be
// tets, kept while one tet's reconnections are weighed: the two dynamic
// programs of an edge's shell ask for the same tets, and the mesh does not
// change in between. Keyed by the vertices in order (the order is the
// orientation).
class TetMemo {
 public:
  void clear() {
    if (++stamp_ == 0) {
      std::fill(slots_.begin(), slots_.end(), Slot{});
      stamp_ = 1;
    }
    used_ = 0;
  }
  const std::pair<double, double>& get(const mesh::TetMesh& m, const std::array<VertId, 4>& v) {
    if (2 * (used_ + 1) > slots_.size()) grow();
    Slot& s = slots_[find(v)];
    if (s.stamp != stamp_) {
      s = {v, stamp_, mean_ratio_and_shape(m.coords[v[0]], m.coords[v[1]], m.coords[v[2]], m.coords[v[3]])};
      ++used_;
    }
    return s.value;
  }
  static double mean_ratio(const mesh::TetMesh& m, const std::array<VertId, 4>& v, const void* memo) {
    return const_cast<TetMemo*>(static_cast<const TetMemo*>(memo))->get(m, v).first;
  }
  static double shape(const mesh::TetMesh& m, const std::array<VertId, 4>& v, const void* memo) {
    return const_cast<TetMemo*>(static_cast<const TetMemo*>(memo))->get(m, v).second;
  }

 private:
  struct Slot {
    std::array<VertId, 4> v{};
    std::uint32_t stamp = 0;
    std::pair<double, double> value;
  };
  std::size_t find(const std::array<VertId, 4>& v) const {
    std::uint64_t h = (std::uint64_t(v[0]) << 32 | v[1]) * 0x9E3779B97F4A7C15ull ^ (std::uint64_t(v[2]) << 32 | v[3]);
    h *= 0xC2B2AE3D27D4EB4Full;
    const std::size_t mask = slots_.size() - 1;
    for (std::size_t i = (h >> 32) & mask;; i = (i + 1) & mask)
      if (slots_[i].stamp != stamp_ || slots_[i].v == v) return i;
  }
  void grow() {
    std::vector<Slot> old = std::move(slots_);
    slots_.assign(std::max<std::size_t>(1024, 2 * old.size()), Slot{});
    for (const Slot& s : old)
      if (s.stamp == stamp_) slots_[find(s.v)] = s;
  }
  std::vector<Slot> slots_;
  std::uint32_t stamp_ = 1;
  std::size_t used_ = 0;
};

// What the cusp tips forbid (ImproveOptions::tips): points inside their
// balls, and moving or collapsing the boundary vertices next to a tip's
// vertex. The two ends of the strip's first cross edge stay aligned, which
// keeps the tip's needle from becoming a cap, and the faces' fans keep the
// fine spacing at the strip that the needles there need (a better mean
// ratio of the needles around asks for the opposite of both).
struct TipRules {
  geom::TipBalls balls;
  std::vector<char> pinned_, tip_vertex;  // per vertex (empty: no tips)
  bool pinned(VertId v) const { return v < pinned_.size() && pinned_[v]; }
  /// Whether tet t has a tip's vertex (a needle of its fan).
  bool at_tip(const mesh::TetMesh& m, TetId t) const {
    for (const VertId v : m.tet2verts[t])
      if (v < tip_vertex.size() && tip_vertex[v]) return true;
    return false;
  }
  /// Whether any of the tets has a tip's vertex.
  bool touches(const mesh::TetMesh& m, std::span<const TetId> tets) const {
    return !tip_vertex.empty() && std::any_of(tets.begin(), tets.end(), [&](TetId t) { return at_tip(m, t); });
  }

  TipRules(const mesh::TetMesh& m, const std::vector<geom::CuspTip>& tips) : balls(tips) {
    if (tips.empty()) return;
    pinned_.assign(m.coords.size(), 0);
    tip_vertex.assign(m.coords.size(), 0);
    std::vector<TetId> ball;
    for (VertId v = 0; v < m.coords.size(); ++v) {
      if (m.vert_class[v].dim != 0) continue;
      const bool tip = std::any_of(tips.begin(), tips.end(), [&](const geom::CuspTip& c) { return c.vertex == m.vert_class[v].tag; });
      if (!tip) continue;
      tip_vertex[v] = 1;
      mesh::collect_ball(m, v, ball);
      for (const TetId t : ball)
        for (const VertId w : m.tet2verts[t])
          if (m.vert_class[w].dim == 1 || m.vert_class[w].dim == 2) pinned_[w] = 1;
    }
  }
};

// Whether the new tets' worst dihedral angle is no worse than the old ones',
// or at least the threshold. By a cusp tip the ball's worst tets by the
// mean ratio are its needles, fair by their angles, and a reconnection that
// trades a needle for a tet flat across the cap is progress by both
// measures (relocation_progresses says the same for moves).
bool keeps_angles(const mesh::TetMesh& m, std::span<const TetId> old_tets, std::span<const modify::NewTet> fill,
                  double dihedral_threshold) {
  double before = 180, after = 180;
  for (const TetId t : old_tets) before = std::min(before, min_dihedral(m, t));
  for (const auto& nt : fill) {
    const auto& v = nt.verts;
    after = std::min(after, quality::tet_min_dihedral(m.coords[v[0]], m.coords[v[1]], m.coords[v[2]], m.coords[v[3]]));
  }
  return after >= std::min(before, dihedral_threshold);
}

// The best reconnection of t: for each of its edges the ring triangulation
// best for the angle-aware measure and the one best for the mean ratio, and
// the 2-3 swap of each face; progress as is_progress() says, the highest
// resulting angle-aware quality (then mean ratio) wins.
bool try_reconnect(modify::MeshEditor& ed, modify::Cavity& cav, const TipRules& tips, double dihedral_threshold,
                   TetId t, ImproveStats& st) {
  const auto& m = ed.mesh();
  int kind = -1, local = 0;
  std::pair<double, double> best{-1, -1};  // (shape, mean ratio) after
  const auto tv = m.tet2verts[t];
  thread_local TetMemo memo;
  memo.clear();
  auto plan = [&](int k, int l) {
    const VertId a = tv[mesh::kTetEdges[l % 6][0]], b = tv[mesh::kTetEdges[l % 6][1]];
    switch (k) {
      case 0: return plan_measured_edge_removal(ed, cav, a, b, t, TetMemo::shape, &memo);
      // The same as modify::plan_edge_removal (the mean ratio is
      // modify::tet_quality), with the memo's values.
      case 1: return plan_measured_edge_removal(ed, cav, a, b, t, TetMemo::mean_ratio, &memo);
      default: return modify::plan_face_swap(ed, cav, t, l);
    }
  };
  for (int k = 0; k < 3; ++k)
    for (int l = 0; l < (k < 2 ? 6 : 4); ++l) {
      const modify::Plan p = plan(k, l);
      if (p.fill.empty() || !(p.after > 0)) continue;
      std::pair<double, double> worst_before{1, 1}, worst_after{1, 1};
      const auto take = [&](const std::array<VertId, 4>& v, std::pair<double, double>& w) {
        const auto& q = memo.get(m, v);
        w = {std::min(w.first, q.first), std::min(w.second, q.second)};
      };
      for (TetId u : cav.tets()) take(m.tet2verts[u], worst_before);
      for (const auto& nt : p.fill) take(nt.verts, worst_after);
      const auto [mr_b, sh_b] = worst_before;
      const auto [mr_a, sh_a] = worst_after;
      if (!is_progress(mr_b, sh_b, mr_a, sh_a) || std::pair{sh_a, mr_a} <= best) continue;
      if (tips.touches(m, cav.tets()) && !keeps_angles(m, cav.tets(), p.fill, dihedral_threshold)) continue;
      best = {sh_a, mr_a};
      kind = k;
      local = l;
    }
  if (kind < 0) return false;
  // Plan again (the cavity was reused by the other candidates) and apply.
  modify::apply(ed, cav, plan(kind, local));
  ++(kind < 2 ? st.edge_removals : st.face_swaps);
  return true;
}

// Whether moving v to r.target is progress for its ball (the planners
// judge the mean ratio; a move that raises it by flattening a sliver
// elsewhere in the ball is none). Nor may the move take the ball's worst
// dihedral angle under the threshold, unless it was there already: by a
// cusp tip the worst tets of a ball by both measures are needles, fair
// by their angles, and a move that keeps them as they are could crush
// another tet to 2° and still count as progress.
// With `needles` (for a point of a tip's cap), the tets at a tip's vertex
// count by their angles only, as plan_searched_relocation ranks them.
bool relocation_progresses(mesh::TetMesh& m, VertId v, const modify::Relocation& r, std::vector<TetId>& ball,
                           double dihedral_threshold, const TipRules* needles = nullptr) {
  if (r.refusal != modify::Refusal::kNone) return false;
  mesh::collect_ball(m, v, ball);
  const auto worst = [&] {
    TetShape w{1, 1, 180};
    for (const TetId t : ball) {
      const auto& tv = m.tet2verts[t];
      const TetShape q = tet_shape(m.coords[tv[0]], m.coords[tv[1]], m.coords[tv[2]], m.coords[tv[3]]);
      if (needles && needles->at_tip(m, t)) {
        w.shape = std::min(w.shape, needle_shape(q));
      } else {
        w.mean_ratio = std::min(w.mean_ratio, q.mean_ratio);
        w.shape = std::min(w.shape, q.shape);
      }
      w.min_dihedral = std::min(w.min_dihedral, q.min_dihedral);
    }
    return w;
  };
  const TetShape before = worst();
  const Vec3 old = m.coords[v];
  m.coords[v] = r.target;
  const TetShape after = worst();
  m.coords[v] = old;
  return is_progress(before.mean_ratio, before.shape, after.mean_ratio, after.shape) &&
         after.min_dihedral >= std::min(before.min_dihedral, dihedral_threshold);
}

// With a model, boundary vertices move too, on their model entity. The
// Laplacian move first (cheap, and right for fair balls), else the search.
bool try_relocate(modify::MeshEditor& ed, modify::Cavity& cav, const modify::BoundaryIndex* boundary,
                  const ImproveOptions& o, const TipRules& tips, bool search, TetId t, ImproveStats& st,
                  std::vector<TetId>& ball) {
  bool moved = false;
  auto& m = ed.mesh();
  const auto tv = m.tet2verts[t];
  for (VertId v : tv) {
    if (tips.pinned(v)) continue;
    auto r = o.model ? modify::plan_relocation(ed, cav, *boundary, v, o.model) : modify::plan_relocation(ed, cav, v);
    // A point of a tip's cap moves only over the cap, which the search
    // keeps it to; the Laplacian move would take it off.
    const bool on_cap = m.vert_class[v].dim == 3 && tips.balls.sphere_of(m.coords[v]);
    bool searched = false;
    if (on_cap || tips.balls.contains(r.target) || !relocation_progresses(m, v, r, ball, o.dihedral_threshold)) {
      if (!search) continue;
      r = plan_searched_relocation(ed, cav, boundary, v, o.model, o.dihedral_threshold, 40, &tips.balls);
      if (tips.balls.contains(r.target) ||
          !relocation_progresses(m, v, r, ball, o.dihedral_threshold, on_cap ? &tips : nullptr))
        continue;
      searched = true;
    }
    modify::apply(ed, cav, v, r);
    ++st.relocations;
    st.boundary_relocations += m.vert_class[v].dim < 3;
    st.searched_relocations += searched;
    moved = true;
    if (ed.is_dead(t)) break;  // t was rebuilt: its other vertices are in new tets
  }
  return moved;
}

// A tet on two or three faces of one model face goes when it is worse than
// the tets across its inner faces (they are what remains there).
bool try_delete(modify::MeshEditor& ed, modify::Cavity& cav, modify::BoundaryIndex& boundary,
                const ImproveOptions& o, TetId t, ImproveStats& st, std::vector<TetId>& touched) {
  const auto& m = ed.mesh();
  int hull = 0;
  for (int f = 0; f < 4; ++f) hull += m.tet2adj[mesh::pack_face(t, f)] == kNone;
  if (hull < 2 || hull == 4) return false;
  const modify::TetDeletion plan =
      modify::plan_tet_deletion(ed, cav, boundary, t, o.model, modify::DeletionOptions{o.chord_alpha});
  if (plan.refusal != modify::Refusal::kNone) return false;
  std::pair<double, double> across{1, 1}, self{1, 1};
  for (int f = 0; f < 4; ++f)
    if (const Index a = m.tet2adj[mesh::pack_face(t, f)]; a != kNone) take_worst(m, m.tet2verts[mesh::face_tet(a)], across);
  take_worst(m, m.tet2verts[t], self);
  if (!is_progress(std::min(self.first, across.first), std::min(self.second, across.second), across.first,
                   across.second))
    return false;
  // The tets across now stand on the boundary with one more face: worth a
  // look again (nothing new was created for the hook to report).
  for (int f = 0; f < 4; ++f)
    if (const Index a = m.tet2adj[mesh::pack_face(t, f)]; a != kNone) touched.push_back(mesh::face_tet(a));
  modify::apply(ed, cav, boundary, plan);
  ++st.deletions;
  return true;
}

// The best collapse of an edge of t (either way): a vertex goes when the
// tets that remain of its ball are progress over the ball. Along a model
// edge or face only with the model (the collapse's own rules), so a thin
// triangle at a sharp corner of a face can lengthen until it is no longer
// thin.
bool try_collapse(modify::MeshEditor& ed, modify::Cavity& cav, modify::BoundaryIndex& boundary,
                  const geom::Model* model, const TipRules& tips, TetId t, ImproveStats& st) {
  auto& m = ed.mesh();
  const auto tv = m.tet2verts[t];
  int best = -1;
  std::pair<double, double> best_after{-1, -1};
  for (int k = 0; k < 12; ++k) {
    const auto& e = mesh::kTetEdges[static_cast<std::size_t>(k % 6)];
    const VertId from = tv[static_cast<std::size_t>(k < 6 ? e[0] : e[1])], to = tv[static_cast<std::size_t>(k < 6 ? e[1] : e[0])];
    if (m.vert_class[from].dim != 3 && !model) continue;
    if (tips.pinned(from)) continue;
    const auto plan = modify::plan_collapse(ed, cav, boundary, from, to, model);
    if (plan.refusal != modify::Refusal::kNone) continue;
    const auto before = worst_of(m, cav.tets());
    std::pair<double, double> after{1, 1};
    for (TetId u : cav.tets()) {
      auto nv = m.tet2verts[u];
      if (std::find(nv.begin(), nv.end(), to) != nv.end()) continue;
      for (VertId& x : nv)
        if (x == from) x = to;
      take_worst(m, nv, after);
    }
    if (!is_progress(before.first, before.second, after.first, after.second)) continue;
    if (std::pair{after.second, after.first} <= std::pair{best_after.second, best_after.first}) continue;
    best = k;
    best_after = after;
  }
  if (best < 0) return false;
  const auto& e = mesh::kTetEdges[static_cast<std::size_t>(best % 6)];
  const VertId from = tv[static_cast<std::size_t>(best < 6 ? e[0] : e[1])], to = tv[static_cast<std::size_t>(best < 6 ? e[1] : e[0])];
  const auto plan = modify::plan_collapse(ed, cav, boundary, from, to, model);
  modify::apply(ed, cav, boundary, plan);
  ++st.collapses;
  return true;
}

// The best point insertion for t: in the shell of one of its six edges,
// else in its neighbourhood one or two face steps deep.
bool try_insert(modify::MeshEditor& ed, modify::Cavity& cav, const TipRules& tips, TetId t, ImproveStats& st) {
  const auto tv = ed.mesh().tet2verts[t];
  int best = -1;
  double best_after = 0;
  for (int e = 0; e < 8; ++e) {
    const auto p = e < 6 ? plan_shell_insertion(ed, cav, tv[mesh::kTetEdges[e][0]], tv[mesh::kTetEdges[e][1]], t)
                         : plan_ball_insertion(ed, cav, t, e - 5);
    if (p.refusal == modify::Refusal::kNone && p.after > best_after && !tips.balls.contains(p.point)) {
      best = e;
      best_after = p.after;
    }
  }
  if (best < 0) return false;
  const auto p = best < 6 ? plan_shell_insertion(ed, cav, tv[mesh::kTetEdges[best][0]], tv[mesh::kTetEdges[best][1]], t)
                          : plan_ball_insertion(ed, cav, t, best - 5);
  apply(ed, cav, p);
  ++st.insertions;
  return true;
}

}  // namespace

ImproveStats improve_quality(mesh::TetMesh& m, const ImproveOptions& o) {
  Timer timer;
  ImproveStats st;
  modify::MeshEditor ed(m);
  modify::mark_boundary_faces(ed);
  // Model-aware relocation reads it, element deletion edits it.
  std::unique_ptr<modify::BoundaryIndex> boundary = std::make_unique<modify::BoundaryIndex>(m);
  modify::Cavity cav;
  const TipRules tips(m, o.tips);
  const Summary before = summarize(ed, o.threshold);
  st.min_before = before.min;
  st.mean_before = before.mean;
  st.below_before = before.below;
  st.min_dihedral_before = before.min_dihedral;
  std::vector<std::pair<double, TetId>> bad;
  std::vector<TetId> ball;
  // After the first pass only the tets an operation made (the hook reports
  // them) and those still waiting can need work: no pass rescans the mesh.
  std::vector<TetId> touched, candidates;
  // A tet every operator refused is refused again, for the same reasons,
  // until an edit makes a tet at one of its vertices (the operators see
  // only those balls) or the mode changes (search and collapse once stuck):
  // it is skipped until then. Its entry: when it was given up on, in which mode.
  detail::EditClock clock(m.num_verts());
  std::vector<std::pair<std::uint64_t, bool>> given_up;
  ed.set_hook([&](const mesh::TetMesh& mesh, std::span<const TetId> created) {
    touched.insert(touched.end(), created.begin(), created.end());
    clock.tick(mesh, created);
  });
  // The search and collapses wait until the cheap operators are stuck: the
  // search drives the mean ratio of the balls it improves down to the
  // progress floor, which then holds their neighbours, and a collapse
  // coarsens; both are for what the others cannot repair.
  // Stuck: a pass that changed nothing, or left the worst tet as it was.
  bool stuck = false;
  double last_worst = -1;
  constexpr std::size_t kWindow = 3;
  constexpr double kStall = 0.01;
  std::vector<std::pair<double, std::size_t>> history;  // per pass: the worst badness, the tets to work on
  for (st.passes = 0; st.passes < o.passes; ++st.passes) {
    if (st.passes == 0) {
      candidates.resize(m.tet2verts.size());
      for (TetId t = 0; t < m.tet2verts.size(); ++t) candidates[t] = t;
    } else {
      candidates.clear();
      for (const auto& [q, t] : bad) candidates.push_back(t);
      candidates.insert(candidates.end(), touched.begin(), touched.end());
      std::sort(candidates.begin(), candidates.end());
      candidates.erase(std::unique(candidates.begin(), candidates.end()), candidates.end());
    }
    touched.clear();
    bad.clear();
    // Which candidates need work, and how badly, measured in parallel (the
    // first pass measures every tet); listed in candidate order.
    std::vector<double> badness(candidates.size(), -2);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, candidates.size(), 1024),
                      [&](const tbb::blocked_range<std::size_t>& r) {
                        for (std::size_t i = r.begin(); i != r.end(); ++i) {
                          const TetId t = candidates[i];
                          if (ed.is_dead(t)) continue;
                          // Worst angle-aware shape first: slivers before
                          // fair-angled tets of the same mean ratio.
                          if (needs_work(m, t, modify::tet_quality(m, m.tet2verts[t]), o, tips.tip_vertex)) badness[i] = shape(m, t);
                        }
                      });
    for (std::size_t i = 0; i < candidates.size(); ++i)
      if (badness[i] > -2) bad.emplace_back(badness[i], candidates[i]);
    if (bad.empty()) break;
    std::sort(bad.begin(), bad.end());
    if (!(bad.front().first > last_worst + 1e-6) && st.passes > 0) stuck = true;
    last_worst = bad.front().first;
    // Converged: over the last kWindow passes neither the worst tet rose by
    // kStall (relative) nor did the tets to work on become kStall fewer.
    // Where the mesh cannot become good (a layer of slivers a thousandth
    // thick between model faces) passes would otherwise go on trading tiny
    // gains between neighbours, seconds each, to the pass limit.
    history.emplace_back(bad.front().first, bad.size());
    if (stuck && history.size() > kWindow) {
      const auto [worst_then, count_then] = history[history.size() - 1 - kWindow];
      if (bad.front().first <= worst_then + kStall * std::abs(worst_then) &&
          static_cast<double>(bad.size()) >= (1 - kStall) * static_cast<double>(count_then))
        break;
    }
    std::size_t changes = 0;
    for (const auto& [q0, t] : bad) {
      if (ed.is_dead(t) || !needs_work(m, t, modify::tet_quality(m, m.tet2verts[t]), o, tips.tip_vertex)) continue;
      if (t < given_up.size() && given_up[t].first != 0 && given_up[t].second == stuck &&
          clock.tet_unchanged_since(given_up[t].first, m.tet2verts[t]))
        continue;
      const std::size_t changes_before = changes;
      if (o.deletion && o.model) {
        Timer op;
        const bool done = try_delete(ed, cav, *boundary, o, t, st, touched);
        st.deletion_seconds += op.seconds();
        if (done) {
          ++changes;
          continue;
        }
      }
      if (o.swaps) {
        Timer op;
        const bool done = try_reconnect(ed, cav, tips, o.dihedral_threshold, t, st);
        st.swap_seconds += op.seconds();
        if (done) {
          ++changes;
          continue;
        }
      }
      if (o.relocation) {
        Timer op;
        const bool moved = try_relocate(ed, cav, boundary.get(), o, tips, stuck && o.search, t, st, ball);
        st.relocation_seconds += op.seconds();
        if (moved) {
          ++changes;
          continue;
        }
      }
      if (o.collapse && stuck) {
        Timer op;
        const bool done = try_collapse(ed, cav, *boundary, o.model, tips, t, st);
        st.collapse_seconds += op.seconds();
        if (done) {
          ++changes;
          continue;
        }
      }
      if (o.insertion) {
        Timer op;
        changes += try_insert(ed, cav, tips, t, st);
        st.insertion_seconds += op.seconds();
      }
      if (changes == changes_before) {
        if (given_up.size() < m.tet2verts.size()) given_up.resize(m.tet2verts.size(), {0, false});
        given_up[t] = {clock.now, stuck};
      }
    }
    if (changes == 0) {
      if (stuck || (!o.search && !o.collapse)) break;
      stuck = true;
    }
  }
  ed.set_hook({});
  ed.compact();
  mesh::drop_unused_vertices(m);
  const Summary after = summarize(ed, o.threshold);
  st.min_after = after.min;
  st.mean_after = after.mean;
  st.below_after = after.below;
  st.min_dihedral_after = after.min_dihedral;
  st.seconds = timer.seconds();
  return st;
}

}  // namespace cm::optimize
