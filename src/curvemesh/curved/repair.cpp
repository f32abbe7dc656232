#include "curvemesh/curved/repair.hpp"

#include <algorithm>
#include <array>
#include <memory>
#include <tuple>
#include <unordered_set>
#include <vector>

#include "curvemesh/core/predicates.hpp"
#include "curvemesh/core/timer.hpp"
#include "curvemesh/curved/nodes.hpp"
#include "curvemesh/mesh/adjacency.hpp"
#include "curvemesh/mesh/topology.hpp"
#include "curvemesh/modify/boundary_swap.hpp"
#include "curvemesh/modify/collapse.hpp"
#include "curvemesh/modify/delete_tet.hpp"
#include "curvemesh/modify/marks.hpp"
#include "curvemesh/modify/relocate.hpp"
#include "curvemesh/modify/split.hpp"
#include "curvemesh/modify/surface.hpp"
#include "curvemesh/modify/swap.hpp"
#include "curvemesh/optimize/measured_swap.hpp"

namespace cm::curved {

namespace {

using Verts = std::array<VertId, 4>;

// A change counts as progress on an equal number of unacceptable tets only
// if their worst score rises by this much: it bounds the number of steps.
constexpr double kGain = 1e-3;
// Budget of operations per unacceptable tet at the start, and overall.
constexpr std::size_t kOpsPerBadTet = 40;
constexpr std::size_t kMinOps = 2000;

// The outcome of a set of tets, the thing candidates are ranked by.
struct Outcome {
  int bad = 0;             // unacceptable (invalid included)
  double worst = 3;        // least ElementCheck::score()
  bool straight_ok = true;  // every straight-sided tet strictly positive
};

bool resolves(const Outcome& o) { return o.straight_ok && o.bad == 0; }

bool improves(const Outcome& after, const Outcome& before) {
  if (!after.straight_ok) return false;
  if (after.bad != before.bad) return after.bad < before.bad;
  return after.bad > 0 && after.worst > before.worst + kGain;
}

// Orders candidates: resolving ones first, then fewer unacceptable tets,
// then a higher worst score.
bool ranks_above(const Outcome& a, const Outcome& b) {
  if (a.straight_ok != b.straight_ok) return a.straight_ok;
  return std::tuple(a.bad, -a.worst) < std::tuple(b.bad, -b.worst);
}

std::uint64_t edge_key(VertId a, VertId b) {
  if (a > b) std::swap(a, b);
  return (std::uint64_t(a) << 32) | b;
}

bool straight_positive(const mesh::TetMesh& m, const Verts& v) {
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
  Repairer(mesh::TetMesh& m, const geom::Model& model, const RepairOptions& o)
      : m_(m), model_(model), o_(o), ed_(m), boundary_(m), placer_(m, model), order_(m.high_order.order()) {
    modify::mark_boundary_faces(ed_);
    ed_.set_hook([this](const mesh::TetMesh&, std::span<const TetId> created) { after_edit(created); });
  }

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
    return check_element(order_, mesh::gather_tet_nodes(m_, v), o_.acceptance);
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
  bool retriangulate(TetId t);
  bool delete_element(TetId t);
  bool remesh(TetId t);
  bool reposition(TetId t);
  void curve_interior(TetId t);
  void straighten(std::vector<TetId> queue);

  // Candidate judging of the point operators: the tets they would create,
  // with the nodes their new boundary entities would get.
  Outcome judge_split(const modify::SplitPlan& plan, std::vector<TetId> shell);
  // The boundary swap of face edge (a, b); bad = -1 when refused. Leaves the
  // cavity holding the edge's shell.
  Outcome judge_boundary_swap(VertId a, VertId b, TetId t);
  Outcome judge_collapse(const modify::CollapsePlan& plan, std::vector<TetId> ball);
  bool keeps_chord_rule(VertId from, VertId to, std::span<const TetId> ball) const;

  mesh::TetMesh& m_;
  const geom::Model& model_;
  const RepairOptions& o_;
  modify::MeshEditor ed_;
  modify::BoundaryIndex boundary_;
  modify::Cavity cav_;
  NodePlacer placer_;
  int order_;
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
};

void Repairer::stamp(std::span<const TetId> tets) {
  ++clock_;
  if (vert_stamp_.size() < m_.coords.size()) vert_stamp_.resize(m_.coords.size(), 0);
  for (TetId t : tets)
    for (VertId v : m_.tet2verts[t]) vert_stamp_[v] = clock_;
}

bool Repairer::unchanged_since_failure(TetId t) const {
  if (t >= failed_at_.size() || failed_at_[t] == 0) return false;
  for (VertId v : m_.tet2verts[t])
    if (v < vert_stamp_.size() && vert_stamp_[v] >= failed_at_[t]) return false;
  return true;
}

void Repairer::note_failure(TetId t) {
  if (failed_at_.size() <= t) failed_at_.resize(std::max<std::size_t>(t + 1, 2 * failed_at_.size()), 0);
  // clock_ + 1: an edit after this one has a stamp >= it.
  failed_at_[t] = clock_ + 1;
}

TetId Repairer::find_tet_with(VertId a, VertId b) const {
  if (a >= m_.vert2tet.size() || m_.vert2tet[a] == kNone) return kNone;
  std::vector<TetId> ball;
  mesh::collect_ball(m_, a, ball);
  for (TetId t : ball)
    if (mesh::local_index(m_, t, b) >= 0) return t;
  return kNone;
}

mesh::ModelRef Repairer::edge_entity(VertId a, VertId b, TetId t) const {
  if (const Index e = boundary_.find_edge(a, b); e != kNone) return {1, m_.edges[e].edge_tag};
  const mesh::Shell shell = mesh::collect_shell(m_, a, b, t);
  for (TetId s : shell.tets)
    for (VertId c : m_.tet2verts[s]) {
      if (c == a || c == b) continue;
      if (const Index i = boundary_.find_tri(a, b, c); i != kNone) return {2, m_.tris[i].face_tag};
    }
  return {3, 0};
}

bool Repairer::is_curved(VertId a, VertId b) const {
  std::array<Vec3, mesh::kMaxOrder> nodes;
  if (!m_.high_order.get_edge(a, b, nodes.data())) return false;
  const Vec3 xa = m_.coords[a], xb = m_.coords[b];
  const double len2 = (xb - xa).squaredNorm();
  for (int s = 1; s < order_; ++s)
    if ((nodes[s - 1] - (xa + (xb - xa) * (double(s) / order_))).squaredNorm() > 1e-20 * len2) return true;
  return false;
}

void Repairer::before_edit(std::span<const TetId> old) {
  old_edges_.clear();
  old_faces_.clear();
  for (TetId t : old) {
    const auto& v = m_.tet2verts[t];
    for (const auto& e : mesh::kTetEdges) old_edges_.push_back({v[e[0]], v[e[1]]});
    if (order_ >= 3)
      for (const auto& f : mesh::kFaceVerts) old_faces_.push_back({v[f[0]], v[f[1]], v[f[2]]});
  }
}

bool Repairer::refresh_edge(VertId a, VertId b, TetId t) {
  std::array<Vec3, mesh::kMaxOrder> old;
  const bool had = m_.high_order.get_edge(a, b, old.data());
  const mesh::ModelRef on = edge_entity(a, b, t);
  if (on.dim == 3) {
    if (had) m_.high_order.erase_edge(a, b);
    return had;
  }
  std::array<Vec3, mesh::kMaxOrder> nodes;
  placer_.edge_nodes(a, b, on, nodes.data());
  m_.high_order.set_edge(a, b, std::span<const Vec3>(nodes.data(), order_ - 1));
  return !had || !std::equal(nodes.begin(), nodes.begin() + (order_ - 1), old.begin());
}

bool Repairer::refresh_face(VertId a, VertId b, VertId c) {
  Vec3 old;
  const bool had = m_.high_order.get_face(a, b, c, &old);
  const Index i = boundary_.find_tri(a, b, c);
  if (i == kNone) {
    if (had) m_.high_order.erase_face(a, b, c);
    return had;
  }
  std::array<std::array<Vec3, 2>, 3> e{};
  const std::array<VertId, 3> v{a, b, c};
  for (int k = 0; k < 3; ++k) m_.high_order.get_edge(v[k], v[(k + 1) % 3], e[k].data());
  Vec3 centre;
  placer_.face_nodes(a, b, c, m_.tris[i].face_tag, e[0].data(), e[1].data(), e[2].data(), &centre);
  m_.high_order.set_face(a, b, c, std::span<const Vec3>(&centre, 1));
  return !had || centre != old;
}

void Repairer::recheck_face(VertId a, VertId b, VertId c) {
  if (const TetId t = find_tet_with(a, b); t != kNone)
    for (TetId s : mesh::collect_shell(m_, a, b, t).tets)
      if (mesh::local_index(m_, s, c) >= 0) created_.push_back(s);
}

void Repairer::after_edit(std::span<const TetId> created) {
  const std::size_t first = created_.size();
  created_.insert(created_.end(), created.begin(), created.end());
  std::vector<std::uint64_t> seen;
  for (TetId t : created) {
    const auto& v = m_.tet2verts[t];
    for (const auto& e : mesh::kTetEdges) {
      const std::uint64_t k = edge_key(v[e[0]], v[e[1]]);
      if (std::find(seen.begin(), seen.end(), k) != seen.end()) continue;
      seen.push_back(k);
      // An edge on the cavity's hull is shared with tets outside it, which
      // change with its nodes.
      if (refresh_edge(v[e[0]], v[e[1]], t)) {
        const mesh::Shell shell = mesh::collect_shell(m_, v[e[0]], v[e[1]], t);
        created_.insert(created_.end(), shell.tets.begin(), shell.tets.end());
      }
    }
  }
  // Entities of the old tets that are in no new one: gone, or kept by tets
  // outside the cavity (an edit that changes the hull can leave some there).
  for (const auto& [a, b] : old_edges_) {
    const std::uint64_t k = edge_key(a, b);
    if (std::find(seen.begin(), seen.end(), k) != seen.end()) continue;
    seen.push_back(k);
    const TetId t = find_tet_with(a, b);
    if (t == kNone) {
      m_.high_order.erase_edge(a, b);
      continue;
    }
    // Kept by tets outside the cavity, its nodes may change with its
    // classification (a collapse merging model-edge segments): those tets
    // are checked again too.
    refresh_edge(a, b, t);
    const mesh::Shell shell = mesh::collect_shell(m_, a, b, t);
    created_.insert(created_.end(), shell.tets.begin(), shell.tets.end());
  }
  if (order_ >= 3) {
    for (TetId t : created) {
      const auto& v = m_.tet2verts[t];
      for (const auto& f : mesh::kFaceVerts)
        if (refresh_face(v[f[0]], v[f[1]], v[f[2]])) recheck_face(v[f[0]], v[f[1]], v[f[2]]);
    }
    for (const auto& f : old_faces_) {
      refresh_face(f[0], f[1], f[2]);
      // A face kept by a tet outside the cavity: that tet is checked again.
      if (boundary_.find_tri(f[0], f[1], f[2]) == kNone) continue;
      recheck_face(f[0], f[1], f[2]);
    }
  }
  old_edges_.clear();
  old_faces_.clear();
  stamp(std::span<const TetId>(created_).subspan(first));
}

// --- problem entities ----------------------------------------------------------

void Repairer::note_problem(TetId t, const ElementCheck& c) {
  const auto& v = m_.tet2verts[t];
  ProblemEntities p;
  p.tet = v;
  p.score = c.score();
  // The mesh entity where det J is least.
  switch (c.where.dim) {
    case 0: p.at = {v[c.where.index]}; break;
    case 1: p.at = {v[mesh::kTetEdges[c.where.index][0]], v[mesh::kTetEdges[c.where.index][1]]}; break;
    case 2:
      for (int k : mesh::kFaceVerts[c.where.index]) p.at.push_back(v[k]);
      break;
    default: p.at.assign(v.begin(), v.end());
  }
  for (const auto& e : mesh::kTetEdges)
    if (is_curved(v[e[0]], v[e[1]])) p.curved_edges.push_back({v[e[0]], v[e[1]]});
  // Least on a curved entity or at its ends (the seed's Fig. 3.1 e, f: a
  // curved entity too far from its straight element), else on an entity
  // that is not curved, which a curved one approaches (Fig. 3.1 a-d).
  const auto on = [&](VertId x) { return std::find(p.at.begin(), p.at.end(), x) != p.at.end(); };
  for (const auto& e : p.curved_edges)
    if (c.where.dim < 3 && (c.where.dim == 0 ? (on(e[0]) || on(e[1])) : (on(e[0]) && on(e[1])))) p.too_far = true;
  ++(p.too_far ? st_.too_far : st_.too_close);
  if (st_.problems.size() < RepairStats::kMaxListed) st_.problems.push_back(std::move(p));
}

// --- step 1: retriangulation -----------------------------------------------------

bool Repairer::retriangulate(TetId t) {
  const Verts tv = m_.tet2verts[t];
  int best_kind = -1, best_local = 0;
  Outcome best;
  Outcome before_best;
  auto plan = [&](int kind, int local) {
    if (kind == 0) {
      const auto& e = mesh::kTetEdges[local];
      return optimize::plan_measured_edge_removal(ed_, cav_, tv[e[0]], tv[e[1]], t, &Repairer::curved_measure, this);
    }
    return optimize::plan_measured_face_swap(ed_, cav_, t, local, &Repairer::curved_measure, this);
  };
  for (int kind = 0; kind < 2; ++kind)
    for (int local = 0; local < (kind == 0 ? 6 : 4); ++local) {
      if (kind == 0) {
        const auto& e = mesh::kTetEdges[local];
        if (m_.high_order.has_edge(tv[e[0]], tv[e[1]])) continue;  // a boundary edge stays
      }
      const modify::Plan p = plan(kind, local);
      if (p.fill.empty() || (p.refusal != modify::Refusal::kNone && p.refusal != modify::Refusal::kNoImprovement))
        continue;
      const Outcome before = evaluate_tets(cav_.tets());
      std::vector<Verts> fill;
      for (const auto& nt : p.fill) fill.push_back(nt.verts);
      const Outcome after = evaluate(fill);
      if (!improves(after, before) && !(resolves(after) && before.bad > 0)) continue;
      if (best_kind < 0 || ranks_above(after, best)) {
        best = after;
        before_best = before;
        best_kind = kind;
        best_local = local;
      }
    }
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
    if (!improves(candidate, before) && !(resolves(candidate) && before.bad > 0)) continue;
    if ((best_kind < 0 && best_swap_edge < 0) || ranks_above(candidate, best)) {
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
  if (best_kind < 0) return false;
  const modify::Plan p = plan(best_kind, best_local);
  before_edit(cav_.tets());
  modify::apply(ed_, cav_, p);
  ++(best_kind == 0 ? st_.edge_removals : st_.face_swaps);
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
  if (!improves(after, before) && !(resolves(after) && before.bad > 0)) return false;
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

// --- step 3: remeshing -----------------------------------------------------------

Outcome Repairer::judge_split(const modify::SplitPlan& plan, std::vector<TetId> shell) {
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
  return evaluate(fill);
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

Outcome Repairer::judge_collapse(const modify::CollapsePlan& plan, std::vector<TetId> ball) {
  const VertId from = plan.from, to = plan.to;
  if (m_.vert_class[from].dim < 3 && !keeps_chord_rule(from, to, ball)) {
    Outcome refused;
    refused.straight_ok = false;
    return refused;
  }
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
  return evaluate(fill);
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
      const Outcome before = evaluate_tets(shell);
      const Outcome after = judge_split(p, shell);
      if (improves(after, before) || (resolves(after) && before.bad > 0)) candidates.push_back({kSplit, a, b, after});
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
      const Outcome before = evaluate_tets(ball);
      const Outcome after = judge_collapse(p, ball);
      if (improves(after, before) || (resolves(after) && before.bad > 0))
        candidates.push_back({kCollapse, from, to, after});
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

// --- step 4: repositioning ---------------------------------------------------------

bool Repairer::reposition(TetId t) {
  const Verts tv = m_.tet2verts[t];
  std::vector<TetId> ball;
  for (VertId v : tv) {
    if (m_.vert_class[v].dim != 3) continue;
    mesh::collect_ball(m_, v, ball);
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
          const Outcome o = evaluate_tets(ball);
          if (ranks_above(o, current) && o.straight_ok && (o.bad < current.bad || o.worst > current.worst + kGain)) {
            current = o;
            x = x + d;
            moved = true;
          }
        }
      }
    }
    m_.coords[v] = start;
    if (!improves(current, before) && !(resolves(current) && before.bad > 0)) continue;
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
    const mesh::Shell shell = mesh::collect_shell(m_, a, b, t);
    const Outcome before = evaluate_tets(shell.tets);
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
          const Outcome o = evaluate_tets(shell.tets);
          if (o.straight_ok && (o.bad < current.bad || (o.bad == current.bad && o.worst > current.worst + kGain))) {
            current = o;
            offset += d;
            moved = true;
          }
        }
      }
    }
    if (improves(current, before)) {
      set(offset);
      interior_curved_.insert(edge_key(a, b));
      touched_.insert(touched_.end(), shell.tets.begin(), shell.tets.end());
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

RepairStats Repairer::run(std::span<const TetId> unacceptable) {
  Timer timer;
  budget_ = std::max(kMinOps, kOpsPerBadTet * unacceptable.size());
  std::vector<TetId> bad(unacceptable.begin(), unacceptable.end());
  std::size_t ops = 0;
  for (st_.passes = 0; st_.passes < o_.passes && !bad.empty() && ops < budget_; ++st_.passes) {
    // Worst first.
    std::vector<std::pair<double, TetId>> order;
    for (TetId t : bad)
      if (!ed_.is_dead(t)) order.emplace_back(check(m_.tet2verts[t]).score(), t);
    std::sort(order.begin(), order.end());
    std::size_t changes = 0;
    for (const auto& [score, t] : order) {
      if (ops >= budget_) break;
      if (ed_.is_dead(t)) continue;
      const ElementCheck c = check(m_.tet2verts[t]);
      if (c.acceptable) continue;
      if (st_.passes == 0) note_problem(t, c);
      if (unchanged_since_failure(t)) continue;
      if (retriangulate(t) || delete_element(t) || remesh(t) || reposition(t)) {
        ++changes;
        ++ops;
      } else {
        note_failure(t);
      }
    }
    // The list, updated: the old entries still unacceptable and the tets
    // the pass created that are (an operation only changes the tets it
    // creates: their nodes are the only ones it moves).
    std::vector<TetId> next;
    for (TetId t : bad)
      if (!ed_.is_dead(t) && !acceptable(t)) next.push_back(t);
    for (TetId t : created_)
      if (!ed_.is_dead(t) && !acceptable(t)) next.push_back(t);
    created_.clear();
    std::sort(next.begin(), next.end());
    next.erase(std::unique(next.begin(), next.end()), next.end());
    bad = std::move(next);
    if (changes == 0) break;
  }
  if (o_.interior_curving && !bad.empty()) {
    for (TetId t : bad)
      if (!ed_.is_dead(t) && !acceptable(t)) curve_interior(t);
    // Curving an edge moves the nodes of its whole shell: a shell is taken
    // when it has fewer unacceptable tets, not only the ones listed, so the
    // list is made again from the listed and the touched tets.
    std::vector<TetId> next;
    for (TetId t : bad)
      if (!ed_.is_dead(t) && !acceptable(t)) next.push_back(t);
    for (TetId t : touched_)
      if (!ed_.is_dead(t) && !acceptable(t)) next.push_back(t);
    std::sort(next.begin(), next.end());
    next.erase(std::unique(next.begin(), next.end()), next.end());
    bad = std::move(next);
  }
  if (o_.straighten) straighten(bad);
  // What is left of them: straightening takes back interior curving first.
  st_.interior_edges_curved = interior_curved_.size();
  ed_.set_hook({});
  ed_.compact();
  st_.seconds = timer.seconds();
  return st_;
}

}  // namespace

RepairStats repair_curved_mesh(mesh::TetMesh& m, const geom::Model& model, std::span<const TetId> unacceptable,
                               const RepairOptions& options) {
  if (m.high_order.order() < 2 || unacceptable.empty()) return {};
  Repairer r(m, model, options);
  return r.run(unacceptable);
}

}  // namespace cm::curved
