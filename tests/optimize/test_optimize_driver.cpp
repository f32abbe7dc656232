// The optimization drivers on poor meshes: perturbed and flattened Kuhn
// boxes. Whatever they do, every tet stays positive, the boundary (vertex
// positions, triangles and their tags) and the volume do not change, and
// the worst tets get strictly better.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <random>
#include <set>
#include <vector>

#include "curvemesh/mesh/structured.hpp"
#include "curvemesh/mesh/validate.hpp"
#include "curvemesh/optimize/adapt.hpp"
#include "curvemesh/optimize/boundary_limit.hpp"
#include "curvemesh/optimize/improve.hpp"
#include "curvemesh/optimize/measured_swap.hpp"
#include "perturbed_box.hpp"

using namespace cm;
using namespace cm::optimize;

namespace {

struct Boundary {
  std::map<VertId, Vec3> verts;  // every vertex not on a region
  std::multiset<std::pair<std::array<VertId, 3>, std::int32_t>> tris;
};

Boundary boundary_of(const mesh::TetMesh& m) {
  Boundary b;
  for (VertId v = 0; v < m.num_verts(); ++v)
    if (m.vert_class[v].dim != 3) b.verts.emplace(v, m.coords[v]);
  for (const auto& t : m.tris) {
    auto k = t.verts;
    std::sort(k.begin(), k.end());
    b.tris.emplace(k, t.face_tag);
  }
  return b;
}

void expect_same_boundary(const Boundary& before, const mesh::TetMesh& m) {
  const Boundary after = boundary_of(m);
  EXPECT_EQ(before.verts.size(), after.verts.size());
  for (const auto& [v, x] : before.verts) EXPECT_EQ(m.coords[v], x) << "boundary vertex " << v << " moved";
  EXPECT_TRUE(before.tris == after.tris) << "boundary triangles changed";
}

void expect_valid(const mesh::TetMesh& m) {
  const auto r = mesh::validate(m, mesh::Level::kFull);
  EXPECT_TRUE(r.valid()) << (r.issues.empty() ? "" : r.issues[0].message);
  EXPECT_EQ(r.num_inverted, 0u);
  EXPECT_EQ(r.num_flat, 0u);
}

}  // namespace

TEST(ImproveDriver, PerturbedAndFlattenedBoxGetsStrictlyBetter) {
  for (unsigned seed : {1u, 2u, 3u}) {
    SCOPED_TRACE(seed);
    auto m = test::perturbed_box(6, seed, 0.45, 25);
    const auto before = summarize_mesh(m);
    ASSERT_EQ(before.inverted, 0u);
    // The fixture is really poor: flat tets and tiny angles.
    ASSERT_LT(before.min_mean_ratio, 0.05);
    ASSERT_LT(before.min_dihedral, 3.0);
    const Boundary boundary = boundary_of(m);
    const auto st = improve_quality(m);
    const auto after = summarize_mesh(m);
    expect_valid(m);
    expect_same_boundary(boundary, m);
    EXPECT_NEAR(after.volume, before.volume, 1e-12 * before.volume);
    EXPECT_GT(after.min_mean_ratio, before.min_mean_ratio);
    EXPECT_GT(after.min_dihedral, before.min_dihedral);
    EXPECT_GT(after.min_mean_ratio, 0.15);  // measured: about 0.3
    EXPECT_GT(after.min_dihedral, 5.0);
    EXPECT_NEAR(st.min_after, after.min_mean_ratio, 1e-12);
    EXPECT_NEAR(st.min_dihedral_after, after.min_dihedral, 1e-9);
    EXPECT_NEAR(st.min_dihedral_before, before.min_dihedral, 1e-9);
    EXPECT_GT(st.edge_removals + st.face_swaps, 0u);
    EXPECT_GT(st.relocations, 0u);
  }
}

TEST(ImproveDriver, RunningTwiceNeverMakesItWorse) {
  auto m = test::perturbed_box(5, 7, 0.4, 10);
  improve_quality(m);
  const auto once = summarize_mesh(m);
  improve_quality(m);
  const auto twice = summarize_mesh(m);
  expect_valid(m);
  EXPECT_GE(twice.min_mean_ratio, once.min_mean_ratio);
}

TEST(AdaptDriver, AnisotropicMetricQualityImproves) {
  // A box ten times longer in z with a metric asking for exactly that
  // stretching: in the metric the perturbed mesh is a perturbed cube.
  auto m = test::perturbed_box(5, 4, 0.4, 10, 10.0);
  auto field = MetricField::from_tensors(std::vector<size::Metric>(m.num_verts(), Vec3(25, 25, 0.25).asDiagonal()));
  const auto before = summarize_mesh(m, &field);
  const Boundary boundary = boundary_of(m);
  AdaptOptions o;
  o.split = o.collapse = false;  // shapes only: the cells are already unit
  const auto st = adapt_to_metric(m, field, o);
  const auto after = summarize_mesh(m, &field);
  expect_valid(m);
  expect_same_boundary(boundary, m);
  EXPECT_NEAR(after.volume, before.volume, 1e-12 * before.volume);
  EXPECT_GT(after.min_metric_quality, before.min_metric_quality);
  EXPECT_GT(after.min_metric_quality, 0.15);
  EXPECT_NEAR(st.min_before, before.min_metric_quality, 1e-12);
  EXPECT_NEAR(st.min_after, after.min_metric_quality, 1e-12);
  // Unit cubes in the metric: cube edges (1) are in range, diagonals (1.41, 1.73) are not.
  const auto& l = st.lengths_after;
  EXPECT_EQ(l.in_range + l.too_short + l.too_long, l.edges);
  EXPECT_GT(l.in_range, l.edges / 5);
  EXPECT_GT(l.too_long, l.edges / 5);
}

TEST(AdaptDriver, RefusesAFieldOfTheWrongSize) {
  auto m = test::perturbed_box(2, 1, 0.2, 0);
  auto field = MetricField::from_sizes(std::vector<double>(3, 1.0));
  EXPECT_THROW(adapt_to_metric(m, field), std::invalid_argument);
}

namespace {

// Every boundary point of `before` is still a vertex of m (coordinates
// compared exactly) and the face tags are all still there.
void expect_boundary_points_kept(const Boundary& before, const mesh::TetMesh& m) {
  std::set<std::array<double, 3>> points;
  for (const Vec3& x : m.coords) points.insert({x.x(), x.y(), x.z()});
  for (const auto& [v, x] : before.verts)
    EXPECT_TRUE(points.count({x.x(), x.y(), x.z()})) << "boundary vertex " << v << " moved or went";
  std::set<std::int32_t> tags_before, tags_after;
  for (const auto& [k, tag] : before.tris) tags_before.insert(tag);
  for (const auto& t : m.tris) tags_after.insert(t.face_tag);
  EXPECT_EQ(tags_before, tags_after);
}

}  // namespace

TEST(AdaptDriver, FinerSizeMapSplitsToUnitLengths) {
  auto m = test::perturbed_box(4, 5, 0.3, 4);  // cells of 0.25
  auto field = MetricField::from_sizes(std::vector<double>(m.num_verts(), 0.1));
  const auto before = summarize_mesh(m, &field);
  const Boundary boundary = boundary_of(m);
  const auto st = adapt_to_metric(m, field);
  const auto after = summarize_mesh(m, &field);
  expect_valid(m);
  expect_boundary_points_kept(boundary, m);
  EXPECT_EQ(field.size(), m.num_verts());
  EXPECT_NEAR(after.volume, before.volume, 1e-12 * before.volume);
  EXPECT_GT(st.splits, 500u);
  EXPECT_LT(st.lengths_before.percent_in_range(), 5.0);
  EXPECT_GT(st.lengths_after.percent_in_range(), 60.0);
  EXPECT_GT(after.min_mean_ratio, before.min_mean_ratio);
  EXPECT_GT(m.num_tets(), 10 * before.tets);
}

TEST(AdaptDriver, CoarserSizeMapCollapsesInteriorVertices) {
  auto m = test::perturbed_box(8, 6, 0.3, 0);  // cells of 0.125
  auto field = MetricField::from_sizes(std::vector<double>(m.num_verts(), 0.3));
  const auto before = summarize_mesh(m, &field);
  const Boundary boundary = boundary_of(m);
  const auto st = adapt_to_metric(m, field);
  const auto after = summarize_mesh(m, &field);
  expect_valid(m);
  expect_boundary_points_kept(boundary, m);
  EXPECT_NEAR(after.volume, before.volume, 1e-12 * before.volume);
  EXPECT_GT(st.collapses, 50u);
  EXPECT_LT(m.num_verts(), before.verts);
  EXPECT_EQ(field.size(), m.num_verts());
  // The boundary vertices cannot go: short edges remain on the boundary, but
  // the interior ones are gone.
  EXPECT_LT(st.lengths_after.too_short, st.lengths_before.too_short);
  for (VertId v = 0; v < m.num_verts(); ++v) EXPECT_NE(m.vert2tet[v], kNone);
}

TEST(BoundaryLimit, SeparatesPinnedFromFreeTets) {
  // A lone sliver: all four faces on the hull, nothing can change it.
  mesh::TetMesh m;
  for (const Vec3& x : {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0.5, 1, 0), Vec3(0.5, 0.4, 0.02)}) m.add_vert(x);
  m.add_tet({0, 1, 2, 3}, 1);
  m.resize_vertex_arrays();
  for (VertId v = 0; v < 4; ++v) m.vert_class[v] = {2, 1};
  const auto one = classify_boundary_limit(m);
  EXPECT_EQ(one.pinned, 1u);
  EXPECT_EQ(one.by_two_faces, 1u);
  EXPECT_EQ(one.free_below, 0u);
  EXPECT_EQ(one.free_min_dihedral, 180.0);
  ASSERT_EQ(one.worst.size(), 1u);
  EXPECT_EQ(one.worst[0].why, BoundaryLimit::Why::kTwoFaces);
  EXPECT_EQ(one.worst[0].boundary_faces, 4);
  EXPECT_NEAR(one.pinned_min_dihedral, summarize_mesh(m).min_dihedral, 1e-12);

  // The flattened box: its slivers are inside, so they are free, and the
  // two minima together are the mesh's.
  auto box = test::perturbed_box(5, 2, 0.45, 12);
  const auto s = summarize_mesh(box);
  const auto l = classify_boundary_limit(box);
  EXPECT_GT(l.free_below, 0u);
  EXPECT_NEAR(std::min(l.pinned_min_dihedral, l.free_min_dihedral), s.min_dihedral, 1e-9);
  EXPECT_NEAR(std::min(l.pinned_min_mean_ratio, l.free_min_mean_ratio), s.min_mean_ratio, 1e-12);
  ASSERT_FALSE(l.worst.empty());
  EXPECT_NEAR(l.worst[0].dihedral, s.min_dihedral, 1e-9);
  for (std::size_t i = 1; i < l.worst.size(); ++i) EXPECT_LE(l.worst[i - 1].dihedral, l.worst[i].dihedral);
}

namespace {

// Every boundary triangle lies on one face of the unit box, exactly: its
// three vertices share a coordinate that is 0 or 1, the same for all the
// triangles of its face tag.
void expect_on_box_faces(const mesh::TetMesh& m) {
  std::map<std::int32_t, std::pair<int, double>> plane_of_tag;
  for (const auto& t : m.tris) {
    int axis = -1;
    for (int c = 0; c < 3 && axis < 0; ++c) {
      const double x = m.coords[t.verts[0]][c];
      if ((x == 0 || x == 1) && m.coords[t.verts[1]][c] == x && m.coords[t.verts[2]][c] == x) axis = c;
    }
    ASSERT_GE(axis, 0) << "a boundary triangle off the box";
    const auto plane = std::pair{axis, m.coords[t.verts[0]][axis]};
    const auto [it, fresh] = plane_of_tag.emplace(t.face_tag, plane);
    EXPECT_TRUE(fresh || it->second == plane) << "face " << t.face_tag << " on two planes";
  }
  EXPECT_EQ(plane_of_tag.size(), 6u);
}

}  // namespace

TEST(AdaptDriver, FlatBoundaryLetsTheBoxFacesAdaptAndKeepsThem) {
  // Fine across x = 0.5, coarse along it: the box's faces need vertices to
  // move and go as much as the interior does.
  auto run = [](bool flat) {
    auto m = mesh::make_box_mesh({5, 5, 5}, Vec3(0, 0, 0), Vec3(1, 1, 1), true);
    std::vector<size::Metric> ms;
    for (const Vec3& x : m.coords) {
      const double hx = 0.04 + 0.3 * std::abs(x.x() - 0.5);
      ms.push_back(Vec3(1 / (hx * hx), 25, 25).asDiagonal());
    }
    auto field = MetricField::from_tensors(std::move(ms));
    AdaptOptions o;
    o.threshold = 0.9;
    o.flat_boundary = flat;
    const auto st = adapt_to_metric(m, field, o);
    return std::pair{std::move(m), st};
  };
  const auto [fixed, fixed_st] = run(false);
  const auto [flat, flat_st] = run(true);
  for (const auto* m : {&fixed, &flat}) {
    expect_valid(*m);
    EXPECT_NEAR(summarize_mesh(*m).volume, 1.0, 1e-12);
    expect_on_box_faces(*m);
  }
  // Without the option every boundary vertex of the box is still there;
  // with it some moved or went, and the lengths came out better.
  const auto box = mesh::make_box_mesh({5, 5, 5}, Vec3(0, 0, 0), Vec3(1, 1, 1), true);
  const Boundary original = boundary_of(box);
  expect_boundary_points_kept(original, fixed);
  std::set<std::array<double, 3>> points;
  for (const Vec3& x : flat.coords) points.insert({x.x(), x.y(), x.z()});
  std::size_t gone = 0;
  for (const auto& [v, x] : original.verts) gone += !points.count({x.x(), x.y(), x.z()});
  EXPECT_GT(gone, 10u);
  for (const Vec3& corner : {Vec3(0, 0, 0), Vec3(1, 1, 1), Vec3(1, 0, 1)})
    EXPECT_TRUE(points.count({corner.x(), corner.y(), corner.z()}));
  EXPECT_GT(flat_st.lengths_after.percent_in_range(), fixed_st.lengths_after.percent_in_range());
  EXPECT_GT(flat_st.lengths_after.percent_in_range(), 92.0);  // measured 94.8 (89.9 without)
}

TEST(BoundaryLimit, AThinFaceHasAPriceAtTheTarget) {
  // On an equilateral face the regular tet is at the target (70.5 deg).
  const Vec3 a(0, 0, 0), b(1, 0, 0), up(0.5, 0.3, 1);
  EXPECT_GT(best_mean_ratio_at_angle(a, b, Vec3(0.5, std::sqrt(3.0) / 2, 0), up, 10), 0.99);
  // On a thin face the angle costs mean ratio, more as the target rises;
  // the apex side does not matter for a flat face.
  const Vec3 thin(0.5, 0.05, 0);
  const double at0 = best_mean_ratio_at_angle(a, b, thin, up, 0);
  const double at5 = best_mean_ratio_at_angle(a, b, thin, up, 5);
  const double at10 = best_mean_ratio_at_angle(a, b, thin, up, 10);
  EXPECT_GT(at10, 0.0);
  EXPECT_LT(at10, at5);
  EXPECT_LE(at5, at0 + 1e-9);
  EXPECT_LT(at10, 0.25);  // measured 0.214 on this face of quality 0.115
  EXPECT_NEAR(best_mean_ratio_at_angle(a, b, thin, Vec3(0.5, 0.3, -1), 10), at10, 1e-9);
  // Unreachable: no tet on a face has all angles above the regular tet's.
  EXPECT_EQ(best_mean_ratio_at_angle(a, b, thin, up, 75), 0.0);

  // In a report, only free tets with one boundary face get a price, and a
  // tet held by a thin face is one whose own mean ratio is above it.
  auto box = test::perturbed_box(5, 2, 0.45, 12);
  const auto l = classify_boundary_limit(box, 10, 1000);
  std::size_t held = 0;
  for (const auto& w : l.worst) {
    if (w.why != BoundaryLimit::Why::kFree || w.boundary_faces != 1) {
      EXPECT_EQ(w.price, 1.0);
      continue;
    }
    EXPECT_GT(w.price, 0.0);
    held += w.price < w.mean_ratio;
  }
  EXPECT_EQ(held, l.held_by_thin_face);
}

// The searches fold each tet into a running minimum through cheap bounds;
// the result must be the very bits of the plain minimum of
// mean_ratio_and_shape, or the optimizer's path would change. Stars of a
// moving point over random fans: fair tets, slivers, needles, inverted.
TEST(MeasuredSwap, FoldingIsThePlainMinimumBitForBit) {
  std::mt19937 rng(31);
  std::uniform_real_distribution<double> u(-1, 1);
  int lowered_late = 0;
  for (int trial = 0; trial < 4000; ++trial) {
    std::pair<double, double> plain{1, 1}, folded{1, 1};
    const Vec3 x(0.3 * u(rng), 0.3 * u(rng), 0.3 * u(rng));
    for (int k = 0; k < 24; ++k) {
      std::array<Vec3, 3> f;
      for (auto& p : f) p = Vec3(u(rng), u(rng), u(rng));
      if (trial % 5 == 1 && k == 7) f[2] = (f[0] + f[1]) / 2 + 1e-5 * Vec3(u(rng), u(rng), u(rng));
      if (trial % 5 == 2 && k == 3) f[1] = f[0] + 1e-4 * Vec3(u(rng), u(rng), u(rng));
      if (trial % 5 == 3 && k == 11) f[2] = x + (f[0] - x) * 1e-6;
      // Positive, as a star's tets are, but for one inverted in some stars.
      const bool positive = (f[1] - f[0]).cross(f[2] - f[0]).dot(x - f[0]) > 0;
      if (positive == (trial % 5 == 4 && k == 9)) std::swap(f[0], f[1]);
      const auto q = mean_ratio_and_shape(f[0], f[1], f[2], x);
      const auto before = plain;
      plain = {std::min(plain.first, q.first), std::min(plain.second, q.second)};
      lowered_late += k > 3 && plain != before;
      fold_mean_ratio_and_shape(folded, f[0], f[1], f[2], x);
      // The worst-tet search's bound: never above the quality itself.
      for (const double at : {q.second, std::nextafter(q.second, 2.0), 0.5 * q.second, plain.second})
        if (angle_aware_quality_at_least(f[0], f[1], f[2], x, at)) {
          ASSERT_GE(q.second, at) << "trial " << trial << " tet " << k;
        }
      ASSERT_EQ(folded.first, plain.first) << "trial " << trial << " tet " << k;
      ASSERT_EQ(folded.second, plain.second) << "trial " << trial << " tet " << k;
    }
  }
  EXPECT_GT(lowered_late, 1000);  // the bounds were put to the test
}
