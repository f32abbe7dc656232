#include "curvemesh/modify/delete_tet.hpp"

#include <algorithm>
#include <vector>

#include "curvemesh/mesh/adjacency.hpp"
#include "curvemesh/mesh/topology.hpp"
#include "curvemesh/modify/measure.hpp"
#include "curvemesh/quality/measures.hpp"

namespace cm::modify {

namespace {

std::array<VertId, 3> face_of(const mesh::TetMesh& m, TetId t, int f) { return tet_face(m.tet2verts[t], f); }

Vec3 centroid(const mesh::TetMesh& m, const std::array<VertId, 3>& v) {
  return (m.coords[v[0]] + m.coords[v[1]] + m.coords[v[2]]) / 3;
}

// Refusal as a value, the plan's fields left as far as they were filled.
TetDeletion refuse(TetDeletion plan, Refusal why) {
  plan.refusal = why;
  return plan;
}

}  // namespace

TetDeletion plan_tet_deletion(MeshEditor& ed, Cavity& cav, const BoundaryIndex& surf, TetId t,
                              const geom::Model* model, const DeletionOptions& o) {
  const auto& m = ed.mesh();
  TetDeletion plan;
  plan.tet = t;
  const auto tv = m.tet2verts[t];
  cav.reset(ed);
  cav.add(ed, t);
  plan.before = tet_quality(m, tv);
  std::array<bool, 4> hull{};
  for (int f = 0; f < 4; ++f) {
    hull[static_cast<std::size_t>(f)] = m.tet2adj[mesh::pack_face(t, f)] == kNone;
    plan.hull_faces += hull[static_cast<std::size_t>(f)];
  }
  if (!model || plan.hull_faces < 2 || plan.hull_faces == 4) return refuse(plan, Refusal::kConstrainedFace);
  for (int f = 0; f < 4; ++f) {
    if (hull[static_cast<std::size_t>(f)]) continue;
    const auto v = face_of(m, t, f);
    if (surf.find_tri(v[0], v[1], v[2]) != kNone) return refuse(plan, Refusal::kConstrainedFace);
  }

  // The hull faces: triangles of one model face, in one orientation
  // convention relative to the tet (m.tris point out of the tet that owns
  // them on the outer boundary; whatever the convention, the new triangles
  // take the same one).
  int convention = 0;  // +1: a triangle lists its tet's face order; -1: the reverse
  plan.face_tag = -1;
  for (int f = 0; f < 4; ++f) {
    if (!hull[static_cast<std::size_t>(f)]) continue;
    const auto v = face_of(m, t, f);
    const Index i = surf.find_tri(v[0], v[1], v[2]);
    if (i == kNone) return refuse(plan, Refusal::kClassification);
    const auto& tri = m.tris[i];
    const int side = same_cycle(tri.verts, v) ? 1 : -1;
    if ((plan.face_tag >= 0 && tri.face_tag != plan.face_tag) || (convention != 0 && side != convention))
      return refuse(plan, Refusal::kClassification);
    plan.face_tag = tri.face_tag;
    convention = side;
    plan.removed[static_cast<std::size_t>(plan.removed_count++)] = tri.verts;
  }
  // The inner faces as the tets across them list them: the new owners.
  plan.after = 1;
  for (int f = 0; f < 4; ++f) {
    if (hull[static_cast<std::size_t>(f)]) continue;
    const Index across = m.tet2adj[mesh::pack_face(t, f)];
    const TetId n = mesh::face_tet(across);
    auto v = face_of(m, n, mesh::face_index(across));
    if (convention < 0) std::swap(v[1], v[2]);
    plan.added[static_cast<std::size_t>(plan.added_count++)] = v;
    plan.after = std::min(plan.after, tet_quality(m, m.tet2verts[n]));
    if (m.tet_region[n] != m.tet_region[t]) return refuse(plan, Refusal::kClassification);
  }
  const int tag = plan.face_tag;

  // Topology. The edge samples of the chord test: the face edge that goes
  // (two faces) and the one that comes.
  std::array<VertId, 2> old_edge{kNone, kNone}, new_edge{kNone, kNone};
  if (plan.hull_faces == 2) {
    // Hull faces f1, f2 share (a, b), the vertices opposite the inner faces;
    // their apexes c, d are opposite the hull faces.
    std::array<int, 2> inner{}, outer{};
    for (int f = 0, ni = 0, no = 0; f < 4; ++f)
      (hull[static_cast<std::size_t>(f)] ? outer[static_cast<std::size_t>(no++)] : inner[static_cast<std::size_t>(ni++)]) = f;
    const VertId a = tv[static_cast<std::size_t>(inner[0])], b = tv[static_cast<std::size_t>(inner[1])];
    const VertId c = tv[static_cast<std::size_t>(outer[0])], d = tv[static_cast<std::size_t>(outer[1])];
    old_edge = {a, b};
    new_edge = {c, d};
    if (surf.find_edge(a, b) != kNone) return refuse(plan, Refusal::kClassification);
    // (c, d) becomes a face edge with the two new triangles: it must not be
    // on the boundary already, or four triangles would meet there.
    if (surf.find_edge(c, d) != kNone) return refuse(plan, Refusal::kNonManifold);
    const mesh::Shell shell = mesh::collect_shell(m, c, d, t);
    if (!shell.closed) return refuse(plan, Refusal::kNonManifold);
    for (TetId s : shell.tets)
      for (VertId r : m.tet2verts[s])
        if (r != c && r != d && surf.find_tri(c, d, r) != kNone) return refuse(plan, Refusal::kNonManifold);
  } else {
    int inner = 0;
    while (hull[static_cast<std::size_t>(inner)]) ++inner;
    const VertId v = tv[static_cast<std::size_t>(inner)];
    if (m.vert_class[v] != mesh::ModelRef{2, tag}) return refuse(plan, Refusal::kClassification);
    thread_local std::vector<TetId> ball;
    mesh::collect_ball(m, v, ball);
    if (ball.size() != 1) return refuse(plan, Refusal::kNonManifold);
    plan.removed_vertex = v;
  }

  // Geometry: no new triangle turns against the ones it replaces or
  // against the model, judged as the boundary check judges it.
  plan.triangles_before = plan.triangles_after = 1;
  double longest = 0;
  for (int k = 0; k < plan.added_count; ++k) {
    const auto& v = plan.added[static_cast<std::size_t>(k)];
    const Vec3 &x = m.coords[v[0]], &y = m.coords[v[1]], &z = m.coords[v[2]];
    const Vec3 n = tri_normal(x, y, z);
    for (int j = 0; j < plan.removed_count; ++j) {
      const auto& w = plan.removed[static_cast<std::size_t>(j)];
      if (!(n.dot(tri_normal(m.coords[w[0]], m.coords[w[1]], m.coords[w[2]])) > 0))
        return refuse(plan, Refusal::kFoldedSurface);
    }
    if (!agrees_with_model(*model, tag, x, y, z, check_hint(m, v, tag))) return refuse(plan, Refusal::kFoldedSurface);
    plan.triangles_after = std::min(plan.triangles_after, quality::triangle_mean_ratio(x, y, z));
    longest = std::max({longest, (y - x).norm(), (z - y).norm(), (x - z).norm()});
  }
  for (int j = 0; j < plan.removed_count; ++j) {
    const auto& w = plan.removed[static_cast<std::size_t>(j)];
    plan.triangles_before =
        std::min(plan.triangles_before, quality::triangle_mean_ratio(m.coords[w[0]], m.coords[w[1]], m.coords[w[2]]));
  }
  // The chord rule: samples of the new surface against the same samples of
  // the old one.
  auto distance = [&](const Vec3& x, const std::array<VertId, 3>& tri) {
    return model->closest_point({2, tag}, x, check_hint(m, tri, tag)).distance;
  };
  auto deviation = [&](const auto& tris, int count, const std::array<VertId, 2>& edge) {
    double d = 0;
    for (int k = 0; k < count; ++k) d = std::max(d, distance(centroid(m, tris[static_cast<std::size_t>(k)]), tris[0]));
    if (edge[0] != kNone) d = std::max(d, distance(0.5 * (m.coords[edge[0]] + m.coords[edge[1]]), tris[0]));
    return d;
  };
  plan.deviation_after = deviation(plan.added, plan.added_count, new_edge);
  plan.deviation_before = deviation(plan.removed, plan.removed_count, old_edge);
  if (plan.deviation_after > std::max(plan.deviation_before, o.max_relative_deviation * longest))
    return refuse(plan, Refusal::kFoldedSurface);
  plan.volume = mesh::tet_volume(m, t);
  return plan;
}

void apply(MeshEditor& ed, Cavity& cav, BoundaryIndex& surf, const TetDeletion& plan) {
  // The hook runs once the new triangles are in m.tris.
  const MeshEditor::DeferredHook defer(ed);
  // Removals from the highest index down: a removal moves the last entry
  // into the hole.
  std::array<Index, 3> old{};
  for (int k = 0; k < plan.removed_count; ++k) {
    const auto& v = plan.removed[static_cast<std::size_t>(k)];
    old[static_cast<std::size_t>(k)] = surf.find_tri(v[0], v[1], v[2]);
  }
  for (int i = 1; i < plan.removed_count; ++i)
    for (int j = i; j > 0 && old[static_cast<std::size_t>(j - 1)] < old[static_cast<std::size_t>(j)]; --j)
      std::swap(old[static_cast<std::size_t>(j - 1)], old[static_cast<std::size_t>(j)]);
  for (int k = 0; k < plan.removed_count; ++k) surf.remove_tri(old[static_cast<std::size_t>(k)]);

  std::array<Index, 2> opened{kNone, kNone};
  int count = 0;
  for (const CavityFace& bf : cav.compute_boundary(ed))
    if (bf.outside != kNone) opened[static_cast<std::size_t>(count++)] = bf.outside;
  rebuild_open(ed, cav, {});
  // The faces the tets across now have on the hull are boundary triangles.
  for (int k = 0; k < count; ++k) ed.mark_face(opened[static_cast<std::size_t>(k)]);
  for (int k = 0; k < plan.added_count; ++k) surf.add_tri({plan.added[static_cast<std::size_t>(k)], plan.face_tag});
}

}  // namespace cm::modify
