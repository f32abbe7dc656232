#include "curvemesh/curved/nodes.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <unordered_map>

#include <fmt/format.h>
#include <tbb/parallel_for.h>

#include "curvemesh/mesh/topology.hpp"
#include "curvemesh/modify/surface.hpp"

namespace cm::curved {

namespace {

// Arc length is tabulated on this many chords between the two parameters:
// the nodes then sit at their fraction of the length to well under a
// percent on any edge a mesh edge spans.
constexpr int kArcSamples = 32;

// A node evaluated at interpolated (u, v) is kept when it lies within this
// fraction of its polyline segment's length from the polyline: a smooth
// face's arc over a segment strays a few percent (its sagitta), a
// parametrization that is degenerate between the two points much more.
constexpr double kMaxStray = 0.25;

// Brings b within half a period of a in the periodic directions.
double near_in_period(double a, double b, bool periodic, double period) {
  if (!periodic || !(period > 0)) return b;
  return b - std::round((b - a) / period) * period;
}

}  // namespace

std::optional<Vec2> NodePlacer::face_hint(VertId v, int face) const {
  return modify::param_on_face(m_, &model_, v, face);
}

Vec3 NodePlacer::project_on_face(int face, const Vec3& x, std::optional<Vec2> hint) const {
  return model_.closest_point({2, face}, x, hint).point;
}

void NodePlacer::edge_nodes(VertId a, VertId b, mesh::ModelRef on, Vec3* out) const {
  const int p = order();
  const Vec3 xa = m_.coords[a], xb = m_.coords[b];
  if (on.dim == 1) {
    const int e = on.tag;
    std::optional<double> ua = modify::param_on_edge(m_, &model_, a, e);
    std::optional<double> ub = modify::param_on_edge(m_, &model_, b, e, ua);
    if (!ua && ub) ua = modify::param_on_edge(m_, &model_, a, e, ub);
    if (ua && ub) {
      const geom::ParamRange r = model_.param_range({1, e});
      const double u0 = *ua, u1 = near_in_period(u0, *ub, r.periodic_u, r.period_u);
      std::array<double, kArcSamples + 1> length{};
      Vec3 prev = xa;
      for (int k = 1; k <= kArcSamples; ++k) {
        const Vec3 x = model_.edge_point(e, u0 + (u1 - u0) * k / kArcSamples);
        length[k] = length[k - 1] + (x - prev).norm();
        prev = x;
      }
      for (int s = 1; s < p; ++s) {
        const double target = length[kArcSamples] * s / p;
        const int k = static_cast<int>(
            std::clamp<std::ptrdiff_t>(std::upper_bound(length.begin(), length.end(), target) - length.begin(), 1,
                                       kArcSamples));
        const double span = length[k] - length[k - 1];
        const double t = span > 0 ? (target - length[k - 1]) / span : 0.5;
        out[s - 1] = model_.edge_point(e, u0 + (u1 - u0) * (k - 1 + t) / kArcSamples);
      }
      return;
    }
    for (int s = 1; s < p; ++s) out[s - 1] = model_.closest_point({1, e}, xa + (xb - xa) * (double(s) / p)).point;
    return;
  }
  const int f = on.tag;
  std::optional<Vec2> ha = face_hint(a, f), hb = face_hint(b, f);
  const geom::ParamRange r = model_.param_range({2, f});
  if (ha && hb) {
    hb = Vec2(near_in_period(ha->x(), hb->x(), r.periodic_u, r.period_u),
              near_in_period(ha->y(), hb->y(), r.periodic_v, r.period_v));
  }
  auto hint_at = [&](double t) {
    return ha && hb ? std::optional<Vec2>(*ha + (*hb - *ha) * t) : (ha ? ha : hb);
  };
  auto on_face = [&](double t) { return model_.closest_point({2, f}, xa + (xb - xa) * t, hint_at(t)); };
  if (p == 2) {
    out[0] = on_face(0.5).point;
    return;
  }
  // Projected chord points bunch toward the ends of an edge that bends
  // much (on a cylinder, the middle third of a quarter-circle edge spans 37°
  // against 26° for the others), and uneven nodes make det J vary. So the
  // chord fractions are corrected once: the polyline through the first
  // projections maps chord fraction to length, piecewise linearly, and the
  // nodes are placed again at equal lengths (within a fraction of a percent
  // of the arc's thirds on a quarter circle). With the vertices' (u, v)
  // known, a corrected node is the face's point at the (u, v) interpolated
  // the same way between the projections' parameters: one evaluation where
  // a projection is several, and on the face by construction. Where that
  // point strays from the polyline (a parametrization degenerate at a pole,
  // a seam), it is projected from the chord instead.
  std::array<double, mesh::kMaxOrder + 1> t{}, length{};
  std::array<Vec3, mesh::kMaxOrder + 1> x{};
  std::array<Vec2, mesh::kMaxOrder + 1> uv{};
  const bool have_params = ha && hb;
  x[0] = xa;
  x[p] = xb;
  if (have_params) {
    uv[0] = *ha;
    uv[p] = *hb;
  }
  for (int s = 0; s <= p; ++s) t[s] = double(s) / p;
  for (int s = 1; s < p; ++s) {
    const geom::Projection q = on_face(t[s]);
    x[s] = q.point;
    if (have_params) {
      const Vec2 near = *hint_at(t[s]);
      uv[s] = Vec2(near_in_period(near.x(), q.param.x(), r.periodic_u, r.period_u),
                   near_in_period(near.y(), q.param.y(), r.periodic_v, r.period_v));
    }
  }
  for (int s = 1; s <= p; ++s) length[s] = length[s - 1] + (x[s] - x[s - 1]).norm();
  for (int s = 1; s < p; ++s) {
    const double target = length[p] * s / p;
    int k = 1;
    while (k < p && length[k] < target) ++k;
    const double span = length[k] - length[k - 1];
    const double w = span > 0 ? (target - length[k - 1]) / span : 0.5;
    if (have_params) {
      const Vec3 y = model_.face_point(f, uv[k - 1] + w * (uv[k] - uv[k - 1]));
      const Vec3 on_polyline = x[k - 1] + w * (x[k] - x[k - 1]);
      if ((y - on_polyline).norm() <= kMaxStray * span) {
        out[s - 1] = y;
        continue;
      }
    }
    out[s - 1] = on_face(t[k - 1] + w * (t[k] - t[k - 1])).point;
  }
}

void NodePlacer::face_nodes(VertId a, VertId b, VertId c, int face, const Vec3* ab, const Vec3* bc, const Vec3* ca,
                            Vec3* out) const {
  if (order() < 3) return;
  // The cubic triangle's centroid from its boundary nodes: exact for any
  // quadratic map, so a triangle whose edges follow a smooth face gets the
  // point the face's second-order shape puts there, before projection.
  const Vec3 edge_sum = ab[0] + ab[1] + bc[0] + bc[1] + ca[0] + ca[1];
  const Vec3 corners = m_.coords[a] + m_.coords[b] + m_.coords[c];
  const Vec3 centroid = edge_sum / 4 - corners / 6;
  std::optional<Vec2> hint;
  const geom::ParamRange r = model_.param_range({2, face});
  Vec2 sum = Vec2::Zero();
  int n = 0;
  std::optional<Vec2> first;
  for (VertId v : {a, b, c}) {
    std::optional<Vec2> h = face_hint(v, face);
    if (!h) continue;
    if (first)
      h = Vec2(near_in_period(first->x(), h->x(), r.periodic_u, r.period_u),
               near_in_period(first->y(), h->y(), r.periodic_v, r.period_v));
    else
      first = h;
    sum += *h;
    ++n;
  }
  if (n > 0) hint = sum / n;
  out[0] = project_on_face(face, centroid, hint);
}

PlacementStats place_boundary_nodes(mesh::TetMesh& m, const geom::Model& model, int order) {
  if (order < 2 || order > 3) throw std::invalid_argument(fmt::format("curved elements of order {}: 2 or 3", order));
  m.high_order.reset(order);
  PlacementStats st;
  auto key = [](VertId a, VertId b) {
    if (a > b) std::swap(a, b);
    return (std::uint64_t(a) << 32) | b;
  };
  std::unordered_map<std::uint64_t, int> model_edge;
  model_edge.reserve(m.edges.size());
  for (const auto& e : m.edges) model_edge.emplace(key(e.verts[0], e.verts[1]), e.edge_tag);
  // Each boundary edge once, with the entity it is on.
  struct Job {
    VertId a, b;
    mesh::ModelRef on;
  };
  std::vector<Job> jobs;
  std::unordered_map<std::uint64_t, std::uint32_t> job_of;
  job_of.reserve(3 * m.tris.size());
  for (const auto& t : m.tris)
    for (const auto& e : mesh::kTriEdges) {
      const VertId a = t.verts[e[0]], b = t.verts[e[1]];
      if (!job_of.emplace(key(a, b), static_cast<std::uint32_t>(jobs.size())).second) continue;
      const auto it = model_edge.find(key(a, b));
      jobs.push_back({a, b, it != model_edge.end() ? mesh::ModelRef{1, it->second} : mesh::ModelRef{2, t.face_tag}});
    }
  // Model edges no triangle holds (a wire of the model) are curved too.
  for (const auto& e : m.edges)
    if (job_of.emplace(key(e.verts[0], e.verts[1]), static_cast<std::uint32_t>(jobs.size())).second)
      jobs.push_back({e.verts[0], e.verts[1], {1, e.edge_tag}});
  const std::size_t per_edge = static_cast<std::size_t>(order - 1);
  std::vector<Vec3> nodes(jobs.size() * per_edge);
  const NodePlacer placer(m, model);
  tbb::parallel_for(std::size_t{0}, jobs.size(),
                    [&](std::size_t i) { placer.edge_nodes(jobs[i].a, jobs[i].b, jobs[i].on, &nodes[i * per_edge]); });
  for (std::size_t i = 0; i < jobs.size(); ++i) {
    m.high_order.set_edge(jobs[i].a, jobs[i].b, std::span<const Vec3>(&nodes[i * per_edge], per_edge));
    ++(jobs[i].on.dim == 1 ? st.edges_on_model_edges : st.edges_on_model_faces);
  }
  if (order == 3) {
    std::vector<Vec3> centre(m.tris.size());
    tbb::parallel_for(std::size_t{0}, m.tris.size(), [&](std::size_t i) {
      const auto& v = m.tris[i].verts;
      std::array<std::array<Vec3, 2>, 3> e;
      for (int k = 0; k < 3; ++k) m.high_order.get_edge(v[k], v[(k + 1) % 3], e[k].data());
      placer.face_nodes(v[0], v[1], v[2], m.tris[i].face_tag, e[0].data(), e[1].data(), e[2].data(), &centre[i]);
    });
    for (std::size_t i = 0; i < m.tris.size(); ++i) {
      const auto& v = m.tris[i].verts;
      m.high_order.set_face(v[0], v[1], v[2], std::span<const Vec3>(&centre[i], 1));
    }
    st.faces = m.tris.size();
  }
  return st;
}

}  // namespace cm::curved
