#include "curvemesh/generate/boundary_mesh.hpp"
#include "curvemesh/generate/classify_on_model.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include <fmt/format.h>
#include <tbb/parallel_for.h>

#include "curvemesh/core/error.hpp"
#include "curvemesh/core/timer.hpp"

namespace cm::generate {

namespace {

VertId add_vertex(mesh::TetMesh& m, const Vec3& x, mesh::ModelRef on, mesh::Param p = {}) {
  m.coords.push_back(x);
  m.vert_class.push_back(on);
  m.vert_param.push_back(p);
  return static_cast<VertId>(m.coords.size() - 1);
}

// Segments along a degenerate (pole) edge in a face's (u, v). The pole
// triangles they bound vanish from the surface mesh, but each segment is a
// front edge that gets its own point at about the size from the pole, and
// those points make the ring of vertices around the pole together with the
// first node of the edges on either side (one node when that is a seam).
// A ring should split the angle θ the face turns around the pole into
// about 60° pieces: round(θ / 60°) + 1 nodes if the fan is open, two of
// them from the edges, round(θ / 60°) if it closes over a seam, one from
// it; either way round(θ / 60°) - 1 segments (at least one). θ is summed
// from the direction leaving the pole (the derivative across the
// degenerate side) at samples along it.
int pole_segments(const geom::Model& model, int face, const geom::OrientedUse& use, const EdgeMesh& em) {
  constexpr int kSamples = 24;
  double turned = 0;
  Vec3 previous = Vec3::Zero();
  for (int k = 0; k <= kSamples; ++k) {
    // Half a step in from the ends, where the side meets other edges.
    const double s = std::clamp(double(k), 0.5, kSamples - 0.5) / kSamples;
    const double t = em.params.front() + s * (em.params.back() - em.params.front());
    const Vec2 uv = model.edge_param_on_face(use.tag, face, t, use.forward);
    const geom::SurfaceDerivatives d = model.face_derivatives(face, uv);
    const Vec3 across = (d.du.squaredNorm() > d.dv.squaredNorm() ? d.du : d.dv).normalized();
    if (!across.allFinite()) continue;
    if (previous != Vec3::Zero()) turned += std::acos(std::clamp(previous.dot(across), -1.0, 1.0));
    previous = across;
  }
  return std::clamp(int(std::lround(turned / (std::numbers::pi / 3))) - 1, 1, 64);
}

// A loop whose uses do not join end to start is an open wire: edges lying
// inside the face that bound nothing, which a general fuse leaves where two
// solids touch along a curve (balls on their races in OCCT's
// Axis_of_bearing sample). Its triangulation would fail later with a
// message about segments; this one names the cause.
void require_closed(const geom::Model& model, int face, const std::vector<geom::Loop>& loops) {
  // The vertex a use starts (last = false) or ends at; 0 for an edge
  // without vertices.
  const auto end_of = [&](const geom::OrientedUse& use, bool last) {
    return model.edge_vertices(use.tag)[use.forward == last ? 1 : 0];
  };
  std::size_t open = 0;
  std::string example;
  for (const geom::Loop& loop : loops) {
    const std::size_t n = loop.edges.size();
    for (std::size_t k = 0; k < n; ++k) {
      const geom::OrientedUse &a = loop.edges[k], &b = loop.edges[(k + 1) % n];
      const int end = end_of(a, true), start = end_of(b, false);
      if (end == start || end == 0 || start == 0) continue;
      if (open++ == 0)
        example = fmt::format("edge {} ends at vertex {}, the next edge starts at vertex {}", a.tag, end, start);
      break;
    }
  }
  if (open > 0)
    throw GeometryError(fmt::format(
        "face {}: {} of its {} loops are open wires ({}): edges inside the face that bound nothing, as a fuse "
        "leaves where solids touch along a curve; every face must be bounded by closed loops (separate the touching "
        "solids, or mesh them one at a time)",
        face, open, loops.size(), example));
}

std::vector<std::vector<BoundaryPoint>> face_loops(const geom::Model& model, int face,
                                                   const std::vector<EdgeMesh>& edges,
                                                   const std::vector<std::vector<VertId>>& nodes,
                                                   const mesh::TetMesh& m) {
  std::vector<std::vector<BoundaryPoint>> loops;
  const std::vector<geom::Loop> model_loops = model.face_loops(face);
  require_closed(model, face, model_loops);
  for (const geom::Loop& loop : model_loops) {
    std::vector<BoundaryPoint> pts;
    for (const geom::OrientedUse& use : loop.edges) {
      const EdgeMesh& em = edges[use.tag - 1];
      const std::vector<VertId>& ids = nodes[use.tag];
      if (em.degenerate) {
        const int n = pole_segments(model, face, use, em);
        for (int k = 0; k < n; ++k) {
          const double t = double(k) / n;
          const double u = use.forward ? em.params.front() + t * (em.params.back() - em.params.front())
                                       : em.params.back() - t * (em.params.back() - em.params.front());
          pts.push_back({model.edge_param_on_face(use.tag, face, u, use.forward), m.coords[ids.front()], ids.front()});
        }
        continue;
      }
      const std::size_t n = em.params.size() - 1;
      // Each use contributes its nodes but the last, which the next use starts with.
      for (std::size_t k = 0; k < n; ++k) {
        const std::size_t i = use.forward ? k : n - k;
        pts.push_back({model.edge_param_on_face(use.tag, face, em.params[i], use.forward), m.coords[ids[i]], ids[i]});
      }
    }
    loops.push_back(std::move(pts));
  }
  return loops;
}

}  // namespace

mesh::TetMesh mesh_boundary(const geom::Model& model, const size::SizeField& size, const BoundaryMeshOptions& o,
                            BoundaryMeshStats* stats) {
  BoundaryMeshStats st;
  Timer timer;
  const std::vector<geom::CuspTip> tips = cusp_tips(model, size);
  const std::vector<geom::WedgeSpan> spans = geom::wedge_spans(model);
  const std::vector<EdgeMesh> edges = discretize_edges(model, size, o.edges, tips, spans);
  st.edges_seconds = timer.seconds();
  st.cusp_tips = tips.size();

  mesh::TetMesh m;
  const int nv = model.count(0), ne = model.count(1), nf = model.count(2);
  std::vector<VertId> vertex_of(nv + 1, kNone);
  for (int v = 1; v <= nv; ++v) vertex_of[v] = add_vertex(m, model.vertex_point(v), {0, v});
  std::vector<std::vector<VertId>> nodes(ne + 1);
  for (int e = 1; e <= ne; ++e) {
    const EdgeMesh& em = edges[e - 1];
    const std::size_t n = em.params.size() - 1;
    std::vector<VertId>& ids = nodes[e];
    ids.resize(n + 1);
    // An edge without vertices (a full circle in some kernels) gets one at u0.
    ids.front() = em.vertices[0] > 0 ? vertex_of[em.vertices[0]]
                                     : add_vertex(m, em.points.front(), {1, e}, {em.params.front(), std::nan("")});
    for (std::size_t k = 1; k < n; ++k)
      ids[k] = em.degenerate ? ids.front() : add_vertex(m, em.points[k], {1, e}, {em.params[k], std::nan("")});
    ids.back() = em.vertices[1] > 0 ? vertex_of[em.vertices[1]] : ids.front();
    if (em.degenerate) continue;
    st.edge_segments += n;
    for (std::size_t k = 0; k < n; ++k) m.edges.push_back({{ids[k], ids[k + 1]}, e});
  }

  timer.reset();
  std::vector<FaceMesh> faces(nf);
  std::vector<std::vector<std::vector<BoundaryPoint>>> loops(nf);
  for (int f = 1; f <= nf; ++f) loops[f - 1] = face_loops(model, f, edges, nodes, m);
  // Each face keeps out of the tips at its own vertices.
  std::vector<std::vector<geom::CuspTip>> face_tips(nf);
  for (const geom::CuspTip& tip : tips) {
    std::vector<int> at;
    for (const int e : model.upward({0, tip.vertex}))
      for (const int f : model.upward({1, e})) at.push_back(f);
    std::sort(at.begin(), at.end());
    at.erase(std::unique(at.begin(), at.end()), at.end());
    for (const int f : at) face_tips[f - 1].push_back(tip);
  }
  // A wedge span's strips keep out of its ball, with no fan.
  std::vector<std::vector<geom::CuspTip>> face_spans(nf);
  for (const geom::WedgeSpan& span : spans)
    for (const int f : span.strips)
      face_spans[f - 1].push_back({span.vertex, model.vertex_point(span.vertex), span.radius, {}});
  tbb::parallel_for(1, nf + 1, [&](int f) {
    faces[f - 1] = mesh_face(model, f, loops[f - 1], size, o.faces, face_tips[f - 1], face_spans[f - 1]);
  });
  st.faces_seconds = timer.seconds();

  timer.reset();
  for (int f = 1; f <= nf; ++f) {
    const FaceMesh& fm = faces[f - 1];
    std::vector<VertId> global(fm.uv.size());
    std::size_t b = 0;
    for (const auto& loop : loops[f - 1])
      for (const BoundaryPoint& p : loop) global[b++] = p.vertex;
    CM_ASSERT(b == fm.num_boundary);
    for (std::size_t i = fm.num_boundary; i < fm.uv.size(); ++i)
      global[i] = add_vertex(m, fm.xyz[i], {2, f}, {fm.uv[i].x(), fm.uv[i].y()});
    // (u, v) counter-clockwise is along du × dv; the mesh follows face_normal.
    bool reverse = false;
    if (!fm.tris.empty()) {
      const auto& t = fm.tris.front();
      const Vec2 c = (fm.uv[t[0]] + fm.uv[t[1]] + fm.uv[t[2]]) / 3;
      const geom::SurfaceDerivatives d = model.face_derivatives(f, c);
      reverse = d.du.cross(d.dv).dot(model.face_normal(f, c)) < 0;
    }
    for (const auto& t : fm.tris) {
      const VertId a = global[t[0]], bb = global[t[1]], c = global[t[2]];
      if (a == bb || bb == c || a == c) continue;  // collapsed at a pole
      m.tris.push_back({reverse ? std::array<VertId, 3>{a, c, bb} : std::array<VertId, 3>{a, bb, c}, f});
    }
    st.refinement_insertions += fm.refinement_insertions;
    st.flips += fm.flips;
    st.smoothing_moves += fm.smoothing_moves;
  }

  m.entities = model_entities(model);
  st.assembly_seconds = timer.seconds();
  if (stats) *stats = st;
  return m;
}

}  // namespace cm::generate
