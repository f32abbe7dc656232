#include <gtest/gtest.h>

#include "curvemesh/mesh/adjacency.hpp"
#include "curvemesh/mesh/structured.hpp"
#include "curvemesh/mesh/validate.hpp"

using namespace cm;
using namespace cm::mesh;
using Kind = ValidationIssue::Kind;

namespace {
std::size_t count_kind(const ValidationReport& r, Kind k) {
  std::size_t n = 0;
  for (const auto& i : r.issues) n += i.kind == k;
  return n;
}
TetMesh box() { return make_box_mesh({2, 2, 2}, Vec3(0, 0, 0), Vec3(1, 1, 1), true); }
}  // namespace

TEST(Validate, BoxIsValid) {
  const auto r = validate(box(), Level::kFull);
  EXPECT_TRUE(r.valid()) << (r.issues.empty() ? "" : r.issues[0].message);
}

TEST(Validate, InvertedTetIsReportedWithItsId) {
  TetMesh m = box();
  std::swap(m.tet2verts[5][0], m.tet2verts[5][1]);
  build_adjacency(m);
  const auto r = validate(m, Level::kFull);
  EXPECT_EQ(r.num_inverted, 1u);
  EXPECT_EQ(r.num_flat, 0u);
  ASSERT_EQ(count_kind(r, Kind::kInverted), 1u);
  EXPECT_EQ(r.issues[0].entity, 5);
}

TEST(Validate, FlatTetIsExactlyZero) {
  TetMesh m;
  // Four coplanar points with coordinates that are not exact in binary: the
  // exact predicate still sees them coplanar because the plane is z = 0.1.
  for (Vec3 p : {Vec3(0, 0, 0.1), Vec3(1, 0, 0.1), Vec3(0, 1, 0.1), Vec3(0.3, 0.3, 0.1)}) m.add_vert(p);
  m.add_tet({0, 1, 2, 3}, 1);
  build_adjacency(m);
  const auto r = validate(m, Level::kTopology);
  EXPECT_EQ(r.num_flat, 1u);
  EXPECT_EQ(r.num_inverted, 0u);
}

TEST(Validate, StaleAdjacencyIsReported) {
  TetMesh m = box();
  std::swap(m.tet2verts[3][0], m.tet2verts[3][1]);  // also inverts it; adjacency now stale
  const auto r = validate(m, Level::kTopology);
  EXPECT_GT(count_kind(r, Kind::kAdjacencyWrongFace) + count_kind(r, Kind::kAdjacencyAsymmetric), 0u);
}

TEST(Validate, NonManifoldFace) {
  TetMesh m = box();
  m.add_tet(m.tet2verts[0], 1);
  build_adjacency(m);
  const auto r = validate(m, Level::kTopology);
  EXPECT_GT(count_kind(r, Kind::kNonManifoldFace), 0u);
  EXPECT_FALSE(r.valid());
}

TEST(Validate, MissingBoundaryClassification) {
  TetMesh m = box();
  m.tris.pop_back();
  const auto r = validate(m, Level::kFull);
  EXPECT_EQ(count_kind(r, Kind::kUnclassifiedBoundary), 1u);
  EXPECT_TRUE(validate(m, Level::kTopology).valid());
}

TEST(Validate, TriangleThatIsNotAFace) {
  TetMesh m = box();
  m.tris.push_back({{0, 13, 26}, 1});  // corner, center, opposite corner: no tet has all three
  const auto r = validate(m, Level::kFull);
  EXPECT_EQ(count_kind(r, Kind::kTriNotOnMesh), 1u);
}

TEST(Validate, VertexClassificationRules) {
  TetMesh m = box();
  // The center of the 2x2x2 box is interior: classifying it on a face is wrong.
  const VertId center = 13;
  ASSERT_EQ(m.vert_class[center].dim, 3);
  m.vert_class[center] = {2, 1};
  EXPECT_GT(validate(m, Level::kFull).num_classification, 0u);
  // A corner vertex on a face that does not contain it.
  TetMesh m2 = box();
  ASSERT_EQ(m2.vert_class[0].dim, 0);
  m2.vert_class[0] = {2, 2};  // face +x does not touch the corner (0,0,0)
  EXPECT_GT(validate(m2, Level::kFull).num_classification, 0u);
  // An unclassified vertex.
  TetMesh m3 = box();
  m3.vert_class[4] = ModelRef{};
  EXPECT_GT(validate(m3, Level::kFull).num_classification, 0u);
}

TEST(Validate, BadVertexIdStopsEarly) {
  TetMesh m = box();
  m.tet2verts[0][2] = 1000;
  const auto r = validate(m, Level::kFull);
  EXPECT_EQ(count_kind(r, Kind::kBadVertexId), 1u);
}
