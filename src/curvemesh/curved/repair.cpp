#include "curvemesh/curved/repair.hpp"

#include <algorithm>
#include <numeric>
#include <vector>

#include "curvemesh/core/timer.hpp"
#include "curvemesh/curved/detail/repairer.hpp"
#include "curvemesh/mesh/adjacency.hpp"

namespace cm::curved::detail {

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
  if (origin_)
    for (TetId t : created) {
      if (rebuilt_.size() <= t) rebuilt_.resize(std::max<std::size_t>(t + 1, m_.tet2verts.size()), 0);
      rebuilt_[t] = 1;
    }
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
      if (st_.passes == 0) {
        // Where det J is least: what the report names as the problem.
        note_problem(t, check_element(order_, mesh::tet_nodes(m_, m_.tet2verts[t]).view(), o_.acceptance));
      }
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
  if (!origin_) {
    ed_.compact();
  } else {
    m_.high_order.set_journal(nullptr);
    const std::vector<char> changed = changed_tets();
    const std::vector<TetId> remap = ed_.compact();
    origin_->assign(m_.tet2verts.size(), kNone);
    for (TetId t = 0; t < entry_tets_; ++t)
      if (remap[t] != kNone && !changed[t]) (*origin_)[remap[t]] = t;
  }
  st_.seconds = timer.seconds();
  return st_;
}

std::vector<char> Repairer::changed_tets() {
  std::vector<char> changed(m_.tet2verts.size(), 0);
  for (TetId t = 0; t < rebuilt_.size() && t < changed.size(); ++t) changed[t] = rebuilt_[t];
  std::sort(journal_.begin(), journal_.end());
  journal_.erase(std::unique(journal_.begin(), journal_.end()), journal_.end());
  std::array<Vec3, mesh::kMaxOrder> before{}, now{};
  for (const auto& [a, b, c] : journal_) {
    // Most entries are a candidate's nodes, set and put back.
    const bool is_edge = c == kNone;
    const bool had = is_edge ? entry_nodes_.get_edge(a, b, before.data()) : entry_nodes_.get_face(a, b, c, before.data());
    const bool has = is_edge ? m_.high_order.get_edge(a, b, now.data()) : m_.high_order.get_face(a, b, c, now.data());
    const std::size_t n = is_edge ? m_.high_order.nodes_per_edge() : m_.high_order.nodes_per_face();
    if (had == has && (!had || std::equal(before.begin(), before.begin() + std::ptrdiff_t(n), now.begin()))) continue;
    const TetId t = find_tet_with(a, b);
    if (t == kNone) continue;  // gone with every tet that held it
    for (TetId s : mesh::collect_shell(m_, a, b, t).tets)
      if (is_edge || mesh::local_index(m_, s, c) >= 0) changed[s] = 1;
  }
  return changed;
}

}  // namespace cm::curved::detail

namespace cm::curved {

RepairStats repair_curved_mesh(mesh::TetMesh& m, const geom::Model& model, std::span<const TetId> unacceptable,
                               const RepairOptions& options, std::vector<TetId>* origin) {
  if (m.high_order.order() < 2 || unacceptable.empty()) {
    if (origin) {
      origin->resize(m.num_tets());
      std::iota(origin->begin(), origin->end(), TetId{0});
    }
    return {};
  }
  detail::Repairer r(m, model, options, origin);
  return r.run(unacceptable);
}

}  // namespace cm::curved
