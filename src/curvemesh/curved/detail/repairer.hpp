#pragma once
// The repairer behind repair_curved_mesh (repair.hpp): its state and the
// ranking of candidates, shared by the files of its steps:
//   repair.cpp              bookkeeping of nodes and of the list of
//                           unacceptable tets, the driver (run);
//   repair_retriangulate.cpp  steps 1-2: edge/multi-face removal, boundary
//                           swaps, element deletion;
//   repair_remesh.cpp       step 3: boundary edge splits, collapses;
//   repair_reposition.cpp   steps 4-6: vertex repositioning, interior
//                           curving, straightening as the last resort.
// Internal to the curved module.
#include <algorithm>
#include <array>
#include <cstdint>
#include <optional>
#include <span>
#include <tuple>
#include <unordered_set>
#include <vector>

#include "curvemesh/core/predicates.hpp"
#include "curvemesh/curved/detail/check_memo.hpp"
#include "curvemesh/curved/element_check.hpp"
#include "curvemesh/curved/nodes.hpp"
#include "curvemesh/curved/repair.hpp"
#include "curvemesh/mesh/high_order.hpp"
#include "curvemesh/mesh/topology.hpp"
#include "curvemesh/modify/boundary_swap.hpp"
#include "curvemesh/modify/collapse.hpp"
#include "curvemesh/modify/marks.hpp"
#include "curvemesh/modify/split.hpp"
#include "curvemesh/modify/surface.hpp"
#include "curvemesh/optimize/measured_swap.hpp"

namespace cm::curved::detail {

using Verts = std::array<VertId, 4>;

// A change counts as progress on an equal number of unacceptable tets only
// if their worst score rises by this much: it bounds the number of steps.
inline constexpr double kGain = 1e-3;
// Budget of operations per unacceptable tet at the start, and overall.
inline constexpr std::size_t kOpsPerBadTet = 40;
inline constexpr std::size_t kMinOps = 2000;

// The outcome of a set of tets, the thing candidates are ranked by.
struct Outcome {
  int bad = 0;             // unacceptable (invalid included)
  double worst = 3;        // least ElementCheck::score()
  bool straight_ok = true;  // every straight-sided tet strictly positive
};

// Progress: fewer unacceptable tets (resolving, none left of some,
// included), or as many and a worst score higher by kGain.
inline bool improves(const Outcome& after, const Outcome& before) {
  if (!after.straight_ok) return false;
  if (after.bad != before.bad) return after.bad < before.bad;
  return after.bad > 0 && after.worst > before.worst + kGain;
}

// Orders candidates: resolving ones first, then fewer unacceptable tets,
// then a higher worst score.
inline bool ranks_above(const Outcome& a, const Outcome& b) {
  if (a.straight_ok != b.straight_ok) return a.straight_ok;
  return std::tuple(a.bad, -a.worst) < std::tuple(b.bad, -b.worst);
}

inline std::uint64_t edge_key(VertId a, VertId b) {
  if (a > b) std::swap(a, b);
  return (std::uint64_t(a) << 32) | b;
}

inline bool straight_positive(const mesh::TetMesh& m, const Verts& v) {
  return predicates::orient3d(m.coords[v[0]].data(), m.coords[v[1]].data(), m.coords[v[2]].data(),
                              m.coords[v[3]].data()) > 0;
}

// Temporarily stored nodes (what a candidate's new boundary entities would
// get), undone on destruction in reverse order.
class NodeOverride {
 public:
  explicit NodeOverride(mesh::HighOrderNodes& h) : h_(h) {}
  NodeOverride(const NodeOverride&) = delete;
  NodeOverride& operator=(const NodeOverride&) = delete;
  ~NodeOverride() {
    for (auto it = saved_.rbegin(); it != saved_.rend(); ++it) {
      const Saved& s = *it;
      if (s.face) {
        if (s.had)
          h_.set_face(s.v[0], s.v[1], s.v[2], s.nodes);
        else
          h_.erase_face(s.v[0], s.v[1], s.v[2]);
      } else {
        if (s.had)
          h_.set_edge(s.v[0], s.v[1], s.nodes);
        else
          h_.erase_edge(s.v[0], s.v[1]);
      }
    }
  }
  void set_edge(VertId a, VertId b, std::span<const Vec3> nodes) {
    Saved s{{a, b, kNone}, false, false, std::vector<Vec3>(h_.nodes_per_edge())};
    s.had = h_.get_edge(a, b, s.nodes.data());
    saved_.push_back(std::move(s));
    h_.set_edge(a, b, nodes);
  }
  void set_face(VertId a, VertId b, VertId c, std::span<const Vec3> nodes) {
    Saved s{{a, b, c}, true, false, std::vector<Vec3>(h_.nodes_per_face())};
    s.had = h_.get_face(a, b, c, s.nodes.data());
    saved_.push_back(std::move(s));
    h_.set_face(a, b, c, nodes);
  }

 private:
  struct Saved {
    std::array<VertId, 3> v;
    bool face, had;
    std::vector<Vec3> nodes;
  };
  mesh::HighOrderNodes& h_;
  std::vector<Saved> saved_;
};

// A vertex that exists only while a candidate is judged (a split's point).
class ScratchVertex {
 public:
  ScratchVertex(mesh::TetMesh& m, const Vec3& x, mesh::ModelRef c, const mesh::Param& p) : m_(m) {
    id_ = static_cast<VertId>(m.coords.size());
    m.coords.push_back(x);
    m.vert_class.push_back(c);
    m.vert_param.push_back(p);
  }
  ScratchVertex(const ScratchVertex&) = delete;
  ScratchVertex& operator=(const ScratchVertex&) = delete;
  ~ScratchVertex() {
    m_.coords.pop_back();
    m_.vert_class.pop_back();
    m_.vert_param.pop_back();
  }
  VertId id() const { return id_; }

 private:
  mesh::TetMesh& m_;
  VertId id_;
};

class Repairer {
 public:
  // With `origin`, run() writes there, for each tet on return, the id it
  // had on entry if it is that tet with the same nodes, else kNone.
  Repairer(mesh::TetMesh& m, const geom::Model& model, const RepairOptions& o, std::vector<TetId>* origin)
      : m_(m),
        model_(model),
        o_(o),
        ed_(m),
        boundary_(m),
        placer_(m, model),
        order_(m.high_order.order()),
        memo_(order_, o.acceptance),
        origin_(origin),
        entry_tets_(m.tet2verts.size()) {
    modify::mark_boundary_faces(ed_);
    ed_.set_hook([this](const mesh::TetMesh&, std::span<const TetId> created) { after_edit(created); });
    if (origin_) {
      entry_nodes_ = m_.high_order;
      m_.high_order.set_journal(&journal_);
    }
  }
  ~Repairer() { m_.high_order.set_journal(nullptr); }
  Repairer(const Repairer&) = delete;
  Repairer& operator=(const Repairer&) = delete;

  RepairStats run(std::span<const TetId> unacceptable);

  // The measure edge removal maximizes (optimize::TetMeasure): the curved
  // score shifted to stay > 0 for every straight-positive tet, so that the
  // dynamic program can still pick the least bad ring triangulation.
  static double curved_measure(const mesh::TetMesh& m, const Verts& v, const void* self) {
    if (!straight_positive(m, v)) return -1;
    const auto* r = static_cast<const Repairer*>(self);
    return 2 + std::clamp(r->check(v).score(), -1.0, 1.0);
  }

 private:
  ElementCheck check(const Verts& v) const {
    const mesh::TetNodes nodes = mesh::tet_nodes(m_, v);
    // A straight-sided tet is one orient3d: cheaper than the memo's lookup.
    if (!nodes.stored) return check_element(order_, nodes.view(), o_.acceptance);
    return memo_(nodes.view());
  }
  Outcome evaluate(std::span<const Verts> tets) const {
    Outcome out;
    for (const Verts& v : tets) {
      if (!straight_positive(m_, v)) {
        out.straight_ok = false;
        out.worst = -1;
        continue;
      }
      const ElementCheck c = check(v);
      out.bad += !c.acceptable;
      out.worst = std::min(out.worst, c.score());
    }
    return out;
  }
  Outcome evaluate_tets(std::span<const TetId> tets) const {
    std::vector<Verts> v;
    v.reserve(tets.size());
    for (TetId t : tets) v.push_back(m_.tet2verts[t]);
    return evaluate(v);
  }
  bool acceptable(TetId t) const { return check(m_.tet2verts[t]).acceptable; }
  // The pattern searches' rule (steps 4 and 5): a move is taken when it
  // leaves fewer unacceptable tets, or as many with a worst score higher by
  // kGain. Judged tet by tet, a move is refused as soon as it cannot meet
  // the rule (the count only grows, the worst only falls), which is where
  // most moves end: `tets` worst first makes that early.
  // Also what finds the retriangulations that resolve (current: none
  // unacceptable, any worst).
  template <class Tets>
  std::optional<Outcome> step_up(const Tets& tets, const Outcome& current) const {
    Outcome out;
    for (const auto& t : tets) {
      const Verts& v = verts_of(t);
      if (!straight_positive(m_, v)) return std::nullopt;
      const ElementCheck c = check(v);
      out.bad += !c.acceptable;
      out.worst = std::min(out.worst, c.score());
      if (out.bad > current.bad || (out.bad == current.bad && out.worst <= current.worst + kGain))
        return std::nullopt;
    }
    return out;
  }
  const Verts& verts_of(TetId t) const { return m_.tet2verts[t]; }
  static const Verts& verts_of(const Verts& v) { return v; }
  // The tets worst first, for step_up.
  void sort_worst_first(std::vector<TetId>& tets) const {
    std::vector<std::pair<double, TetId>> scored;
    scored.reserve(tets.size());
    for (TetId t : tets) scored.emplace_back(check(m_.tet2verts[t]).score(), t);
    std::sort(scored.begin(), scored.end());
    for (std::size_t i = 0; i < tets.size(); ++i) tets[i] = scored[i].second;
  }

  // --- nodes of the entities an edit creates -------------------------------
  // The model entity edge (a, b) of live tet t lies on: a model edge, a
  // model face (a boundary triangle through it), or {3, 0}: inside.
  mesh::ModelRef edge_entity(VertId a, VertId b, TetId t) const;
  bool is_curved(VertId a, VertId b) const;
  // Records the entities of the tets an edit is about to replace.
  void before_edit(std::span<const TetId> old);
  void after_edit(std::span<const TetId> created);
  // Both return whether the entity's nodes changed (appeared, went, moved).
  bool refresh_edge(VertId a, VertId b, TetId t);
  bool refresh_face(VertId a, VertId b, VertId c);
  // Queues for a new check the live tets holding face (a, b, c).
  void recheck_face(VertId a, VertId b, VertId c);
  TetId find_tet_with(VertId a, VertId b) const;

  // --- steps ---------------------------------------------------------------
  void note_problem(TetId t, const ElementCheck& c);
  // An edge removal (kind 0, local edge) or 2-3 face swap (kind 1, local
  // face) of a tet, and what it leaves.
  struct Retriangulation {
    int kind = -1;
    int local = 0;
    Outcome after;
  };
  modify::Plan plan_retriangulation(TetId t, const Retriangulation& r, optimize::TetMeasure measure,
                                    const void* context);
  // The best of t's retriangulations, each planned to maximize `measure`
  // and judged curved: among those that make progress, or with
  // `resolving_only` among those that leave every new tet acceptable.
  Retriangulation best_retriangulation(TetId t, optimize::TetMeasure measure, const void* context,
                                       bool resolving_only);
  bool apply_retriangulation(TetId t, const Retriangulation& r, optimize::TetMeasure measure, const void* context);
  bool retriangulate(TetId t);
  bool delete_element(TetId t);
  bool remesh(TetId t);
  bool reposition(TetId t);
  void curve_interior(TetId t);
  void straighten(std::vector<TetId> queue);

  // Candidate judging of the point operators: the tets they would create,
  // with the nodes their new boundary entities would get.
  // Both give nothing when the candidate is no progress over `before` (the
  // outcome of the tets it replaces), as step_up judges it.
  std::optional<Outcome> judge_split(const modify::SplitPlan& plan, std::vector<TetId> shell, const Outcome& before);
  // The boundary swap of face edge (a, b); bad = -1 when refused. Leaves the
  // cavity holding the edge's shell.
  Outcome judge_boundary_swap(VertId a, VertId b, TetId t);
  std::optional<Outcome> judge_collapse(const modify::CollapsePlan& plan, std::vector<TetId> ball,
                                        const Outcome& before);
  bool keeps_chord_rule(VertId from, VertId to, std::span<const TetId> ball) const;

  mesh::TetMesh& m_;
  const geom::Model& model_;
  const RepairOptions& o_;
  modify::MeshEditor ed_;
  modify::BoundaryIndex boundary_;
  modify::Cavity cav_;
  NodePlacer placer_;
  int order_;
  mutable CheckMemo memo_;
  RepairStats st_;
  std::size_t budget_ = 0;
  // Entities of the tets being replaced (before_edit).
  std::vector<std::array<VertId, 2>> old_edges_;
  std::vector<std::array<VertId, 3>> old_faces_;
  // Interior edges given nodes by curve_interior.
  std::unordered_set<std::uint64_t> interior_curved_;
  // Tets created since the list of unacceptable tets was last updated.
  std::vector<TetId> created_;
  // Every step judges only tets through a vertex of the tet it repairs, so
  // a tet all steps failed on fails again until an edit creates a tet
  // through one of its vertices: edits are counted (clock_), vertices
  // stamped with the last edit that touched them, failures with the clock.
  std::uint64_t clock_ = 0;
  std::vector<std::uint64_t> vert_stamp_;
  std::vector<std::uint64_t> failed_at_;  // per tet; 0: not failed
  void stamp(std::span<const TetId> tets);
  bool unchanged_since_failure(TetId t) const;
  void note_failure(TetId t);
  // Tets whose nodes curve_interior changed.
  std::vector<TetId> touched_;
  // For `origin`: the nodes on entry, the entities given nodes or stripped
  // of them since (net change or not), the tet slots edits filled.
  std::vector<TetId>* origin_;
  std::size_t entry_tets_;
  mesh::HighOrderNodes entry_nodes_;
  std::vector<std::array<VertId, 3>> journal_;
  std::vector<char> rebuilt_;
  // Per tet slot (before compaction): rebuilt, or holding an entity whose
  // nodes differ from those on entry.
  std::vector<char> changed_tets();
};

}  // namespace cm::curved::detail
