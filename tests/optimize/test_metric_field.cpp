// Measures in a metric field: edge lengths against hand-computed integrals,
// log-Euclidean interpolation against closed forms, tet quality in a
// metric, building, clamping and grading a per-vertex field.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <stdexcept>

#include <Eigen/Geometry>

#include "curvemesh/mesh/structured.hpp"
#include "curvemesh/optimize/metric_field.hpp"

using namespace cm;
using namespace cm::optimize;

namespace {

Mat3 rotation() { return Eigen::AngleAxisd(0.7, Vec3(1, 2, 3).normalized()).toRotationMatrix(); }

Mat3 rotated_diag(const Vec3& d) { return rotation() * d.asDiagonal() * rotation().transpose(); }

}  // namespace

TEST(MetricLength, UsesSizeLinearAlongTheEdge) {
  // e = (2,0,0); at p the size along x is 1 (l_a = 2), at q it is 1/2
  // (l_b = 4). With h(t) = 1 - t/2, L = ∫ 2 / h(t) dt = 4 ln 2.
  const Vec3 p(0, 0, 0), q(2, 0, 0);
  const Mat3 mp = Mat3::Identity();
  const Mat3 mq = Vec3(4, 1, 1).asDiagonal();
  EXPECT_NEAR(edge_metric_length(p, q, mp, mq), 4 * std::log(2.0), 1e-14);
  EXPECT_NEAR(edge_metric_length(q, p, mq, mp), 4 * std::log(2.0), 1e-14);  // symmetric
  // A metric constant along the edge gives sqrt(eᵀMe).
  const Mat3 m = rotated_diag(Vec3(1, 4, 9));
  EXPECT_NEAR(edge_metric_length(p, Vec3(0.3, -0.2, 0.5), m, m),
              size::metric_length(m, p, Vec3(0.3, -0.2, 0.5)), 1e-14);
  // Nearly equal endpoint lengths take the series branch without a jump.
  const Mat3 close = Mat3::Identity() * (1 + 2e-4);
  const Mat3 closer = Mat3::Identity() * (1 + 1e-5);
  const double a = edge_metric_length(p, q, mp, close), b = edge_metric_length(p, q, mp, closer);
  EXPECT_GT(a, b);
  EXPECT_NEAR(b, 2 * (1 + 0.25e-5), 1e-9);
}

TEST(MetricLength, FieldMeasuresMeshEdges) {
  auto m = mesh::make_box_mesh({1, 1, 1}, Vec3(0, 0, 0), Vec3(1, 1, 1), false);
  std::vector<double> h(m.num_verts(), 0.5);
  h[0] = 0.25;
  const auto f = MetricField::from_sizes(h);
  EXPECT_FALSE(f.anisotropic());
  // Vertex 0 at the origin, vertex 1 at (1,0,0): sizes 0.25 and 0.5 give
  // l_a = 4, l_b = 2, L = 8 ln 2 / 2.
  ASSERT_EQ(m.coords[1], Vec3(1, 0, 0));
  EXPECT_NEAR(f.edge_length(m, 0, 1), 4 * std::log(2.0), 1e-14);
  const auto stats = measure_lengths(m, f);
  EXPECT_EQ(stats.edges, 19u);  // 12 cube edges, 6 face diagonals, 1 main diagonal
  EXPECT_EQ(stats.in_range, 0u);
  EXPECT_EQ(stats.too_long, 19u);
}

TEST(LogEuclidean, CommutingMetricsInterpolateGeometrically) {
  const Mat3 a = rotated_diag(Vec3(1, 4, 9)), b = rotated_diag(Vec3(16, 1, 1));
  const double w = 0.3;
  const Mat3 expected = rotated_diag(Vec3(std::pow(1.0, 1 - w) * std::pow(16.0, w), std::pow(4.0, 1 - w),
                                          std::pow(9.0, 1 - w)));
  auto f = MetricField::from_tensors({a, b});
  f.set_interpolated(2, 0, 1, w);
  EXPECT_LT((f.metric(2) - expected).norm(), 1e-12 * expected.norm());
  const std::array<Mat3, 2> ms{a, b};
  const std::array<double, 2> ws{1 - w, w};
  EXPECT_LT((size::interpolate(ms, ws) - expected).norm(), 1e-12 * expected.norm());
}

TEST(LogEuclidean, DeterminantIsGeometricForAnyPair) {
  // det exp(A) = exp(tr A) and the trace is linear: det M(t) =
  // det(A)^(1-t) det(B)^t even when A and B do not commute.
  const Mat3 a = rotated_diag(Vec3(1, 4, 9));
  const Mat3 b = Vec3(0.5, 2, 30).asDiagonal();
  auto f = MetricField::from_tensors({a, b});
  for (double t : {0.0, 0.25, 0.5, 1.0}) {
    f.set_interpolated(2, 0, 1, t);
    const double expected = std::pow(a.determinant(), 1 - t) * std::pow(b.determinant(), t);
    EXPECT_NEAR(f.metric(2).determinant(), expected, 1e-10 * expected) << t;
    EXPECT_TRUE(size::is_metric(f.metric(2)));
  }
  f.set_interpolated(2, 0, 1, 0.0);
  EXPECT_LT((f.metric(2) - a).norm(), 1e-12 * a.norm());
}

TEST(MetricQuality, StretchedRegularTetIsRegularInItsMetric) {
  mesh::TetMesh m;
  const double s = 10;  // stretch along z
  for (const Vec3& p : {Vec3(1, 1, 1), Vec3(1, -1, -1), Vec3(-1, 1, -1), Vec3(-1, -1, 1)})
    m.add_vert(Vec3(p.x(), p.y(), s * p.z()));
  // (a,b,c,d) positive: det[b-a, c-a, d-a] > 0.
  std::array<VertId, 4> tet{0, 1, 2, 3};
  const Vec3 e1 = m.coords[1] - m.coords[0], e2 = m.coords[2] - m.coords[0], e3 = m.coords[3] - m.coords[0];
  if (e1.dot(e2.cross(e3)) < 0) std::swap(tet[0], tet[1]);
  const Mat3 metric = Vec3(1, 1, 1 / (s * s)).asDiagonal();
  const auto iso = MetricField::from_sizes(std::vector<double>(4, 1.0));
  const auto ani = MetricField::from_tensors(std::vector<Mat3>(4, metric));
  EXPECT_LT(iso.tet_quality(m, tet), 0.3);
  EXPECT_NEAR(ani.tet_quality(m, tet), 1.0, 1e-12);
  std::swap(tet[0], tet[1]);
  EXPECT_EQ(ani.tet_quality(m, tet), -1);  // inverted
}

TEST(MetricField, FromValuesChecksCountsAndTensors) {
  const std::vector<double> three{1, 2, 3};
  try {
    metric_field_from_values(three, 1, 4);
    FAIL() << "expected an error";
  } catch (const std::invalid_argument& e) {
    EXPECT_STREQ(e.what(), "3 sizes for the 4 vertices of the mesh");
  }
  EXPECT_THROW(metric_field_from_values(std::vector<double>{1, 0, 1, 0, 0, 1, 1}, 6, 1), std::invalid_argument);
  EXPECT_THROW(metric_field_from_values(std::vector<double>{1, -1}, 1, 2), std::invalid_argument);
  // MMG order m11 m12 m22 m13 m23 m33; an indefinite one is refused with its vertex.
  const auto f = metric_field_from_values(std::vector<double>{4, 1, 9, 2, 3, 16}, 6, 1);
  Mat3 expected;
  expected << 4, 1, 2, 1, 9, 3, 2, 3, 16;
  EXPECT_EQ(f.metric(0), expected);
  try {
    metric_field_from_values(std::vector<double>{1, 0, 1, 0, 0, 1, 1, 0, 1, 0, 0, -1}, 6, 2);
    FAIL() << "expected an error";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("vertex 2"), std::string::npos) << e.what();
  }
}

TEST(MetricField, ValuesGiveBackWhatTheFieldWasMadeFrom) {
  // What a .sol written from a field holds reads back as the same field.
  const std::vector<double> tensors{4, 1, 9, 2, 3, 16, 1, 0, 1, 0, 0, 1};
  const auto values = metric_field_values(metric_field_from_values(tensors, 6, 2));
  ASSERT_EQ(values.size(), tensors.size());
  for (std::size_t k = 0; k < values.size(); ++k) EXPECT_NEAR(values[k], tensors[k], 1e-12 * 16) << k;
  const std::vector<double> sizes{0.5, 2, 0.125};
  const auto iso = metric_field_values(metric_field_from_values(sizes, 1, 3));
  ASSERT_EQ(iso.size(), sizes.size());
  for (std::size_t k = 0; k < iso.size(); ++k) EXPECT_NEAR(iso[k], sizes[k], 1e-15) << k;
}

TEST(MetricField, ClampAndGrade) {
  auto m = mesh::make_box_mesh({4, 4, 4}, Vec3(0, 0, 0), Vec3(1, 1, 1), true);
  std::vector<double> h(m.num_verts(), 1.0);
  h[0] = 0.01;
  auto f = MetricField::from_sizes(h);
  clamp_sizes(f, 0.02, 0.5);
  EXPECT_NEAR(f.size_at(0), 0.02, 1e-15);
  EXPECT_NEAR(f.size_at(1), 0.5, 1e-15);
  EXPECT_THROW(clamp_sizes(f, 1, 0.5), std::invalid_argument);
  grade(f, m, 1.3);
  // The bound holds on every edge and the source keeps its size.
  EXPECT_NEAR(f.size_at(0), 0.02, 1e-15);
  for (const auto& tv : m.tet2verts)
    for (const auto& e : mesh::kTetEdges) {
      const VertId a = tv[e[0]], b = tv[e[1]];
      const double d = (m.coords[a] - m.coords[b]).norm();
      EXPECT_LE(f.size_at(b), f.size_at(a) + 0.3 * d + 1e-12);
    }
  EXPECT_NEAR(f.size_at(1), 0.02 + 0.3 * 0.25, 1e-12);  // one cell edge from vertex 0

  // Anisotropic: eigenvalues clamped, directions kept.
  auto g = MetricField::from_tensors({rotated_diag(Vec3(1e6, 1, 1e-6))});
  clamp_sizes(g, 0.01, 10);
  const Vec3 sizes = size::metric_sizes(g.metric(0));
  EXPECT_NEAR(sizes[0], 0.01, 1e-11);
  EXPECT_NEAR(sizes[1], 1, 1e-9);
  EXPECT_NEAR(sizes[2], 10, 1e-8);
}

TEST(MetricField, MeshShapeRecoversStretching) {
  // Cells 0.25 x 0.25 x 2.5: the fitted metric is about 10 times finer
  // across than along z, z being its coarsest direction.
  auto m = mesh::make_box_mesh({4, 4, 4}, Vec3(0, 0, 0), Vec3(1, 1, 10), true);
  const auto f = metric_field_from_mesh_shape(m);
  ASSERT_TRUE(f.anisotropic());
  Mat3 dirs;
  const VertId center = static_cast<VertId>(2 + 5 * 2 + 25 * 2);
  ASSERT_EQ(m.coords[center], Vec3(0.5, 0.5, 5));
  const Vec3 sizes = size::metric_sizes(f.metric(center), &dirs);
  EXPECT_GT(sizes[2] / sizes[0], 5);
  EXPECT_GT(std::abs(dirs.col(2).z()), 0.99);
  const auto iso = metric_field_from_mesh_sizes(m);
  EXPECT_FALSE(iso.anisotropic());
  EXPECT_GT(iso.size_at(center), 1.0);
}
