#include "curvemesh/optimize/vertex_search.hpp"

#include <algorithm>
#include <cmath>
#include <span>
#include <vector>

#include "curvemesh/mesh/adjacency.hpp"
#include "curvemesh/mesh/topology.hpp"
#include "curvemesh/optimize/measured_swap.hpp"

namespace cm::optimize {

namespace {

// A point of the search: where it is, its parameters on the entity, and
// its rank: the worst angle-aware quality of the tets it makes up to the
// goal (-1 where a tet would be invalid or its mean ratio under the floor),
// then their worst mean ratio. Past the goal the search raises the mean
// ratio instead of trading it for angles no one asked for.
struct Poll {
  Vec3 point = Vec3::Zero();
  Vec2 param = Vec2::Zero();
  double score = -1, tie = -1;
};

bool better(const Poll& p, const Poll& q, double margin) {
  return p.score > q.score + margin || (p.score >= q.score - 1e-12 && p.tie > q.tie + margin);
}

// Compass search from `first` (offset 0): each round polls the directions
// `guided` proposes at the current best, then ± each axis of `frame`, at
// step h, and moves to the first poll that improves (then on along it, the
// step doubling, while that pays); a round without improvement halves h.
// Stops after max_polls polls or when h falls under h0 / 64.
// poll_at(offset, below) -> Poll; guided(point, directions&) appends unit
// vectors. A poll whose worst tet already scores under `below` cannot be
// better than the current best, so poll_at may stop there and return a
// failed poll (score -1): most polls fail, and most fail at the tet that
// was worst before.
template <class PollAt, class Guided>
Poll compass_search(const Poll& first, std::span<const Vec3> frame, double h0, int max_polls, PollAt&& poll_at,
                    Guided&& guided) {
  Poll best = first;
  Vec3 offset = Vec3::Zero();
  double h = h0;
  int polls = 0;
  thread_local std::vector<Vec3> directions;
  while (polls < max_polls && h > h0 / 64) {
    directions.clear();
    guided(best.point, directions);
    for (const Vec3& axis : frame) {
      directions.push_back(axis);
      directions.push_back(-axis);
    }
    bool moved = false;
    for (const Vec3& d : directions) {
      if (polls >= max_polls) break;
      ++polls;
      const Poll p = poll_at(offset + h * d, best.score - 1e-12);
      if (!better(p, best, 1e-9)) continue;
      best = p;
      offset += h * d;
      moved = true;
      // Keep going while it pays: a sliver may need a long way.
      while (polls < max_polls) {
        ++polls;
        const Poll q = poll_at(offset + 2 * h * d, best.score - 1e-12);
        if (!better(q, best, 1e-9)) break;
        best = q;
        h *= 2;
        offset += h * d;
      }
      break;
    }
    if (!moved) h *= 0.5;
  }
  return best;
}

}  // namespace

modify::Relocation plan_searched_relocation(modify::MeshEditor& ed, modify::Cavity& cav,
                                            const modify::BoundaryIndex* boundary, VertId v,
                                            const geom::Model* model, double angle_goal, int max_polls,
                                            const geom::TipBalls* keep_out) {
  auto& m = ed.mesh();
  modify::Relocation refused;
  refused.refusal = modify::Refusal::kClassification;
  const mesh::ModelRef c = v < m.vert_class.size() ? m.vert_class[v] : mesh::ModelRef{};
  const int dim = c.dim == 3 ? 3 : c.dim == 2 ? 2 : c.dim == 1 ? 1 : 0;
  if (dim == 0 || m.vert2tet[v] == kNone || (dim < 3 && (!model || !boundary))) return refused;

  thread_local std::vector<TetId> ball;
  mesh::collect_ball(m, v, ball);
  const Vec3 start = m.coords[v];
  // A point of a tip's cap moves over the cap only: off the sphere, it
  // leaves a hole in the cap that the needles at the tip's vertex span.
  // The needles (its tets at the tip's vertex) are ranked by their angles
  // alone, as the driver judges them: their mean ratio is low by design,
  // and raising it widens the cap triangles whatever their shape.
  const geom::CuspTip* cap = dim == 3 && keep_out ? keep_out->sphere_of(start) : nullptr;
  thread_local std::vector<char> needle;
  needle.assign(ball.size(), 0);
  if (cap)
    for (std::size_t i = 0; i < ball.size(); ++i)
      for (const VertId w : m.tet2verts[ball[i]])
        needle[i] = needle[i] || m.coords[w] == cap->point;
  // Ranks a position (see Poll), the mean ratio floor being what
  // is_progress keeps the ball's worst at (mean_ratio_floor of its worst
  // now), so the search never leaves what the driver accepts.
  const double goal = angle_goal / kRegularDihedral;
  double floor = -1;
  // The tet that scored worst at the last rank goes first: a failing poll
  // usually fails there, and is cut short (compass_search's `below`).
  std::size_t lead = 0;
  auto rank_at = [&](Poll& p, double below) {
    m.coords[v] = p.point;
    double shape = 1, mr = 1;
    bool cut = false;
    const std::size_t led = lead;
    for (std::size_t k = 0; k < ball.size(); ++k) {
      const std::size_t i = k == 0 ? led : k == led ? 0 : k;
      const auto& tv = m.tet2verts[ball[i]];
      const double shape_before = shape;
      if (needle[i]) {
        const TetShape q = tet_shape(m.coords[tv[0]], m.coords[tv[1]], m.coords[tv[2]], m.coords[tv[3]]);
        shape = std::min(shape, needle_shape(q));
      } else {
        std::pair<double, double> worst{mr, shape};
        fold_mean_ratio_and_shape(worst, m.coords[tv[0]], m.coords[tv[1]], m.coords[tv[2]], m.coords[tv[3]]);
        mr = worst.first;
        shape = worst.second;
      }
      if (shape < shape_before) lead = i;
      if (shape <= 0 || mr < floor) break;
      if (shape < below) {
        cut = true;
        break;
      }
    }
    m.coords[v] = start;
    if (floor < 0) floor = mean_ratio_floor(mr, shape);  // the first call: at the start
    const bool ok = !cut && shape > 0 && mr >= floor;
    p.score = ok ? std::min(shape, goal) : -1;
    p.tie = ok ? mr : -1;
  };
  // The entity's tangent frame at the start; polls are offsets in it.
  const geom::EntityRef entity{c.dim, c.tag};
  Vec2 param0 = Vec2::Zero();
  std::array<Vec3, 3> frame{Vec3::UnitX(), Vec3::UnitY(), Vec3::UnitZ()};
  if (dim < 3) {
    const mesh::Param& own = m.vert_param[v];
    param0 = own.has_u() && (dim == 1 || !std::isnan(own.v)) ? Vec2(own.u, dim == 1 ? 0.0 : own.v)
                                                               : model->closest_point(entity, start).param;
    if (dim == 2) {
      const Vec3 n = model->face_normal(c.tag, param0);
      const Vec3 a = std::abs(n.x()) < 0.9 ? Vec3::UnitX() : Vec3::UnitY();
      frame[0] = n.cross(a).normalized();
      frame[1] = n.cross(frame[0]);
    } else {
      const Vec3 t = model->edge_derivatives(c.tag, param0.x()).d1;
      if (!(t.squaredNorm() > 0)) return refused;
      frame[0] = t.normalized();
    }
  }
  auto tangential = [&](const Vec3& d) {
    Vec3 r = Vec3::Zero();
    for (int k = 0; k < dim; ++k) r += d.dot(frame[static_cast<std::size_t>(k)]) * frame[static_cast<std::size_t>(k)];
    return r;
  };
  auto poll_at = [&](const Vec3& offset, double below) {
    Poll p;
    if (dim == 3) {
      p.point = start + offset;
      if (const geom::CuspTip* tip = cap ? cap : keep_out ? keep_out->find(p.point) : nullptr) {
        if (!((p.point - tip->point).squaredNorm() > 0)) return p;
        p.point = geom::TipBalls::onto_sphere(*tip, p.point);
      }
    } else {
      const geom::Projection pr = model->closest_point(entity, start + offset, param0);
      p.point = pr.point;
      p.param = pr.param;
    }
    if (keep_out && keep_out->contains(p.point)) return p;
    rank_at(p, below);
    return p;
  };

  // Step: a tenth of the mean distance to the ball's other vertices.
  double spread = 0;
  int count = 0;
  Vec3 centroid = Vec3::Zero();
  for (TetId t : ball)
    for (VertId w : m.tet2verts[t])
      if (w != v) {
        spread += (m.coords[w] - start).norm();
        centroid += m.coords[w];
        ++count;
      }
  centroid /= count;
  const double h0 = 0.1 * spread / count;

  Poll first;
  first.point = start;
  first.param = param0;
  rank_at(first, -INFINITY);
  auto lift_and_pull = [&](const Vec3& at, std::vector<Vec3>& directions) {
    // The worst tet's vertex lifted off its opposite face (the move that
    // opens a sliver), then the pull toward the centroid.
    m.coords[v] = at;
    TetId worst = ball.front();
    double worst_q = 2;
    for (TetId t : ball) {
      const auto& tv = m.tet2verts[t];
      // Cannot be the first worst: most of the ball, by a cheap bound.
      if (worst_q <= 1 &&
          angle_aware_quality_at_least(m.coords[tv[0]], m.coords[tv[1]], m.coords[tv[2]], m.coords[tv[3]], worst_q))
        continue;
      const double q = angle_aware_measure(m, tv, nullptr);
      if (q < worst_q) worst_q = q, worst = t;
    }
    m.coords[v] = start;
    const auto& tv = m.tet2verts[worst];
    const auto& fv = mesh::kFaceVerts[static_cast<std::size_t>(mesh::local_index(m, worst, v))];
    // The face's normal points out of the tet, away from v.
    const Vec3 n = -(m.coords[tv[fv[1]]] - m.coords[tv[fv[0]]]).cross(m.coords[tv[fv[2]]] - m.coords[tv[fv[0]]]);
    if (const Vec3 lift = tangential(n); lift.squaredNorm() > 0) directions.push_back(lift.normalized());
    if (const Vec3 pull = tangential(centroid - at); pull.squaredNorm() > 0) directions.push_back(pull.normalized());
  };
  const Poll best = compass_search(first, std::span<const Vec3>(frame.data(), static_cast<std::size_t>(dim)), h0,
                                   max_polls, poll_at, lift_and_pull);
  if (!better(best, first, 1e-6)) {
    modify::Relocation r;
    r.refusal = modify::Refusal::kNoImprovement;
    return r;
  }
  mesh::Param param;
  param.u = best.param.x();
  if (dim == 2) param.v = best.param.y();
  return modify::plan_relocation_to(ed, cav, boundary, v, model, best.point, param);
}

Vec3 search_star_point(const mesh::TetMesh& m, std::span<const modify::CavityFace> faces, const Vec3& start,
                       double mean_ratio_floor, double angle_goal, int max_polls) {
  // A boundary face lists its vertices with the normal out of the cavity,
  // so (f1, f0, f2, x) is the positive order of the star's tet.
  auto tet_score = [&](const modify::CavityFace& f, const Vec3& x) {
    return angle_aware_quality(m.coords[f.verts[1]], m.coords[f.verts[0]], m.coords[f.verts[2]], x);
  };
  const double goal = angle_goal / kRegularDihedral;
  std::size_t lead = 0;  // as in plan_searched_relocation
  auto poll_at = [&](const Vec3& offset, double below) {
    Poll p;
    p.point = start + offset;
    double shape = 1, mr = 1;
    bool cut = false;
    const std::size_t led = lead;
    for (std::size_t k = 0; k < faces.size(); ++k) {
      const std::size_t i = k == 0 ? led : k == led ? 0 : k;
      const auto& f = faces[i];
      std::pair<double, double> worst{mr, shape};
      fold_mean_ratio_and_shape(worst, m.coords[f.verts[1]], m.coords[f.verts[0]], m.coords[f.verts[2]], p.point);
      mr = worst.first;
      if (worst.second < shape) {
        shape = worst.second;
        lead = i;
      }
      if (shape <= 0 || mr < mean_ratio_floor) break;
      if (shape < below) {
        cut = true;
        break;
      }
    }
    const bool ok = !cut && shape > 0 && mr >= mean_ratio_floor;
    p.score = ok ? std::min(shape, goal) : -1;
    p.tie = ok ? mr : -1;
    return p;
  };
  double spread = 0;
  for (const auto& f : faces)
    for (VertId w : f.verts) spread += (m.coords[w] - start).norm();
  const double h0 = 0.1 * spread / (3.0 * static_cast<double>(faces.size()));
  // Guided: the worst tet's apex lifted off its face, into the cavity.
  auto lift = [&](const Vec3& at, std::vector<Vec3>& directions) {
    const modify::CavityFace* worst = nullptr;
    double worst_q = 2;
    for (const auto& f : faces) {
      if (worst_q <= 1 && angle_aware_quality_at_least(m.coords[f.verts[1]], m.coords[f.verts[0]],
                                                       m.coords[f.verts[2]], at, worst_q))
        continue;  // as in lift_and_pull
      if (const double q = tet_score(f, at); q < worst_q) worst_q = q, worst = &f;
    }
    if (!worst) return;
    const Vec3 &a = m.coords[worst->verts[0]], &b = m.coords[worst->verts[1]], &c = m.coords[worst->verts[2]];
    const Vec3 n = -(b - a).cross(c - a);
    if (n.squaredNorm() > 0) directions.push_back(n.normalized());
  };
  const std::array<Vec3, 3> frame{Vec3::UnitX(), Vec3::UnitY(), Vec3::UnitZ()};
  return compass_search(poll_at(Vec3::Zero(), -INFINITY), frame, h0, max_polls, poll_at, lift).point;
}

}  // namespace cm::optimize
