#include "curvemesh/generate/boundary_recovery.hpp"

#include <algorithm>
#include <cmath>
#include <functional>
#include <optional>
#include <tuple>
#include <unordered_map>
#include <unordered_set>

#include <fmt/format.h>
#include <tbb/parallel_invoke.h>
#include <tbb/parallel_sort.h>

#include "curvemesh/core/error.hpp"
#include "curvemesh/generate/flip_recovery.hpp"
#include "curvemesh/generate/surface_intersection.hpp"
#include "curvemesh/mesh/adjacency.hpp"

namespace cm::generate {

namespace {

using Triple = std::array<VertId, 3>;
Triple sorted3(Triple k) {
  std::sort(k.begin(), k.end());
  return k;
}

std::uint64_t edge_key(VertId a, VertId b) {
  if (a > b) std::swap(a, b);
  return (std::uint64_t{a} << 32) | b;
}

// The surface mesh with the incidences splitting needs: edge -> triangles,
// edge -> model-edge segment.
class Surface {
 public:
  Surface(const geom::Model& model, mesh::TetMesh& m) : model_(model), m_(m), first_steiner_(m.coords.size()) {
    for (std::uint32_t t = 0; t < m.tris.size(); ++t)
      for (const auto& e : mesh::kTriEdges) tris_of_[edge_key(m.tris[t].verts[e[0]], m.tris[t].verts[e[1]])].push_back(t);
    for (std::uint32_t s = 0; s < m.edges.size(); ++s) segment_of_[edge_key(m.edges[s].verts[0], m.edges[s].verts[1])] = s;
  }

  const std::unordered_map<std::uint64_t, std::vector<std::uint32_t>>& edges() const { return tris_of_; }
  bool exists(VertId a, VertId b) const { return tris_of_.count(edge_key(a, b)) || segment_of_.count(edge_key(a, b)); }
  bool is_segment(VertId a, VertId b) const { return segment_of_.count(edge_key(a, b)) != 0; }

  /// Mesh edges that the meshes of two or more faces both run inside (no
  /// model edge joins their ends): a region boundary through such an edge
  /// is not a manifold. It happens where two faces pass within a hair of
  /// each other at two shared corners, e.g. beside a chamfer a few model
  /// tolerances wide. Each entry is (a, b, a face to take the edge out of);
  /// the face with the smallest tag keeps it.
  std::vector<std::tuple<VertId, VertId, int>> shared_chords() const {
    std::vector<std::tuple<VertId, VertId, int>> out;
    for (const auto& [key, tris] : tris_of_) {
      if (tris.size() <= 2 || segment_of_.count(key)) continue;
      std::vector<int> faces;
      for (const std::uint32_t t : tris) faces.push_back(m_.tris[t].face_tag);
      std::sort(faces.begin(), faces.end());
      faces.erase(std::unique(faces.begin(), faces.end()), faces.end());
      for (std::size_t i = 1; i < faces.size(); ++i)
        out.emplace_back(static_cast<VertId>(key >> 32), static_cast<VertId>(key & 0xffffffffu), faces[i]);
    }
    std::sort(out.begin(), out.end());
    return out;
  }

  /// Splits surface edge (a, b) on its model entity; returns the new vertex.
  /// With `only_face`, an edge inside that face's mesh is split there alone:
  /// the other faces' triangles keep it.
  VertId split(VertId a, VertId b, RecoveryStats& st, int only_face, const std::function<bool(const Vec3&)>& taken) {
    const std::uint64_t key = edge_key(a, b);
    // Where to split: the midpoint, except on an edge from an original
    // vertex to a Steiner point, which is split at a power-of-two distance
    // from the original vertex (Ruppert's concentric shells). Splits around
    // a vertex with small angles between its surface edges then land on
    // common spheres and stop encroaching on each other; plain midpoints can
    // cascade forever there.
    double w = 0.5;  // fraction of the way from a to b
    const bool a_orig = a < first_steiner_, b_orig = b < first_steiner_;
    if (a_orig != b_orig) {
      const double len = (m_.coords[b] - m_.coords[a]).norm();
      const double d = std::exp2(std::round(std::log2(0.5 * len)));
      w = std::clamp(a_orig ? d / len : 1.0 - d / len, 0.25, 0.75);
    }
    const auto seg = only_face == 0 ? segment_of_.find(key) : segment_of_.end();
    const int e = seg != segment_of_.end() ? m_.edges[seg->second].edge_tag : 0;
    int f = only_face;
    std::optional<Vec2> hint;
    std::optional<double> ua, ub;
    if (e != 0) {
      // Halve the parameter interval when both ends have a parameter on the
      // edge: progress is guaranteed even where closest-point projection is
      // ambiguous (tiny or nearly closed edges).
      ua = param_on_edge(a, e);
      ub = param_on_edge(b, e, ua);
      if (ua) hint = Vec2(*ua, 0);
      if (ub) hint = Vec2(*ub, 0);
    } else {
      const auto& around = tris_of_.at(key);
      if (f == 0) f = m_.tris[around.front()].face_tag;
      for (std::uint32_t t : around)
        for (VertId v : m_.tris[t].verts)
          if (!hint && m_.vert_class[v] == mesh::ModelRef{2, f}) hint = Vec2(m_.vert_param[v].u, m_.vert_param[v].v);
    }
    const auto place = [&](double at) {
      if (e != 0 && ua && ub) {
        const double u = (1 - at) * *ua + at * *ub;
        return geom::Projection{model_.edge_point(e, u), Vec2(u, 0), 0};
      }
      const Vec3 mid = (1 - at) * m_.coords[a] + at * m_.coords[b];
      return e != 0 ? model_.closest_point({1, e}, mid, hint) : model_.closest_point({2, f}, mid, hint);
    };
    // Where a face is narrower than the edge is long, closest points clamp
    // to its trim, and two edges' splits can land on one point (a KiCad
    // terminal block's face): the next fractions are tried then.
    geom::Projection pr = place(w);
    for (const double other : {0.5, 0.375, 0.625, 0.25, 0.75}) {
      if (!taken(pr.point)) break;
      pr = place(other);
    }
    if (taken(pr.point))
      throw GeometryError(fmt::format("{} {}: every point tried to split the mesh edge of length {:.3g} at ({:.6g}, "
                                      "{:.6g}, {:.6g}) lands on a mesh vertex",
                                      e != 0 ? "edge" : "face", e != 0 ? e : f, (m_.coords[b] - m_.coords[a]).norm(),
                                      pr.point.x(), pr.point.y(), pr.point.z()));
    const VertId p = m_.add_vert(pr.point);
    m_.resize_vertex_arrays();
    if (e != 0) {
      m_.vert_class[p] = {1, e};
      m_.vert_param[p].u = pr.param.x();
      const std::uint32_t s = seg->second;
      segment_of_.erase(seg);
      m_.edges[s].verts = {a, p};
      m_.edges.push_back({{p, b}, e});
      segment_of_[edge_key(a, p)] = s;
      segment_of_[edge_key(p, b)] = static_cast<std::uint32_t>(m_.edges.size() - 1);
      ++st.steiner_on_edges;
    } else {
      m_.vert_class[p] = {2, f};
      m_.vert_param[p].u = pr.param.x();
      m_.vert_param[p].v = pr.param.y();
      ++st.steiner_on_faces;
    }
    // Split every triangle on the edge (of that face) into two, keeping its
    // orientation.
    std::vector<std::uint32_t> around = tris_of_[key], kept;
    if (only_face != 0) {
      std::erase_if(around, [&](std::uint32_t t) {
        if (m_.tris[t].face_tag == only_face) return false;
        kept.push_back(t);
        return true;
      });
    }
    if (kept.empty())
      tris_of_.erase(key);
    else
      tris_of_[key] = kept;
    for (std::uint32_t t : around) {
      auto tv = m_.tris[t].verts;
      int k = 0;  // rotate so that the tri reads (x, y, c) with {x, y} = {a, b}
      while (!((tv[k] == a && tv[(k + 1) % 3] == b) || (tv[k] == b && tv[(k + 1) % 3] == a))) ++k;
      const VertId x = tv[k], y = tv[(k + 1) % 3], c = tv[(k + 2) % 3];
      const auto t2 = static_cast<std::uint32_t>(m_.tris.size());
      m_.tris[t].verts = {x, p, c};
      m_.tris.push_back({{p, y, c}, m_.tris[t].face_tag});
      tris_of_[edge_key(x, p)].push_back(t);
      tris_of_[edge_key(p, y)].push_back(t2);
      auto& pc = tris_of_[edge_key(p, c)];
      pc.push_back(t);
      pc.push_back(t2);
      for (auto& id : tris_of_[edge_key(y, c)])
        if (id == t) id = t2;
    }
    return p;
  }

  /// Flips surface edge (a, b) to (c, d), the other diagonal of its two
  /// triangles, when that diagonal is an edge of the tetrahedralization and
  /// the flip is valid on the surface. Only edges inside one model face are
  /// flipped: they are not constraints of the model, any triangulation of the
  /// face's points will do, and the one the 3D Delaunay mesh already contains
  /// costs no Steiner point. Splitting such edges instead bisects triangles
  /// towards their opposite vertex, which shrinks their angles; in a face
  /// tapering to a sharp tip that cascades without end. Returns false when
  /// the flip does not apply.
  bool flip_to_mesh(VertId a, VertId b, std::vector<TetId>& scratch) {
    const std::uint64_t key = edge_key(a, b);
    if (segment_of_.count(key)) return false;
    const auto it = tris_of_.find(key);
    if (it == tris_of_.end() || it->second.size() != 2) return false;
    const std::uint32_t t1 = it->second[0], t2 = it->second[1];
    if (m_.tris[t1].face_tag != m_.tris[t2].face_tag) return false;
    // Read t1 as (a, b, c): then a consistently oriented t2 is (b, a, d).
    auto rotate_to = [&](std::uint32_t t, VertId x, VertId y) -> std::optional<VertId> {
      const auto& v = m_.tris[t].verts;
      for (int k = 0; k < 3; ++k)
        if (v[k] == x && v[(k + 1) % 3] == y) return v[(k + 2) % 3];
      return {};
    };
    auto c = rotate_to(t1, a, b);
    std::uint32_t ta = t1, tb = t2;
    if (!c) {
      std::swap(ta, tb);
      c = rotate_to(ta, a, b);
    }
    const auto d = rotate_to(tb, b, a);
    if (!c || !d || *c == *d) return false;
    if (tris_of_.count(edge_key(*c, *d)) || segment_of_.count(edge_key(*c, *d))) return false;
    if (!has_edge(m_, *c, *d, scratch)) return false;
    // Valid on the surface: both new triangles face the way the old pair
    // does (the quad is convex seen along its normal, nothing folds).
    const auto& x = m_.coords;
    const Vec3 n = (x[b] - x[a]).cross(x[*c] - x[a]) + (x[a] - x[b]).cross(x[*d] - x[b]);
    const Vec3 n1 = (x[*d] - x[a]).cross(x[*c] - x[a]), n2 = (x[*c] - x[b]).cross(x[*d] - x[b]);
    if (!(n1.dot(n) > 0 && n2.dot(n) > 0)) return false;
    m_.tris[ta].verts = {a, *d, *c};
    m_.tris[tb].verts = {b, *c, *d};
    tris_of_.erase(it);
    tris_of_[edge_key(*c, *d)] = {ta, tb};
    // (b, c) moved from ta to tb and (a, d) from tb to ta.
    for (auto& id : tris_of_[edge_key(b, *c)])
      if (id == ta) id = tb;
    for (auto& id : tris_of_[edge_key(a, *d)])
      if (id == tb) id = ta;
    return true;
  }

 private:
  /// Parameter of vertex v on model edge e: its own u, or the end of e it
  /// sits at (for a closed edge, the end nearer `near`).
  std::optional<double> param_on_edge(VertId v, int e, std::optional<double> near = {}) const {
    const auto c = m_.vert_class[v];
    if (c == mesh::ModelRef{1, e}) return m_.vert_param[v].u;
    if (c.dim != 0) return {};
    const auto ends = model_.edge_vertices(e);
    const auto r = model_.param_range({1, e});
    const bool at0 = ends[0] == c.tag, at1 = ends[1] == c.tag;
    if (at0 && at1) return near && std::abs(*near - r.u1) < std::abs(*near - r.u0) ? r.u1 : r.u0;
    if (at0) return r.u0;
    if (at1) return r.u1;
    return {};
  }

  const geom::Model& model_;
  mesh::TetMesh& m_;
  std::size_t first_steiner_;  // vertices from here on were added by recovery (or are far vertices)
  std::unordered_map<std::uint64_t, std::vector<std::uint32_t>> tris_of_;
  std::unordered_map<std::uint64_t, std::uint32_t> segment_of_;
};

}  // namespace

bool has_edge(const mesh::TetMesh& m, VertId a, VertId b, std::vector<TetId>& scratch) {
  if (m.vert2tet[a] == kNone) return false;
  mesh::collect_ball(m, a, scratch);
  for (TetId t : scratch)
    if (mesh::local_index(m, t, b) >= 0) return true;
  return false;
}

bool has_face(const mesh::TetMesh& m, VertId a, VertId b, VertId c, std::vector<TetId>& scratch) {
  if (m.vert2tet[a] == kNone) return false;
  mesh::collect_ball(m, a, scratch);
  for (TetId t : scratch)
    if (mesh::local_index(m, t, b) >= 0 && mesh::local_index(m, t, c) >= 0) return true;
  return false;
}

bool recovery_diverges(std::span<const std::size_t> missing) {
  constexpr std::size_t kRounds = 4, kFactor = 8;
  const std::size_t n = missing.size();
  if (n <= kRounds) return false;
  for (std::size_t i = n - kRounds; i < n; ++i)
    if (missing[i] <= missing[i - 1]) return false;
  return missing.back() > kFactor * std::max<std::size_t>(missing.front(), 1);
}

RecoveryStats recover_boundary(const geom::Model& model, Delaunay3d& dt, const RecoveryOptions& o) {
  auto& m = dt.mesh();
  RecoveryStats st;
  Surface surf(model, m);
  std::size_t surface_verts = 0;
  for (VertId v = 0; v < m.coords.size(); ++v) surface_verts += m.vert_class[v].dim >= 0 && m.vert_class[v].dim <= 2;
  const auto max_steiner = static_cast<std::size_t>(o.max_steiner_factor * static_cast<double>(surface_verts)) + 1000;
  std::vector<std::pair<VertId, VertId>> to_split;
  std::vector<TetId> ball;
  std::vector<std::uint64_t> all_edges;
  std::unordered_set<std::uint64_t> flip_made;
  std::vector<Triple> all_faces;
  int last_face = 0;
  // Flips never remove an edge of the surface mesh (present or not), hence
  // never a recovered edge or triangle.
  FlipRecovery flips(dt.editor(), [&surf](VertId a, VertId b) { return surf.exists(a, b); });
  auto split_and_insert = [&](VertId a, VertId b, int only_face = 0) {
    // A point already in the mesh is a vertex of the tet that holds it.
    const auto taken = [&](const Vec3& x) {
      try {
        const TetId t = dt.locate(x, m.vert2tet[a]);
        for (const VertId v : m.tet2verts[t])
          if (m.coords[v] == x) return true;
        return false;
      } catch (const std::domain_error&) {
        return false;
      }
    };
    const VertId p = surf.split(a, b, st, only_face, taken);
    // Any flip, even one of a failed attempt, ends Delaunay insertion's
    // assumption that cavities are star-shaped.
    if (flips.stats().face_swaps + flips.stats().edge_removals != 0) dt.set_non_delaunay();
    const auto r = dt.insert(p, m.vert2tet[a]);
    if (r.refusal != modify::Refusal::kNone)
      throw GeometryError(fmt::format("face {}: Steiner point {} could not be inserted ({})", last_face, p,
                                      modify::to_string(r.refusal)));
  };
  // A mesh edge two faces' meshes both run inside goes out of all but one
  // of them first, split on each such face: no region boundary can be a
  // manifold through it.
  for (const auto& [a, b, f] : surf.shared_chords()) {
    last_face = f;
    split_and_insert(a, b, f);
  }
  // Crossing triangles next: no tetrahedralization contains both, and
  // splitting them only where they are missing would never end. They come
  // from triangles coarser than a thin feature (two faces closer than the
  // chord error); splitting their longest edges on the model brings the
  // mesh to the surfaces, which do not cross, so a few rounds end it.
  std::vector<char> planar(static_cast<std::size_t>(model.count(2)) + 1, 0);
  for (int f = 1; f <= model.count(2); ++f) planar[f] = model.type({2, f}) == geom::ShapeType::kPlane;
  // Faces that truly intersect cross at every scale: each round then
  // doubles the pairs (a KiCad transformer's 21k pairs took 16 GB). Rounds
  // must halve them over any three, as refining toward surfaces that do not
  // cross does.
  std::vector<std::size_t> pair_counts;
  for (int round = 0;; ++round) {
    const auto pairs = crossing_triangles(m.coords, m.tris, planar);
    if (round == 0) st.crossing_pairs_initial = pairs.size();
    if (pairs.empty()) break;
    pair_counts.push_back(pairs.size());
    const bool stalled = round >= 3 && 2 * pairs.size() > pair_counts[static_cast<std::size_t>(round) - 3];
    if (round >= 30 || stalled || st.steiner_on_edges + st.steiner_on_faces > max_steiner) {
      const auto& t = m.tris[pairs.front()[0]];
      const auto& u = m.tris[pairs.front()[1]];
      const Vec3 x = m.coords[t.verts[0]];
      throw GeometryError(fmt::format("faces {} and {}: the surface mesh still crosses itself near ({:.6g} {:.6g} "
                                      "{:.6g}) after {} rounds of refinement ({} crossing pairs); do the model's "
                                      "faces intersect?",
                                      t.face_tag, u.face_tag, x.x(), x.y(), x.z(), round, pairs.size()));
    }
    std::vector<std::pair<VertId, VertId>> longest;
    for (const auto& pair : pairs)
      for (std::uint32_t i : pair) {
        const auto& v = m.tris[i].verts;
        int e = 0;
        double best = -1;
        for (int k = 0; k < 3; ++k) {
          const double l = (m.coords[v[k]] - m.coords[v[(k + 1) % 3]]).squaredNorm();
          if (l > best) {
            best = l;
            e = k;
          }
        }
        longest.emplace_back(std::min(v[e], v[(e + 1) % 3]), std::max(v[e], v[(e + 1) % 3]));
      }
    std::sort(longest.begin(), longest.end());
    longest.erase(std::unique(longest.begin(), longest.end()), longest.end());
    for (const auto& [a, b] : longest) {
      if (!surf.exists(a, b)) continue;
      last_face = m.tris[pairs.front()[0]].face_tag;
      split_and_insert(a, b);
      ++st.crossing_splits;
    }
  }
  // After the first round only simplices touching a vertex of a new tet can
  // have changed: every missing one was split, every other one that vanished
  // lost it to a cavity, whose vertices all lie in the new tets.
  std::vector<char> dirty(m.coords.size(), 1);
  auto& ed = dt.editor();
  ed.set_hook([&dirty](const mesh::TetMesh& mm, std::span<const TetId> created) {
    if (dirty.size() < mm.coords.size()) dirty.resize(mm.coords.size() + mm.coords.size() / 2, 0);
    for (TetId t : created)
      for (VertId v : mm.tet2verts[t]) dirty[v] = 1;
  });
  struct HookReset {
    modify::MeshEditor& ed;
    ~HookReset() { ed.set_hook({}); }
  } hook_reset{ed};
  auto volume_flips_now = [&] { return st.rounds >= o.flips_from_round; };
  std::vector<std::size_t> missing_counts;  // missing edges and triangles, per round
  for (st.rounds = 0;; ++st.rounds) {
    to_split.clear();
    std::size_t missing_tris = 0;
    std::vector<char> checking(dirty.size(), 0);
    checking.swap(dirty);
    auto check = [&](VertId v) { return v < checking.size() && checking[v]; };
    // Read every tet once rather than walking a ball per surface simplex:
    // balls of a boundary-only Delaunay mesh can hold thousands of tets.
    // Only simplices at a vertex under check are collected.
    // Sorted arrays rather than hash sets: built once per round and only
    // searched, they take a third of the memory and no allocation per entry.
    all_edges.clear();
    all_faces.clear();
    for (TetId t = 0; t < m.tet2verts.size(); ++t) {
      if (dt.editor().is_dead(t)) continue;
      const auto& tv = m.tet2verts[t];
      if (!check(tv[0]) && !check(tv[1]) && !check(tv[2]) && !check(tv[3])) continue;
      for (const auto& e : mesh::kTetEdges)
        if (check(tv[e[0]]) || check(tv[e[1]])) all_edges.push_back(edge_key(tv[e[0]], tv[e[1]]));
      for (const auto& f : mesh::kFaceVerts)
        if (check(tv[f[0]]) || check(tv[f[1]]) || check(tv[f[2]]))
          all_faces.push_back(sorted3({tv[f[0]], tv[f[1]], tv[f[2]]}));
    }
    // Keys equal only when the simplices are: the parallel sort gives the
    // same arrays as a serial one.
    tbb::parallel_invoke([&] { tbb::parallel_sort(all_edges.begin(), all_edges.end()); },
                         [&] { tbb::parallel_sort(all_faces.begin(), all_faces.end()); });
    auto edge_in = [&](VertId a, VertId b) {
      return std::binary_search(all_edges.begin(), all_edges.end(), edge_key(a, b));
    };
    auto face_in = [&](const std::array<VertId, 3>& v) {
      return std::binary_search(all_faces.begin(), all_faces.end(), sorted3(v));
    };
    for (const auto& [key, tris] : surf.edges()) {
      const auto a = static_cast<VertId>(key >> 32), b = static_cast<VertId>(key & 0xFFFFFFFFu);
      if (!check(a) && !check(b)) continue;
      if (!edge_in(a, b)) {
        to_split.emplace_back(a, b);
        last_face = m.tris[tris.front()].face_tag;
      }
    }
    for (const auto& s : m.edges)
      if ((check(s.verts[0]) || check(s.verts[1])) && !surf.edges().count(edge_key(s.verts[0], s.verts[1])) &&
          !edge_in(s.verts[0], s.verts[1]))
        to_split.emplace_back(s.verts[0], s.verts[1]);
    const std::size_t missing_edges = to_split.size();
    // Triangles are checked every round but split only once the edges are
    // in (a missing edge usually explains its triangles); deferred ones keep
    // their vertices under check.
    for (const auto& t : m.tris) {
      const auto& v = t.verts;
      if (!check(v[0]) && !check(v[1]) && !check(v[2])) continue;
      if (face_in(v)) continue;
      ++missing_tris;
      if (missing_edges != 0) {
        if (dirty.size() < checking.size()) dirty.resize(checking.size(), 0);
        for (VertId x : v) dirty[x] = 1;
        continue;
      }
      if (volume_flips_now() && flips.recover_triangle(v[0], v[1], v[2])) continue;
      last_face = t.face_tag;
      int longest = 0;
      double best = -1;
      for (int e = 0; e < 3; ++e) {
        const double l = (m.coords[v[mesh::kTriEdges[e][0]]] - m.coords[v[mesh::kTriEdges[e][1]]]).squaredNorm();
        if (l > best) {
          best = l;
          longest = e;
        }
      }
      to_split.emplace_back(v[mesh::kTriEdges[longest][0]], v[mesh::kTriEdges[longest][1]]);
    }
    if (st.rounds == 0) {
      st.missing_edges_initial = missing_edges;
      st.missing_triangles_initial = missing_tris;
    }
    if (to_split.empty()) {
      st.volume_flips = flips.stats().face_swaps + flips.stats().edge_removals;
      st.edges_by_volume_flips = flips.stats().edges_recovered;
      st.triangles_by_volume_flips = flips.stats().triangles_recovered;
      return st;
    }
    // Surface flips first: a flipped edge needs no Steiner point. Vertices
    // of flipped triangles are checked again next round (no tet changed, so
    // the rebuild hook did not mark them).
    // Only edges missing from the tetrahedralization are flipped (the split
    // of a missing triangle's longest edge stays a split), and never an edge
    // a flip made: flips then only ever add Delaunay edges to the surface
    // and cannot undo each other, so they end.
    const auto first_missing = to_split.front();
    std::size_t flipped = 0, index = 0;
    std::erase_if(to_split, [&](const std::pair<VertId, VertId>& e) {
      const auto [a, b] = e;
      if (index++ >= missing_edges || !surf.exists(a, b)) return false;
      if (flip_made.count(edge_key(a, b))) return volume_flips_now() && flips.recover_edge(a, b);
      const auto it = surf.edges().find(edge_key(a, b));
      std::array<VertId, 4> quad{a, b, kNone, kNone};
      if (it != surf.edges().end() && it->second.size() == 2)
        for (int k = 0; k < 2; ++k)
          for (VertId v : m.tris[it->second[k]].verts)
            if (v != a && v != b) quad[2 + k] = v;
      if (!surf.flip_to_mesh(a, b, ball)) return volume_flips_now() && flips.recover_edge(a, b);
      flip_made.insert(edge_key(quad[2], quad[3]));
      if (dirty.size() < m.coords.size()) dirty.resize(m.coords.size(), 0);
      for (VertId v : quad) dirty[v] = 1;
      ++flipped;
      return true;
    });
    st.surface_flips += flipped;
    missing_counts.push_back(missing_edges + missing_tris);
    const bool diverges = recovery_diverges(missing_counts);
    if (st.rounds >= o.max_rounds || st.steiner_on_edges + st.steiner_on_faces > max_steiner || diverges) {
      const auto [a, b] = first_missing;
      const Vec3 x = m.coords[a], y = m.coords[b];
      throw GeometryError(fmt::format("face {}: boundary recovery {} ({} rounds, {} Steiner points, "
                                      "{} edges and {} triangles still missing; one is the edge ({:.6g} {:.6g} "
                                      "{:.6g})-({:.6g} {:.6g} {:.6g}) of length {:.3g})",
                                      last_face, diverges ? "diverges: its splits make ever more simplices go missing" : "did not converge",
                                      st.rounds, st.steiner_on_edges + st.steiner_on_faces, missing_edges,
                                      missing_tris, x.x(), x.y(), x.z(), y.x(), y.y(), y.z(), (x - y).norm()));
    }
    if (to_split.empty()) continue;  // only flips this round
    std::sort(to_split.begin(), to_split.end());
    for (const auto& [a, b] : to_split) {
      if (!surf.exists(a, b)) continue;  // already split this round
      // A cascade (surfaces meeting at a tiny angle or nearly touching) can
      // multiply the splits of one round: stop as soon as the budget is spent.
      if (st.steiner_on_edges + st.steiner_on_faces > max_steiner) break;
      split_and_insert(a, b);
    }
  }
}

}  // namespace cm::generate
