#include "curvemesh/optimize/improve.hpp"

#include <algorithm>
#include <memory>

#include "curvemesh/core/timer.hpp"
#include "curvemesh/mesh/topology.hpp"
#include "curvemesh/modify/marks.hpp"
#include "curvemesh/modify/measure.hpp"
#include "curvemesh/modify/relocate.hpp"
#include "curvemesh/modify/surface.hpp"
#include "curvemesh/modify/swap.hpp"
#include "curvemesh/optimize/shell_insert.hpp"
#include "curvemesh/quality/measures.hpp"

namespace cm::optimize {

namespace {

struct Summary {
  double min = 1, mean = 0, min_dihedral = 180;
  std::size_t below = 0;
};

double min_dihedral(const mesh::TetMesh& m, TetId t) {
  const auto& v = m.tet2verts[t];
  return quality::tet_dihedral_range(m.coords[v[0]], m.coords[v[1]], m.coords[v[2]], m.coords[v[3]]).min;
}

Summary summarize(const modify::MeshEditor& ed, double threshold) {
  const auto& m = ed.mesh();
  Summary s;
  std::size_t n = 0;
  for (TetId t = 0; t < m.tet2verts.size(); ++t) {
    if (ed.is_dead(t)) continue;
    const double q = modify::tet_quality(m, m.tet2verts[t]);
    s.min = std::min(s.min, q);
    s.min_dihedral = std::min(s.min_dihedral, min_dihedral(m, t));
    s.mean += q;
    s.below += q < threshold;
    ++n;
  }
  s.mean = n ? s.mean / static_cast<double>(n) : 0;
  return s;
}

bool needs_work(const mesh::TetMesh& m, TetId t, double q, const ImproveOptions& o) {
  return q < o.threshold || min_dihedral(m, t) < o.dihedral_threshold;
}

// The best reconnection of tet t: which operator, on what, and how good.
struct Choice {
  int kind = -1;  // 0 edge removal, 1 face swap
  int local = 0;  // edge or face index in t
  double after = 0;
};

bool try_reconnect(modify::MeshEditor& ed, modify::Cavity& cav, TetId t, ImproveStats& st) {
  const auto& m = ed.mesh();
  Choice best;
  best.after = modify::tet_quality(m, m.tet2verts[t]);
  const auto tv = m.tet2verts[t];
  for (int e = 0; e < 6; ++e) {
    const auto p = modify::plan_edge_removal(ed, cav, tv[mesh::kTetEdges[e][0]], tv[mesh::kTetEdges[e][1]], t);
    if (p.improves() && p.after > best.after) best = {0, e, p.after};
  }
  for (int f = 0; f < 4; ++f) {
    const auto p = modify::plan_face_swap(ed, cav, t, f);
    if (p.improves() && p.after > best.after) best = {1, f, p.after};
  }
  if (best.kind < 0) return false;
  // Plan again (the cavity was reused by the other candidates) and apply.
  const auto p = best.kind == 0 ? modify::plan_edge_removal(ed, cav, tv[mesh::kTetEdges[best.local][0]],
                                                           tv[mesh::kTetEdges[best.local][1]], t)
                                : modify::plan_face_swap(ed, cav, t, best.local);
  modify::apply(ed, cav, p);
  ++(best.kind == 0 ? st.edge_removals : st.face_swaps);
  return true;
}

// With a model, boundary vertices move too, on their model entity.
bool try_relocate(modify::MeshEditor& ed, modify::Cavity& cav, const modify::BoundaryIndex* boundary,
                  const geom::Model* model, TetId t, ImproveStats& st) {
  bool moved = false;
  const auto tv = ed.mesh().tet2verts[t];
  for (VertId v : tv) {
    const auto r = model ? modify::plan_relocation(ed, cav, *boundary, v, model) : modify::plan_relocation(ed, cav, v);
    if (r.refusal != modify::Refusal::kNone) continue;
    modify::apply(ed, cav, v, r);
    ++st.relocations;
    moved = true;
    if (ed.is_dead(t)) break;  // t was rebuilt: its other vertices are in new tets
  }
  return moved;
}

// The best point insertion for t: in the shell of one of its six edges,
// else in its neighbourhood one or two face steps deep.
bool try_insert(modify::MeshEditor& ed, modify::Cavity& cav, TetId t, ImproveStats& st) {
  const auto tv = ed.mesh().tet2verts[t];
  int best = -1;
  double best_after = 0;
  for (int e = 0; e < 8; ++e) {
    const auto p = e < 6 ? plan_shell_insertion(ed, cav, tv[mesh::kTetEdges[e][0]], tv[mesh::kTetEdges[e][1]], t)
                         : plan_ball_insertion(ed, cav, t, e - 5);
    if (p.refusal == modify::Refusal::kNone && p.after > best_after) {
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
  // Only model-aware relocation reads it; it never edits m.tris or m.edges.
  std::unique_ptr<modify::BoundaryIndex> boundary;
  if (o.model) boundary = std::make_unique<modify::BoundaryIndex>(m);
  modify::Cavity cav;
  const Summary before = summarize(ed, o.threshold);
  st.min_before = before.min;
  st.mean_before = before.mean;
  st.below_before = before.below;
  st.min_dihedral_before = before.min_dihedral;
  std::vector<std::pair<double, TetId>> bad;
  for (st.passes = 0; st.passes < o.passes; ++st.passes) {
    bad.clear();
    for (TetId t = 0; t < m.tet2verts.size(); ++t) {
      if (ed.is_dead(t)) continue;
      const double q = modify::tet_quality(m, m.tet2verts[t]);
      if (needs_work(m, t, q, o)) bad.emplace_back(q, t);
    }
    if (bad.empty()) break;
    std::sort(bad.begin(), bad.end());
    std::size_t changes = 0;
    for (const auto& [q0, t] : bad) {
      if (ed.is_dead(t) || !needs_work(m, t, modify::tet_quality(m, m.tet2verts[t]), o)) continue;
      if (o.swaps) {
        Timer op;
        const bool done = try_reconnect(ed, cav, t, st);
        st.swap_seconds += op.seconds();
        if (done) {
          ++changes;
          continue;
        }
      }
      if (o.relocation) {
        Timer op;
        const bool moved = try_relocate(ed, cav, boundary.get(), o.model, t, st);
        st.relocation_seconds += op.seconds();
        if (moved) {
          ++changes;
          continue;
        }
      }
      if (o.insertion) {
        Timer op;
        changes += try_insert(ed, cav, t, st);
        st.insertion_seconds += op.seconds();
      }
    }
    if (changes == 0) break;
  }
  ed.compact();
  const Summary after = summarize(ed, o.threshold);
  st.min_after = after.min;
  st.mean_after = after.mean;
  st.below_after = after.below;
  st.min_dihedral_after = after.min_dihedral;
  st.seconds = timer.seconds();
  return st;
}

}  // namespace cm::optimize
