// Validity checks of curved tets and the repair (curved/element_check.hpp,
// curved/repair.hpp, curved/curve.hpp): known-invalid elements flagged at
// the right place, and coarse meshes of curved models that curving breaks
// ending with every element certified valid and acceptable, the mesh still
// a geometric triangulation of its model, the node storage exactly the
// boundary's, and the same result for any thread count.
#include <cmath>
#include <set>

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include "curved_support.hpp"
#include "curvemesh/curved/detail/check_memo.hpp"
#include "curvemesh/curved/nodes.hpp"
#include "curvemesh/generate/boundary_check.hpp"
#include "curvemesh/mesh/high_order.hpp"
#include "curvemesh/mesh/topology.hpp"
#include "curvemesh/mesh/validate.hpp"
#include "curvemesh/quality/shape_measure.hpp"
#include "curvemesh/size/size_field.hpp"

namespace cm::test {
namespace {

std::vector<Vec3> straight_p2(const std::array<Vec3, 4>& v) {
  std::vector<Vec3> n(v.begin(), v.end());
  for (const auto& e : mesh::kTetEdges) n.push_back(0.5 * (v[e[0]] + v[e[1]]));
  return n;
}

const std::array<Vec3, 4> kUnit{Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(0, 0, 1)};

TEST(ElementCheck, StraightTetIsValidAndAcceptable) {
  const auto c = curved::check_element(2, straight_p2(kUnit), {});
  EXPECT_EQ(c.verdict, quality::Validity::kValid);
  EXPECT_TRUE(c.acceptable);
  EXPECT_DOUBLE_EQ(c.scaled_jacobian, 1);
  std::array<Vec3, 4> flipped = kUnit;
  std::swap(flipped[1], flipped[2]);
  const auto f = curved::check_element(2, straight_p2(flipped), {});
  EXPECT_EQ(f.verdict, quality::Validity::kInvalid);
  EXPECT_FALSE(f.acceptable);
}

TEST(ElementCheck, EdgeBentThroughTheOppositeFaceIsInvalidThere) {
  // The midpoint of edge (0, 1) pushed far past the face (1, 2, 3): det J
  // changes sign near that edge.
  auto n = straight_p2(kUnit);
  n[4] = Vec3(0.5, 1.2, 1.2);
  const auto c = curved::check_element(2, n, {});
  EXPECT_EQ(c.verdict, quality::Validity::kInvalid);
  EXPECT_FALSE(c.acceptable);
  EXPECT_LT(c.score(), 0);
  // Least det J on edge 0 or at one of its ends.
  const bool on_edge = c.where.dim == 1 && c.where.index == 0;
  const bool at_end = c.where.dim == 0 && (c.where.index == 0 || c.where.index == 1);
  EXPECT_TRUE(on_edge || at_end) << c.where.dim << "/" << c.where.index;
  // A mild bend is valid but below a demanding threshold.
  n[4] = Vec3(0.5, 0.05, 0.05);
  const auto mild = curved::check_element(2, n, {});
  EXPECT_EQ(mild.verdict, quality::Validity::kValid);
  EXPECT_LT(mild.scaled_jacobian, 1);
  curved::Acceptance strict;
  strict.min_scaled_jacobian = 0.99;
  EXPECT_FALSE(curved::check_element(2, n, strict).acceptable);
}

// The repair's memo of checks gives what check_element gives, and only
// for exactly the same nodes.
TEST(ElementCheck, MemoAnswersOnlyForTheSameNodes) {
  curved::detail::CheckMemo memo(2, {});
  auto bent = straight_p2(kUnit);
  bent[4] = Vec3(0.5, 1.2, 1.2);
  const auto direct = curved::check_element(2, bent, {});
  for (int round = 0; round < 2; ++round) {
    const auto c = memo(std::vector<Vec3>(bent));
    EXPECT_EQ(c.verdict, direct.verdict);
    EXPECT_EQ(c.scaled_jacobian, direct.scaled_jacobian);
    EXPECT_EQ(c.acceptable, direct.acceptable);
  }
  EXPECT_EQ(memo.hits(), 1u);
  // The smallest change of one node is a new element.
  auto moved = bent;
  moved[4].x() = std::nextafter(moved[4].x(), 1.0);
  memo(std::vector<Vec3>(moved));
  EXPECT_EQ(memo.hits(), 1u);
  EXPECT_EQ(memo.misses(), 2u);
  const auto straight = memo(straight_p2(kUnit));
  EXPECT_TRUE(straight.acceptable);
}

// The cache's table grows past many entries and still finds each one by
// its exact nodes, and nothing else.
TEST(ElementCheck, CacheFindsEveryEntryAfterGrowing) {
  curved::CheckCache cache(2);
  std::vector<std::vector<Vec3>> stored;
  for (int k = 0; k < 3000; ++k) {
    auto n = straight_p2(kUnit);
    n[4] = Vec3(0.5, 1e-3 * k, 0);
    curved::ElementCheck c;
    c.scaled_jacobian = k;
    cache.add(n, c);
    stored.push_back(n);
  }
  EXPECT_EQ(cache.size(), 3000u);
  for (int k = 0; k < 3000; ++k) {
    const curved::ElementCheck* c = cache.find(stored[static_cast<std::size_t>(k)]);
    ASSERT_NE(c, nullptr) << k;
    EXPECT_EQ(c->scaled_jacobian, k);
    auto other = stored[static_cast<std::size_t>(k)];
    other[5].z() = std::nextafter(other[5].z(), 1.0);
    EXPECT_EQ(cache.find(other), nullptr) << k;
  }
  // A repeated node list keeps its first result.
  curved::ElementCheck later;
  later.scaled_jacobian = -1;
  cache.add(stored[7], later);
  EXPECT_EQ(cache.find(stored[7])->scaled_jacobian, 7);
  cache.clear();
  EXPECT_EQ(cache.find(stored[7]), nullptr);
}

// check_mesh again with the first one's cache gives what a fresh check
// gives, after a node moved too.
TEST(ElementCheck, RecheckWithTheCacheEqualsAFreshCheck) {
  Meshed r = mesh_for_curving("builtin:torus", 0.25);
  curved::place_boundary_nodes(r.m, *r.model, 2);
  const curved::Acceptance acc;
  curved::CheckCache cache;
  const auto first = curved::check_mesh(r.m, acc, true, nullptr, &cache);
  ASSERT_GT(cache.size(), 0u);
  const auto same = [](const curved::MeshCheck& a, const curved::MeshCheck& b) {
    EXPECT_EQ(a.invalid, b.invalid);
    EXPECT_EQ(a.unacceptable, b.unacceptable);
    EXPECT_EQ(a.min_scaled_jacobian, b.min_scaled_jacobian);
    EXPECT_EQ(a.mean_scaled_jacobian, b.mean_scaled_jacobian);
    EXPECT_EQ(a.min_measure, b.min_measure);
  };
  same(curved::check_mesh(r.m, acc, true, &cache), first);
  // Push one boundary edge's node through its tets.
  const auto& t = r.m.tris.front();
  const VertId a = t.verts[0], b = t.verts[1];
  const Vec3 far = 0.5 * (r.m.coords[a] + r.m.coords[b]) + 3 * (r.m.coords[t.verts[2]] - r.m.coords[a]);
  r.m.high_order.set_edge(a, b, std::span<const Vec3>(&far, 1));
  const auto fresh = curved::check_mesh(r.m, acc, true);
  EXPECT_GT(fresh.unacceptable.size(), first.unacceptable.size());
  same(curved::check_mesh(r.m, acc, true, &cache), fresh);
}

// The repair's `origin` names, for each tet it leaves, the entry tet with
// the same nodes, and only the tets near what it changed are new.
TEST(ElementCheck, RepairOriginNamesTetsWithTheirEntryNodes) {
  for (const int order : {2, 3}) {
    Meshed r = mesh_for_curving("builtin:holes", 0.25);
    curved::place_boundary_nodes(r.m, *r.model, order);
    const curved::Acceptance acc;
    std::vector<curved::ElementCheck> first;
    const auto before = curved::check_mesh(r.m, acc, true, nullptr, nullptr, &first);
    ASSERT_GT(before.unacceptable.size(), 0u);
    ASSERT_EQ(first.size(), r.m.num_tets());
    std::vector<std::vector<Vec3>> entry;
    for (TetId t = 0; t < r.m.num_tets(); ++t) entry.push_back(mesh::gather_tet_nodes(r.m, t));
    curved::RepairOptions o;
    std::vector<TetId> origin;
    const auto st = curved::repair_curved_mesh(r.m, *r.model, before.unacceptable, o, &origin);
    ASSERT_GT(st.edge_removals + st.splits + st.boundary_swaps + st.collapses, 0u);
    ASSERT_EQ(origin.size(), r.m.num_tets());
    std::size_t renewed = 0;
    for (TetId t = 0; t < r.m.num_tets(); ++t) {
      if (origin[t] == kNone) {
        ++renewed;
        continue;
      }
      ASSERT_LT(origin[t], entry.size());
      ASSERT_EQ(mesh::gather_tet_nodes(r.m, t), entry[origin[t]]) << "order " << order << " tet " << t;
    }
    EXPECT_GT(renewed, 0u);
    EXPECT_LT(renewed, r.m.num_tets() / 4) << "order " << order;
    // recheck_mesh on those origins is a fresh check.
    const auto again = curved::recheck_mesh(r.m, acc, true, first, origin);
    const auto fresh = curved::check_mesh(r.m, acc, true);
    EXPECT_EQ(again.unacceptable, fresh.unacceptable);
    EXPECT_EQ(again.mean_scaled_jacobian, fresh.mean_scaled_jacobian);
    EXPECT_EQ(again.min_measure, fresh.min_measure);
    EXPECT_THROW(curved::recheck_mesh(r.m, acc, true, first, std::span<const TetId>(origin).first(1)),
                 std::invalid_argument);
  }
}

// The least I check_mesh reports is the least exact I over every tet,
// though it measures only the tets whose bound could hold it.
TEST(ElementCheck, LeastMeasureIsExact) {
  for (const int order : {2, 3}) {
    Meshed r = mesh_for_curving("builtin:torus", 0.25);
    curved::place_boundary_nodes(r.m, *r.model, order);
    const curved::Acceptance acc;
    double least = 1;
    for (TetId t = 0; t < r.m.num_tets(); ++t) least = std::min(least, curved::check_tet(r.m, t, acc, true).measure);
    ASSERT_LT(least, 1);
    EXPECT_EQ(curved::check_mesh(r.m, acc, true).min_measure, least) << "order " << order;
    // Without it, a lower bound.
    EXPECT_LE(curved::check_mesh(r.m, acc, false).min_measure, least) << "order " << order;
  }
}

struct Case {
  const char* name;
  const char* spec;
  int order;
  bool expect_problems;  ///< curving makes some tets unacceptable before repair
  double hmax = 0;       ///< 0: the default; set where the default leaves nothing to repair
};

class Repair : public ::testing::TestWithParam<Case> {};

TEST_P(Repair, EveryElementEndsCertifiedValidAndAcceptable) {
  const Case& c = GetParam();
  Meshed r = mesh_for_curving(c.spec, 0.25, c.hmax);
  curved::CurveOptions o;
  o.order = c.order;
  const curved::CurveReport rep = curved::curve_mesh(r.m, *r.model, o);
  if (c.expect_problems) {
    EXPECT_GT(rep.unacceptable_before, 0u);
  }
  EXPECT_EQ(rep.after.invalid.size(), 0u);
  EXPECT_EQ(rep.after.unacceptable.size(), 0u);
  EXPECT_GE(rep.after.min_scaled_jacobian, o.repair.acceptance.min_scaled_jacobian);
  EXPECT_GE(rep.after.min_measure, o.repair.acceptance.min_measure);
  // The report after the repair checks only the tets it changed: it is
  // what a check of the whole mesh gives.
  const curved::MeshCheck fresh = curved::check_mesh(r.m, o.repair.acceptance, true);
  EXPECT_EQ(rep.after.invalid, fresh.invalid);
  EXPECT_EQ(rep.after.unacceptable, fresh.unacceptable);
  EXPECT_EQ(rep.after.min_scaled_jacobian, fresh.min_scaled_jacobian);
  EXPECT_EQ(rep.after.mean_scaled_jacobian, fresh.mean_scaled_jacobian);
  EXPECT_EQ(rep.after.min_measure, fresh.min_measure);
  EXPECT_EQ(rep.after.quick, fresh.quick);
  // Certified again from scratch, through the quality module directly.
  for (TetId t = 0; t < r.m.num_tets(); ++t)
    ASSERT_EQ(quality::certify_tet(r.m, t).verdict, quality::Validity::kValid) << "tet " << t;
  // Still a geometric triangulation of the model.
  const auto v = mesh::validate(r.m, mesh::Level::kFull);
  EXPECT_TRUE(v.valid()) << (v.issues.empty() ? "" : v.issues.front().message);
  const size::UniformSizeField field(r.model->bounding_box().diagonal() / 20);
  const auto b = generate::check_boundary(*r.model, r.m, field);
  EXPECT_EQ(b.vertices_off_entity, 0u);
  EXPECT_EQ(b.folded_triangles, 0u);
  // The node storage: every boundary edge (and order-3 triangle) has nodes;
  // the only other edges with nodes are the ones the repair curved inside.
  const auto boundary = boundary_edges(r.m);
  std::set<std::pair<VertId, VertId>> interior_with_nodes;
  for (const auto& tv : r.m.tet2verts)
    for (const auto& e : mesh::kTetEdges) {
      const std::pair<VertId, VertId> k{std::min(tv[e[0]], tv[e[1]]), std::max(tv[e[0]], tv[e[1]])};
      const bool has = r.m.high_order.has_edge(k.first, k.second);
      if (boundary.count(k))
        ASSERT_TRUE(has) << "boundary edge " << k.first << "-" << k.second << " has no nodes";
      else if (has)
        interior_with_nodes.insert(k);
    }
  EXPECT_EQ(interior_with_nodes.size(), rep.repair.interior_edges_curved);
  if (c.order == 3) {
    for (const auto& t : r.m.tris) ASSERT_TRUE(r.m.high_order.has_face(t.verts[0], t.verts[1], t.verts[2]));
  }
  // Boundary nodes are on the model, but where step 5 straightened edges.
  const double scale = r.model->bounding_box().diagonal();
  std::size_t off = 0;
  for (const auto& t : r.m.tris)
    for (const auto& e : mesh::kTriEdges) {
      std::array<Vec3, 2> n;
      r.m.high_order.get_edge(t.verts[e[0]], t.verts[e[1]], n.data());
      for (int s = 0; s < c.order - 1; ++s) off += r.model->closest_point({2, t.face_tag}, n[s]).distance > 1e-7 * scale;
    }
  // Each straightened edge is seen from its (at most two) triangles.
  EXPECT_LE(off, 2 * (c.order - 1) * rep.repair.edges_straightened);
  // Curving brings the boundary closer to the model.
  EXPECT_LT(rep.error_curved.mean, 0.5 * rep.error_straight.mean);
}

const Case kCases[] = {
    {"HolesP2", "builtin:holes", 2, true},        {"HolesP3", "builtin:holes", 3, true},
    {"ThinWallP2", "builtin:thinwall", 2, true},  {"ThinWallP3", "builtin:thinwall", 3, true},
    {"TorusP2", "builtin:torus", 2, true},        {"TorusP3", "builtin:torus", 3, true},
    {"PartP3", "builtin:part", 3, true, 6.0},          {"RingP2", "ring.brep", 2, true},
    {"RingP3", "ring.brep", 3, true},             {"TorusCadP3", "Torus_1.brep", 3, true},
    {"SphereP2", "builtin:sphere", 2, false},      {"InclusionP3", "builtin:inclusion", 3, false},
};

INSTANTIATE_TEST_SUITE_P(Models, Repair, ::testing::ValuesIn(kCases),
                         [](const testing::TestParamInfo<Case>& param_info) { return std::string(param_info.param.name); });

// Curved tets bound the model's volume far better than straight ones:
// sphere of radius 1, volume by a quadrature exact for each element.
TEST(Curving, VolumeOfACurvedSphereMeshIsCloseToTheSpheres) {
  for (int order : {2, 3}) {
    Meshed r = mesh_for_curving("builtin:sphere", 0.1);
    double straight = 0;
    for (TetId t = 0; t < r.m.num_tets(); ++t) straight += mesh::tet_volume(r.m, t);
    curved::CurveOptions o;
    o.order = order;
    curved::curve_mesh(r.m, *r.model, o);
    double curved = 0;
    for (TetId t = 0; t < r.m.num_tets(); ++t) curved += quality::shape_measure(r.m, t).volume;
    const double exact = 4.0 / 3 * std::numbers::pi;
    EXPECT_LT(std::abs(curved - exact), 0.02 * std::abs(straight - exact)) << "order " << order;
  }
}

TEST(Curving, ResultDoesNotDependOnTheThreadCount) {
  auto run = [](int threads) {
    const tbb::global_control limit(tbb::global_control::max_allowed_parallelism, threads);
    Meshed r = mesh_for_curving("builtin:holes", 0.25);
    curved::CurveOptions o;
    o.order = 2;
    curved::curve_mesh(r.m, *r.model, o);
    return r.m;
  };
  const mesh::TetMesh a = run(1), b = run(2);
  ASSERT_EQ(a.num_tets(), b.num_tets());
  ASSERT_EQ(a.num_verts(), b.num_verts());
  EXPECT_EQ(a.tet2verts, b.tet2verts);
  EXPECT_EQ(a.coords, b.coords);
  for (TetId t = 0; t < a.num_tets(); ++t) ASSERT_EQ(mesh::gather_tet_nodes(a, t), mesh::gather_tet_nodes(b, t));
}

}  // namespace
}  // namespace cm::test
