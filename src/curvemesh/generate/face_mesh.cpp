#include "curvemesh/generate/face_mesh.hpp"

#include <algorithm>
#include <cmath>

#include <fmt/format.h>

#include "curvemesh/core/error.hpp"
#include "curvemesh/core/predicates.hpp"
#include "curvemesh/quality/measures.hpp"
#include "curvemesh/generate/triangulation2d.hpp"

namespace cm::generate {

namespace {

// The face seen through (u, v) scaled by the mean first fundamental form:
// lengths in the scaled plane approximate lengths on the surface, so that a
// Euclidean Delaunay triangulation there is close to the surface's own.
struct Scaling {
  double su = 1, sv = 1;
  Vec2 to_plane(const Vec2& uv) const { return {su * uv.x(), sv * uv.y()}; }
  Vec2 to_uv(const Vec2& p) const { return {p.x() / su, p.y() / sv}; }
};

Scaling face_scaling(const geom::Model& m, int face) {
  const geom::ParamRange r = m.param_range({2, face});
  double e = 0, g = 0;
  int n = 0;
  for (int i = 0; i < 5; ++i)
    for (int j = 0; j < 5; ++j) {
      const Vec2 uv(r.u0 + (r.u1 - r.u0) * (i + 0.5) / 5, r.v0 + (r.v1 - r.v0) * (j + 0.5) / 5);
      const geom::SurfaceDerivatives d = m.face_derivatives(face, uv);
      if (!d.du.allFinite() || !d.dv.allFinite()) continue;
      e += d.du.norm();
      g += d.dv.norm();
      ++n;
    }
  Scaling s;
  if (n > 0 && e > 0 && g > 0) {
    s.su = e / n;
    s.sv = g / n;
  }
  return s;
}

class FaceMesher {
 public:
  FaceMesher(const geom::Model& m, int face, const size::SizeField& size, const FaceMeshOptions& o)
      : m_(m), face_(face), size_(size), o_(o), scale_(face_scaling(m, face)) {}

  FaceMesh run(const std::vector<std::vector<BoundaryPoint>>& loops) {
    CdtInput in;
    for (const auto& loop : loops) {
      const int first = static_cast<int>(in.points.size());
      for (const BoundaryPoint& p : loop) {
        in.points.push_back(scale_.to_plane(p.uv));
        xyz_.push_back(p.xyz);
        uv_.push_back(p.uv);
      }
      const int n = static_cast<int>(loop.size());
      for (int k = 0; k < n; ++k) in.segments.push_back({first + k, first + (k + 1) % n});
    }
    out_.num_boundary = in.points.size();
    try {
      t_ = constrained_delaunay(in).mesh;
    } catch (const GeometryError& e) {
      throw GeometryError(fmt::format("face {}: its boundary cannot be triangulated in (u, v): {}", face_, e.what()));
    }
    for (std::size_t i = 0; i < xyz_.size(); ++i) h_.push_back(size_at(i));
    refine();
    for (int pass = 0; pass < o_.optimize_passes; ++pass) {
      const int changed = flip_pass() + smooth_pass();
      if (changed == 0) break;
    }
    out_.uv = uv_;
    out_.xyz = xyz_;
    for (std::size_t t = 0; t < t_.tris.size(); ++t)
      if (alive(t)) out_.tris.push_back(t_.tris[t]);
    return std::move(out_);
  }

 private:
  bool alive(std::size_t t) const { return t_.tris[t][0] >= 0; }

  double size_at(std::size_t i) const { return size_.size(xyz_[i], {{2, face_}, uv_[i]}); }

  // Longest edge of a triangle in units of the local size.
  double longest(const std::array<int, 3>& t, int* edge = nullptr) const {
    double worst = 0;
    for (int k = 0; k < 3; ++k) {
      const int a = t[(k + 1) % 3], b = t[(k + 2) % 3];
      const double l = (xyz_[a] - xyz_[b]).norm() * 2 / (h_[a] + h_[b]);
      if (l > worst) {
        worst = l;
        if (edge) *edge = k;
      }
    }
    return worst;
  }

  int add_point(const Vec2& plane, int hint) {
    const int id = insert_point(t_, plane, hint);
    if (id < 0) return id;
    const Vec2 uv = scale_.to_uv(plane);
    uv_.push_back(uv);
    xyz_.push_back(m_.face_point(face_, uv));
    h_.push_back(size_at(uv_.size() - 1));
    CM_ASSERT(static_cast<std::size_t>(id) + 1 == uv_.size());
    return id;
  }

  // Too close, in 3D and relative to the size, to a vertex of triangle t?
  bool crowded(const Vec2& plane, int t) const {
    const Vec3 x = m_.face_point(face_, scale_.to_uv(plane));
    for (const int v : t_.tris[t])
      if ((x - xyz_[v]).norm() < 0.5 * h_[v]) return true;
    return false;
  }

  static bool circumcentre(const Vec2& a, const Vec2& b, const Vec2& c, Vec2* out) {
    const Vec2 ab = b - a, ac = c - a;
    const double d = 2 * (ab.x() * ac.y() - ab.y() * ac.x());
    if (!(std::abs(d) > 0)) return false;
    const double ab2 = ab.squaredNorm(), ac2 = ac.squaredNorm();
    *out = a + Vec2(ac.y() * ab2 - ab.y() * ac2, ab.x() * ac2 - ac.x() * ab2) / d;
    return out->allFinite();
  }

  void refine() {
    for (;;) {
      struct Candidate {
        double length;
        int tri;
        std::array<int, 3> verts;
      };
      std::vector<Candidate> cands;
      for (std::size_t t = 0; t < t_.tris.size(); ++t) {
        if (!alive(t)) continue;
        const double l = longest(t_.tris[t]);
        if (l > o_.max_edge) cands.push_back({l, static_cast<int>(t), t_.tris[t]});
      }
      if (cands.empty()) break;
      std::sort(cands.begin(), cands.end(), [](const Candidate& a, const Candidate& b) {
        return a.length > b.length || (a.length == b.length && a.tri < b.tri);
      });
      int inserted = 0;
      for (const Candidate& c : cands) {
        if (uv_.size() >= o_.max_points) break;
        if (!alive(c.tri) || t_.tris[c.tri] != c.verts) continue;  // changed by an earlier insertion
        const auto& p = t_.points;
        const Vec2 centroid = (p[c.verts[0]] + p[c.verts[1]] + p[c.verts[2]]) / 3;
        Vec2 cc;
        int id = -1;
        if (circumcentre(p[c.verts[0]], p[c.verts[1]], p[c.verts[2]], &cc)) {
          const int where = locate(t_, cc, c.tri);
          if (where >= 0 && !crowded(cc, where)) id = add_point(cc, where);
        }
        if (id < 0 && !crowded(centroid, c.tri)) id = add_point(centroid, c.tri);
        if (id >= 0) ++inserted;
      }
      out_.refinement_insertions += inserted;
      if (inserted == 0) break;
    }
  }

  // Quality of a (u, v)-triangle on the surface: its 3D mean ratio, or -1 if
  // it is inverted in (u, v) or folds against the surface normal.
  double quality(int a, int b, int c) const {
    const auto& p = t_.points;
    if (predicates::orient2d(p[a].data(), p[b].data(), p[c].data()) <= 0) return -1;
    const Vec3 n = (xyz_[b] - xyz_[a]).cross(xyz_[c] - xyz_[a]);
    const geom::SurfaceDerivatives d = m_.face_derivatives(face_, (uv_[a] + uv_[b] + uv_[c]) / 3);
    if (n.dot(d.du.cross(d.dv)) <= 0) return -1;
    return quality::triangle_mean_ratio(xyz_[a], xyz_[b], xyz_[c]);
  }

  int flip_pass() {
    int flips = 0;
    for (std::size_t t = 0; t < t_.tris.size(); ++t) {
      if (!alive(t)) continue;
      for (int i = 0; i < 3; ++i) {
        const int u = t_.adj[t][i];
        if (u < 0 || static_cast<std::size_t>(u) < t || (t_.constrained[t] >> i) & 1) continue;
        const auto tv = t_.tris[t];
        const int a = tv[(i + 1) % 3], b = tv[(i + 2) % 3], c = tv[i];
        int j = 0;
        while (t_.adj[u][j] != static_cast<int>(t)) ++j;
        const int d = t_.tris[u][j];
        // t = (c, a, b) and u = (b, a, d) share a–b; flipped: (c, a, d), (c, d, b).
        const double before = std::min(quality(c, a, b), quality(d, b, a));
        const double after = std::min(quality(c, a, d), quality(c, d, b));
        if (after > 0 && after > before + 1e-6 * std::abs(before) + 1e-12) {
          t_.flip(static_cast<int>(t), i);
          ++flips;
          break;  // t changed; its other edges are seen next pass
        }
      }
    }
    out_.flips += flips;
    return flips;
  }

  int smooth_pass() {
    const std::size_t nv = uv_.size();
    std::vector<std::vector<int>> ring(nv);
    for (std::size_t t = 0; t < t_.tris.size(); ++t)
      if (alive(t))
        for (const int v : t_.tris[t]) ring[v].push_back(static_cast<int>(t));
    int moves = 0;
    for (std::size_t v = out_.num_boundary; v < nv; ++v) {
      if (ring[v].empty()) continue;
      Vec2 target = Vec2::Zero();
      double worst = 1;
      int count = 0;
      for (const int t : ring[v]) {
        const auto& tv = t_.tris[t];
        worst = std::min(worst, quality(tv[0], tv[1], tv[2]));
        for (const int w : tv)
          if (w != static_cast<int>(v)) {
            target += t_.points[w];
            ++count;
          }
      }
      target /= count;
      const Vec2 old_plane = t_.points[v], old_uv = uv_[v];
      const Vec3 old_xyz = xyz_[v];
      const double old_h = h_[v];
      t_.points[v] = target;
      uv_[v] = scale_.to_uv(target);
      xyz_[v] = m_.face_point(face_, uv_[v]);
      h_[v] = size_at(v);
      double now = 1;
      for (const int t : ring[v]) {
        const auto& tv = t_.tris[t];
        now = std::min(now, quality(tv[0], tv[1], tv[2]));
      }
      if (now > 0 && now > worst + 1e-6 * std::abs(worst)) {
        ++moves;
      } else {
        t_.points[v] = old_plane;
        uv_[v] = old_uv;
        xyz_[v] = old_xyz;
        h_[v] = old_h;
      }
    }
    out_.smoothing_moves += moves;
    return moves;
  }

  const geom::Model& m_;
  int face_;
  const size::SizeField& size_;
  const FaceMeshOptions& o_;
  Scaling scale_;
  Triangulation2d t_;
  std::vector<Vec2> uv_;
  std::vector<Vec3> xyz_;
  std::vector<double> h_;
  FaceMesh out_;
};

}  // namespace

FaceMesh mesh_face(const geom::Model& model, int face, const std::vector<std::vector<BoundaryPoint>>& loops,
                   const size::SizeField& size, const FaceMeshOptions& options) {
  return FaceMesher(model, face, size, options).run(loops);
}

}  // namespace cm::generate
