#include "curvemesh/optimize/adapt.hpp"

#include <algorithm>
#include <limits>
#include <optional>
#include <stdexcept>
#include <tuple>
#include <unordered_map>
#include <vector>

#include <fmt/format.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_reduce.h>

#include "curvemesh/core/predicates.hpp"
#include "curvemesh/core/timer.hpp"
#include "curvemesh/mesh/adjacency.hpp"
#include "curvemesh/mesh/topology.hpp"
#include "curvemesh/modify/collapse.hpp"
#include "curvemesh/modify/delete_tet.hpp"
#include "curvemesh/modify/marks.hpp"
#include "curvemesh/modify/relocate.hpp"
#include "curvemesh/modify/split.hpp"
#include "curvemesh/modify/swap.hpp"
#include "curvemesh/optimize/detail/edit_clock.hpp"
#include "curvemesh/optimize/measured_swap.hpp"
#include "curvemesh/optimize/shell_insert.hpp"
#include "curvemesh/quality/measures.hpp"

namespace cm::optimize {

namespace {

// Improvements smaller than this are noise, and accepting them could cycle.
constexpr double kMargin = 1e-6;

double min_metric_quality(const mesh::TetMesh& m, const MetricField& f, std::span<const TetId> tets) {
  double q = 1;
  for (TetId t : tets) q = std::min(q, f.tet_quality(m, m.tet2verts[t]));
  return q;
}

double metric_measure(const mesh::TetMesh& m, const std::array<VertId, 4>& v, const void* field) {
  return static_cast<const MetricField*>(field)->tet_quality(m, v);
}

using detail::EditClock;

// Reconnections found not to help, remembered until an edit touches them:
// an edge's shell is rebuilt (stamping both its ends) by any edit of one of
// its tets, and a face's two tets likewise stamp its three vertices. A poor
// tet's neighbours are poor too and share its edges and faces, so without
// this each shell would be solved again for each of them, pass after pass.
class ReconnectMemo {
 public:
  explicit ReconnectMemo(const EditClock& clock) : clock_(clock) {}
  bool edge_refused(VertId a, VertId b) const {
    const auto it = edges_.find(edge_key(a, b));
    return it != edges_.end() && clock_.unchanged_since(it->second, a, b);
  }
  void refuse_edge(VertId a, VertId b) { edges_[edge_key(a, b)] = clock_.now; }
  bool face_refused(std::array<VertId, 3> f) const {
    std::sort(f.begin(), f.end());
    const auto it = faces_.find(f);
    return it != faces_.end() && clock_.unchanged_since(it->second, f[0], f[1], f[2]);
  }
  void refuse_face(std::array<VertId, 3> f) {
    std::sort(f.begin(), f.end());
    faces_[f] = clock_.now;
  }

 private:
  static std::uint64_t edge_key(VertId a, VertId b) {
    return a < b ? (std::uint64_t{a} << 32 | b) : (std::uint64_t{b} << 32 | a);
  }
  struct FaceHash {
    std::size_t operator()(const std::array<VertId, 3>& f) const {
      return std::hash<std::uint64_t>()((std::uint64_t{f[0]} << 32 | f[1]) * 0x9E3779B97F4A7C15ull ^ f[2]);
    }
  };
  const EditClock& clock_;
  std::unordered_map<std::uint64_t, std::uint64_t> edges_;
  std::unordered_map<std::array<VertId, 3>, std::uint64_t, FaceHash> faces_;
};

// The best reconnection of t in the metric: edge removal whose ring
// triangulation is chosen in the metric, or a 2-3 face swap. Candidates
// the memo knows to fail are skipped; those that fail are remembered.
bool reconnect(modify::MeshEditor& ed, modify::Cavity& cav, const MetricField& f, TetId t, ReconnectMemo& memo,
               AdaptStats& st) {
  const auto& m = ed.mesh();
  int kind = -1, local = 0;
  double best_gain = kMargin;
  const auto tv = m.tet2verts[t];
  auto consider = [&](const modify::Plan& p, int k, int l) {
    if (p.refusal == modify::Refusal::kNone && p.after - p.before > best_gain) {
      best_gain = p.after - p.before;
      kind = k;
      local = l;
    }
  };
  for (int e = 0; e < 6; ++e) {
    const VertId a = tv[mesh::kTetEdges[e][0]], b = tv[mesh::kTetEdges[e][1]];
    if (memo.edge_refused(a, b)) continue;
    const auto p = plan_measured_edge_removal(ed, cav, a, b, t, metric_measure, &f);
    if (p.refusal != modify::Refusal::kNone || !(p.after - p.before > kMargin))
      memo.refuse_edge(a, b);
    else
      consider(p, 0, e);
  }
  for (int fi = 0; fi < 4; ++fi) {
    const auto face = modify::tet_face(tv, fi);
    if (memo.face_refused(face)) continue;
    const auto p = plan_measured_face_swap(ed, cav, t, fi, metric_measure, &f);
    if (p.refusal != modify::Refusal::kNone || !(p.after - p.before > kMargin))
      memo.refuse_face(face);
    else
      consider(p, 1, fi);
  }
  if (kind < 0) return false;
  const auto p = kind == 0 ? plan_measured_edge_removal(ed, cav, tv[mesh::kTetEdges[local][0]],
                                                        tv[mesh::kTetEdges[local][1]], t, metric_measure, &f)
                           : plan_measured_face_swap(ed, cav, t, local, metric_measure, &f);
  modify::apply(ed, cav, p);
  ++(kind == 0 ? st.edge_removals : st.face_swaps);
  return true;
}

// The worst metric quality of a vertex's ball as the vertex moves. The
// tets' metrics are the means of their vertices' and do not depend on where
// the vertex is, so each is computed once (one eigen-solve) and a candidate
// position costs a mean ratio per tet.
class BallQuality {
 public:
  void reset(const mesh::TetMesh& m, const MetricField& f, std::span<const TetId> ball) {
    field_ = &f;
    tets_.assign(ball.begin(), ball.end());
    metrics_.clear();
    if (f.anisotropic())
      for (TetId t : tets_) metrics_.push_back(f.tet_metric(m.tet2verts[t]));
  }
  double min(const mesh::TetMesh& m) const {
    if (!field_->anisotropic()) return min_metric_quality(m, *field_, tets_);
    double q = 1;
    for (std::size_t i = 0; i < tets_.size(); ++i) {
      const auto& v = m.tet2verts[tets_[i]];
      const Vec3 &a = m.coords[v[0]], &b = m.coords[v[1]], &c = m.coords[v[2]], &d = m.coords[v[3]];
      if (predicates::orient3d(a.data(), b.data(), c.data(), d.data()) <= 0) return -1;
      q = std::min(q, std::max(quality::tet_metric_mean_ratio(a, b, c, d, metrics_[i]), 0.0));
    }
    return q;
  }

 private:
  const MetricField* field_ = nullptr;
  std::vector<TetId> tets_;
  std::vector<size::Metric> metrics_;
};

// Moves v where its ball is best in the metric: candidates are the centroid
// of its neighbours and the point at unit metric distance from each of them
// (their average), each tried whole and damped.
// A boundary vertex moves only with a model, on its entity: the
// model-aware planner proposes, the metric decides.
bool relocate_on_model(modify::MeshEditor& ed, modify::Cavity& cav, const modify::BoundaryIndex& boundary,
                       const geom::Model* model, const MetricField& f, VertId v, std::vector<TetId>& ball) {
  auto& m = ed.mesh();
  const int dim = m.vert_class[v].dim;
  if (!model || (dim != 1 && dim != 2) || m.vert2tet[v] == kNone) return false;
  const modify::Relocation r = modify::plan_relocation(ed, cav, boundary, v, model);
  if (r.refusal != modify::Refusal::kNone) return false;
  if (f.anisotropic()) {
    mesh::collect_ball(m, v, ball);
    const double before = min_metric_quality(m, f, ball);
    const Vec3 old = m.coords[v];
    m.coords[v] = r.target;
    const double after = min_metric_quality(m, f, ball);
    m.coords[v] = old;
    if (!(after > before + kMargin)) return false;
  }
  modify::apply(ed, cav, v, r);
  return true;
}

// Region vertices move freely; with flat_boundary (no model), boundary
// vertices move within an exactly flat face or straight model edge
// (modify::FlatBoundary), so the surface stays as it was. Their
// parameters are then unknown (NaN).
bool relocate(modify::MeshEditor& ed, modify::Cavity& cav, const modify::BoundaryIndex& boundary,
              bool flat_boundary, const MetricField& f, VertId v, std::vector<TetId>& ball,
              std::vector<VertId>& ring) {
  auto& m = ed.mesh();
  if (v >= m.vert_class.size() || m.vert2tet[v] == kNone) return false;
  const int dim = m.vert_class[v].dim;
  if (dim != 3 && (!flat_boundary || dim < 1)) return false;
  mesh::collect_ball(m, v, ball);
  thread_local std::vector<Index> tris;
  std::optional<modify::FlatBoundary> flat;
  if (dim != 3) {
    modify::tris_through(m, boundary, v, ball, tris);
    flat = modify::FlatBoundary::at(m, boundary, v, tris, ball);
    if (!flat) return false;
  }
  cav.reset(ed);
  ring.clear();
  for (TetId t : ball) {
    cav.add(ed, t);
    for (VertId w : m.tet2verts[t])
      if (w != v) ring.push_back(w);
  }
  std::sort(ring.begin(), ring.end());
  ring.erase(std::unique(ring.begin(), ring.end()), ring.end());
  const Vec3 old = m.coords[v];
  Vec3 centroid = Vec3::Zero(), unit = Vec3::Zero();
  for (VertId w : ring) {
    centroid += m.coords[w];
    const double l = f.edge_length(m, v, w);
    unit += l > 0 ? Vec3(m.coords[w] + (old - m.coords[w]) / l) : old;
  }
  centroid /= static_cast<double>(ring.size());
  unit /= static_cast<double>(ring.size());
  thread_local BallQuality quality;
  quality.reset(m, f, ball);
  const double before = quality.min(m);
  modify::Relocation r;
  r.before = r.after = before;
  r.target = old;
  for (const Vec3& goal : {centroid, unit})
    for (double w : {1.0, 0.5, 0.25}) {
      std::optional<Vec3> x = old + w * (goal - old);
      if (flat) x = flat->slide(*x);
      if (!x) continue;
      m.coords[v] = *x;
      const double q = quality.min(m);
      if (q > r.after) {
        r.after = q;
        r.target = *x;
      }
      m.coords[v] = old;
    }
  if (!(r.after > r.before + kMargin)) return false;
  modify::apply(ed, cav, v, r);
  if (dim != 3) m.vert_param[v] = mesh::Param{};
  return true;
}

// With the analytic field the metric came from, a new or moved vertex takes
// its exact value: interpolating between the ends of a coarse edge across a
// shock would blur the very feature the size map asks for.
void refresh(MetricField& f, const AdaptOptions& o, const mesh::TetMesh& m, VertId v) {
  if (!o.sizes) return;
  const Vec3& x = m.coords[v];
  if (f.anisotropic()) {
    f.set(v, o.sizes->metric(x));
  } else {
    const double h = o.sizes->size(x);
    f.set(v, size::Metric::Identity() / (h * h));
  }
}

// A tet on two or three faces of one model face goes (with a model) when it
// is worse in the metric than every tet across its inner faces.
bool delete_in_metric(modify::MeshEditor& ed, modify::Cavity& cav, modify::BoundaryIndex& boundary,
                      const AdaptOptions& o, const MetricField& f, TetId t) {
  const auto& m = ed.mesh();
  int hull = 0;
  for (int i = 0; i < 4; ++i) hull += m.tet2adj[mesh::pack_face(t, i)] == kNone;
  if (!o.model || hull < 2 || hull == 4) return false;
  const modify::TetDeletion plan =
      modify::plan_tet_deletion(ed, cav, boundary, t, o.model, modify::DeletionOptions{o.chord_alpha});
  if (plan.refusal != modify::Refusal::kNone) return false;
  double across = 1;
  for (int i = 0; i < 4; ++i)
    if (const Index a = m.tet2adj[mesh::pack_face(t, i)]; a != kNone)
      across = std::min(across, f.tet_quality(m, m.tet2verts[mesh::face_tet(a)]));
  if (!(across > f.tet_quality(m, m.tet2verts[t]) + kMargin)) return false;
  modify::apply(ed, cav, boundary, plan);
  return true;
}

// A split or collapse may leave tets this poor: the shape pass that follows
// repairs them, but a nearly flat tet would hold it back.
constexpr double kMinNewQuality = 0.02;

struct EdgeTask {
  double length;
  VertId a, b;
  TetId tet;  // held both when collected
};

// Edges of live tets whose metric length is outside [lo, hi], each once.
std::vector<EdgeTask> collect_edges(const modify::MeshEditor& ed, const MetricField& f, double lo, double hi) {
  const auto& m = ed.mesh();
  std::vector<EdgeTask> tasks;
  for (TetId t = 0; t < m.tet2verts.size(); ++t) {
    if (ed.is_dead(t)) continue;
    const auto& tv = m.tet2verts[t];
    for (const auto& e : mesh::kTetEdges) {
      const auto [a, b] = std::minmax(tv[e[0]], tv[e[1]]);
      const double l = f.edge_length(m, a, b);
      if (l < lo || l > hi) tasks.push_back({l, a, b, t});
    }
  }
  std::sort(tasks.begin(), tasks.end(),
            [](const EdgeTask& x, const EdgeTask& y) { return std::tie(x.a, x.b) < std::tie(y.a, y.b); });
  tasks.erase(std::unique(tasks.begin(), tasks.end(),
                          [](const EdgeTask& x, const EdgeTask& y) { return x.a == y.a && x.b == y.b; }),
              tasks.end());
  return tasks;
}

// A live tet holding both a and b, or kNone when (a, b) is no longer an edge.
TetId find_edge_tet(const modify::MeshEditor& ed, VertId a, VertId b, TetId hint, std::vector<TetId>& ball) {
  const auto& m = ed.mesh();
  auto holds = [&](TetId t) {
    const auto& tv = m.tet2verts[t];
    return std::find(tv.begin(), tv.end(), a) != tv.end() && std::find(tv.begin(), tv.end(), b) != tv.end();
  };
  if (!ed.is_dead(hint) && holds(hint)) return hint;
  if (a >= m.vert2tet.size() || m.vert2tet[a] == kNone) return kNone;
  mesh::collect_ball(m, a, ball);
  for (TetId t : ball)
    if (holds(t)) return t;
  return kNone;
}

std::size_t split_long_edges(modify::MeshEditor& ed, modify::Cavity& cav, modify::BoundaryIndex& boundary,
                             MetricField& f, const AdaptOptions& o, std::vector<TetId>& ball) {
  auto& m = ed.mesh();
  auto tasks = collect_edges(ed, f, 0, kLongEdge);
  std::erase_if(tasks, [](const EdgeTask& e) { return e.length < kLongEdge; });
  std::sort(tasks.begin(), tasks.end(), [](const EdgeTask& x, const EdgeTask& y) {
    return x.length != y.length ? x.length > y.length : std::tie(x.a, x.b) < std::tie(y.a, y.b);
  });
  std::size_t done = 0;
  for (const EdgeTask& e : tasks) {
    const TetId start = find_edge_tet(ed, e.a, e.b, e.tet, ball);
    if (start == kNone) continue;
    const modify::SplitPlan plan = modify::plan_split(ed, cav, boundary, e.a, e.b, start, o.model);
    if (plan.refusal != modify::Refusal::kNone) continue;
    double q = plan.after;
    if (f.anisotropic()) {
      // The new tets: each shell tet with a, then b, replaced by the point.
      const size::Metric log_p = 0.5 * (f.log_metric(e.a) + f.log_metric(e.b));
      q = 1;
      for (TetId t : cav.tets())
        for (VertId gone : {e.a, e.b}) {
          std::array<Vec3, 4> x;
          std::array<const size::Metric*, 4> logs;
          for (int k = 0; k < 4; ++k) {
            const VertId w = m.tet2verts[t][k];
            x[k] = w == gone ? plan.point : m.coords[w];
            logs[k] = w == gone ? &log_p : &f.log_metric(w);
          }
          q = std::min(q, f.tet_quality_at(x, logs));
        }
    }
    if (q < kMinNewQuality) continue;
    const VertId p = modify::apply(ed, cav, boundary, plan);
    f.set_interpolated(p, e.a, e.b, 0.5);
    refresh(f, o, m, p);
    ++done;
  }
  return done;
}

std::size_t collapse_short_edges(modify::MeshEditor& ed, modify::Cavity& cav, modify::BoundaryIndex& boundary,
                                 const MetricField& f, const AdaptOptions& o, std::vector<TetId>& ball,
                                 std::vector<VertId>& ring) {
  auto& m = ed.mesh();
  auto tasks = collect_edges(ed, f, kShortEdge, std::numeric_limits<double>::infinity());
  std::sort(tasks.begin(), tasks.end(), [](const EdgeTask& x, const EdgeTask& y) {
    return x.length != y.length ? x.length < y.length : std::tie(x.a, x.b) < std::tie(y.a, y.b);
  });
  std::size_t done = 0;
  for (const EdgeTask& e : tasks) {
    if (find_edge_tet(ed, e.a, e.b, e.tet, ball) == kNone) continue;
    for (const auto& [from, to] : {std::pair{e.a, e.b}, std::pair{e.b, e.a}}) {
      const modify::CollapsePlan plan = modify::plan_collapse(ed, cav, boundary, from, to, o.model);
      if (plan.refusal != modify::Refusal::kNone) continue;
      // Without a model a boundary vertex goes only when allowed, and
      // where the surface is exactly flat around it (straight along a
      // model edge), so the surface and the volume stay what they were,
      // as boundary splits at midpoints leave them.
      if (!o.model && m.vert_class[from].dim != 3 && !(o.flat_boundary && plan.keeps_surface)) continue;
      // The tets that survive, with from replaced by to; and the edges
      // from to to the rest of the ball, which must not come out long.
      double q = 1;
      bool too_long = false;
      ring.clear();
      for (TetId t : cav.tets()) {
        const auto& tv = m.tet2verts[t];
        if (std::find(tv.begin(), tv.end(), to) != tv.end()) continue;
        std::array<Vec3, 4> x;
        std::array<const size::Metric*, 4> logs;
        for (int k = 0; k < 4; ++k) {
          const VertId w = tv[k] == from ? to : tv[k];
          x[k] = m.coords[w];
          logs[k] = &f.log_metric(w);
          if (w != to) ring.push_back(w);
        }
        q = std::min(q, f.tet_quality_at(x, logs));
      }
      std::sort(ring.begin(), ring.end());
      ring.erase(std::unique(ring.begin(), ring.end()), ring.end());
      for (VertId w : ring) too_long |= f.edge_length(m, to, w) > kLongEdge;
      if (too_long || q < std::min(kMinNewQuality, plan.before)) continue;
      modify::apply(ed, cav, boundary, plan);
      ++done;
      break;
    }
  }
  return done;
}

// Drops the vertices collapses left in no tet, and their metrics.
void drop_unused_vertices(mesh::TetMesh& m, MetricField& f) {
  const std::size_t nv = m.num_verts();
  const std::vector<VertId> old2new = mesh::drop_unused_vertices(m);
  if (old2new.empty()) return;
  std::vector<size::Metric> tensors;
  std::vector<double> sizes;
  for (VertId v = 0; v < nv; ++v) {
    if (old2new[v] == kNone) continue;
    if (f.anisotropic())
      tensors.push_back(f.metric(v));
    else
      sizes.push_back(f.size_at(v));
  }
  f = f.anisotropic() ? MetricField::from_tensors(std::move(tensors)) : MetricField::from_sizes(sizes);
}

struct Census {
  double min = 1, mean = 0;
  std::size_t below = 0;
};

Census census(const modify::MeshEditor& ed, const MetricField& f, double threshold) {
  const auto& m = ed.mesh();
  Census c;
  std::size_t n = 0;
  for (TetId t = 0; t < m.tet2verts.size(); ++t) {
    if (ed.is_dead(t)) continue;
    const double q = f.tet_quality(m, m.tet2verts[t]);
    c.min = std::min(c.min, q);
    c.mean += q;
    c.below += q < threshold;
    ++n;
  }
  c.mean = n ? c.mean / static_cast<double>(n) : 0;
  return c;
}

}  // namespace

AdaptStats adapt_to_metric(mesh::TetMesh& m, MetricField& field, const AdaptOptions& o) {
  if (field.size() != m.num_verts())
    throw std::invalid_argument(
        fmt::format("adapt_to_metric: {} metrics for the {} vertices of the mesh", field.size(), m.num_verts()));
  Timer timer;
  AdaptStats st;
  st.lengths_before = measure_lengths(m, field);
  modify::MeshEditor ed(m);
  modify::mark_boundary_faces(ed);
  modify::BoundaryIndex boundary(m);
  modify::Cavity cav;
  const Census before = census(ed, field, o.threshold);
  st.min_before = before.min;
  st.mean_before = before.mean;
  st.below_before = before.below;
  std::vector<std::pair<double, TetId>> bad;
  std::vector<TetId> ball;
  std::vector<VertId> ring;
  std::vector<int> tried;  // the last pass that tried to relocate each vertex
  // A tet that nothing improved is worked on again only after an edit
  // touched one of its vertices: until then every operator would refuse it
  // for the same reasons (swaps see the same shells, relocations the same
  // balls). A tet remembers when it was last given up on.
  EditClock clock(m.num_verts());
  std::vector<std::uint64_t> given_up;
  ed.set_hook([&](const mesh::TetMesh& mm, std::span<const TetId> created) { clock.tick(mm, created); });
  ReconnectMemo memo(clock);
  auto unchanged_since_given_up = [&](TetId t) {
    return t < given_up.size() && clock.tet_unchanged_since(given_up[t], m.tet2verts[t]);
  };
  // Lengths settle in a few passes (each split halves an edge); shapes may
  // need more, so passes go on while anything changes, up to twice the
  // budget of size passes.
  for (st.passes = 0; st.passes < 2 * o.passes; ++st.passes) {
    std::size_t changes = 0;
    if (st.passes < o.passes) {
      if (o.split) {
        Timer op;
        const std::size_t n = split_long_edges(ed, cav, boundary, field, o, ball);
        st.splits += n;
        changes += n;
        st.split_seconds += op.seconds();
      }
      if (o.collapse) {
        Timer op;
        const std::size_t n = collapse_short_edges(ed, cav, boundary, field, o, ball, ring);
        st.collapses += n;
        changes += n;
        st.collapse_seconds += op.seconds();
      }
    }
    bad.clear();
    for (TetId t = 0; t < m.tet2verts.size(); ++t) {
      if (ed.is_dead(t)) continue;
      const double q = field.tet_quality(m, m.tet2verts[t]);
      if (q < o.threshold) bad.emplace_back(q, t);
    }
    std::sort(bad.begin(), bad.end());
    for (const auto& [q0, t] : bad) {
      if (ed.is_dead(t) || unchanged_since_given_up(t) || field.tet_quality(m, m.tet2verts[t]) >= o.threshold)
        continue;
      if (o.deletion && delete_in_metric(ed, cav, boundary, o, field, t)) {
        ++st.deletions;
        ++changes;
        continue;
      }
      if (o.swaps) {
        Timer op;
        const bool done = reconnect(ed, cav, field, t, memo, st);
        st.swap_seconds += op.seconds();
        if (done) {
          ++changes;
          continue;
        }
      }
      if (o.relocation) {
        Timer op;
        const auto tv = m.tet2verts[t];
        bool moved = false;
        for (VertId v : tv) {
          // Each vertex once a pass, as a smoothing sweep: a vertex in many
          // poor tets would otherwise be searched again for each of them.
          if (tried.size() < m.num_verts()) tried.resize(m.num_verts(), -1);
          if (tried[v] == st.passes) continue;
          tried[v] = st.passes;
          if (!relocate(ed, cav, boundary, o.flat_boundary && !o.model, field, v, ball, ring) &&
              !relocate_on_model(ed, cav, boundary, o.model, field, v, ball))
            continue;
          refresh(field, o, m, v);
          ++st.relocations;
          moved = true;
          if (ed.is_dead(t)) break;  // rebuilt: its other vertices are in new tets
        }
        st.relocation_seconds += op.seconds();
        if (moved) {
          ++changes;
          continue;
        }
      }
      // The point insertion ranks by the isotropic mean ratio, which is the
      // metric quality only for an isotropic field.
      if (o.insertion && !field.anisotropic()) {
        Timer op;
        const auto tv = m.tet2verts[t];
        int best = -1;
        double best_after = 0;
        for (int e = 0; e < 6; ++e) {
          const auto p = plan_shell_insertion(ed, cav, tv[mesh::kTetEdges[e][0]], tv[mesh::kTetEdges[e][1]], t);
          if (p.refusal == modify::Refusal::kNone && p.after > best_after) {
            best = e;
            best_after = p.after;
          }
        }
        if (best >= 0) {
          const VertId a = tv[mesh::kTetEdges[best][0]], b = tv[mesh::kTetEdges[best][1]];
          const VertId p = apply(ed, cav, plan_shell_insertion(ed, cav, a, b, t));
          field.set_interpolated(p, a, b, 0.5);
          refresh(field, o, m, p);
          ++st.insertions;
          ++changes;
        }
        st.insertion_seconds += op.seconds();
        if (best >= 0) continue;
      }
      if (given_up.size() < m.tet2verts.size()) given_up.resize(m.tet2verts.size(), 0);
      given_up[t] = clock.now;
    }
    if (changes == 0) break;
  }
  ed.set_hook(nullptr);
  ed.compact();
  drop_unused_vertices(m, field);
  const Census after = census(ed, field, o.threshold);
  st.min_after = after.min;
  st.mean_after = after.mean;
  st.below_after = after.below;
  st.lengths_after = measure_lengths(m, field);
  st.seconds = timer.seconds();
  return st;
}

MeshSummary summarize_mesh(const mesh::TetMesh& m, const MetricField* field) {
  struct Acc {
    double min_q = 1, sum_q = 0, min_d = 180, max_d = 0, min_mq = 1, sum_mq = 0, volume = 0;
    std::size_t inverted = 0;
  };
  const bool use_metric = field && field->size() == m.num_verts();
  const Acc acc = tbb::parallel_reduce(
      tbb::blocked_range<std::size_t>(0, m.num_tets()), Acc{},
      [&](const tbb::blocked_range<std::size_t>& r, Acc a) {
        for (std::size_t t = r.begin(); t != r.end(); ++t) {
          const auto& v = m.tet2verts[t];
          const Vec3 &p0 = m.coords[v[0]], &p1 = m.coords[v[1]], &p2 = m.coords[v[2]], &p3 = m.coords[v[3]];
          const double q = quality::tet_mean_ratio(p0, p1, p2, p3);
          const auto d = quality::tet_dihedral_range(p0, p1, p2, p3);
          a.min_q = std::min(a.min_q, q);
          a.sum_q += q;
          a.min_d = std::min(a.min_d, d.min);
          a.max_d = std::max(a.max_d, d.max);
          a.volume += quality::tet_signed_volume(p0, p1, p2, p3);
          a.inverted += predicates::orient3d(p0.data(), p1.data(), p2.data(), p3.data()) <= 0;
          const double mq = use_metric ? field->tet_quality(m, v) : q;
          a.min_mq = std::min(a.min_mq, mq);
          a.sum_mq += mq;
        }
        return a;
      },
      [](Acc a, const Acc& b) {
        a.min_q = std::min(a.min_q, b.min_q);
        a.sum_q += b.sum_q;
        a.min_d = std::min(a.min_d, b.min_d);
        a.max_d = std::max(a.max_d, b.max_d);
        a.min_mq = std::min(a.min_mq, b.min_mq);
        a.sum_mq += b.sum_mq;
        a.volume += b.volume;
        a.inverted += b.inverted;
        return a;
      });
  MeshSummary s;
  s.verts = m.num_verts();
  s.tets = m.num_tets();
  const double n = s.tets ? static_cast<double>(s.tets) : 1.0;
  s.min_mean_ratio = acc.min_q;
  s.mean_mean_ratio = acc.sum_q / n;
  s.min_dihedral = acc.min_d;
  s.max_dihedral = acc.max_d;
  s.min_metric_quality = acc.min_mq;
  s.mean_metric_quality = acc.sum_mq / n;
  s.volume = acc.volume;
  s.inverted = acc.inverted;
  return s;
}

}  // namespace cm::optimize
