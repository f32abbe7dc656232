#include "curvemesh/generate/volume_mesh.hpp"

#include <algorithm>
#include <map>
#include <numbers>

#include <fmt/format.h>
#include <tbb/parallel_for.h>

#include "curvemesh/core/error.hpp"
#include "curvemesh/core/predicates.hpp"
#include "curvemesh/core/timer.hpp"
#include "curvemesh/generate/delaunay3d.hpp"
#include "curvemesh/generate/spatial_sort.hpp"
#include "curvemesh/mesh/adjacency.hpp"
#include "curvemesh/mesh/topology.hpp"

namespace cm::generate {

namespace {

// Which region lies behind (against the normal) and in front of each model
// face, from the regions' shells; 0 = no region (outside the model).
struct FaceSides {
  std::vector<std::int32_t> behind, front;
};

FaceSides face_sides(const geom::Model& model) {
  FaceSides s;
  const int nf = model.count(2);
  s.behind.assign(static_cast<std::size_t>(nf) + 1, 0);
  s.front.assign(static_cast<std::size_t>(nf) + 1, 0);
  for (int r = 1; r <= model.count(3); ++r)
    for (const auto& use : model.region_faces(r)) (use.forward ? s.behind : s.front)[use.tag] = r;
  return s;
}

bool same_cycle(const std::array<VertId, 3>& a, const std::array<VertId, 3>& b) {
  for (int k = 0; k < 3; ++k)
    if (a[0] == b[k] && a[1] == b[(k + 1) % 3] && a[2] == b[(k + 2) % 3]) return true;
  return false;
}

std::array<VertId, 3> sorted3(std::array<VertId, 3> k) {
  std::sort(k.begin(), k.end());
  return k;
}

// Region classification by inheritance: tets connected without crossing a
// boundary triangle form a component; each boundary triangle tells, by its
// orientation, which region lies on each of its sides; a component takes the
// region its triangles vote for. Components touching the enclosing tet are
// outside. Returns the number of triangles whose vote disagreed.
//
// The boundary triangles are the faces protect_all() marked: only those are
// looked up, by binary search, and every other face is crossed at once.
std::size_t classify_regions(const geom::Model& model, Delaunay3d& dt) {
  auto& m = dt.mesh();
  auto& ed = dt.editor();
  const FaceSides sides = face_sides(model);
  std::vector<std::pair<std::array<VertId, 3>, std::uint32_t>> tri_of(m.tris.size());
  for (std::uint32_t i = 0; i < m.tris.size(); ++i) tri_of[i] = {sorted3(m.tris[i].verts), i};
  std::sort(tri_of.begin(), tri_of.end());
  const auto find_tri = [&tri_of](const std::array<VertId, 3>& face) {
    const auto key = sorted3(face);
    const auto it = std::lower_bound(tri_of.begin(), tri_of.end(), key,
                                     [](const auto& entry, const auto& k) { return entry.first < k; });
    return it != tri_of.end() && it->first == key ? it : tri_of.end();
  };

  const std::size_t nt = m.tet2verts.size();
  std::vector<std::int32_t> comp(nt, -1);
  std::vector<TetId> stack;
  std::size_t conflicts = 0;
  int ncomp = 0;
  for (TetId seed = 0; seed < nt; ++seed) {
    if (ed.is_dead(seed) || comp[seed] >= 0) continue;
    std::map<std::int32_t, std::size_t> votes;
    bool far = false;
    std::vector<TetId> members;
    comp[seed] = ncomp;
    stack.assign(1, seed);
    while (!stack.empty()) {
      const TetId t = stack.back();
      stack.pop_back();
      members.push_back(t);
      const auto& tv = m.tet2verts[t];
      for (VertId v : tv) far |= dt.is_far(v);
      for (int f = 0; f < 4; ++f) {
        const auto& fv = mesh::kFaceVerts[f];
        const std::array<VertId, 3> face{tv[fv[0]], tv[fv[1]], tv[fv[2]]};
        if (auto it = ed.face_marked(mesh::pack_face(t, f)) ? find_tri(face) : tri_of.end(); it != tri_of.end()) {
          const auto& tri = m.tris[it->second];
          // t's face is oriented out of t: same orientation as the triangle
          // (which follows the face normal) means t is behind the face.
          const bool behind = same_cycle(face, tri.verts);
          ++votes[behind ? sides.behind[tri.face_tag] : sides.front[tri.face_tag]];
          continue;
        }
        const Index a = m.tet2adj[4 * t + f];
        if (a == kNone) continue;
        const TetId n = mesh::face_tet(a);
        if (comp[n] < 0) {
          comp[n] = ncomp;
          stack.push_back(n);
        }
      }
    }
    std::int32_t region = 0;
    if (!far) {
      std::size_t best = 0;
      for (const auto& [r, c] : votes)
        if (c > best) {
          best = c;
          region = r;
        }
    }
    for (const auto& [r, c] : votes)
      if (r != region) conflicts += c;
    for (TetId t : members) m.tet_region[t] = region;
    ++ncomp;
  }
  return conflicts;
}

// Deletes the tets of region 0 (hull faces left kNone).
std::size_t remove_outside(Delaunay3d& dt) {
  auto& m = dt.mesh();
  auto& ed = dt.editor();
  std::size_t removed = 0;
  for (TetId t = 0; t < m.tet2verts.size(); ++t) {
    if (ed.is_dead(t) || m.tet_region[t] != 0) continue;
    for (int f = 0; f < 4; ++f) {
      const Index a = m.tet2adj[4 * t + f];
      if (a != kNone && m.tet_region[mesh::face_tet(a)] != 0) m.tet2adj[a] = kNone;
    }
    ed.release(t);
    ++removed;
  }
  for (VertId v = 0; v < m.vert2tet.size(); ++v)
    if (m.vert2tet[v] != kNone && ed.is_dead(m.vert2tet[v])) m.vert2tet[v] = kNone;
  // Survivors re-seed their vertices.
  for (TetId t = 0; t < m.tet2verts.size(); ++t)
    if (!ed.is_dead(t))
      for (VertId v : m.tet2verts[t]) m.vert2tet[v] = t;
  return removed;
}

Vec3 circumcentre(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) {
  const Vec3 u = b - a, v = c - a, w = d - a;
  const double det = 2.0 * u.dot(v.cross(w));
  return a + (u.squaredNorm() * v.cross(w) + v.squaredNorm() * w.cross(u) + w.squaredNorm() * u.cross(v)) / det;
}

// Where a tet whose circumcentre `x` lies in a cusp tip's ball gets its
// point instead, on the sphere: the ball holds no point but its vertex.
// - A tet of the tip's fan (a corner at the vertex): its far face is a
//   triangle of the fan's cap, and the cap is refined as a surface, Delaunay
//   refinement on the sphere, while that face's circumradius is over the
//   size or over √2 its shortest edge (angles under 20°) and half the size.
//   The points are the face's circumcentre, then its centroid, then the
//   middle of its longest edge (the circumcentre of a thin face by the ring
//   lies outside the solid), each taken to the sphere along the ray from
//   the vertex. On the sphere, not beyond it: the tet's circumsphere passes
//   through the sphere's centre, so it holds the cap of the sphere over the
//   far face, and the point's cavity takes the tet. `h` gets the far face's
//   size (the mean of its vertices'), the one its points are judged by: the
//   tip's vertex has its own, larger, from the ball around it.
// - Any other tet (a flat one just outside the sphere, on cap points): x
//   taken out to the sphere, which splits the cap under it.
std::vector<Vec3> shell_points(const mesh::TetMesh& m, const std::array<VertId, 4>& tv,
                               const std::map<VertId, const geom::CuspTip*>& tip_of, const std::vector<double>& vh,
                               const geom::CuspTip& ball, const Vec3& x, double* h_face) {
  const auto to_sphere = [](const geom::CuspTip& tip, const Vec3& c, std::vector<Vec3>& out) {
    const Vec3 ray = c - tip.point;
    if (ray.norm() > 0) out.push_back(tip.point + ray * (tip.radius / ray.norm()));
  };
  std::vector<Vec3> out;
  for (int k = 0; k < 4; ++k) {
    const auto it = tip_of.find(tv[k]);
    if (it == tip_of.end()) continue;
    const geom::CuspTip& tip = *it->second;
    std::array<Vec3, 3> f;
    double h = 0;
    for (int i = 0, j = 0; i < 4; ++i)
      if (i != k) {
        f[j++] = m.coords[tv[i]];
        h += vh[tv[i]] / 3;
      }
    const Vec3 u = f[1] - f[0], v = f[2] - f[0], n = u.cross(v);
    if (!(n.squaredNorm() > 0)) return {};
    const Vec3 centre = f[0] + (u.squaredNorm() * v.cross(n) + v.squaredNorm() * n.cross(u)) / (2 * n.squaredNorm());
    const double radius = (centre - f[0]).norm();
    const double shortest = std::min({u.norm(), v.norm(), (f[2] - f[1]).norm()});
    // Poor shapes are refined only while the circumradius is over half the
    // size: the new point is that far from every other, so this ends.
    if (radius <= h && (radius <= std::numbers::sqrt2 * shortest || radius <= 0.5 * h)) return {};
    *h_face = h;
    int longest = 0;  // the edge f[longest] -> f[longest + 1]
    for (int e = 1; e < 3; ++e)
      if ((f[(e + 1) % 3] - f[e]).squaredNorm() > (f[(longest + 1) % 3] - f[longest]).squaredNorm()) longest = e;
    for (const Vec3& c : {centre, Vec3((f[0] + f[1] + f[2]) / 3), Vec3(0.5 * (f[longest] + f[(longest + 1) % 3]))})
      to_sphere(tip, c, out);
    return out;
  }
  to_sphere(ball, x, out);
  return out;
}

// Delaunay refinement to the size field: circumcentres of tets too large for
// the size are inserted (never across a boundary face), in sweeps. Each sweep
// collects the circumcentres of the bad tets among those created by the
// previous one and inserts them in BRIO + Hilbert order: consecutive points
// are close, so walks are short and the tets touched stay in cache. A
// candidate whose tet a neighbour's insertion already destroyed is dropped:
// its replacements are judged in the next sweep, which keeps points from
// crowding. The size of a tet is the mean of its vertices' sizes, each
// queried once, rather than a size-field query per tet tested (about seven
// per point inserted).
void refine_interior(const size::SizeField& size, const std::vector<geom::CuspTip>& tip_list, Delaunay3d& dt,
                     const VolumeMeshOptions& o, VolumeMeshStats& st) {
  auto& m = dt.mesh();
  auto& ed = dt.editor();
  const geom::TipBalls tips(tip_list);
  std::map<VertId, const geom::CuspTip*> tip_of;
  for (VertId v = 0; v < m.coords.size(); ++v)
    if (m.vert_class[v].dim == 0)
      for (const geom::CuspTip& tip : tip_list)
        if (tip.vertex == m.vert_class[v].tag) tip_of[v] = &tip;
  std::vector<double> vh(m.coords.size(), INFINITY);
  tbb::parallel_for(VertId{0}, static_cast<VertId>(m.coords.size()), [&](VertId v) {
    if (!dt.is_far(v)) vh[v] = size.size(m.coords[v]);
  });
  std::vector<TetId> queue;
  for (TetId t = 0; t < m.tet2verts.size(); ++t)
    if (!ed.is_dead(t)) queue.push_back(t);
  ed.set_hook([&queue](const mesh::TetMesh&, std::span<const TetId> created) {
    queue.insert(queue.end(), created.begin(), created.end());
  });
  struct Candidate {
    Vec3 centre;
    double h;
    TetId tet;
    std::array<VertId, 4> verts;
  };
  std::vector<Candidate> candidates;
  std::vector<Vec3> centres;
  // A bound on the points the tips' caps take, whatever their geometry.
  constexpr std::size_t kMaxShellPoints = 100'000;
  std::size_t shell_inserted = 0;
  while (!queue.empty()) {
    candidates.clear();
    for (TetId t : queue) {
      if (ed.is_dead(t) || m.tet_region[t] == 0) continue;
      const auto& tv = m.tet2verts[t];
      const Vec3 cc = circumcentre(m.coords[tv[0]], m.coords[tv[1]], m.coords[tv[2]], m.coords[tv[3]]);
      if (!cc.allFinite()) continue;
      const double h = 0.25 * (vh[tv[0]] + vh[tv[1]] + vh[tv[2]] + vh[tv[3]]);
      if ((cc - m.coords[tv[0]]).norm() > o.radius_factor * h) candidates.push_back({cc, h, t, tv});
    }
    queue.clear();
    centres.resize(candidates.size());
    for (std::size_t i = 0; i < candidates.size(); ++i) centres[i] = candidates[i].centre;
    for (const std::uint32_t i : brio_order(centres)) {
      const Candidate& c = candidates[i];
      if (ed.is_dead(c.tet) || m.tet2verts[c.tet] != c.verts) continue;
      // The point, and where it goes: the circumcentre, or in a cusp tip's
      // fan the first of its shell points that lands in the tet's region.
      Vec3 x = c.centre;
      double h = c.h;
      TetId home = kNone;
      if (const geom::CuspTip* ball = tips.find(x)) {
        for (const Vec3& y : shell_points(m, c.verts, tip_of, vh, *ball, x, &h)) {
          try {
            const TetId at = dt.locate(y, c.tet);
            if (m.tet_region[at] != m.tet_region[c.tet] || m.tet_region[at] == 0) continue;
            // Never nearer than half the face's size to a point around it:
            // the cap's vertices are not all on the sphere, so a projected
            // centre can land next to one, and refinement must end.
            bool crowded = false;
            for (const TetId near : {at, c.tet})
              for (const VertId w : m.tet2verts[near])
                crowded = crowded || (m.coords[w] - y).norm() < 0.5 * h;
            if (crowded) continue;
            x = y;
            home = at;
            break;
          } catch (const std::domain_error&) {
          }
        }
        if (home == kNone || ++shell_inserted > kMaxShellPoints) {
          ++st.refused_points;
          continue;
        }
      } else {
        try {
          home = dt.locate(x, c.tet);
        } catch (const std::domain_error&) {
          continue;
        }
        if (m.tet_region[home] != m.tet_region[c.tet] || m.tet_region[home] == 0) continue;
      }
      // Too close to the boundary: the new tets against it would be flat.
      bool close = false;
      for (int f = 0; f < 4 && !close; ++f) {
        if (!ed.face_marked(mesh::pack_face(home, f))) continue;
        const auto& hv = m.tet2verts[home];
        const auto& fv = mesh::kFaceVerts[f];
        const std::array<VertId, 3> face{hv[fv[0]], hv[fv[1]], hv[fv[2]]};
        const Vec3 n = (m.coords[face[1]] - m.coords[face[0]]).cross(m.coords[face[2]] - m.coords[face[0]]);
        close = std::abs(n.normalized().dot(x - m.coords[face[0]])) < o.boundary_clearance * h;
      }
      if (close) {
        ++st.refused_points;
        continue;
      }
      const VertId p = m.add_vert(x);
      m.resize_vertex_arrays();
      m.vert_class[p] = {3, m.tet_region[home]};
      vh.push_back(size.size(x));
      const auto res = dt.insert(p, home);
      if (res.refusal != modify::Refusal::kNone) {
        m.coords.pop_back();
        m.resize_vertex_arrays();
        m.vert2tet.resize(m.coords.size());
        vh.pop_back();
        ++st.refused_points;
        continue;
      }
      ++st.interior_points;
    }
  }
  ed.set_hook({});
}

// Drops far and unused vertices and renumbers everything.
void compact_vertices(mesh::TetMesh& m) {
  std::vector<VertId> remap(m.coords.size(), kNone);
  VertId next = 0;
  std::vector<char> used(m.coords.size(), 0);
  for (const auto& t : m.tet2verts)
    for (VertId v : t) used[v] = 1;
  for (VertId v = 0; v < m.coords.size(); ++v)
    if (used[v]) {
      remap[v] = next;
      m.coords[next] = m.coords[v];
      m.vert_class[next] = m.vert_class[v];
      m.vert_param[next] = m.vert_param[v];
      ++next;
    }
  m.coords.resize(next);
  m.vert_class.resize(next);
  m.vert_param.resize(next);
  for (auto& t : m.tet2verts)
    for (VertId& v : t) v = remap[v];
  for (auto& t : m.tris)
    for (VertId& v : t.verts) v = remap[v];
  for (auto& e : m.edges)
    for (VertId& v : e.verts) v = remap[v];
  m.vert2tet.assign(next, kNone);
  for (TetId t = 0; t < m.tet2verts.size(); ++t)
    for (VertId v : m.tet2verts[t]) m.vert2tet[v] = t;
}

}  // namespace

mesh::TetMesh mesh_volume_from_boundary(const geom::Model& model, const size::SizeField& size, mesh::TetMesh m,
                                        const VolumeMeshOptions& o, VolumeMeshStats* stats) {
  VolumeMeshStats local;
  VolumeMeshStats& st = stats ? *stats : local;
  st.boundary_vertices = m.num_verts();
  st.boundary_triangles = m.tris.size();
  if (m.tris.empty()) throw GeometryError("the model has no boundary faces to mesh");
  Timer step;
  m.tet2verts.clear();
  m.tet_region.clear();
  m.tet2adj.clear();
  m.vert2tet.assign(m.coords.size(), kNone);
  geom::BoundingBox box;
  for (const Vec3& x : m.coords) box.add(x);
  std::vector<VertId> ids(m.coords.size());
  for (VertId v = 0; v < ids.size(); ++v) ids[v] = v;
  Delaunay3d dt(m, box.min, box.max);
  const auto dup = dt.insert_all(ids);
  for (std::size_t i = 0; i < dup.size(); ++i)
    if (dup[i] != kNone)
      throw GeometryError(fmt::format("boundary vertices {} and {} coincide (at {:.6g} {:.6g} {:.6g})", i, dup[i],
                                      m.coords[i].x(), m.coords[i].y(), m.coords[i].z()));
  st.delaunay_seconds = step.seconds();
  step.reset();
  st.recovery = recover_boundary(model, dt, o.recovery);
  st.recovery_seconds = step.seconds();
  step.reset();
  // Recovered, the boundary is protected: classification reads the marks,
  // and interior refinement never crosses them.
  if (const std::size_t lost = dt.protect_all(m.tris); lost != 0 && o.refine)
    throw InternalError(fmt::format("interior refinement: {} recovered boundary triangles are no face", lost));
  st.region_conflicts = classify_regions(model, dt);
  st.outside_tets = remove_outside(dt);
  st.classify_seconds = step.seconds();
  step.reset();
  st.tips = cusp_tips(model, size);
  if (o.refine) refine_interior(size, st.tips, dt, o, st);
  st.refine_seconds = step.seconds();
  dt.editor().compact();
  compact_vertices(m);
  return m;
}

mesh::TetMesh mesh_volume(const geom::Model& model, const size::SizeField& size, const VolumeMeshOptions& o,
                          VolumeMeshStats* stats) {
  VolumeMeshStats local;
  VolumeMeshStats& st = stats ? *stats : local;
  Timer step;
  mesh::TetMesh surface = mesh_boundary(model, size, o.boundary, &st.boundary);
  st.boundary_seconds = step.seconds();
  return mesh_volume_from_boundary(model, size, std::move(surface), o, &st);
}

}  // namespace cm::generate
