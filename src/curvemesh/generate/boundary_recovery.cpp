#include "curvemesh/generate/boundary_recovery.hpp"

#include <algorithm>
#include <unordered_map>

#include <fmt/format.h>

#include "curvemesh/core/error.hpp"
#include "curvemesh/mesh/adjacency.hpp"

namespace cm::generate {

namespace {

std::uint64_t edge_key(VertId a, VertId b) {
  if (a > b) std::swap(a, b);
  return (std::uint64_t{a} << 32) | b;
}

// The surface mesh with the incidences splitting needs: edge -> triangles,
// edge -> model-edge segment.
class Surface {
 public:
  Surface(const geom::Model& model, mesh::TetMesh& m) : model_(model), m_(m) {
    for (std::uint32_t t = 0; t < m.tris.size(); ++t)
      for (const auto& e : mesh::kTriEdges) tris_of_[edge_key(m.tris[t].verts[e[0]], m.tris[t].verts[e[1]])].push_back(t);
    for (std::uint32_t s = 0; s < m.edges.size(); ++s) segment_of_[edge_key(m.edges[s].verts[0], m.edges[s].verts[1])] = s;
  }

  const std::unordered_map<std::uint64_t, std::vector<std::uint32_t>>& edges() const { return tris_of_; }
  bool exists(VertId a, VertId b) const { return tris_of_.count(edge_key(a, b)) || segment_of_.count(edge_key(a, b)); }
  bool is_segment(VertId a, VertId b) const { return segment_of_.count(edge_key(a, b)) != 0; }

  /// Splits surface edge (a, b) on its model entity; returns the new vertex.
  VertId split(VertId a, VertId b, RecoveryStats& st) {
    const std::uint64_t key = edge_key(a, b);
    const Vec3 mid = 0.5 * (m_.coords[a] + m_.coords[b]);
    VertId p;
    if (auto seg = segment_of_.find(key); seg != segment_of_.end()) {
      const int e = m_.edges[seg->second].edge_tag;
      std::optional<Vec2> hint;
      for (VertId v : {a, b})
        if (m_.vert_class[v] == mesh::ModelRef{1, e}) hint = Vec2(m_.vert_param[v].u, 0);
      const auto pr = model_.closest_point({1, e}, mid, hint);
      p = m_.add_vert(pr.point);
      m_.resize_vertex_arrays();
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
      const auto& around = tris_of_.at(key);
      const int f = m_.tris[around.front()].face_tag;
      std::optional<Vec2> hint;
      for (std::uint32_t t : around)
        for (VertId v : m_.tris[t].verts)
          if (!hint && m_.vert_class[v] == mesh::ModelRef{2, f}) hint = Vec2(m_.vert_param[v].u, m_.vert_param[v].v);
      const auto pr = model_.closest_point({2, f}, mid, hint);
      p = m_.add_vert(pr.point);
      m_.resize_vertex_arrays();
      m_.vert_class[p] = {2, f};
      m_.vert_param[p].u = pr.param.x();
      m_.vert_param[p].v = pr.param.y();
      ++st.steiner_on_faces;
    }
    // Split every triangle on the edge into two, keeping its orientation.
    const std::vector<std::uint32_t> around = tris_of_[key];
    tris_of_.erase(key);
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

 private:
  const geom::Model& model_;
  mesh::TetMesh& m_;
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

RecoveryStats recover_boundary(const geom::Model& model, Delaunay3d& dt, const RecoveryOptions& o) {
  auto& m = dt.mesh();
  RecoveryStats st;
  Surface surf(model, m);
  std::size_t surface_verts = 0;
  for (VertId v = 0; v < m.coords.size(); ++v) surface_verts += m.vert_class[v].dim >= 0 && m.vert_class[v].dim <= 2;
  const auto max_steiner = static_cast<std::size_t>(o.max_steiner_factor * static_cast<double>(surface_verts)) + 1000;
  std::vector<TetId> scratch;
  std::vector<std::pair<VertId, VertId>> to_split;
  int last_face = 0;
  for (st.rounds = 0;; ++st.rounds) {
    to_split.clear();
    std::size_t missing_tris = 0;
    for (const auto& [key, tris] : surf.edges()) {
      const auto a = static_cast<VertId>(key >> 32), b = static_cast<VertId>(key & 0xFFFFFFFFu);
      if (!has_edge(m, a, b, scratch)) {
        to_split.emplace_back(a, b);
        last_face = m.tris[tris.front()].face_tag;
      }
    }
    for (const auto& s : m.edges)
      if (!surf.edges().count(edge_key(s.verts[0], s.verts[1])) && !has_edge(m, s.verts[0], s.verts[1], scratch))
        to_split.emplace_back(s.verts[0], s.verts[1]);
    const std::size_t missing_edges = to_split.size();
    if (missing_edges == 0) {
      // Edges all present: a missing triangle gets its longest edge split.
      for (const auto& t : m.tris) {
        const auto& v = t.verts;
        if (has_face(m, v[0], v[1], v[2], scratch)) continue;
        ++missing_tris;
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
    }
    if (st.rounds == 0) {
      st.missing_edges_initial = missing_edges;
      st.missing_triangles_initial = missing_tris;
    }
    if (to_split.empty()) return st;
    if (st.rounds >= o.max_rounds || st.steiner_on_edges + st.steiner_on_faces > max_steiner)
      throw GeometryError(fmt::format("face {}: boundary recovery did not converge ({} rounds, {} Steiner points, "
                                      "{} edges and {} triangles still missing)",
                                      last_face, st.rounds, st.steiner_on_edges + st.steiner_on_faces, missing_edges,
                                      missing_tris));
    std::sort(to_split.begin(), to_split.end());
    for (const auto& [a, b] : to_split) {
      if (!surf.exists(a, b)) continue;  // already split this round
      const VertId p = surf.split(a, b, st);
      const auto r = dt.insert(p, m.vert2tet[a]);
      if (r.refusal != modify::Refusal::kNone)
        throw GeometryError(fmt::format("face {}: Steiner point {} could not be inserted ({})", last_face, p,
                                        modify::to_string(r.refusal)));
    }
  }
}

}  // namespace cm::generate
