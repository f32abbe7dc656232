// classify_on_model, second half: regions, the boundary and its orientation,
// mesh edges on model edges, vertices, entities, and the write-back.
#include "curvemesh/generate/classify_on_model.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <optional>
#include <set>
#include <span>
#include <unordered_map>

#include <fmt/format.h>
#include <tbb/parallel_for.h>

#include "curvemesh/core/error.hpp"
#include "curvemesh/core/timer.hpp"
#include "curvemesh/generate/classify_support.hpp"
#include "curvemesh/mesh/topology.hpp"

namespace cm::generate {

using classify::BoundaryTri;
using classify::ModelIndex;
using classify::Projected;
using classify::ProjectionTable;

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
// Tets per input region whose centroids vote for a model region.
constexpr std::size_t kRegionSamples = 7;
// A mesh edge on a model edge is a chord of it: its midpoint is off the
// curve by the sagitta, at most half its length (a half circle).
constexpr double kChordSag = 0.5;

using TriKey = std::array<VertId, 3>;
struct TriKeyHash {
  std::size_t operator()(const TriKey& k) const {
    std::uint64_t h = k[0] * 0x9E3779B97F4A7C15ull;
    h ^= (k[1] + 0x632BE59BD9B4E019ull) * 0xC2B2AE3D27D4EB4Full;
    h ^= (k[2] + 0x85EBCA77C2B2AE63ull) * 0x165667B19E3779F9ull;
    return static_cast<std::size_t>(h ^ (h >> 29));
  }
};
TriKey sorted_key(std::array<VertId, 3> v) {
  std::sort(v.begin(), v.end());
  return v;
}
std::uint64_t edge_key(VertId a, VertId b) { return (std::uint64_t(std::min(a, b)) << 32) | std::max(a, b); }

std::string point_text(const Vec3& x) { return fmt::format("({:.6g}, {:.6g}, {:.6g})", x.x(), x.y(), x.z()); }

std::string join(const std::vector<int>& tags) {
  std::string s;
  for (const int t : tags) s += (s.empty() ? "" : ", ") + std::to_string(t);
  return s;
}

class Problems {
 public:
  Problems(std::vector<std::string>& out, std::size_t& count, std::size_t max) : out_(out), count_(count), max_(max) {}
  void add(std::string s) {
    ++count_;
    if (out_.size() < max_) out_.push_back(std::move(s));
  }

 private:
  std::vector<std::string>& out_;
  std::size_t& count_;
  std::size_t max_;
};

// When nothing fits, the likeliest cause: a mesh in other length units.
std::string size_hint(const geom::Model& g, const mesh::TetMesh& m) {
  geom::BoundingBox mb;
  for (const Vec3& x : m.coords) mb.add(x);
  const geom::BoundingBox gb = g.bounding_box();
  const double ratio = mb.diagonal() / gb.diagonal();
  const std::string units = g.units().empty() ? "" : fmt::format(" (model units: {})", g.units());
  // Ratios between the common length units: mm, cm, m, inch, ft.
  static constexpr double kUnitRatios[] = {10, 100, 1000, 25.4, 2.54, 0.0254, 304.8, 30.48, 0.3048, 12};
  for (const double f : kUnitRatios)
    for (const double r : {f, 1 / f})
      if (std::abs(ratio / r - 1) < 0.03)
        return fmt::format("; the mesh is {:.4g} times the size of the model{}: made in other length units? (Gmsh "
                           "reads STEP in millimetres unless given -setstring Geometry.OCCTargetUnit)",
                           ratio, units);
  if ((mb.min - gb.min).norm() > 0.05 * gb.diagonal() || (mb.max - gb.max).norm() > 0.05 * gb.diagonal())
    return fmt::format("; the mesh's bounding box {} - {} is not the model's {} - {}", point_text(mb.min),
                       point_text(mb.max), point_text(gb.min), point_text(gb.max));
  return "";
}

// --- regions ---------------------------------------------------------------

// Each input region tag goes to the model region most of a few of its tets
// lie in, those away from the input's boundary first (their centroids are
// inside the model even where the boundary's chords cut a concave surface).
std::vector<TagMapping> map_regions(const geom::Model& g, const mesh::TetMesh& m, const ClassifyOptions& o) {
  std::vector<char> on_boundary(m.num_verts(), 0);
  for (const auto& t : m.tris)
    for (const VertId v : t.verts) on_boundary[v] = 1;
  std::map<int, std::pair<std::vector<TetId>, std::vector<TetId>>> tets;  // tag -> (deep, all)
  for (TetId t = 0; t < m.num_tets(); ++t) {
    auto& lists = tets[m.tet_region[t]];
    lists.second.push_back(t);
    const auto& v = m.tet2verts[t];
    if (!on_boundary[v[0]] && !on_boundary[v[1]] && !on_boundary[v[2]] && !on_boundary[v[3]]) lists.first.push_back(t);
  }
  std::vector<TagMapping> out;
  for (const auto& [tag, lists] : tets) {
    const std::vector<TetId>& pool = lists.first.empty() ? lists.second : lists.first;
    std::map<int, int> votes;
    const std::size_t n = std::min(kRegionSamples, pool.size());
    Vec3 example = Vec3::Zero();
    for (std::size_t k = 0; k < n; ++k) {
      const TetId t = pool[n <= 1 ? 0 : k * (pool.size() - 1) / (n - 1)];
      const auto& v = m.tet2verts[t];
      const Vec3 c = (m.coords[v[0]] + m.coords[v[1]] + m.coords[v[2]] + m.coords[v[3]]) / 4;
      if (k == 0) example = c;
      for (int r = 1; r <= g.count(3); ++r) {
        const geom::BoundingBox b = g.bounding_box({3, r});
        if ((c.array() < b.min.array() - g.tolerance({3, r})).any() ||
            (c.array() > b.max.array() + g.tolerance({3, r})).any())
          continue;
        const geom::Containment where = g.classify_point(r, c);
        votes[r] += where == geom::Containment::kInside ? 2 : where == geom::Containment::kOn ? 1 : 0;
      }
    }
    int best = 0, best_votes = 0;
    for (const auto& [r, count] : votes)
      if (count > best_votes) {
        best = r;
        best_votes = count;
      }
    if (best == 0)
      throw InputError(o.mesh_name, -1, -1,
                       fmt::format("the mesh is not of this model: the tets of its region {} (one centred at {}) "
                                   "are in no region of the model{}",
                                   tag,
                                   point_text(example), size_hint(g, m)));
    out.push_back({tag, best, lists.second.size(), 0});
  }
  return out;
}

// --- boundary --------------------------------------------------------------

// Hull faces and faces between tets of different (model) regions, each
// listed with its normal out of its first tet.
std::vector<BoundaryTri> extract_boundary(const mesh::TetMesh& m, const std::vector<std::int32_t>& region) {
  std::vector<BoundaryTri> out;
  for (TetId t = 0; t < m.num_tets(); ++t)
    for (int f = 0; f < 4; ++f) {
      const Index adj = m.tet2adj[mesh::pack_face(t, f)];
      TetId other = kNone;
      if (adj != kNone) {
        other = mesh::face_tet(adj);
        if (region[other] == region[t] || other < t) continue;
      }
      const auto& tv = m.tet2verts[t];
      const auto& fv = mesh::kFaceVerts[f];
      out.push_back({{tv[fv[0]], tv[fv[1]], tv[fv[2]]}, t, other, -1, 0});
    }
  return out;
}

// Follows face_normal: out of the face's first region (check_boundary's
// convention), also for a triangle whose tet is in the face's other region
// with nothing across (a face two regions share, each meshed on its own).
// Reports faces whose triangles lie between regions the face does not
// bound, and shared faces where the mesh does not conform.
void orient(const ModelIndex& ix, const std::vector<std::int32_t>& region, std::vector<BoundaryTri>& tris,
            Problems& problems) {
  std::map<int, std::set<std::pair<int, int>>> wrong;      // face -> (region inside, outside)
  std::map<int, std::map<int, std::size_t>> one_sided;      // shared face -> region -> hull triangles
  for (BoundaryTri& t : tris) {
    const std::vector<int>& up = ix.face_regions[t.face];
    const int in = region[t.inside], out = t.outside == kNone ? 0 : region[t.outside];
    const auto has = [&](int r) { return std::find(up.begin(), up.end(), r) != up.end(); };
    const int first = up.empty() ? 0 : up.front();
    if (in != first && (out == first || (out == 0 && has(in)))) std::swap(t.verts[1], t.verts[2]);
    if (out == 0 && up.size() > 1) ++one_sided[t.face][in];
    if (!has(in) || (out != 0 && !has(out))) wrong[t.face].insert({in, out});
  }
  for (const auto& [face, pairs] : wrong) {
    std::string sides;
    for (const auto& [a, b] : pairs)
      sides += fmt::format("{}({} | {})", sides.empty() ? "" : ", ", a, b ? std::to_string(b) : "outside");
    problems.add(fmt::format("model face {} bounds regions {} but some of its triangles lie between regions {}", face,
                             join(ix.face_regions[face]), sides));
  }
  for (const auto& [face, by_region] : one_sided) {
    std::string counts;
    for (const auto& [r, n] : by_region) counts += fmt::format("{}{} of region {}", counts.empty() ? "" : ", ", n, r);
    problems.add(fmt::format("model face {} is shared by regions {}, but the mesh does not conform there: {} "
                             "triangles are on its hull ({}), the regions meshed each on its own",
                             face, join(ix.face_regions[face]),
                             [&] {
                               std::size_t n = 0;
                               for (const auto& [r, k] : by_region) n += k;
                               return n;
                             }(),
                             counts));
  }
}

// --- mesh edges ------------------------------------------------------------

struct MeshEdge {
  VertId a, b;
  int tag;
};

// The mesh edges on model edges: where triangles of different faces meet
// (the edges those faces share are the candidates) or, inside one face, on
// an edge bounding that face only (a seam). A candidate fits if both ends
// lie on it and the midpoint (or the high-order nodes) within a chord's
// sagitta; of several, the nearest to the midpoint.
struct MeshEdges {
  std::vector<MeshEdge> edges;
  ProjectionTable projections;  ///< ends of candidate mesh edges on the candidate model edges
};

MeshEdges find_mesh_edges(const ModelIndex& ix, const mesh::TetMesh& m, const std::vector<BoundaryTri>& tris,
                          Problems& problems) {
  const geom::Model& g = ix.model;
  std::vector<std::pair<std::uint64_t, int>> uses;  // edge key, face
  uses.reserve(3 * tris.size());
  for (const BoundaryTri& t : tris)
    for (const auto& e : mesh::kTriEdges) uses.emplace_back(edge_key(t.verts[e[0]], t.verts[e[1]]), t.face);
  std::sort(uses.begin(), uses.end());
  struct Candidate {
    std::uint64_t key;
    std::vector<int> faces, edges;
  };
  std::vector<Candidate> cands;
  std::map<std::vector<int>, std::size_t> no_shared_edge;
  for (std::size_t i = 0; i < uses.size();) {
    std::size_t j = i;
    std::vector<int> faces;
    while (j < uses.size() && uses[j].first == uses[i].first) faces.push_back(uses[j++].second);
    faces.erase(std::unique(faces.begin(), faces.end()), faces.end());
    std::vector<int> edges;
    if (faces.size() == 1) {
      edges = ix.face_lone_edges[faces[0]];
    } else {
      edges = ix.face_edges[faces[0]];
      for (std::size_t k = 1; k < faces.size(); ++k) {
        std::vector<int> both;
        std::set_intersection(edges.begin(), edges.end(), ix.face_edges[faces[k]].begin(),
                              ix.face_edges[faces[k]].end(), std::back_inserter(both));
        edges.swap(both);
      }
      if (edges.empty()) ++no_shared_edge[faces];
    }
    if (!edges.empty()) cands.push_back({uses[i].first, std::move(faces), std::move(edges)});
    i = j;
  }
  for (const auto& [faces, count] : no_shared_edge)
    problems.add(fmt::format("{} mesh edges lie where model faces {} meet, which share no model edge", count, join(faces)));

  std::vector<Projected> requests;
  for (const Candidate& c : cands)
    for (const int e : c.edges) {
      requests.push_back({static_cast<VertId>(c.key >> 32), e, Vec2::Zero(), 0});
      requests.push_back({static_cast<VertId>(c.key & 0xffffffffu), e, Vec2::Zero(), 0});
    }
  std::sort(requests.begin(), requests.end());
  requests.erase(std::unique(requests.begin(), requests.end(),
                             [](const Projected& p, const Projected& q) { return p.vert == q.vert && p.entity == q.entity; }),
                 requests.end());
  tbb::parallel_for(std::size_t{0}, requests.size(), [&](std::size_t k) {
    Projected& r = requests[k];
    const geom::Projection p = g.closest_point({1, r.entity}, m.coords[r.vert]);
    r.param = p.param;
    r.distance = p.distance;
  });
  ProjectionTable proj(std::move(requests));

  const std::size_t per_edge = m.high_order.nodes_per_edge();
  std::vector<int> chosen(cands.size(), 0);
  tbb::parallel_for(std::size_t{0}, cands.size(), [&](std::size_t k) {
    const Candidate& c = cands[k];
    const VertId a = static_cast<VertId>(c.key >> 32), b = static_cast<VertId>(c.key & 0xffffffffu);
    std::vector<Vec3> probes(per_edge);
    if (per_edge == 0 || !m.high_order.get_edge(a, b, probes.data())) probes.assign(1, 0.5 * (m.coords[a] + m.coords[b]));
    const double length = (m.coords[a] - m.coords[b]).norm();
    double best = kInf;
    for (const int e : c.edges) {
      const Projected* pa = proj.find(a, e);
      const Projected* pb = proj.find(b, e);
      const double ends = std::max(pa->distance, pb->distance);
      if (ends > ix.edge_reach[e]) continue;
      double off = 0;
      for (const Vec3& x : probes) off = std::max(off, g.closest_point({1, e}, x, pa->param).distance);
      if (off <= ix.edge_reach[e] + kChordSag * length && off < best) {
        best = off;
        chosen[k] = e;
      }
    }
  });
  std::vector<MeshEdge> out;
  std::map<std::vector<int>, std::pair<std::size_t, std::uint64_t>> unplaced;  // faces -> count, example
  for (std::size_t k = 0; k < cands.size(); ++k) {
    if (chosen[k] != 0) {
      out.push_back({static_cast<VertId>(cands[k].key >> 32), static_cast<VertId>(cands[k].key & 0xffffffffu), chosen[k]});
    } else if (cands[k].faces.size() > 1) {
      auto& u = unplaced[cands[k].faces];
      if (u.first++ == 0) u.second = cands[k].key;
    }
  }
  for (const auto& [faces, u] : unplaced) {
    const Vec3 mid = 0.5 * (m.coords[u.second >> 32] + m.coords[u.second & 0xffffffffu]);
    problems.add(fmt::format("{} mesh edges where model faces {} meet (one at {}) lie on none of the model edges they "
                             "share",
                             u.first, join(faces), point_text(mid)));
  }
  return {std::move(out), std::move(proj)};
}

// --- vertices --------------------------------------------------------------

struct VertexResult {
  mesh::ModelRef on;
  mesh::Param param;
  double distance = 0, tolerance = 1;
  enum class Issue { kNone, kEdgesWithoutVertex, kFacesWithoutEdge, kNoProjection } issue = Issue::kNone;
};

// Model tags per mesh vertex in one flat array (offsets per vertex), sorted;
// `distinct` drops repeats.
class TagsOfVertex {
 public:
  TagsOfVertex(std::size_t n, std::vector<std::pair<VertId, int>> pairs, bool distinct) : start_(n + 1, 0) {
    std::sort(pairs.begin(), pairs.end());
    if (distinct) pairs.erase(std::unique(pairs.begin(), pairs.end()), pairs.end());
    for (const auto& [v, tag] : pairs) ++start_[v + 1];
    for (std::size_t v = 0; v < n; ++v) start_[v + 1] += start_[v];
    tags_.reserve(pairs.size());
    for (const auto& [v, tag] : pairs) tags_.push_back(tag);
  }
  std::span<const int> of(VertId v) const { return {tags_.data() + start_[v], start_[v + 1] - start_[v]}; }

 private:
  std::vector<std::size_t> start_;
  std::vector<int> tags_;
};

// {0, V} at a model vertex in the closure of the vertex's faces and at an
// end of its edges (unless `allow_vertex` is off: V has a nearer mesh
// vertex); else {1, E} on the one model edge its mesh edges follow; else
// {2, F} on its one face. Anything else is reported and classified on the
// nearest candidate.
VertexResult classify_vertex(const ModelIndex& ix, const Vec3& x, VertId v, std::span<const int> faces,
                             std::span<const int> edges, const ProjectionTable& face_proj,
                             const ProjectionTable& edge_proj, bool allow_vertex) {
  VertexResult r;
  const int vertex = allow_vertex ? ix.vertex_at(x) : 0;
  const auto in_closure = [&](int f) {
    return std::binary_search(ix.face_vertices[f].begin(), ix.face_vertices[f].end(), vertex);
  };
  const auto ends_at = [&](int e) { return ix.edge_ends[e][0] == vertex || ix.edge_ends[e][1] == vertex; };
  if (vertex && std::all_of(faces.begin(), faces.end(), in_closure) && std::all_of(edges.begin(), edges.end(), ends_at)) {
    r.on = {0, vertex};
    r.distance = (ix.model.vertex_point(vertex) - x).norm();
    r.tolerance = ix.vertex_tol[vertex];
    return r;
  }
  const int dim = edges.empty() ? 2 : 1;
  const std::span<const int> tags = edges.empty() ? faces : edges;
  std::optional<Projected> best;
  for (const int t : tags) {
    const Projected* p = (dim == 1 ? edge_proj : face_proj).find(v, t);
    // Vertices on the border of an input face were not projected on it;
    // those that are inside a model face after all (where the input splits
    // one of the model's faces) are now.
    std::optional<Projected> here;
    if (p) {
      here = *p;
    } else if (dim == 2) {
      const geom::Projection q = ix.model.closest_point({2, t}, x);
      here = Projected{v, t, q.param, q.distance};
    }
    if (here && (!best || here->distance < best->distance)) best = here;
  }
  if (!best) {
    r.issue = VertexResult::Issue::kNoProjection;
    return r;
  }
  r.on = {dim, best->entity};
  const Vec2 param = ix.normalized(dim, best->entity, best->param);
  r.param.u = param.x();
  if (dim == 2) r.param.v = param.y();
  r.distance = best->distance;
  r.tolerance = (dim == 1 ? ix.edge_tol : ix.face_tol)[best->entity];
  if (tags.size() > 1) r.issue = dim == 1 ? VertexResult::Issue::kEdgesWithoutVertex : VertexResult::Issue::kFacesWithoutEdge;
  return r;
}

// --- entities --------------------------------------------------------------

// Physical groups and names of the input's entities, carried to the model
// entities their elements went to; merging different ones is reported.
void carry_groups(const std::map<mesh::ModelRef, std::set<int>>& sources, const std::vector<mesh::EntityInfo>& input,
                  std::vector<mesh::EntityInfo>& entities, Problems& problems) {
  std::map<mesh::ModelRef, const mesh::EntityInfo*> by_ref;
  for (const auto& e : input) by_ref[{e.dim, e.tag}] = &e;
  static const char* const kNames[] = {"vertex", "edge", "face", "region"};
  for (mesh::EntityInfo& e : entities) {
    const auto it = sources.find({e.dim, e.tag});
    if (it == sources.end()) continue;
    std::set<std::vector<std::int32_t>> groups;
    std::set<std::string> names;
    for (const int tag : it->second) {
      const auto src = by_ref.find({e.dim, tag});
      if (src == by_ref.end()) continue;
      std::vector<std::int32_t> p = src->second->physicals;
      std::sort(p.begin(), p.end());
      if (!p.empty()) groups.insert(p);
      if (!src->second->name.empty()) names.insert(src->second->name);
    }
    std::set<std::int32_t> all;
    for (const auto& p : groups) all.insert(p.begin(), p.end());
    e.physicals.assign(all.begin(), all.end());
    if (!names.empty()) e.name = *names.begin();
    if (groups.size() > 1 || names.size() > 1)
      problems.add(fmt::format("model {} {} takes the elements of input {}s {} with different physical groups or names",
                               kNames[e.dim], e.tag, kNames[e.dim], join(std::vector<int>(it->second.begin(), it->second.end()))));
  }
}

}  // namespace

std::vector<mesh::EntityInfo> model_entities(const geom::Model& model) {
  std::vector<mesh::EntityInfo> out;
  for (int v = 1; v <= model.count(0); ++v) out.push_back({0, v, {}, {}, {}});
  for (int e = 1; e <= model.count(1); ++e) {
    const auto v = model.edge_vertices(e);
    std::vector<std::int32_t> bounding;
    if (v[0] > 0) bounding.push_back(v[0]);
    if (v[1] > 0 && v[1] != v[0]) bounding.push_back(-v[1]);
    out.push_back({1, e, bounding, {}, {}});
  }
  for (int f = 1; f <= model.count(2); ++f) {
    std::vector<std::int32_t> bounding;
    for (const geom::Loop& loop : model.face_loops(f))
      for (const geom::OrientedUse& use : loop.edges)
        if (!model.is_degenerate(use.tag)) bounding.push_back(use.forward ? use.tag : -use.tag);
    out.push_back({2, f, bounding, {}, {}});
  }
  for (int r = 1; r <= model.count(3); ++r) {
    std::vector<std::int32_t> bounding;
    for (const geom::OrientedUse& use : model.region_faces(r)) bounding.push_back(use.forward ? use.tag : -use.tag);
    out.push_back({3, r, bounding, {}, {}});
  }
  return out;
}

ModelClassification classify_on_model(mesh::TetMesh& m, const geom::Model& model, const ClassifyOptions& o) {
  const Timer timer;
  if (m.num_tets() == 0) throw InputError(o.mesh_name, -1, -1, "the mesh has no tetrahedra to classify");
  CM_ASSERT_OP(m.tet2adj.size(), ==, 4 * m.num_tets());
  CM_ASSERT_OP(m.vert2tet.size(), ==, m.num_verts());
  m.resize_vertex_arrays();
  ModelClassification res;
  Problems problems(res.problems, res.num_problems, o.max_problems);
  const ModelIndex ix(model);

  res.region_map = map_regions(model, m, o);
  std::map<int, int> region_of;
  for (const TagMapping& r : res.region_map) region_of[r.input] = r.model;
  std::vector<std::int32_t> region(m.num_tets());
  for (TetId t = 0; t < m.num_tets(); ++t) {
    region[t] = region_of[m.tet_region[t]];
    res.tets_changed += region[t] != m.tet_region[t];
  }

  std::vector<BoundaryTri> tris = extract_boundary(m, region);
  res.boundary_triangles = tris.size();
  std::unordered_map<TriKey, Index, TriKeyHash> input_tri;
  input_tri.reserve(m.tris.size());
  for (Index i = 0; i < m.tris.size(); ++i) input_tri.try_emplace(sorted_key(m.tris[i].verts), i);
  std::map<int, int> group_of;
  for (const auto& t : m.tris) group_of.try_emplace(t.face_tag, 0);
  std::vector<int> group_tag;
  for (auto& [tag, index] : group_of) {
    index = static_cast<int>(group_tag.size());
    group_tag.push_back(tag);
  }
  std::vector<Index> source(tris.size(), kNone);  // index in the input's m.tris
  for (std::size_t i = 0; i < tris.size(); ++i)
    if (const auto it = input_tri.find(sorted_key(tris[i].verts)); it != input_tri.end()) {
      source[i] = it->second;
      tris[i].group = group_of[m.tris[it->second].face_tag];
    }

  classify::FaceAssignment fa = classify::assign_faces(ix, m, tris, group_tag.size());
  if (!fa.misfits.empty()) {
    const classify::Misfit& w = fa.misfits.front();
    const BoundaryTri& t = tris[w.tri];
    const std::string tag = t.group >= 0 ? fmt::format(" (input face {})", group_tag[t.group]) : "";
    const std::string where =
        w.nearest_face == 0
            ? "no model face comes near it"
            : fmt::format("its vertex at {} is {:.3g} from model face {}, the nearest that could hold it (within "
                          "{:.3g})",
                          point_text(m.coords[w.worst_vertex]), w.distance, w.nearest_face, ix.face_reach[w.nearest_face]);
    throw InputError(o.mesh_name, -1, -1,
                     fmt::format("the mesh is not of this model: its boundary triangle at {}{} lies on no model face: "
                                 "{}; {}{} such triangles{}",
                                 point_text(classify::triangle_probe(m, t.verts)), tag, where,
                                 fa.unsearched > 0 ? "at least " : "", fa.misfits.size(), size_hint(model, m)));
  }
  res.input_faces = fa.groups;
  res.input_faces_whole = fa.groups_whole;
  res.triangles_searched = fa.searched;
  const ProjectionTable face_proj(std::move(fa.face_projections));

  orient(ix, region, tris, problems);
  const MeshEdges found = find_mesh_edges(ix, m, tris, problems);
  const std::vector<MeshEdge>& mesh_edges = found.edges;
  const ProjectionTable& edge_proj = found.projections;

  // Vertices.
  const std::size_t nv = m.num_verts();
  std::vector<std::pair<VertId, int>> vf, ve;
  for (const BoundaryTri& t : tris)
    for (const VertId v : t.verts) vf.emplace_back(v, t.face);
  for (const MeshEdge& e : mesh_edges) {
    ve.emplace_back(e.a, e.tag);
    ve.emplace_back(e.b, e.tag);
  }
  const TagsOfVertex faces_of(nv, std::move(vf), true), edges_of(nv, std::move(ve), true);
  std::vector<VertexResult> vr(nv);
  tbb::parallel_for(std::size_t{0}, nv, [&](std::size_t v) {
    if (faces_of.of(static_cast<VertId>(v)).empty()) {
      const TetId t = m.vert2tet[v];
      vr[v].on = {3, t != kNone ? region[t] : 0};
      return;
    }
    vr[v] = classify_vertex(ix, m.coords[v], static_cast<VertId>(v), faces_of.of(static_cast<VertId>(v)),
                            edges_of.of(static_cast<VertId>(v)), face_proj, edge_proj, true);
  });
  // A model vertex takes the nearest mesh vertex; one farther off inside a
  // single model edge (shorter than the vertex's tolerance) or face goes on
  // it. Mesh vertices as near (each region's copy where the regions do not
  // conform) or where model edges meet stay on the model vertex.
  {
    std::map<int, VertId> nearest;
    for (VertId v = 0; v < nv; ++v) {
      if (vr[v].on.dim != 0) continue;
      const auto [it, fresh] = nearest.try_emplace(vr[v].on.tag, v);
      if (!fresh && vr[v].distance < vr[it->second].distance) it->second = v;
    }
    for (VertId v = 0; v < nv; ++v) {
      if (vr[v].on.dim != 0 || vr[v].distance <= vr[nearest[vr[v].on.tag]].distance) continue;
      if (edges_of.of(v).size() <= 1)
        vr[v] = classify_vertex(ix, m.coords[v], v, faces_of.of(v), edges_of.of(v), face_proj, edge_proj, false);
    }
  }
  std::map<std::vector<int>, std::pair<std::size_t, VertId>> junctions, touching;
  std::size_t off = 0;
  VertId off_example = kNone;
  for (VertId v = 0; v < nv; ++v) {
    const VertexResult& r = vr[v];
    using Issue = VertexResult::Issue;
    if (r.issue == Issue::kNoProjection)
      throw InternalError(fmt::format("classify_on_model: vertex {} has no projection on its entity", v));
    if (r.issue == Issue::kEdgesWithoutVertex || r.issue == Issue::kFacesWithoutEdge) {
      const auto list = r.issue == Issue::kEdgesWithoutVertex ? edges_of.of(v) : faces_of.of(v);
      auto& slot = (r.issue == Issue::kEdgesWithoutVertex ? junctions : touching)[{list.begin(), list.end()}];
      if (slot.first++ == 0) slot.second = v;
    }
    if (r.on.dim == 3) continue;
    res.max_distance = std::max(res.max_distance, r.distance);
    res.max_relative_distance = std::max(res.max_relative_distance, r.distance / r.tolerance);
    if (r.distance > r.tolerance && off++ == 0) off_example = v;
  }
  for (const auto& [list, slot] : junctions)
    problems.add(fmt::format("{} mesh vertices (one at {}) join mesh edges on model edges {} away from any model vertex",
                             slot.first, point_text(m.coords[slot.second]), join(list)));
  for (const auto& [list, slot] : touching)
    problems.add(fmt::format("{} mesh vertices (one at {}) touch model faces {} on no model edge or vertex", slot.first,
                             point_text(m.coords[slot.second]), join(list)));
  if (off > 0)
    problems.add(fmt::format("{} boundary vertices are off their model entity by more than its tolerance; one at {} "
                             "is {:.3g} from ({}, {}) (tolerance {:.3g})",
                             off, point_text(m.coords[off_example]), vr[off_example].distance, vr[off_example].on.dim,
                             vr[off_example].on.tag, vr[off_example].tolerance));

  // A mesh edge on model edge E joins vertices on E or at its ends; each
  // vertex inside E has two mesh edges along it.
  std::vector<std::size_t> edge_count(model.count(1) + 1, 0);
  std::map<int, std::size_t> spanning, broken_chain;
  std::vector<std::pair<VertId, int>> along;
  for (const MeshEdge& e : mesh_edges) {
    ++edge_count[e.tag];
    for (const VertId v : {e.a, e.b}) {
      const mesh::ModelRef c = vr[v].on;
      const bool ok = c == mesh::ModelRef{1, e.tag} ||
                      (c.dim == 0 && (ix.edge_ends[e.tag][0] == c.tag || ix.edge_ends[e.tag][1] == c.tag));
      if (!ok) ++spanning[e.tag];
      if (c == mesh::ModelRef{1, e.tag}) along.emplace_back(v, e.tag);
    }
  }
  std::sort(along.begin(), along.end());
  for (std::size_t i = 0; i < along.size();) {
    std::size_t j = i;
    while (j < along.size() && along[j] == along[i]) ++j;
    if (j - i != 2) ++broken_chain[along[i].second];
    i = j;
  }
  for (const auto& [tag, count] : spanning)
    problems.add(fmt::format("model edge {}: {} ends of its mesh edges are on other model entities (a mesh edge "
                             "spans two model edges)",
                             tag, count));
  for (const auto& [tag, count] : broken_chain)
    problems.add(fmt::format("model edge {}: {} of its mesh vertices have other than two mesh edges along it", tag, count));
  std::vector<std::size_t> tri_count(model.count(2) + 1, 0);
  for (const BoundaryTri& t : tris) ++tri_count[t.face];
  for (int f = 1; f <= model.count(2); ++f)
    if (tri_count[f] == 0) problems.add(fmt::format("model face {} has no triangle", f));
  for (int e = 1; e <= model.count(1); ++e)
    if (edge_count[e] == 0 && !model.is_degenerate(e)) problems.add(fmt::format("model edge {} has no mesh edge", e));
  {
    std::vector<char> has(model.count(0) + 1, 0);
    for (const VertexResult& r : vr)
      if (r.on.dim == 0) has[r.on.tag] = 1;
    for (int v = 1; v <= model.count(0); ++v)
      if (!has[v]) problems.add(fmt::format("model vertex {} at {} has no mesh vertex", v, point_text(model.vertex_point(v))));
    std::vector<char> used(model.count(3) + 1, 0);
    for (const std::int32_t r : region) used[r] = 1;
    for (int r = 1; r <= model.count(3); ++r)
      if (!used[r]) problems.add(fmt::format("model region {} has no tet", r));
  }

  // Input faces: where their triangles went.
  {
    std::vector<std::map<int, std::size_t>> went(group_tag.size());
    for (const BoundaryTri& t : tris)
      if (t.group >= 0) ++went[t.group][t.face];
    for (std::size_t k = 0; k < group_tag.size(); ++k) {
      TagMapping tm{group_tag[k], 0, 0, 0};
      std::size_t most = 0;
      for (const auto& [face, count] : went[k]) {
        tm.count += count;
        if (count > most) {
          most = count;
          tm.model = face;
        }
      }
      tm.others = tm.count - most;
      if (tm.count > 0) res.face_map.push_back(tm);
    }
  }

  // Entities, with the input's physical groups.
  std::vector<mesh::EntityInfo> entities = model_entities(model);
  if (std::any_of(m.entities.begin(), m.entities.end(),
                  [](const mesh::EntityInfo& e) { return !e.physicals.empty() || !e.name.empty(); })) {
    std::map<mesh::ModelRef, std::set<int>> sources;
    for (const BoundaryTri& t : tris)
      if (t.group >= 0) sources[{2, t.face}].insert(group_tag[t.group]);
    for (const TagMapping& r : res.region_map) sources[{3, r.model}].insert(r.input);
    std::unordered_map<std::uint64_t, int> new_edge;
    for (const MeshEdge& e : mesh_edges) new_edge[edge_key(e.a, e.b)] = e.tag;
    for (const auto& e : m.edges)
      if (const auto it = new_edge.find(edge_key(e.verts[0], e.verts[1])); it != new_edge.end())
        sources[{1, it->second}].insert(e.edge_tag);
    for (VertId v = 0; v < nv; ++v)
      if (vr[v].on.dim == 0 && m.vert_class[v].dim == 0) sources[vr[v].on].insert(m.vert_class[v].tag);
    carry_groups(sources, m.entities, entities, problems);
  }

  // Write back, keeping the input's order and vertex rotation where it had
  // the element.
  std::vector<std::size_t> order(tris.size());
  for (std::size_t i = 0; i < tris.size(); ++i) order[i] = i;
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return source[a] < source[b]; });
  std::vector<mesh::ClassifiedTri> new_tris;
  new_tris.reserve(tris.size());
  std::vector<char> kept(m.tris.size(), 0);
  for (const std::size_t i : order) {
    const BoundaryTri& t = tris[i];
    std::array<VertId, 3> v = t.verts;
    if (source[i] != kNone) {
      const mesh::ClassifiedTri& in = m.tris[source[i]];
      kept[source[i]] = 1;
      v = in.verts;
      // Same orientation iff the input, rotated to start at our first
      // vertex, continues with our second.
      const int at = static_cast<int>(std::find(v.begin(), v.end(), t.verts[0]) - v.begin());
      if (v[(at + 1) % 3] != t.verts[1]) {
        std::swap(v[1], v[2]);
        ++res.triangles_flipped;
      }
      res.triangles_changed += in.face_tag != t.face;
    } else {
      ++res.triangles_changed;
    }
    new_tris.push_back({v, t.face});
  }
  res.triangles_dropped = static_cast<std::size_t>(std::count(kept.begin(), kept.end(), 0));

  std::unordered_map<std::uint64_t, int> new_edge_tag;
  for (const MeshEdge& e : mesh_edges) new_edge_tag[edge_key(e.a, e.b)] = e.tag;
  std::vector<mesh::ClassifiedEdge> new_edges;
  std::unordered_map<std::uint64_t, char> placed;
  for (const auto& e : m.edges) {
    const std::uint64_t key = edge_key(e.verts[0], e.verts[1]);
    const auto it = new_edge_tag.find(key);
    if (it == new_edge_tag.end() || placed.count(key)) {
      ++res.edges_changed;
      continue;
    }
    placed[key] = 1;
    res.edges_changed += it->second != e.edge_tag;
    new_edges.push_back({e.verts, it->second});
  }
  std::vector<MeshEdge> added;
  for (const MeshEdge& e : mesh_edges)
    if (!placed.count(edge_key(e.a, e.b))) added.push_back(e);
  std::sort(added.begin(), added.end(), [](const MeshEdge& a, const MeshEdge& b) { return edge_key(a.a, a.b) < edge_key(b.a, b.b); });
  for (const MeshEdge& e : added) new_edges.push_back({{std::min(e.a, e.b), std::max(e.a, e.b)}, e.tag});
  res.edges_changed += added.size();
  res.mesh_edges_on_model_edges = new_edges.size();

  for (VertId v = 0; v < nv; ++v) {
    const VertexResult& r = vr[v];
    res.vertices_changed += r.on != m.vert_class[v];
    switch (r.on.dim) {
      case 0: ++res.vertices_on_model_vertices; break;
      case 1: ++res.vertices_on_model_edges; break;
      case 2: ++res.vertices_on_model_faces; break;
      default: ++res.interior_vertices; break;
    }
    m.vert_class[v] = r.on;
    m.vert_param[v] = r.param;
  }
  m.tet_region = std::move(region);
  m.tris = std::move(new_tris);
  m.edges = std::move(new_edges);
  m.entities = std::move(entities);
  res.seconds = timer.seconds();
  return res;
}

}  // namespace cm::generate
