// Element deletion with reclassification, on a hand-built ball: the unit
// octahedron inscribed in the analytic unit sphere (its poles and seam
// where the model has them), with three cap tets standing on it: one over a
// single face (three hull faces around a valence-3 vertex) and two over a
// pair of faces (two hull faces each). Exact counts at every step, every
// refusal reason, and the octahedron back at the end. Then a small domain
// where the new face edge would already be on the boundary.
#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <map>
#include <numbers>
#include <random>
#include <set>

#include "curvemesh/geom/analytic_model.hpp"
#include "curvemesh/modify/delete_tet.hpp"
#include "curvemesh/modify/marks.hpp"
#include "curvemesh/size/size_field.hpp"
#include "point_ops_support.hpp"

using namespace cm;
using namespace cm::modify;

namespace {

constexpr double kPi = std::numbers::pi;

struct Ball {
  std::unique_ptr<geom::Model> model = geom::make_analytic_sphere(Vec3::Zero(), 1.0);
  mesh::TetMesh m;
  // Vertex ids.
  VertId o = 0, px = 1, py = 2, nx = 3, ny = 4, pz = 5, nz = 6, e3 = 7, e2 = 8;
  // The cap tets.
  TetId cap3 = kNone, cap2a = kNone, cap2b = kNone;
};

// A vertex on the sphere's face with its (u, v).
VertId face_vertex(mesh::TetMesh& m, double u, double v) {
  const VertId id = m.add_vert(Vec3(std::cos(v) * std::cos(u), std::cos(v) * std::sin(u), std::sin(v)));
  m.resize_vertex_arrays();
  m.vert_class[id] = {2, 1};
  m.vert_param[id] = {u, v};
  return id;
}

Ball make_capped_octahedron() {
  Ball b;
  auto& m = b.m;
  auto vertex = [&](const Vec3& x, mesh::ModelRef c, mesh::Param p) {
    const VertId id = m.add_vert(x);
    m.resize_vertex_arrays();
    m.vert_class[id] = c;
    m.vert_param[id] = p;
    return id;
  };
  vertex(Vec3::Zero(), {3, 1}, {});
  vertex(Vec3(1, 0, 0), {1, 2}, {0.0, std::nan("")});  // on the seam
  face_vertex(m, kPi / 2, 0);
  face_vertex(m, kPi, 0);
  face_vertex(m, 3 * kPi / 2, 0);
  vertex(Vec3(0, 0, 1), {0, 1}, {});  // north pole
  vertex(Vec3(0, 0, -1), {0, 2}, {});
  face_vertex(m, 5 * kPi / 4, std::asin(1 / std::sqrt(3.0)));  // above face (-x, -y, +z)
  face_vertex(m, kPi + 0.3, -kPi / 4);                          // near edge (-x, -z)
  const VertId o = b.o, px = b.px, py = b.py, nx = b.nx, ny = b.ny, pz = b.pz, nz = b.nz, e3 = b.e3, e2 = b.e2;
  // Outward octahedron faces; two of them and one more are capped.
  const std::array<std::array<VertId, 3>, 8> octa{{{px, py, pz},
                                                   {py, nx, pz},
                                                   {nx, ny, pz},
                                                   {ny, px, pz},
                                                   {py, px, nz},
                                                   {nx, py, nz},
                                                   {ny, nx, nz},
                                                   {px, ny, nz}}};
  for (const auto& f : octa) m.add_tet({o, f[0], f[1], f[2]}, 1);
  b.cap3 = m.add_tet({nx, ny, pz, e3}, 1);
  b.cap2a = m.add_tet({nx, py, nz, e2}, 1);
  b.cap2b = m.add_tet({ny, nx, nz, e2}, 1);
  for (int k : {0, 1, 3, 4, 7}) m.tris.push_back({octa[static_cast<std::size_t>(k)], 1});
  for (const auto& t : std::array<std::array<VertId, 3>, 7>{{{ny, pz, e3},
                                                            {nx, e3, pz},
                                                            {nx, ny, e3},
                                                            {nx, py, e2},
                                                            {py, nz, e2},
                                                            {ny, nx, e2},
                                                            {ny, e2, nz}}})
    m.tris.push_back({t, 1});
  m.edges.push_back({{nz, px}, 2});
  m.edges.push_back({{px, pz}, 2});
  mesh::build_adjacency(m);
  return b;
}

std::set<std::array<VertId, 4>> live_tets(const MeshEditor& ed) {
  std::set<std::array<VertId, 4>> s;
  const auto& m = ed.mesh();
  for (TetId t = 0; t < m.tet2verts.size(); ++t) {
    if (ed.is_dead(t)) continue;
    auto k = m.tet2verts[t];
    std::sort(k.begin(), k.end());
    s.insert(k);
  }
  return s;
}

}  // namespace

TEST(DeleteTet, CappedOctahedronBackToTheOctahedron) {
  Ball b = make_capped_octahedron();
  auto& m = b.m;
  ASSERT_TRUE(mesh::validate(m, mesh::Level::kFull).valid());
  const size::UniformSizeField size(0.5);
  ASSERT_TRUE(generate::check_boundary(*b.model, m, size).valid());
  MeshEditor ed(m);
  ASSERT_EQ(mark_boundary_faces(ed), 0u);
  BoundaryIndex surf(m);
  const auto ref = cm::test::make_reference(ed, false);
  int hooked = 0;
  ed.set_hook([&](const mesh::TetMesh&, std::span<const TetId> created) {
    ++hooked;
    EXPECT_TRUE(created.empty());
  });
  Cavity cav;
  const auto before = m.tet2verts;
  const DeletionOptions loose{1.0};  // the octahedron's faces are far from the sphere

  // Refusals, each changing nothing.
  EXPECT_EQ(plan_tet_deletion(ed, cav, surf, b.cap2a, nullptr, loose).refusal, Refusal::kConstrainedFace);
  EXPECT_EQ(plan_tet_deletion(ed, cav, surf, 0, b.model.get(), loose).refusal, Refusal::kConstrainedFace);
  // The new triangle (-x, -z, +y) is an octahedron face: its centroid lies
  // 0.42 inside the sphere, the capped surface 0.30.
  const auto chord = plan_tet_deletion(ed, cav, surf, b.cap2a, b.model.get());
  EXPECT_EQ(chord.refusal, Refusal::kFoldedSurface);
  EXPECT_NEAR(chord.deviation_after, 1 - 1 / std::sqrt(3.0), 1e-9);
  EXPECT_LT(chord.deviation_before, chord.deviation_after);
  EXPECT_EQ(m.tet2verts, before);
  EXPECT_EQ(m.tris.size(), 12u);

  // Two hull faces: the cap over (-x, +y, -z) goes, (+y, e2) with it.
  const auto two = plan_tet_deletion(ed, cav, surf, b.cap2a, b.model.get(), loose);
  ASSERT_EQ(two.refusal, Refusal::kNone);
  EXPECT_EQ(two.hull_faces, 2);
  EXPECT_EQ(two.removed_count, 2);
  EXPECT_EQ(two.added_count, 2);
  EXPECT_EQ(two.removed_vertex, kNone);
  EXPECT_GT(two.volume, 0);
  EXPECT_EQ(plan_tet_deletion(ed, cav, surf, b.cap2a, b.model.get(), loose).refusal, Refusal::kNone);
  apply(ed, cav, surf, two);
  EXPECT_EQ(hooked, 1);
  EXPECT_EQ(ed.live_tets(), 10u);
  EXPECT_EQ(m.tris.size(), 12u);
  EXPECT_EQ(m.edges.size(), 2u);
  EXPECT_NE(surf.find_tri(b.nx, b.nz, b.py), kNone);  // the octahedron face is back
  EXPECT_NE(surf.find_tri(b.nx, b.nz, b.e2), kNone);  // reclassified onto the face
  EXPECT_EQ(surf.find_tri(b.nx, b.py, b.e2), kNone);
  cm::test::expect_everything(ed, surf, ref, b.model.get(), &size);

  // The other cap now stands on three hull faces around e2: it goes with e2.
  const auto three = plan_tet_deletion(ed, cav, surf, b.cap2b, b.model.get(), loose);
  ASSERT_EQ(three.refusal, Refusal::kNone);
  EXPECT_EQ(three.hull_faces, 3);
  EXPECT_EQ(three.removed_count, 3);
  EXPECT_EQ(three.added_count, 1);
  EXPECT_EQ(three.removed_vertex, b.e2);
  apply(ed, cav, surf, three);
  EXPECT_EQ(ed.live_tets(), 9u);
  EXPECT_EQ(m.tris.size(), 10u);
  EXPECT_EQ(m.vert2tet[b.e2], kNone);
  cm::test::expect_everything(ed, surf, ref, b.model.get(), &size);

  // The single cap: with the default chord rule refused, relaxed it goes.
  EXPECT_EQ(plan_tet_deletion(ed, cav, surf, b.cap3, b.model.get()).refusal, Refusal::kFoldedSurface);
  const auto single = plan_tet_deletion(ed, cav, surf, b.cap3, b.model.get(), loose);
  ASSERT_EQ(single.refusal, Refusal::kNone);
  EXPECT_EQ(single.removed_vertex, b.e3);
  apply(ed, cav, surf, single);
  EXPECT_EQ(ed.live_tets(), 8u);
  EXPECT_EQ(m.tris.size(), 8u);
  cm::test::expect_everything(ed, surf, ref, b.model.get(), &size);
  std::set<std::array<VertId, 4>> octahedron;
  for (TetId t = 0; t < 8; ++t) {
    auto k = before[t];
    std::sort(k.begin(), k.end());
    octahedron.insert(k);
  }
  EXPECT_EQ(live_tets(ed), octahedron);
  // Nothing left to delete: every tet has one hull face.
  for (TetId t = 0; t < m.tet2verts.size(); ++t)
    if (!ed.is_dead(t)) {
      EXPECT_EQ(plan_tet_deletion(ed, cav, surf, t, b.model.get(), loose).refusal, Refusal::kConstrainedFace);
    }
}

TEST(DeleteTet, ClassificationRefusals) {
  Ball b = make_capped_octahedron();
  auto& m = b.m;
  MeshEditor ed(m);
  mark_boundary_faces(ed);
  BoundaryIndex surf(m);
  Cavity cav;
  const DeletionOptions loose{1.0};
  // The shared edge of the two hull faces on a model edge: it is not the
  // face's to flip.
  const Index e = surf.add_edge({{b.py, b.e2}, 1});
  EXPECT_EQ(plan_tet_deletion(ed, cav, surf, b.cap2a, b.model.get(), loose).refusal, Refusal::kClassification);
  surf.remove_edge(e);
  // Hull faces on two model faces.
  const Index i = surf.find_tri(b.nx, b.py, b.e2);
  m.tris[i].face_tag = 2;
  EXPECT_EQ(plan_tet_deletion(ed, cav, surf, b.cap2a, b.model.get(), loose).refusal, Refusal::kClassification);
  m.tris[i].face_tag = 1;
  ASSERT_EQ(plan_tet_deletion(ed, cav, surf, b.cap2a, b.model.get(), loose).refusal, Refusal::kNone);
  // A vertex the three-face deletion would remove must be the face's.
  m.vert_class[b.e3] = {0, 1};
  EXPECT_EQ(plan_tet_deletion(ed, cav, surf, b.cap3, b.model.get(), loose).refusal, Refusal::kClassification);
  m.vert_class[b.e3] = {2, 1};
  EXPECT_EQ(plan_tet_deletion(ed, cav, surf, b.cap3, b.model.get(), loose).refusal, Refusal::kNone);
  // An inner face that is a classified triangle (an interface) stays.
  surf.add_tri({{b.nx, b.pz, b.ny}, 1});
  EXPECT_EQ(plan_tet_deletion(ed, cav, surf, b.cap3, b.model.get(), loose).refusal, Refusal::kConstrainedFace);
}

TEST(DeleteTet, NewFaceEdgeAlreadyOnTheBoundaryIsRefused) {
  // Three tets in an open fan around (c, d): the middle one has hull faces
  // (a, b, c) and (a, b, d) only, but (c, d) is a hull edge of the fan's end
  // tets: four triangles would meet there.
  auto model = geom::make_analytic_sphere(Vec3::Zero(), 1.0);
  mesh::TetMesh m;
  const VertId a = face_vertex(m, 0.3, 0.1), b = face_vertex(m, 0.5, -0.2), c = face_vertex(m, 1.2, 0.6),
               d = face_vertex(m, 1.0, -0.7), p = face_vertex(m, 2.4, 0.3), q = face_vertex(m, 2.0, -0.4);
  auto positive = [&](std::array<VertId, 4> t) {
    if (predicates::orient3d(m.coords[t[0]].data(), m.coords[t[1]].data(), m.coords[t[2]].data(),
                             m.coords[t[3]].data()) < 0)
      std::swap(t[0], t[1]);
    return t;
  };
  const TetId mid = m.add_tet(positive({a, b, c, d}), 1);
  m.add_tet(positive({a, c, d, p}), 1);
  m.add_tet(positive({b, c, d, q}), 1);
  mesh::build_adjacency(m);
  // Every hull face is a triangle of the sphere's face, outward.
  for (TetId t = 0; t < m.num_tets(); ++t)
    for (int f = 0; f < 4; ++f)
      if (m.tet2adj[mesh::pack_face(t, f)] == kNone) {
        const auto& fv = mesh::kFaceVerts[static_cast<std::size_t>(f)];
        const auto& tv = m.tet2verts[t];
        m.tris.push_back({{tv[fv[0]], tv[fv[1]], tv[fv[2]]}, 1});
      }
  ASSERT_EQ(m.tris.size(), 8u);
  MeshEditor ed(m);
  mark_boundary_faces(ed);
  BoundaryIndex surf(m);
  Cavity cav;
  const auto plan = plan_tet_deletion(ed, cav, surf, mid, model.get(), DeletionOptions{1.0});
  EXPECT_EQ(plan.hull_faces, 2);
  EXPECT_EQ(plan.refusal, Refusal::kNonManifold);
}

namespace {

// Rounds of deletions of every tet with two or more hull faces that may go
// (in a seeded random order, with the mesher's chord rule or a loose one):
// each deletion opens new faces on the tets across, so later rounds peel
// the tets behind. Everything is checked after each round. Returns the
// deletions, and those that took their vertex.
std::pair<int, int> peel(cm::test::MeshedModel& r, unsigned seed, int rounds) {
  auto& m = r.m;
  MeshEditor ed(m);
  EXPECT_EQ(mark_boundary_faces(ed), 0u);
  BoundaryIndex surf(m);
  const auto ref = cm::test::make_reference(ed, false);
  Cavity cav;
  std::mt19937 rng(seed);
  int deleted = 0, with_vertex = 0;
  std::map<Refusal, int> refusals;
  for (int round = 0; round < rounds; ++round) {
    std::vector<TetId> capped;
    for (TetId t = 0; t < m.tet2verts.size(); ++t) {
      if (ed.is_dead(t)) continue;
      int hull = 0;
      for (int f = 0; f < 4; ++f) hull += m.tet2adj[mesh::pack_face(t, f)] == kNone;
      if (hull >= 2) capped.push_back(t);
    }
    std::shuffle(capped.begin(), capped.end(), rng);
    int applied = 0;
    for (TetId t : capped) {
      if (ed.is_dead(t)) continue;
      const double volume = mesh::tet_volume(m, t);
      const auto plan = plan_tet_deletion(ed, cav, surf, t, r.model.get(), DeletionOptions{rng() % 2 ? 0.04 : 0.5});
      ++refusals[plan.refusal];
      if (plan.refusal != Refusal::kNone) continue;
      EXPECT_EQ(plan.volume, volume);
      const std::size_t tris = m.tris.size();
      apply(ed, cav, surf, plan);
      EXPECT_EQ(m.tris.size() + static_cast<std::size_t>(plan.removed_count - plan.added_count), tris);
      with_vertex += plan.removed_vertex != kNone;
      ++applied;
    }
    deleted += applied;
    cm::test::expect_everything(ed, surf, ref, r.model.get(), r.size.field.get());
    if (::testing::Test::HasFatalFailure() || applied == 0) break;
  }
  std::printf("deleted %d (%d with their vertex);", deleted, with_vertex);
  for (const auto& [why, n] : refusals) std::printf(" %s: %d;", std::string(to_string(why)).c_str(), n);
  std::printf("\n");
  return {deleted, with_vertex};
}

}  // namespace

TEST(DeleteTet, PeelingCurvedModelsKeepsEverything) {
  int vertices_removed = 0;
  for (const auto& [spec, h] : {std::pair<std::string, double>{"builtin:sphere", 0.35}, {"builtin:torus", 0.3},
                                {"builtin:part", 0}}) {
    SCOPED_TRACE(spec);
    // Boundary points only: many tets stand on the surface with two or
    // three faces.
    auto r = cm::test::mesh_model(spec, h, false);
    const auto [deleted, with_vertex] = peel(r, 7, 30);
    EXPECT_GT(deleted, 100);
    vertices_removed += with_vertex;
  }
  EXPECT_GT(vertices_removed, 50);
}

TEST(DeleteTet, PeelingASharedCadModelKeepsEverything) {
  const std::string path = std::string(CM_SHARED_DIR) + "/models/Torus_1.brep";
  if (!std::filesystem::exists(path)) GTEST_SKIP() << "shared models not found";
  auto r = cm::test::mesh_model(path, 0, false);
  EXPECT_GT(peel(r, 9, 30).first, 1000);
}
