#include "curvemesh/generate/face_mesh.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <queue>

#include <fmt/format.h>
#include <tbb/parallel_invoke.h>

#include "curvemesh/core/error.hpp"
#include "curvemesh/core/predicates.hpp"
#include "curvemesh/quality/measures.hpp"
#include "curvemesh/generate/plane_metric.hpp"
#include "curvemesh/generate/triangulation2d.hpp"

namespace cm::generate {

namespace {

constexpr double kHalfSqrt3 = 0.8660254037844386;
constexpr double kNearFold = 0.17;  // cos 80°: see FaceMesher::folds

std::vector<geom::CuspTip> joined(std::vector<geom::CuspTip> a, const std::vector<geom::CuspTip>& b) {
  a.insert(a.end(), b.begin(), b.end());
  return a;
}

class FaceMesher {
 public:
  FaceMesher(const geom::Model& m, int face, const size::SizeField& size, const FaceMeshOptions& o,
             const std::vector<geom::CuspTip>& tips, const std::vector<geom::CuspTip>& keep_out)
      : m_(m), face_(face), size_(size), o_(o), tip_list_(tips), tips_(joined(tips, keep_out)),
        scale_(face_scaling(m, face)), accepted_(0.5 * o.max_edge) {}

  FaceMesh run(const std::vector<std::vector<BoundaryPoint>>& loops) {
    CdtInput in;
    for (const auto& loop : loops) {
      const int first = static_cast<int>(in.points.size());
      for (const BoundaryPoint& p : loop) {
        in.points.push_back(scale_.to_plane(p.uv));
        add_vertex(p.uv, m_.face_derivatives(face_, p.uv));
        xyz_.back() = p.xyz;  // the shared vertex itself, not the face's evaluation of it
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
    tip_of_.assign(out_.num_boundary, -1);
    for (std::size_t i = 0; i < tip_of_.size(); ++i)
      for (std::size_t k = 0; k < tip_list_.size(); ++k)
        if (xyz_[i] == tip_list_[k].point) tip_of_[i] = static_cast<int>(k);
    // Plane Delaunay -> surface Delaunay -> refinement -> what it left ->
    // validity -> quality -> validity under the exact fold test.
    std::vector<std::pair<int, int>> edges;
    for (std::size_t t = 0; t < t_.tris.size(); ++t)
      if (alive(t))
        for (int i = 0; i < 3; ++i) edges.push_back({static_cast<int>(t), i});
    metric_flips(edges);
    refine_frontal();
    split_long_edges();
    fix_folds();
    optimize();
    fix_folds();
    out_.uv = uv_;
    out_.xyz = xyz_;
    for (std::size_t t = 0; t < t_.tris.size(); ++t)
      if (alive(t)) out_.tris.push_back(t_.tris[t]);
    return std::move(out_);
  }

 private:
  // New points closer than this many sizes to a vertex are refused.
  static constexpr double kCrowded = 0.5;
  // The same for a tip fan's ring points (split_shell): the front may reach
  // the sphere before the fan is split, and a ring edge left several sizes
  // long beside a narrow strip makes a needle with a flat cap (fusee: 6.1°).
  static constexpr double kCrowdedOnSphere = 0.25;
  // Balls whose worst triangle is at least this good are smoothed for the
  // sum of qualities, the others for their worst triangle.
  static constexpr double kSmoothForMean = 0.7;
  // Valence flips: how many rounds (each followed by smoothing), and how
  // poor a pair of triangles they may leave for the smoothing to even out.
  static constexpr int kValencePasses = 2;
  // Below, the copy and the task of optimize's side-by-side runs cost more.
  static constexpr std::size_t kSideBySideVertices = 400;
  static constexpr double kValenceFloor = 0.6;

  bool alive(std::size_t t) const { return t_.is_live(static_cast<int>(t)); }

  // Inside a cusp tip's ball, which keeps no point but its vertex.
  bool in_tip(const Vec3& x) const { return tips_.contains(x); }

  double size_at(std::size_t i) const { return size_.size(xyz_[i], {{2, face_}, uv_[i]}); }

  // The first fundamental form in the scaled plane, at a plane point and at
  // vertex v.
  Metric2 surface_metric(const Vec2& plane) const {
    const geom::SurfaceDerivatives d = m_.face_derivatives(face_, scale_.to_uv(plane));
    const Vec3 ju = d.du / scale_.su, jv = d.dv / scale_.sv;
    return {ju.dot(ju), ju.dot(jv), jv.dot(jv)};
  }
  Metric2 metric(int v) const {
    const auto& [ju, jv] = tangent_[v];
    return {ju.dot(ju), ju.dot(jv), jv.dot(jv)};
  }
  // du × dv, or zero where the parametrization is singular (a pole).
  static Vec3 surface_normal(const geom::SurfaceDerivatives& d) {
    const Vec3 n = d.du.cross(d.dv);
    return n.norm() > 1e-12 * (d.du.squaredNorm() + d.dv.squaredNorm()) ? n.normalized() : Vec3::Zero();
  }

  // Vertex data but the size (h_), which costs curvature evaluations and is
  // only needed during refinement.
  void add_vertex(const Vec2& uv, const geom::SurfaceDerivatives& d) {
    uv_.push_back(uv);
    xyz_.push_back(d.point);
    normal_.push_back(surface_normal(d));
    tangent_.push_back({d.du / scale_.su, d.dv / scale_.sv});
  }

  // ---- Refinement ---------------------------------------------------------

  // 3D circumradius of a triangle in units of its vertices' mean size.
  double radius(const std::array<int, 3>& t) const {
    const Vec3 &a = xyz_[t[0]], &b = xyz_[t[1]], &c = xyz_[t[2]];
    const double la = (b - c).norm(), lb = (c - a).norm(), lc = (a - b).norm();
    const double h = (h_[t[0]] + h_[t[1]] + h_[t[2]]) / 3;
    const double longest = std::max({la, lb, lc}), shortest = std::min({la, lb, lc});
    const double area2 = (b - a).cross(c - a).norm();
    if (!(area2 > 1e-10 * longest * longest)) {
      // Two points of a pole: the triangle disappears from the surface mesh,
      // leaving its longest edge, which then wants the size.
      if (shortest <= 1e-9 * longest) return longest / (2 * h);
      return std::numeric_limits<double>::infinity();  // a sliver to split
    }
    return la * lb * lc / (2 * area2 * h);
  }

  // The edge of t on the front (the domain boundary or an accepted
  // neighbour) whose length is closest to the size, or -1.
  int front_edge(int t) const {
    int best = -1;
    double best_gap = 0;
    for (int i = 0; i < 3; ++i) {
      const int n = t_.adj[t][i];
      if (n >= 0 && !t_.is_constrained(t, i) && radius_[n] > accepted_) continue;
      const auto [a, b] = t_.edge(t, i);
      const double gap = std::abs((xyz_[a] - xyz_[b]).norm() * 2 / (h_[a] + h_[b]) - 1);
      if (best < 0 || gap < best_gap) {
        best = i;
        best_gap = gap;
      }
    }
    return best;
  }

  struct Active {
    double radius;
    int tri;
    std::array<int, 3> verts;
    bool operator<(const Active& o) const { return radius < o.radius || (radius == o.radius && tri > o.tri); }
  };

  void push_if_active(int t) {
    if (radius_[t] > accepted_ && front_edge(t) >= 0) active_.push({radius_[t], t, t_.tris[t]});
  }

  // Frontal-Delaunay refinement (Rebay; as in Gmsh's default surface
  // mesher): the largest triangle that touches the front (the boundary or
  // triangles already small enough) gets a point facing its front edge at
  // the height of an equilateral triangle of the local size, measured in
  // the surface's metric, so the points come in rows of near-equilateral
  // triangles instead of the scattered circumcentres of plain Delaunay
  // refinement. Each point goes in by a Bowyer–Watson cavity grown with the
  // anisotropic in-circle test of that metric, so a parametrization that
  // stretches one direction (towards a pole, on a long B-spline) does not
  // force an isotropic, and far too fine, point set in (u, v).
  void refine_frontal() {
    radius_.assign(t_.tris.size(), 0);
    for (std::size_t t = 0; t < t_.tris.size(); ++t)
      if (alive(t)) radius_[t] = radius(t_.tris[t]);
    for (std::size_t t = 0; t < t_.tris.size(); ++t)
      if (alive(t)) push_if_active(static_cast<int>(t));
    std::vector<int> fan;
    while (!active_.empty()) {
      const Active top = active_.top();
      active_.pop();
      if (!alive(top.tri) || t_.tris[top.tri] != top.verts || radius_[top.tri] != top.radius) continue;
      const int edge = front_edge(top.tri);
      if (edge < 0) continue;  // pushed again when a neighbour is accepted
      if (uv_.size() >= o_.max_points) break;
      if (!insert_frontal(top.tri, edge, fan)) {
        // Give up on this triangle (split_long_edges() may still split it)
        // and let the front move on past it.
        radius_[top.tri] = 0;
        for (const int n : t_.adj[top.tri])
          if (n >= 0) push_if_active(n);
        continue;
      }
      ++out_.refinement_insertions;
      radius_.resize(t_.tris.size(), 0);
      for (const int f : fan) radius_[f] = radius(t_.tris[f]);
      for (const int f : fan) {
        if (radius_[f] > accepted_) {
          push_if_active(f);
          continue;
        }
        for (const int n : t_.adj[f])
          if (n >= 0 && std::find(fan.begin(), fan.end(), n) == fan.end()) push_if_active(n);
      }
      if (alive(top.tri) && t_.tris[top.tri] == top.verts) push_if_active(top.tri);
    }
  }

  // The frontal point of triangle t facing its edge i, inserted; where the
  // face is narrower than the size it falls outside the face or onto the
  // far side, so t's circumcentre, else its centroid, is tried instead.
  bool insert_frontal(int t, int i, std::vector<int>& fan) {
    if (tip_corner(t) >= 0) return split_shell(t, fan);
    const auto& p = t_.points;
    const auto tv = t_.tris[t];
    const int a = tv[Triangulation2d::next(i)], b = tv[Triangulation2d::prev(i)];
    const Vec2 centroid = (p[tv[0]] + p[tv[1]] + p[tv[2]]) / 3;
    const Metric2 surface = surface_metric(centroid);
    const double h = 0.5 * (h_[a] + h_[b]);
    const Metric2 m = surface.scaled(1 / (h * h));  // unit length = the local size
    if (!m.positive()) return false;
    Vec2 centre;
    double r2;
    if (!metric_circumcircle(p[tv[0]], p[tv[1]], p[tv[2]], m, &centre, &r2)) return false;
    const Vec2 mid = 0.5 * (p[a] + p[b]);
    const Vec2 n = metric_normal(p[b] - p[a], m);  // into t, which lies left of a -> b
    // Never past the circumcentre, so the point stays inside t's
    // circumcircle and the cavity removes t.
    const double q = m.dot(centre - mid, n);
    const double along = q > 0 ? std::min(kHalfSqrt3, q) : std::min(kHalfSqrt3, 0.5 * (std::sqrt(r2) + q));
    if (along > 0 && insert_metric(mid + along * n, t, surface, fan) >= 0) return true;
    return insert_metric(centre, t, surface, fan) >= 0 || insert_metric(centroid, t, surface, fan) >= 0;
  }

  bool is_tip_vertex(int v) const {
    return static_cast<std::size_t>(v) < tip_of_.size() && tip_of_[static_cast<std::size_t>(v)] >= 0;
  }

  // The corner of t that is a cusp tip's vertex, or -1.
  int tip_corner(int t) const {
    for (int k = 0; k < 3; ++k)
      if (is_tip_vertex(t_.tris[t][k])) return k;
    return -1;
  }

  // A triangle of a tip's fan (its corner at the tip's vertex, the ball
  // holding no point) gets a point only on the sphere's trace it spans:
  // where the ray from the vertex through the middle of its far edge leaves
  // the ball, so the fan gets more, narrower needles while that edge is
  // longer than max_edge sizes. On the sphere, not beyond: the triangle's
  // circumcircle passes through the vertex, the sphere's centre, so it
  // holds the sphere's arc between the far edge's ends, and the point's
  // cavity takes the triangle.
  bool split_shell(int t, std::vector<int>& fan) {
    const int k = tip_corner(t);
    if (k < 0) return false;
    const auto tv = t_.tris[t];
    const int v = tv[k], a = tv[Triangulation2d::next(k)], b = tv[Triangulation2d::prev(k)];
    if ((xyz_[a] - xyz_[b]).norm() <= o_.max_edge * 0.5 * (h_[a] + h_[b])) return false;
    const geom::CuspTip& tip = tip_list_[tip_of_[v]];
    const Vec2 origin = t_.points[v], ray = 0.5 * (t_.points[a] + t_.points[b]) - origin;
    const double s = ray_leaves_ball(m_, face_, scale_, origin, ray, tip.point, tip.radius);
    if (std::isnan(s)) return false;
    const Vec2 x = origin + s * ray;
    Metric2 m = surface_metric(x);
    if (!m.positive()) m = Metric2{};
    return insert_metric(x, t, m, fan, true, kCrowdedOnSphere) >= 0;
  }

  // Inserts plane point x by a Bowyer–Watson cavity grown from the triangle
  // holding it (and from `seed` when x is in its circumcircle) with the
  // in-circle test of metric m; falls back to the exact Delaunay insertion
  // of the plane if that cavity is not star-shaped. Returns the vertex, or
  // -1 if x is outside the face or (with `crowding`) closer in 3D than
  // `crowded` sizes to a vertex of the cavity. `fan` gets the new triangles.
  int insert_metric(const Vec2& x, int seed, const Metric2& m, std::vector<int>& fan, bool crowding = true,
                    double crowded = kCrowded) {
    const Location loc = locate_point(t_, x, seed);
    if (loc.kind == Location::kOutside || loc.kind == Location::kOnVertex) return -1;
    const auto& p = t_.points;
    const auto in_circle = [&](int t) {
      const auto& tv = t_.tris[t];
      Vec2 centre;
      double r2;
      return metric_circumcircle(p[tv[0]], p[tv[1]], p[tv[2]], m, &centre, &r2) && m.norm2(x - centre) < r2;
    };
    cavity_.clear();
    const auto grow = [&](int from) {
      if (std::find(cavity_.begin(), cavity_.end(), from) != cavity_.end()) return;
      const std::size_t first = cavity_.size();
      cavity_.push_back(from);
      for (std::size_t k = first; k < cavity_.size(); ++k)
        for (int i = 0; i < 3; ++i) {
          const int n = t_.adj[cavity_[k]][i];
          if (n < 0 || t_.is_constrained(cavity_[k], i)) continue;
          if (std::find(cavity_.begin(), cavity_.end(), n) != cavity_.end() || !in_circle(n)) continue;
          cavity_.push_back(n);
        }
    };
    grow(loc.tri);
    if (seed != loc.tri && in_circle(seed)) grow(seed);
    const Vec2 uv = scale_.to_uv(x);
    const geom::SurfaceDerivatives d = m_.face_derivatives(face_, uv);
    // Even uncrowded, never onto a vertex (a folded sliver's centroid can be).
    const double apart = crowding ? crowded : 1e-9;
    if (crowding && in_tip(d.point)) return -1;
    for (const int t : cavity_)
      for (const int v : t_.tris[t])
        if ((d.point - xyz_[v]).norm() < apart * h_[v]) return -1;
    int id = t_.insert_in_cavity(x, cavity_, &fan);
    if (id < 0) {
      if (loc.kind == Location::kOnEdge && t_.is_constrained(loc.tri, loc.index)) return -1;
      id = insert_point(t_, x, loc.tri);
      if (id < 0) return -1;
      t_.triangles_around(id, fan);
    }
    add_vertex(uv, d);
    h_.push_back(size_at(uv_.size() - 1));
    CM_ASSERT(static_cast<std::size_t>(id) + 1 == uv_.size());
    return id;
  }

  // Longest edge of a triangle in units of the local size.
  double longest(const std::array<int, 3>& t) const {
    double worst = 0;
    for (int k = 0; k < 3; ++k) {
      const int a = t[(k + 1) % 3], b = t[(k + 2) % 3];
      worst = std::max(worst, (xyz_[a] - xyz_[b]).norm() * 2 / (h_[a] + h_[b]));
    }
    return worst;
  }

  // What the front left behind (triangles it gave up on, sizes that vary
  // faster than the front can follow): triangles with an edge over
  // max_edge get their metric circumcentre, else their centroid, longest
  // first, until none can take a point.
  void split_long_edges() {
    struct Candidate {
      double length;
      int tri;
      std::array<int, 3> verts;
    };
    std::vector<Candidate> cands;
    std::vector<int> fan;
    for (;;) {
      cands.clear();
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
        if (tip_corner(c.tri) >= 0) {
          if (split_shell(c.tri, fan)) ++inserted;
          continue;
        }
        const auto& p = t_.points;
        const Vec2 centroid = (p[c.verts[0]] + p[c.verts[1]] + p[c.verts[2]]) / 3;
        Metric2 m = surface_metric(centroid);
        if (!m.positive()) m = Metric2{};
        Vec2 centre;
        double r2;
        if ((metric_circumcircle(p[c.verts[0]], p[c.verts[1]], p[c.verts[2]], m, &centre, &r2) &&
             insert_metric(centre, c.tri, m, fan) >= 0) ||
            insert_metric(centroid, c.tri, m, fan) >= 0)
          ++inserted;
      }
      out_.refinement_insertions += inserted;
      if (inserted == 0) break;
    }
  }

  // ---- Connectivity -------------------------------------------------------

  // Lawson flips towards the Delaunay triangulation of the surface's own
  // metric: an edge goes when the opposite vertex lies inside the metric
  // circumcircle, the metric being the first fundamental form at the centre
  // of the quadrilateral (the same for both of its diagonals, so a flipped
  // edge never flips back at once). Where (u, v) is far from isometric (a
  // pole, a narrow wedge) the plane's Delaunay triangles joining points
  // close in (u, v) but far apart on the surface become the surface's.
  // Only strictly convex quadrilaterals flip, so (u, v) stays valid; the
  // metric varies, so the count is bounded rather than proven finite.
  void metric_flips(std::vector<std::pair<int, int>>& edges) {
    const auto& p = t_.points;
    std::size_t budget = 8 * edges.size() + 64;
    while (!edges.empty() && budget-- > 0) {
      const auto [t, i] = edges.back();
      edges.pop_back();
      if (!alive(t)) continue;
      const int u = t_.adj[t][i];
      if (u < 0 || t_.is_constrained(t, i)) continue;
      const auto& tv = t_.tris[t];
      const int a = tv[i], b = tv[Triangulation2d::next(i)], c = tv[Triangulation2d::prev(i)];
      const int d = t_.tris[u][t_.mirror(t, i)];
      if (predicates::orient2d(p[a].data(), p[b].data(), p[d].data()) <= 0 ||
          predicates::orient2d(p[d].data(), p[c].data(), p[a].data()) <= 0)
        continue;
      const Metric2 m = surface_metric((p[a] + p[b] + p[c] + p[d]) / 4);
      Vec2 centre;
      double r2;
      if (!m.positive() || !metric_circumcircle(p[a], p[b], p[c], m, &centre, &r2) || !(m.norm2(p[d] - centre) < r2))
        continue;
      t_.flip(t, i);  // t = (a, b, d), u = (d, c, a)
      ++out_.flips;
      edges.push_back({t, 0});
      edges.push_back({t, 2});
      edges.push_back({u, 0});
      edges.push_back({u, 2});
    }
  }

  // Whether (a, b, c), positive in (u, v), folds against the surface: its
  // normal against du × dv at its centroid (as the boundary check judges),
  // turned by more than about 80°. A triangle nearly edge-on to its face (a
  // fan over a tiny, strongly curved face) counts: a Steiner point that
  // recovery puts on the face there folds the triangles it splits.
  bool folds(int a, int b, int c) const {
    if (xyz_[a] == xyz_[b] || xyz_[b] == xyz_[c] || xyz_[c] == xyz_[a]) return false;  // vanishes at a pole
    const Vec3 n = (xyz_[b] - xyz_[a]).cross(xyz_[c] - xyz_[a]);
    const geom::SurfaceDerivatives d = m_.face_derivatives(face_, (uv_[a] + uv_[b] + uv_[c]) / 3);
    const Vec3 sn = d.du.cross(d.dv);
    return !(n.dot(sn) > kNearFold * n.norm() * sn.norm());
  }

  // Triangles that fold against the surface (a sliver of boundary points
  // over a sharp bend, what the optimization's cheaper test let through)
  // are invalid whatever their size: each gets the flip of one of its edges
  // that makes both new triangles positive, else a point at its centroid
  // however close that is to its vertices.
  void fix_folds() {
    std::vector<int> fan;
    for (int round = 0; round < 4; ++round) {
      int fixed = 0;
      // A centroid's triangles may fold again: split in the same sweep they
      // went on without end (a KiCad connector, 23 GB); they wait a round.
      const std::size_t existing = t_.tris.size();
      for (std::size_t ut = 0; ut < existing; ++ut) {
        const int t = static_cast<int>(ut);
        if (!alive(t)) continue;
        const auto tv = t_.tris[t];
        if (!folds(tv[0], tv[1], tv[2])) continue;
        int best = -1;
        double best_q = 0;
        for (int i = 0; i < 3; ++i) {
          const int u = t_.adj[t][i];
          if (u < 0 || t_.is_constrained(t, i)) continue;
          const int a = tv[i], b = tv[Triangulation2d::next(i)], c = tv[Triangulation2d::prev(i)];
          const int d = t_.tris[u][t_.mirror(t, i)];
          // flip(t, i) makes (a, b, d) and (d, c, a).
          if (folds(a, b, d) || folds(d, c, a)) continue;
          const double q = std::min(quality(a, b, d), quality(d, c, a));
          if (q > best_q) {
            best = i;
            best_q = q;
          }
        }
        if (best >= 0) {
          t_.flip(t, best);
          ++fixed;
          continue;
        }
        const auto& p = t_.points;
        const Vec2 centroid = (p[tv[0]] + p[tv[1]] + p[tv[2]]) / 3;
        Metric2 m = surface_metric(centroid);
        if (!m.positive()) m = Metric2{};
        if (insert_metric(centroid, t, m, fan, false) >= 0) ++fixed;
      }
      if (fixed == 0) break;
    }
  }

  // ---- Optimization -------------------------------------------------------

  // Quality of a triangle on the surface, as the optimization judges it: its
  // 3D mean ratio, or -1 if it is inverted in (u, v) or its normal turns
  // away from the surface normal at one of its vertices (cached, so a move
  // costs one evaluation of the surface; fix_folds() checks the centroid).
  double quality(int a, int b, int c) const {
    const auto& p = t_.points;
    if (predicates::orient2d(p[a].data(), p[b].data(), p[c].data()) <= 0) return -1;
    // Two points of a pole: the triangle vanishes from the surface mesh.
    if (xyz_[a] == xyz_[b] || xyz_[b] == xyz_[c] || xyz_[c] == xyz_[a]) return 1;
    const Vec3 n = (xyz_[b] - xyz_[a]).cross(xyz_[c] - xyz_[a]);
    if (!(n.dot(normal_[a]) >= 0 && n.dot(normal_[b]) >= 0 && n.dot(normal_[c]) >= 0) ||
        (normal_[a] + normal_[b] + normal_[c]).dot(n) <= 0)
      return -1;
    return quality::triangle_mean_ratio(xyz_[a], xyz_[b], xyz_[c]);
  }

  // One sweep over the unconstrained edges, each seen once from its
  // lower-numbered triangle: edge b-c of t = (a, b, c) and
  // u = (d, c, b) is flipped to (a, b, d), (d, c, a) when decide(a, b, c, d)
  // says so (decide may record the flip it accepts). Each triangle flips at
  // most once per sweep; its other edges are seen on the next one. The
  // spokes of a tip's fan stay: its needles are poor by any triangle
  // measure, and what a flip would make of them is worse (a cap).
  template <class Decide>
  int flip_where(Decide decide) {
    int flips = 0;
    for (std::size_t t = 0; t < t_.tris.size(); ++t) {
      if (!alive(t)) continue;
      for (int i = 0; i < 3; ++i) {
        const int u = t_.adj[t][i];
        if (u < 0 || static_cast<std::size_t>(u) < t || t_.is_constrained(static_cast<int>(t), i)) continue;
        const auto tv = t_.tris[t];
        const int a = tv[i], b = tv[Triangulation2d::next(i)], c = tv[Triangulation2d::prev(i)];
        const int d = t_.tris[u][t_.mirror(static_cast<int>(t), i)];
        if (is_tip_vertex(b) || is_tip_vertex(c)) continue;
        if (decide(a, b, c, d)) {
          t_.flip(static_cast<int>(t), i);
          ++flips;
          break;
        }
      }
    }
    out_.flips += flips;
    return flips;
  }

  // Flips for the pair's worst triangle.
  int flip_pass() {
    return flip_where([&](int a, int b, int c, int d) {
      const double before = std::min(quality(a, b, c), quality(d, c, b));
      const double after = std::min(quality(a, b, d), quality(d, c, a));
      return after > 0 && after > before + 1e-6 * std::abs(before) + 1e-12;
    });
  }

  // The vertex state the optimization changes (not h_), from a copy.
  void take_state(FaceMesher&& other) {
    t_ = std::move(other.t_);
    uv_ = std::move(other.uv_);
    xyz_ = std::move(other.xyz_);
    normal_ = std::move(other.normal_);
    tangent_ = std::move(other.tangent_);
    out_.flips = other.out_.flips;
    out_.smoothing_moves = other.out_.smoothing_moves;
  }
  // Worst and sum of the triangle qualities.
  std::pair<double, double> quality_summary() const {
    double worst = 1, sum = 0;
    for (std::size_t t = 0; t < t_.tris.size(); ++t)
      if (alive(t)) {
        const auto& v = t_.tris[t];
        const double q = quality(v[0], v[1], v[2]);
        worst = std::min(worst, q);
        sum += q;
      }
    return {worst, sum};
  }

  // Flips and smoothing for the worst triangles converge to a mesh whose
  // vertex valences stay as the refinement left them; flips towards valence
  // 6 first, then the same passes, give more regular and on average better
  // triangles, but may leave a worse worst one where a flip to a poorer pair
  // is not undone. Both run from the same start, the regular one on a copy
  // (side by side for a large face: one big face, a torus, would leave a
  // core idle), and it is kept only when its worst triangle is no worse and
  // its sum is larger: the extra step never lowers the face's worst.
  void optimize() {
    const auto passes = [](FaceMesher& f) {
      for (int pass = 0; pass < f.o_.optimize_passes; ++pass)
        if (f.flip_pass() + f.smooth_pass() == 0) break;
    };
    const auto regular_passes = [&](FaceMesher& f) {
      for (int pass = 0; pass < kValencePasses; ++pass) {
        if (f.valence_pass() == 0) break;
        f.smooth_pass();
      }
      passes(f);
    };
    FaceMesher regular(*this);
    if (uv_.size() >= kSideBySideVertices) {
      tbb::parallel_invoke([&] { passes(*this); }, [&] { regular_passes(regular); });
    } else {
      passes(*this);
      regular_passes(regular);
    }
    const auto [plain_worst, plain_sum] = quality_summary();
    const auto [regular_worst, regular_sum] = regular.quality_summary();
    if (regular_worst >= plain_worst && regular_sum > plain_sum) take_state(std::move(regular));
  }

  // Flips an edge when that brings the valences of its four vertices (the
  // interior ones: a boundary vertex's ideal valence depends on its angle)
  // closer to 6 and leaves the pair's worst triangle above kValenceFloor or
  // no worse than before.
  int valence_pass() {
    std::vector<int> val(uv_.size(), 0);
    for (std::size_t t = 0; t < t_.tris.size(); ++t)
      if (alive(t))
        for (const int v : t_.tris[t]) ++val[v];
    const auto nb = static_cast<int>(out_.num_boundary);
    const auto dev = [&](int v, int dv) { return v < nb ? 0 : std::abs(val[v] + dv - 6); };
    return flip_where([&](int a, int b, int c, int d) {
      if (dev(a, 1) + dev(b, -1) + dev(c, -1) + dev(d, 1) >= dev(a, 0) + dev(b, 0) + dev(c, 0) + dev(d, 0))
        return false;
      const double before = std::min(quality(a, b, c), quality(d, c, b));
      const double after = std::min(quality(a, b, d), quality(d, c, a));
      if (!(after > 0 && after >= std::min(before, kValenceFloor))) return false;
      ++val[a];
      ++val[d];
      --val[b];
      --val[c];
      return true;
    });
  }

  // Moves each interior vertex towards the mean of the apexes of the
  // equilateral triangles standing on the edges of its ball, built in 3D in
  // the tangent plane at the vertex and taken back to the plane through the
  // tangent map (least squares), which evens out shapes and edge lengths
  // whatever the parametrization does. A move is kept when no triangle of
  // the ball folds, its worst one does not get worse and the sum of
  // qualities grows; balls with a poor triangle (or where that fails) take
  // whichever of that point, the plain centroid of the neighbours and the
  // halfway points raises their worst triangle most.
  int smooth_pass() {
    const std::size_t nv = uv_.size();
    const Triangulation2d::Balls balls = t_.balls();
    int moves = 0;
    for (std::size_t uv = out_.num_boundary; uv < nv; ++uv) {
      const int v = static_cast<int>(uv);
      const int* first = balls.tris_of.data() + balls.start[uv];
      const int* last = balls.tris_of.data() + balls.start[uv + 1];
      if (first == last) continue;
      // A tip's fan keeps its far points where they went in, on the sphere.
      if (std::any_of(first, last, [&](int t) { return tip_corner(t) >= 0; })) continue;
      const auto ball_quality = [&](double* worst) {
        double sum = 0;
        *worst = 1;
        for (const int* t = first; t != last; ++t) {
          const auto& tv = t_.tris[*t];
          const double q = quality(tv[0], tv[1], tv[2]);
          *worst = std::min(*worst, q);
          sum += q;
        }
        return sum;
      };
      double old_worst;
      const double old_sum = ball_quality(&old_worst);
      const double count = static_cast<double>(last - first);
      const Vec2 old_plane = t_.points[v];
      Vec2 centroid = Vec2::Zero();
      Vec3 apexes = Vec3::Zero();
      for (const int* t = first; t != last; ++t) {
        const auto& tv = t_.tris[*t];
        const int k = t_.local_index(*t, v);
        const int a = tv[Triangulation2d::next(k)], b = tv[Triangulation2d::prev(k)];
        centroid += t_.points[a] + t_.points[b];
        // On the side of a -> b where v is, seen along the normal.
        const Vec3 e = xyz_[b] - xyz_[a];
        Vec3 w = normal_[v].cross(e);
        const double wn = w.norm();
        if (wn > 0) w *= kHalfSqrt3 * e.norm() / wn;
        apexes += 0.5 * (xyz_[a] + xyz_[b]) + w;
      }
      centroid /= 2 * count;
      const Vec3 pull = apexes / count - xyz_[v];
      const Metric2 m = metric(v);
      const double ru = tangent_[v][0].dot(pull), rv = tangent_[v][1].dot(pull), det = m.a * m.c - m.b * m.b;
      const Vec2 ideal = old_plane + Vec2(m.c * ru - m.b * rv, m.a * rv - m.b * ru) / det;
      const Vec2 old_uv = uv_[v];
      const Vec3 old_xyz = xyz_[v], old_normal = normal_[v];
      const auto old_tangent = tangent_[v];
      const auto try_move = [&](const Vec2& to) {
        if (!to.allFinite()) return false;
        const Vec2 to_uv = scale_.to_uv(to);
        const geom::SurfaceDerivatives d = m_.face_derivatives(face_, to_uv);
        if (in_tip(d.point)) return false;
        t_.points[v] = to;
        uv_[v] = to_uv;
        xyz_[v] = d.point;
        normal_[v] = surface_normal(d);
        tangent_[v] = {d.du / scale_.su, d.dv / scale_.sv};
        return true;
      };
      // Good balls chase the mean; poor ones (or if that fails) take the
      // candidate with the best worst triangle.
      bool moved = false;
      if (old_worst >= kSmoothForMean && m.positive())
        for (const double step : {1.0, 0.5}) {
          if (!try_move(old_plane + step * (ideal - old_plane))) break;
          double worst;
          const double sum = ball_quality(&worst);
          if (worst > 0 && worst >= old_worst && sum > old_sum + 1e-9 * count) {
            moved = true;
            break;
          }
        }
      if (!moved) {
        Vec2 best = old_plane;
        double best_worst = old_worst + 1e-6 * std::abs(old_worst);
        const Vec2 candidates[] = {centroid, ideal, 0.5 * (old_plane + ideal), 0.5 * (old_plane + centroid)};
        for (const Vec2& c : candidates) {
          if (!try_move(c)) continue;
          double worst;
          ball_quality(&worst);
          if (worst > best_worst) {
            best = c;
            best_worst = worst;
          }
        }
        // A poor ball left poor: a compass search on its worst triangle.
        if (best_worst < kSmoothForMean) {
          double reach = 0;
          for (const int* t = first; t != last; ++t)
            for (const int w : t_.tris[*t]) reach = std::max(reach, (t_.points[w] - old_plane).norm());
          for (double step = 0.25 * reach; step > 1e-3 * reach;) {
            bool better = false;
            const Vec2 from = best;
            for (int k = 0; k < 8; ++k) {
              const double angle = k * std::numbers::pi / 4;
              const Vec2 c = from + step * Vec2(std::cos(angle), std::sin(angle));
              if (!try_move(c)) continue;
              double worst;
              ball_quality(&worst);
              if (worst > best_worst) {
                best = c;
                best_worst = worst;
                better = true;
              }
            }
            if (!better) step *= 0.5;
          }
        }
        moved = best != old_plane && try_move(best);
      }
      if (moved) {
        ++moves;
      } else {
        t_.points[v] = old_plane;
        uv_[v] = old_uv;
        xyz_[v] = old_xyz;
        normal_[v] = old_normal;
        tangent_[v] = old_tangent;
      }
    }
    out_.smoothing_moves += moves;
    return moves;
  }

  const geom::Model& m_;
  int face_;
  const size::SizeField& size_;
  const FaceMeshOptions& o_;
  const std::vector<geom::CuspTip>& tip_list_;
  geom::TipBalls tips_;
  std::vector<int> tip_of_;  // per boundary point (only those can be): the tip it is the vertex of, or -1
  Scaling scale_;
  // A triangle whose 3D circumradius is under this many local sizes has all
  // its edges under max_edge sizes: it needs no point.
  double accepted_;
  Triangulation2d t_;
  // Per vertex: (u, v), the point, the unit normal du × dv (zero at a pole),
  // the derivatives of the point along the scaled plane's axes, the size
  // (refinement only: the optimization does not update it).
  std::vector<Vec2> uv_;
  std::vector<Vec3> xyz_;
  std::vector<Vec3> normal_;
  std::vector<std::array<Vec3, 2>> tangent_;
  std::vector<double> h_;
  // Refinement state: per triangle slot, its radius(); the front; scratch.
  std::vector<double> radius_;
  std::priority_queue<Active> active_;
  std::vector<int> cavity_;
  FaceMesh out_;
};

}  // namespace

FaceMesh mesh_face(const geom::Model& model, int face, const std::vector<std::vector<BoundaryPoint>>& loops,
                   const size::SizeField& size, const FaceMeshOptions& options,
                   const std::vector<geom::CuspTip>& tips, const std::vector<geom::CuspTip>& keep_out) {
  return FaceMesher(model, face, size, options, tips, keep_out).run(loops);
}

}  // namespace cm::generate
