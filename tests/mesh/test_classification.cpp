#include <gtest/gtest.h>

#include <map>

#include "curvemesh/mesh/adjacency.hpp"
#include "curvemesh/mesh/classification.hpp"
#include "curvemesh/mesh/structured.hpp"
#include "curvemesh/mesh/validate.hpp"

using namespace cm;
using namespace cm::mesh;

namespace {
std::map<int, int> count_entities(const TetMesh& m) {
  std::map<int, int> c;
  for (const auto& e : m.entities) ++c[e.dim];
  return c;
}
std::map<int, int> count_vertex_dims(const TetMesh& m) {
  std::map<int, int> c;
  for (const auto& r : m.vert_class) ++c[r.dim];
  return c;
}
const EntityInfo* find_entity(const TetMesh& m, int dim, int tag) {
  for (const auto& e : m.entities)
    if (e.dim == dim && e.tag == tag) return &e;
  return nullptr;
}
}  // namespace

TEST(Classification, BoxWithSixTaggedSides) {
  TetMesh m = make_box_mesh({3, 3, 3}, Vec3(0, 0, 0), Vec3(1, 1, 1), true);
  EXPECT_TRUE(is_fully_classified(m));
  EXPECT_EQ(m.tris.size(), 6u * 9 * 2);
  auto ents = count_entities(m);
  EXPECT_EQ(ents[0], 8);
  EXPECT_EQ(ents[1], 12);
  EXPECT_EQ(ents[2], 6);
  EXPECT_EQ(ents[3], 1);
  auto dims = count_vertex_dims(m);
  EXPECT_EQ(dims[0], 8);
  EXPECT_EQ(dims[1], 12 * 2);
  EXPECT_EQ(dims[2], 6 * 4);
  EXPECT_EQ(dims[3], 8);
  for (const auto& e : m.entities) {
    const std::size_t expected = e.dim == 1 ? 2 : e.dim == 2 ? 4 : e.dim == 3 ? 6 : 0;
    EXPECT_EQ(e.bounding.size(), expected) << "entity (" << e.dim << ", " << e.tag << ")";
  }
  EXPECT_EQ(m.edges.size(), 12u * 3);
  EXPECT_TRUE(validate(m, Level::kFull).valid());
}

TEST(Classification, TetsOnlyGiveOneSurface) {
  TetMesh m = make_box_mesh({2, 2, 2}, Vec3(0, 0, 0), Vec3(1, 1, 1), false);
  build_adjacency(m);
  derive_classification(m);
  auto ents = count_entities(m);
  EXPECT_EQ(ents[0], 0);
  EXPECT_EQ(ents[1], 0);
  EXPECT_EQ(ents[2], 1);
  EXPECT_EQ(ents[3], 1);
  EXPECT_EQ(m.tris.size(), 6u * 4 * 2);
  EXPECT_EQ(count_vertex_dims(m)[2], 26);
  EXPECT_TRUE(validate(m, Level::kFull).valid());
}

TEST(Classification, TwoRegionsShareAnInterface) {
  TetMesh m = make_box_mesh({2, 1, 1}, Vec3(0, 0, 0), Vec3(2, 1, 1), false);
  for (TetId t = 0; t < m.num_tets(); ++t) {
    Vec3 c = Vec3::Zero();
    for (VertId v : m.tet2verts[t]) c += m.coords[v] / 4;
    m.tet_region[t] = c.x() < 1 ? 1 : 2;
  }
  build_adjacency(m);
  derive_classification(m);
  auto ents = count_entities(m);
  EXPECT_EQ(ents[3], 2);
  EXPECT_EQ(ents[2], 3);  // outside of region 1, outside of region 2, interface
  EXPECT_EQ(ents[1], 1);  // the closed loop where the three surfaces meet
  EXPECT_EQ(ents[0], 0);
  // The interface is listed once, and bounds both volumes.
  const EntityInfo* v1 = find_entity(m, 3, 1);
  const EntityInfo* v2 = find_entity(m, 3, 2);
  ASSERT_TRUE(v1 && v2);
  EXPECT_EQ(v1->bounding.size(), 2u);
  EXPECT_EQ(v2->bounding.size(), 2u);
  EXPECT_TRUE(validate(m, Level::kFull).valid());
  // The loop has the 4 vertices of the interface square on it.
  EXPECT_EQ(count_vertex_dims(m)[1], 4);
}

TEST(Classification, DeterministicTags) {
  TetMesh a = make_box_mesh({3, 2, 2}, Vec3(0, 0, 0), Vec3(1, 1, 1), true);
  TetMesh b = make_box_mesh({3, 2, 2}, Vec3(0, 0, 0), Vec3(1, 1, 1), true);
  ASSERT_EQ(a.vert_class.size(), b.vert_class.size());
  for (std::size_t i = 0; i < a.vert_class.size(); ++i) EXPECT_EQ(a.vert_class[i], b.vert_class[i]);
  ASSERT_EQ(a.edges.size(), b.edges.size());
  for (std::size_t i = 0; i < a.edges.size(); ++i) EXPECT_EQ(a.edges[i].edge_tag, b.edges[i].edge_tag);
}
