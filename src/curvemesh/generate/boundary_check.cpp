#include "curvemesh/generate/boundary_check.hpp"
#include "curvemesh/generate/surface_intersection.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <map>
#include <mutex>
#include <numbers>

#include <fmt/format.h>
#include <tbb/parallel_for.h>

#include "curvemesh/quality/measures.hpp"

namespace cm::generate {

namespace {

std::uint64_t edge_key(VertId a, VertId b) { return (std::uint64_t(std::min(a, b)) << 32) | std::max(a, b); }

}  // namespace

BoundaryReport check_boundary(const geom::Model& model, const mesh::TetMesh& m, const size::SizeField& size) {
  BoundaryReport r;
  std::mutex problems_mutex;
  const auto problem = [&](std::string s) {
    std::lock_guard lock(problems_mutex);
    if (r.problems.size() < 20) r.problems.push_back(std::move(s));
  };
  const double floor = 1e-9 * model.bounding_box().diagonal();

  // Every vertex on its entity at its own parameters.
  std::atomic<std::size_t> off{0};
  std::vector<double> rel(m.num_verts(), 0);
  tbb::parallel_for(std::size_t{0}, m.num_verts(), [&](std::size_t v) {
    const mesh::ModelRef c = m.vert_class[v];
    if (c.dim == 3) return;  // interior vertices of a volume mesh are on their region by construction
    Vec3 on;
    if (c.dim == 0) on = model.vertex_point(c.tag);
    else if (c.dim == 1) on = model.edge_point(c.tag, m.vert_param[v].u);
    else on = model.face_point(c.tag, Vec2(m.vert_param[v].u, m.vert_param[v].v));
    const double tol = std::max(model.tolerance({c.dim, c.tag}), floor);
    const double d = (m.coords[v] - on).norm();
    rel[v] = d / tol;
    if (!(d <= tol)) {
      ++off;
      problem(fmt::format("vertex {} is {:.3g} from its entity ({}, {}), tolerance {:.3g}", v, d, c.dim, c.tag, tol));
    }
  });
  r.vertices_off_entity = off;
  r.max_vertex_distance = m.num_verts() ? *std::max_element(rel.begin(), rel.end()) : 0;

  // Triangles: fold against the surface, quality, corners.
  r.triangles = m.tris.size();
  std::vector<double> q(m.tris.size());
  std::atomic<std::size_t> folded{0}, poor{0}, poor_sharp{0}, poor_small{0};
  tbb::parallel_for(std::size_t{0}, m.tris.size(), [&](std::size_t i) {
    const auto& t = m.tris[i];
    const Vec3 a = m.coords[t.verts[0]], b = m.coords[t.verts[1]], c = m.coords[t.verts[2]];
    q[i] = quality::triangle_mean_ratio(a, b, c);
    std::optional<Vec2> hint;
    for (const VertId v : t.verts)
      if (m.vert_class[v].dim == 2 && m.vert_class[v].tag == t.face_tag)
        hint = Vec2(m.vert_param[v].u, m.vert_param[v].v);
    const geom::Projection p = model.closest_point({2, t.face_tag}, (a + b + c) / 3, hint);
    const Vec3 n = (b - a).cross(c - a);
    if (!(n.dot(model.face_normal(t.face_tag, p.param)) > 0)) {
      ++folded;
      problem(fmt::format("triangle {} of face {} folds against the surface normal", i, t.face_tag));
    }
    if (q[i] < 0.1) {
      bool sharp = false;
      for (int k = 0; k < 3; ++k) {
        if (m.vert_class[t.verts[k]].dim != 0) continue;
        const Vec3 p0 = m.coords[t.verts[k]], p1 = m.coords[t.verts[(k + 1) % 3]], p2 = m.coords[t.verts[(k + 2) % 3]];
        const double cosine = (p1 - p0).normalized().dot((p2 - p0).normalized());
        if (cosine > std::cos(std::numbers::pi / 6)) sharp = true;
      }
      const double shortest = std::min({(b - a).norm(), (c - b).norm(), (a - c).norm()});
      const bool small = shortest < 0.1 * size.size((a + b + c) / 3);
      ++(sharp ? poor_sharp : small ? poor_small : poor);
    }
  });
  r.folded_triangles = folded;
  std::vector<char> planar(static_cast<std::size_t>(model.count(2)) + 1, 0);
  for (int f = 1; f <= model.count(2); ++f) planar[f] = model.type({2, f}) == geom::ShapeType::kPlane;
  const auto crossing = crossing_triangles(m.coords, m.tris, planar);
  r.crossing_pairs = crossing.size();
  for (const auto& [i, j] : crossing)
    problem(fmt::format("triangles {} (face {}) and {} (face {}) cross", i, m.tris[i].face_tag, j, m.tris[j].face_tag));
  r.poor_triangles = poor;
  r.poor_at_sharp_corners = poor_sharp;
  r.poor_at_small_features = poor_small;
  if (!q.empty()) {
    r.min_quality = *std::min_element(q.begin(), q.end());
    double sum = 0;
    for (const double x : q) {
      sum += x;
      r.good_triangles += x >= 0.6;
    }
    r.mean_quality = sum / q.size();
  }

  // Faces without triangles.
  std::vector<std::size_t> per_face(model.count(2) + 1, 0);
  for (const auto& t : m.tris) ++per_face[t.face_tag];
  for (int f = 1; f <= model.count(2); ++f)
    if (per_face[f] == 0) {
      ++r.unmeshed_faces;
      problem(fmt::format("face {} has no triangle", f));
    }

  // Each region's boundary: a closed, oriented 2-manifold. Triangles follow
  // face_normal, i.e. the orientation of the face in its first region's
  // shell; a region that uses the face the other way sees them reversed.
  std::vector<std::vector<std::size_t>> tris_of(model.count(2) + 1);
  for (std::size_t i = 0; i < m.tris.size(); ++i) tris_of[m.tris[i].face_tag].push_back(i);
  for (int reg = 1; reg <= model.count(3); ++reg) {
    std::map<std::uint64_t, std::pair<int, int>> uses;  // key -> (a<b uses, a>b uses)
    for (const geom::OrientedUse& use : model.region_faces(reg)) {
      const std::vector<int> up = model.upward({2, use.tag});
      bool flip = false;
      if (!up.empty() && up.front() != reg)
        for (const geom::OrientedUse& first : model.region_faces(up.front()))
          if (first.tag == use.tag) flip = first.forward != use.forward;
      for (const std::size_t i : tris_of[use.tag]) {
        auto v = m.tris[i].verts;
        if (flip) std::swap(v[1], v[2]);
        for (int k = 0; k < 3; ++k) {
          const VertId a = v[k], b = v[(k + 1) % 3];
          auto& u = uses[edge_key(a, b)];
          ++(a < b ? u.first : u.second);
        }
      }
    }
    for (const auto& [key, u] : uses)
      if (u.first != 1 || u.second != 1) {
        ++r.open_region_edges;
        problem(fmt::format("region {}: edge ({}, {}) is used {} + {} times", reg, key >> 32, key & 0xffffffffu,
                            u.first, u.second));
      }
  }

  // Edge lengths against the size field.
  std::vector<std::uint64_t> keys;
  keys.reserve(3 * m.tris.size());
  for (const auto& t : m.tris)
    for (int k = 0; k < 3; ++k) keys.push_back(edge_key(t.verts[k], t.verts[(k + 1) % 3]));
  std::sort(keys.begin(), keys.end());
  keys.erase(std::unique(keys.begin(), keys.end()), keys.end());
  r.edges = keys.size();
  std::atomic<std::size_t> in_range{0};
  tbb::parallel_for(std::size_t{0}, keys.size(), [&](std::size_t i) {
    const Vec3 a = m.coords[keys[i] >> 32], b = m.coords[keys[i] & 0xffffffffu];
    const double l = (a - b).norm() / size.size(0.5 * (a + b));
    if (l >= 0.7 && l <= 1.4) ++in_range;
  });
  r.edges_in_range = in_range;
  return r;
}

}  // namespace cm::generate
