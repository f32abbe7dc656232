// classify_on_model, first half: the model's tolerances and face index, and
// the assignment of boundary triangles to model faces.
#include <algorithm>
#include <cmath>
#include <limits>
#include <unordered_map>

#include <tbb/parallel_for.h>

#include "curvemesh/generate/classify_support.hpp"

namespace cm::generate::classify {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
// Vertices of a group tried on each candidate face before all of them are.
constexpr std::size_t kGroupSamples = 7;
// Triangles per projection task: Newton from a neighbour's (u, v) within a
// task, a global search at its first vertex.
constexpr std::size_t kChunk = 512;
// A triangle's centroid is off its face by at most the sagitta of its
// longest chord, half its length (a half circle).
constexpr double kChordSag = 0.5;

bool box_contains(const geom::BoundingBox& outer, const geom::BoundingBox& inner) {
  return (outer.min.array() <= inner.min.array()).all() && (inner.max.array() <= outer.max.array()).all();
}

geom::BoundingBox inflated(geom::BoundingBox b, double by) {
  b.min.array() -= by;
  b.max.array() += by;
  return b;
}

// Newton from a neighbour's parameters lands in the wrong basin now and
// then (across a thin feature of the face): a miss is asked again globally.
geom::Projection project(const geom::Model& g, geom::EntityRef e, const Vec3& x, std::optional<Vec2> hint,
                         double reach) {
  geom::Projection p = g.closest_point(e, x, hint);
  if (hint && p.distance > reach) {
    const geom::Projection q = g.closest_point(e, x);
    if (q.distance < p.distance) p = q;
  }
  return p;
}

}  // namespace

ModelIndex::ModelIndex(const geom::Model& g) : model(g) {
  const int nv = g.count(0), ne = g.count(1), nf = g.count(2);
  floor = 1e-9 * g.bounding_box().diagonal();
  vertex_tol.assign(nv + 1, 0);
  edge_tol.assign(ne + 1, 0);
  edge_reach.assign(ne + 1, 0);
  face_tol.assign(nf + 1, 0);
  face_reach.assign(nf + 1, 0);
  face_box.resize(nf + 1);
  face_edges.resize(nf + 1);
  face_lone_edges.resize(nf + 1);
  face_vertices.resize(nf + 1);
  face_regions.resize(nf + 1);
  edge_ends.assign(ne + 1, {0, 0});
  edge_range.resize(ne + 1);
  face_range.resize(nf + 1);
  for (int v = 1; v <= nv; ++v) {
    vertex_tol[v] = std::max(g.tolerance({0, v}), floor);
    max_vertex_tol_ = std::max(max_vertex_tol_, vertex_tol[v]);
    vertex_by_x_.emplace_back(g.vertex_point(v).x(), v);
  }
  std::sort(vertex_by_x_.begin(), vertex_by_x_.end());
  for (int e = 1; e <= ne; ++e) {
    edge_ends[e] = g.edge_vertices(e);
    edge_range[e] = g.param_range({1, e});
    edge_tol[e] = std::max(g.tolerance({1, e}), floor);
    edge_reach[e] = edge_tol[e];
    for (const int v : edge_ends[e])
      if (v > 0) edge_reach[e] = std::max(edge_reach[e], 2 * vertex_tol[v]);
  }
  for (int f = 1; f <= nf; ++f) {
    face_tol[f] = std::max(g.tolerance({2, f}), floor);
    face_range[f] = g.param_range({2, f});
    face_reach[f] = face_tol[f];
    for (const geom::Loop& loop : g.face_loops(f))
      for (const geom::OrientedUse& use : loop.edges) {
        for (const int v : edge_ends[use.tag])
          if (v > 0) face_vertices[f].push_back(v);
        if (g.is_degenerate(use.tag)) continue;
        face_edges[f].push_back(use.tag);
        face_reach[f] = std::max(face_reach[f], 2 * edge_tol[use.tag]);
      }
    for (auto* list : {&face_edges[f], &face_vertices[f]}) {
      std::sort(list->begin(), list->end());
      list->erase(std::unique(list->begin(), list->end()), list->end());
    }
    for (const int v : face_vertices[f]) face_reach[f] = std::max(face_reach[f], 2 * vertex_tol[v]);
    for (const int e : face_edges[f]) {
      const std::vector<int> up = g.upward({1, e});
      if (std::all_of(up.begin(), up.end(), [&](int u) { return u == f; })) face_lone_edges[f].push_back(e);
    }
    face_regions[f] = g.upward({2, f});
    const geom::BoundingBox b = g.bounding_box({2, f});
    // Boxes of faces are tight but not certified (interior extremes found by
    // ascent): a margin of a percent keeps a face among its candidates.
    face_box[f] = inflated(b, 0.01 * b.diagonal() + 2 * face_reach[f] + floor);
  }

  // A uniform grid of cells over the faces' boxes, each listing the faces
  // whose box meets it.
  for (int f = 1; f <= nf; ++f) {
    grid_box_.add(face_box[f].min);
    grid_box_.add(face_box[f].max);
  }
  if (nf == 0) return;
  const int n = std::clamp(static_cast<int>(std::cbrt(8.0 * nf)), 1, 32);
  grid_n_ = {n, n, n};
  cell_ = (grid_box_.size() / n).cwiseMax(1e-300);
  const auto cell_range = [&](const geom::BoundingBox& b, std::array<int, 3>& lo, std::array<int, 3>& hi) {
    for (int k = 0; k < 3; ++k) {
      lo[k] = std::clamp(static_cast<int>(std::floor((b.min[k] - grid_box_.min[k]) / cell_[k])), 0, n - 1);
      hi[k] = std::clamp(static_cast<int>(std::floor((b.max[k] - grid_box_.min[k]) / cell_[k])), 0, n - 1);
    }
  };
  const std::size_t cells = static_cast<std::size_t>(n) * n * n;
  std::vector<std::size_t> count(cells + 1, 0);
  for (int pass = 0; pass < 2; ++pass) {
    if (pass == 1) {
      cell_start_.assign(cells + 1, 0);
      for (std::size_t c = 0; c < cells; ++c) cell_start_[c + 1] = cell_start_[c] + count[c];
      cell_faces_.resize(cell_start_[cells]);
      std::fill(count.begin(), count.end(), 0);
    }
    for (int f = 1; f <= nf; ++f) {
      std::array<int, 3> lo, hi;
      cell_range(face_box[f], lo, hi);
      for (int i = lo[0]; i <= hi[0]; ++i)
        for (int j = lo[1]; j <= hi[1]; ++j)
          for (int k = lo[2]; k <= hi[2]; ++k) {
            const std::size_t c = (static_cast<std::size_t>(i) * n + j) * n + k;
            if (pass == 1) cell_faces_[cell_start_[c] + count[c]] = f;
            ++count[c];
          }
    }
  }
}

Vec2 ModelIndex::normalized(int dim, int tag, Vec2 param) const {
  const geom::ParamRange& r = dim == 1 ? edge_range[tag] : face_range[tag];
  const auto wrap = [](double t, double lo, double period) {
    t -= std::floor((t - lo) / period) * period;
    return t >= lo + period ? t - period : t;
  };
  if (r.periodic_u && r.period_u > 0) param.x() = wrap(param.x(), r.u0, r.period_u);
  if (dim == 2 && r.periodic_v && r.period_v > 0) param.y() = wrap(param.y(), r.v0, r.period_v);
  return param;
}

std::span<const int> ModelIndex::faces_near(const Vec3& x) const {
  if (cell_start_.empty()) return {};
  std::array<int, 3> ijk;
  for (int k = 0; k < 3; ++k)
    ijk[k] = std::clamp(static_cast<int>(std::floor((x[k] - grid_box_.min[k]) / cell_[k])), 0, grid_n_[k] - 1);
  const std::size_t c = (static_cast<std::size_t>(ijk[0]) * grid_n_[1] + ijk[1]) * grid_n_[2] + ijk[2];
  return {cell_faces_.data() + cell_start_[c], cell_start_[c + 1] - cell_start_[c]};
}

int ModelIndex::vertex_at(const Vec3& x) const {
  auto it = std::lower_bound(vertex_by_x_.begin(), vertex_by_x_.end(), std::make_pair(x.x() - max_vertex_tol_, 0));
  int best = 0;
  double best_d = kInf;
  for (; it != vertex_by_x_.end() && it->first <= x.x() + max_vertex_tol_; ++it) {
    const double d = (model.vertex_point(it->second) - x).norm();
    if (d <= vertex_tol[it->second] && d < best_d) {
      best = it->second;
      best_d = d;
    }
  }
  return best;
}

ProjectionTable::ProjectionTable(std::vector<Projected> all) : items_(std::move(all)) {
  // Of two answers for one pair (a triangle that fit no group and was
  // searched again), the nearer: a Newton run that missed loses.
  std::stable_sort(items_.begin(), items_.end(), [](const Projected& a, const Projected& b) {
    return a < b || (!(b < a) && a.distance < b.distance);
  });
  items_.erase(std::unique(items_.begin(), items_.end(),
                           [](const Projected& a, const Projected& b) { return a.vert == b.vert && a.entity == b.entity; }),
               items_.end());
}

const Projected* ProjectionTable::find(VertId v, int entity) const {
  const Projected key{v, entity, Vec2::Zero(), 0};
  const auto it = std::lower_bound(items_.begin(), items_.end(), key);
  return it != items_.end() && it->vert == v && it->entity == entity ? &*it : nullptr;
}

Vec3 triangle_probe(const mesh::TetMesh& m, const std::array<VertId, 3>& v) {
  const Vec3& a = m.coords[v[0]];
  const Vec3& b = m.coords[v[1]];
  const Vec3& c = m.coords[v[2]];
  if (m.high_order.order() == 2) {
    Vec3 mid[3];
    bool all = true;
    for (int k = 0; k < 3 && all; ++k) all = m.high_order.get_edge(v[k], v[(k + 1) % 3], &mid[k]);
    // The quadratic triangle at barycentric (1/3, 1/3, 1/3): corner shape
    // functions -1/9, edge ones 4/9.
    if (all) return (4 * (mid[0] + mid[1] + mid[2]) - (a + b + c)) / 9;
  }
  return (a + b + c) / 3;
}

namespace {

struct Group {
  std::vector<std::size_t> tris;
  std::vector<VertId> verts;
  geom::BoundingBox box;
  int face = 0;
};

// The face all of the group's sampled vertices lie on; of several (a group
// along the edge where two faces meet), the one nearest its triangles.
int choose_group_face(const ModelIndex& ix, const mesh::TetMesh& m, const std::vector<BoundaryTri>& tris,
                      const Group& grp) {
  std::vector<int> cands;
  for (const int f : ix.faces_near(m.coords[grp.verts.front()]))
    if (box_contains(ix.face_box[f], grp.box)) cands.push_back(f);
  const auto spread = [](std::size_t n, std::size_t k, std::size_t count) {
    return count <= 1 ? 0 : k * (n - 1) / (count - 1);
  };
  const std::size_t nv = std::min(kGroupSamples, grp.verts.size());
  const std::size_t nt = std::min(kGroupSamples, grp.tris.size());
  int best = 0;
  double best_score = kInf;
  for (const int f : cands) {
    bool fits = true;
    for (std::size_t k = 0; k < nv && fits; ++k) {
      const Vec3& x = m.coords[grp.verts[spread(grp.verts.size(), k, nv)]];
      fits = ix.model.closest_point({2, f}, x).distance <= ix.face_reach[f];
    }
    if (!fits) continue;
    if (cands.size() == 1) return f;
    double score = 0;
    for (std::size_t k = 0; k < nt; ++k)
      score += ix.model.closest_point({2, f}, triangle_probe(m, tris[grp.tris[spread(grp.tris.size(), k, nt)]].verts))
                   .distance;
    if (score < best_score) {
      best_score = score;
      best = f;
    }
  }
  return best;
}

struct Task {
  std::size_t group, begin, end;
};

struct TaskResult {
  std::vector<Projected> projections;
  std::vector<std::size_t> misfits;  // triangle indices
};

// Projects the vertices of a run of the group's triangles on its face,
// each from the parameters of a vertex of its triangle already projected.
// Vertices on the group's border are left out: they are on model edges when
// the group is one face, and the closest point of a point on a face's
// boundary is its slowest (the trimming test near the loops). A triangle
// with all three there is judged by its probe point, within a chord's
// sagitta.
TaskResult project_task(const ModelIndex& ix, const mesh::TetMesh& m, const std::vector<BoundaryTri>& tris,
                        const std::vector<char>& on_border, const Group& grp, const Task& task) {
  TaskResult out;
  const int f = grp.face;
  const double reach = ix.face_reach[f];
  std::unordered_map<VertId, std::size_t> done;
  for (std::size_t k = task.begin; k < task.end; ++k) {
    const std::size_t i = grp.tris[k];
    const auto& tv = tris[i].verts;
    if (on_border[tv[0]] && on_border[tv[1]] && on_border[tv[2]]) {
      double longest = 0;
      for (int c = 0; c < 3; ++c) longest = std::max(longest, (m.coords[tv[c]] - m.coords[tv[(c + 1) % 3]]).norm());
      if (ix.model.closest_point({2, f}, triangle_probe(m, tv)).distance > reach + kChordSag * longest)
        out.misfits.push_back(i);
      continue;
    }
    bool misfit = false;
    for (int c = 0; c < 3; ++c) {
      const VertId v = tv[c];
      if (on_border[v]) continue;
      auto it = done.find(v);
      if (it == done.end()) {
        std::optional<Vec2> hint;
        for (int d = 0; d < 3 && !hint; ++d)
          if (auto h = done.find(tris[i].verts[d]); h != done.end()) hint = out.projections[h->second].param;
        const geom::Projection p = project(ix.model, {2, f}, m.coords[v], hint, reach);
        it = done.emplace(v, out.projections.size()).first;
        out.projections.push_back({v, f, p.param, p.distance});
      }
      misfit = misfit || out.projections[it->second].distance > reach;
    }
    if (misfit) out.misfits.push_back(i);
  }
  return out;
}

struct Search {
  int face = 0;
  std::array<Projected, 3> projections;
  Misfit misfit{kNone};  ///< tri stays kNone unless searched
};

// One triangle against every face whose box holds it: the face all three
// vertices lie on, nearest its probe point.
Search search_triangle(const ModelIndex& ix, const mesh::TetMesh& m, const BoundaryTri& t, std::size_t index) {
  Search s;
  s.misfit.tri = index;
  s.misfit.distance = kInf;
  geom::BoundingBox box;
  for (const VertId v : t.verts) box.add(m.coords[v]);
  const Vec3 probe = triangle_probe(m, t.verts);
  double best_score = kInf, nearest_ratio = kInf;
  for (const int f : ix.faces_near(probe)) {
    if (!box_contains(ix.face_box[f], box)) continue;
    const double reach = ix.face_reach[f];
    std::array<Projected, 3> pr;
    double worst = 0;
    VertId worst_vertex = t.verts[0];
    std::optional<Vec2> hint;
    for (int c = 0; c < 3 && worst <= reach; ++c) {
      const geom::Projection p = project(ix.model, {2, f}, m.coords[t.verts[c]], hint, reach);
      pr[c] = {t.verts[c], f, p.param, p.distance};
      hint = p.param;
      if (p.distance > worst) {
        worst = p.distance;
        worst_vertex = t.verts[c];
      }
    }
    if (worst > reach) {
      if (worst / reach < nearest_ratio) {
        nearest_ratio = worst / reach;
        s.misfit = {index, f, worst_vertex, worst};
      }
      continue;
    }
    const double score = ix.model.closest_point({2, f}, probe, pr[0].param).distance;
    if (score < best_score) {
      best_score = score;
      s.face = f;
      s.projections = pr;
    }
  }
  return s;
}

}  // namespace

FaceAssignment assign_faces(const ModelIndex& ix, const mesh::TetMesh& m, std::vector<BoundaryTri>& tris,
                            std::size_t num_groups) {
  FaceAssignment out;
  std::vector<Group> groups(num_groups);
  std::vector<std::size_t> searched;
  for (std::size_t i = 0; i < tris.size(); ++i) {
    if (tris[i].group < 0) {
      searched.push_back(i);
      continue;
    }
    Group& grp = groups[static_cast<std::size_t>(tris[i].group)];
    grp.tris.push_back(i);
    for (const VertId v : tris[i].verts) {
      grp.verts.push_back(v);
      grp.box.add(m.coords[v]);
    }
  }
  tbb::parallel_for(std::size_t{0}, num_groups, [&](std::size_t k) {
    Group& grp = groups[k];
    std::sort(grp.verts.begin(), grp.verts.end());
    grp.verts.erase(std::unique(grp.verts.begin(), grp.verts.end()), grp.verts.end());
    if (!grp.verts.empty()) grp.face = choose_group_face(ix, m, tris, grp);
  });

  std::vector<Task> tasks;
  for (std::size_t k = 0; k < num_groups; ++k) {
    if (groups[k].face == 0) {
      searched.insert(searched.end(), groups[k].tris.begin(), groups[k].tris.end());
      continue;
    }
    for (std::size_t b = 0; b < groups[k].tris.size(); b += kChunk)
      tasks.push_back({k, b, std::min(groups[k].tris.size(), b + kChunk)});
  }
  std::vector<TaskResult> results(tasks.size());
  // Border: vertices with triangles in two groups (or untagged ones).
  std::vector<char> on_border(m.num_verts(), 0);
  {
    std::vector<std::pair<VertId, int>> vg;
    vg.reserve(3 * tris.size());
    for (const BoundaryTri& t : tris)
      for (const VertId v : t.verts) vg.emplace_back(v, t.group);
    std::sort(vg.begin(), vg.end());
    vg.erase(std::unique(vg.begin(), vg.end()), vg.end());
    for (std::size_t i = 0; i + 1 < vg.size(); ++i)
      if (vg[i].first == vg[i + 1].first) on_border[vg[i].first] = on_border[vg[i + 1].first] = 1;
    for (const auto& [v, group] : vg)
      if (group < 0) on_border[v] = 1;
  }
  tbb::parallel_for(std::size_t{0}, tasks.size(), [&](std::size_t k) {
    results[k] = project_task(ix, m, tris, on_border, groups[tasks[k].group], tasks[k]);
  });
  std::vector<char> group_split(num_groups, 0);
  for (std::size_t k = 0; k < tasks.size(); ++k) {
    const Group& grp = groups[tasks[k].group];
    for (std::size_t j = tasks[k].begin; j < tasks[k].end; ++j) tris[grp.tris[j]].face = grp.face;
    for (const std::size_t i : results[k].misfits) {
      tris[i].face = 0;
      searched.push_back(i);
      group_split[tasks[k].group] = 1;
    }
    out.face_projections.insert(out.face_projections.end(), results[k].projections.begin(),
                                results[k].projections.end());
  }
  for (std::size_t k = 0; k < num_groups; ++k) {
    out.groups += !groups[k].tris.empty();
    out.groups_whole += groups[k].face != 0 && !group_split[k];
  }

  std::sort(searched.begin(), searched.end());
  out.searched = searched.size();
  // In blocks, so that where the search stops does not depend on the
  // threads' timing.
  std::vector<Search> found(searched.size());
  constexpr std::size_t kBlock = 1024;
  std::size_t misfits = 0;
  for (std::size_t b = 0; b < searched.size() && misfits < kMisfitsEnough; b += kBlock) {
    const std::size_t e = std::min(searched.size(), b + kBlock);
    tbb::parallel_for(b, e, [&](std::size_t k) { found[k] = search_triangle(ix, m, tris[searched[k]], searched[k]); });
    for (std::size_t k = b; k < e; ++k) misfits += found[k].face == 0;
  }
  for (std::size_t k = 0; k < searched.size(); ++k) {
    const std::size_t i = searched[k];
    tris[i].face = found[k].face;
    if (found[k].face == 0) {
      if (found[k].misfit.tri == i) out.misfits.push_back(found[k].misfit);
      else ++out.unsearched;
      continue;
    }
    out.face_projections.insert(out.face_projections.end(), found[k].projections.begin(), found[k].projections.end());
  }
  return out;
}

}  // namespace cm::generate::classify
