#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <iostream>
#include <limits>
#include <random>
#include <set>
#include <stdexcept>
#include <string>
#include <utility>

#include <Eigen/Eigenvalues>
#include <tbb/parallel_for.h>

#include "curvemesh/mesh/structured.hpp"
#include "curvemesh/size/background_field.hpp"

using namespace cm;
using namespace cm::size;

namespace {

// Moves every vertex not on the box boundary by up to `amount` cells per
// axis, so the tets are no longer the regular Kuhn ones; the domain stays the
// box (boundary vertices do not move).
void jitter_interior(mesh::TetMesh& m, const std::array<int, 3>& n, const Vec3& lo, const Vec3& hi, double amount,
                     std::mt19937& rng) {
  std::uniform_real_distribution<double> u(-amount, amount);
  for (Vec3& x : m.coords) {
    bool boundary = false;
    for (int k = 0; k < 3; ++k) boundary = boundary || x[k] == lo[k] || x[k] == hi[k];
    if (boundary) continue;
    for (int k = 0; k < 3; ++k) x[k] += u(rng) * (hi[k] - lo[k]) / n[k];
  }
}

bool all_positive(const mesh::TetMesh& m) {
  for (TetId t = 0; t < m.num_tets(); ++t)
    if (!(mesh::tet_volume(m, t) > 0)) return false;
  return true;
}

template <class F>
std::vector<double> at_vertices(const mesh::TetMesh& m, F f) {
  std::vector<double> h;
  for (const Vec3& x : m.coords) h.push_back(f(x));
  return h;
}

Vec3 random_point(std::mt19937& rng, const Vec3& lo, const Vec3& hi) {
  std::uniform_real_distribution<double> u(0, 1);
  Vec3 x;
  for (int k = 0; k < 3; ++k) x[k] = lo[k] + u(rng) * (hi[k] - lo[k]);
  return x;
}

Vec3 clamp_to_box(const Vec3& x, const Vec3& lo, const Vec3& hi) { return x.cwiseMax(lo).cwiseMin(hi); }

std::vector<std::pair<VertId, VertId>> mesh_edges(const mesh::TetMesh& m) {
  std::set<std::pair<VertId, VertId>> edges;
  for (const auto& tv : m.tet2verts)
    for (const auto& e : mesh::kTetEdges) edges.insert(std::minmax(tv[e[0]], tv[e[1]]));
  return {edges.begin(), edges.end()};
}

Metric random_metric(std::mt19937& rng, double hmin, double hmax) {
  std::normal_distribution<double> g;
  std::uniform_real_distribution<double> u(std::log(hmin), std::log(hmax));
  const Mat3 r = Eigen::Quaterniond(g(rng), g(rng), g(rng), g(rng)).normalized().toRotationMatrix();
  const Vec3 h(std::exp(u(rng)), std::exp(u(rng)), std::exp(u(rng)));
  return metric_from_sizes({r.col(0), r.col(1), r.col(2)}, h);
}

// Largest λ with a·u = λ·b·u: > 1 iff a asks for a shorter size than b in
// some direction.
double excess(const Metric& a, const Metric& b) {
  const Eigen::GeneralizedSelfAdjointEigenSolver<Metric> ges(a, b, Eigen::EigenvaluesOnly | Eigen::Ax_lBx);
  return ges.eigenvalues()[2];
}

double relative_difference(const Metric& a, const Metric& b) { return (a - b).norm() / b.norm(); }

template <class F>
std::string invalid_argument_message(F f) {
  try {
    f();
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "<no std::invalid_argument thrown>";
}

mesh::TetMesh unit_cube_mesh(int n) { return mesh::make_box_mesh({n, n, n}, Vec3(0, 0, 0), Vec3(1, 1, 1), false); }

}  // namespace

TEST(BackgroundField, LinearSizeReproducedInside) {
  std::mt19937 rng(1);
  const Vec3 lo(0, 0, 0), hi(2, 3, 1.5);
  const std::array<int, 3> n{5, 6, 7};
  mesh::TetMesh m = mesh::make_box_mesh(n, lo, hi, false);
  jitter_interior(m, n, lo, hi, 0.2, rng);
  ASSERT_TRUE(all_positive(m));
  auto h = [](const Vec3& x) { return 1 + x.x() + 2 * x.y(); };
  const auto sizes = at_vertices(m, h);
  const BackgroundField field(m, sizes);
  EXPECT_EQ(field.num_tets(), m.num_tets());
  EXPECT_FALSE(field.anisotropic());
  for (int i = 0; i < 2000; ++i) {
    const Vec3 x = random_point(rng, lo, hi);
    EXPECT_NEAR(field.size(x), h(x), 1e-12) << x.transpose();
    const auto loc = field.locate(x);
    EXPECT_EQ(loc.distance, 0.0);
    EXPECT_LT(relative_difference(field.metric(x), isotropic_metric(h(x))), 1e-12);
  }
  for (VertId v = 0; v < m.num_verts(); ++v) EXPECT_NEAR(field.size(m.coords[v]), sizes[v], 1e-12);
}

TEST(BackgroundField, OutsidePointsGetTheNearestBoundaryValue) {
  std::mt19937 rng(2);
  const Vec3 lo(0, 0, 0), hi(2, 3, 1.5);
  const std::array<int, 3> n{4, 5, 3};
  mesh::TetMesh m = mesh::make_box_mesh(n, lo, hi, false);
  jitter_interior(m, n, lo, hi, 0.2, rng);
  auto h = [](const Vec3& x) { return 1 + x.x() + 2 * x.y(); };
  const BackgroundField field(m, at_vertices(m, h));
  int outside = 0;
  for (int i = 0; i < 2000; ++i) {
    const Vec3 x = random_point(rng, Vec3(-2, -2, -2), Vec3(4, 5, 3.5));
    const Vec3 c = clamp_to_box(x, lo, hi);
    if (c == x) continue;
    ++outside;
    const auto loc = field.locate(x);
    EXPECT_NEAR(loc.distance, (x - c).norm(), 1e-12) << x.transpose();
    EXPECT_NEAR(field.size(x), h(c), 1e-12) << x.transpose();
  }
  EXPECT_GT(outside, 1000);
}

TEST(BackgroundField, NearestInsideANotchOfANonConvexMesh) {
  // An L-shaped prism: the unit cube without the quarter x > 1/2, y > 1/2.
  // Points of the notch are inside the mesh's bounding box but in no tet.
  mesh::TetMesh box = unit_cube_mesh(4);
  mesh::TetMesh m;
  m.coords = box.coords;
  for (TetId t = 0; t < box.num_tets(); ++t) {
    Vec3 c = Vec3::Zero();
    for (VertId v : box.tet2verts[t]) c += box.coords[v] / 4;
    if (!(c.x() > 0.5 && c.y() > 0.5)) m.add_tet(box.tet2verts[t], 1);
  }
  auto h = [](const Vec3& x) { return 2 + 3 * x.x() + 2 * x.y() - x.z(); };
  const BackgroundField field(m, at_vertices(m, h));
  std::mt19937 rng(3);
  for (int i = 0; i < 500; ++i) {
    const Vec3 x = random_point(rng, Vec3(0.5, 0.5, 0), Vec3(1, 1, 1));
    Vec3 c = x;
    if (x.x() - 0.5 < x.y() - 0.5)
      c.x() = 0.5;
    else
      c.y() = 0.5;
    EXPECT_NEAR(field.locate(x).distance, (x - c).norm(), 1e-12) << x.transpose();
    EXPECT_NEAR(field.size(x), h(c), 1e-12) << x.transpose();
  }
}

TEST(BackgroundField, FlatTetsStillServeTheOutsideProjection) {
  // A proper tet next to a flat one (four coplanar points, z = 0) and a
  // needle (three collinear corners): neither can contain a point, but the
  // nearest point of the mesh may lie on them.
  mesh::TetMesh m;
  for (const Vec3& x : {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(0, 0, 1), Vec3(3, 0, 0), Vec3(4, 0, 0),
                        Vec3(3, 1, 0), Vec3(4, 1, 0), Vec3(6, 0, 0), Vec3(7, 0, 0), Vec3(8, 0, 0), Vec3(7, 0, 1)})
    m.add_vert(x);
  m.add_tet({0, 1, 2, 3}, 1);
  m.add_tet({4, 5, 6, 7}, 1);
  m.add_tet({8, 9, 10, 11}, 1);
  auto h = [](const Vec3& x) { return 1 + x.x() + 0.5 * x.y() + 0.25 * x.z(); };
  const BackgroundField field(m, at_vertices(m, h));
  const auto flat = field.locate(Vec3(3.5, 0.25, 1));
  EXPECT_EQ(flat.tet, 1u);
  EXPECT_NEAR(flat.distance, 1, 1e-12);
  EXPECT_NEAR(field.size(Vec3(3.5, 0.25, 1)), h(Vec3(3.5, 0.25, 0)), 1e-12);
  const auto needle = field.locate(Vec3(7.5, -2, 0));
  EXPECT_EQ(needle.tet, 2u);
  EXPECT_NEAR(needle.distance, 2, 1e-12);
  EXPECT_NEAR(field.size(Vec3(7.5, -2, 0)), h(Vec3(7.5, 0, 0)), 1e-12);
  EXPECT_NEAR(field.size(Vec3(0.2, 0.2, 0.2)), h(Vec3(0.2, 0.2, 0.2)), 1e-12);
}

TEST(BackgroundField, ConstantTensorInterpolatesToItself) {
  std::mt19937 rng(4);
  const mesh::TetMesh m = unit_cube_mesh(3);
  const Metric c = random_metric(rng, 0.01, 1);
  const BackgroundField field(m, std::vector<Metric>(m.num_verts(), c));
  EXPECT_TRUE(field.anisotropic());
  for (int i = 0; i < 500; ++i) {
    const Vec3 x = random_point(rng, Vec3(-0.5, -0.5, -0.5), Vec3(1.5, 1.5, 1.5));
    EXPECT_LT(relative_difference(field.metric(x), c), 1e-10);
    EXPECT_NEAR(field.size(x), min_size(c), 1e-12);
  }
}

TEST(BackgroundField, LogEuclideanMidpointIsTheGeometricMean) {
  const mesh::TetMesh m = unit_cube_mesh(1);
  const Metric a = Vec3(1, 4, 100).asDiagonal(), b = Vec3(16, 1, 1).asDiagonal();
  std::vector<Metric> metrics;
  for (const Vec3& x : m.coords) metrics.push_back(x.x() == 0 ? a : b);
  const BackgroundField field(m, metrics);
  std::mt19937 rng(5);
  for (int i = 0; i < 100; ++i) {
    const Vec3 x(0.5, std::uniform_real_distribution<double>(0, 1)(rng), std::uniform_real_distribution<double>(0, 1)(rng));
    const Metric expected = Vec3(4, 2, 10).asDiagonal();
    EXPECT_LT(relative_difference(field.metric(x), expected), 1e-12) << field.metric(x);
    EXPECT_NEAR(field.size(x), 1 / std::sqrt(10.0), 1e-12);
  }
}

TEST(BackgroundField, TensorFieldMatchesInterpolateOfTheCorners) {
  std::mt19937 rng(6);
  const mesh::TetMesh m = unit_cube_mesh(3);
  std::vector<Metric> metrics;
  for (std::size_t v = 0; v < m.num_verts(); ++v) metrics.push_back(random_metric(rng, 0.01, 1));
  const BackgroundField field(m, metrics);
  for (int i = 0; i < 500; ++i) {
    const Vec3 x = random_point(rng, Vec3(-0.3, -0.3, -0.3), Vec3(1.3, 1.3, 1.3));
    const auto loc = field.locate(x);
    ASSERT_NE(loc.tet, kNone);
    std::array<Metric, 4> corners;
    for (int k = 0; k < 4; ++k) corners[k] = metrics[m.tet2verts[loc.tet][k]];
    const Metric expected = interpolate(corners, loc.bary);
    EXPECT_LT(relative_difference(field.metric(x), expected), 1e-10);
    EXPECT_NEAR(field.size(x), min_size(expected), 1e-12 * min_size(expected));
  }
}

TEST(BackgroundField, BadInputsNameTheVertex) {
  const mesh::TetMesh m = unit_cube_mesh(1);  // 8 vertices
  const double nan = std::numeric_limits<double>::quiet_NaN(), inf = std::numeric_limits<double>::infinity();
  auto sizes_with = [&](std::size_t v, double value) {
    std::vector<double> h(m.num_verts(), 1.0);
    h[v] = value;
    return h;
  };
  auto scalar = [&](std::vector<double> h) { return [&m, h] { BackgroundField f(m, h); }; };
  EXPECT_NE(invalid_argument_message(scalar(sizes_with(6, nan))).find("vertex 7"), std::string::npos);
  EXPECT_NE(invalid_argument_message(scalar(sizes_with(2, -1))).find("vertex 3"), std::string::npos);
  EXPECT_NE(invalid_argument_message(scalar(sizes_with(0, 0))).find("vertex 1"), std::string::npos);
  EXPECT_NE(invalid_argument_message(scalar(sizes_with(7, inf))).find("vertex 8"), std::string::npos);
  EXPECT_NE(invalid_argument_message(scalar(std::vector<double>(7, 1.0))).find("7 sizes given for 8"),
            std::string::npos);

  auto metrics_with = [&](std::size_t v, const Metric& value) {
    std::vector<Metric> ms(m.num_verts(), Metric::Identity());
    ms[v] = value;
    return ms;
  };
  auto tensor = [&](std::vector<Metric> ms) { return [&m, ms] { BackgroundField f(m, ms); }; };
  const std::string indefinite = invalid_argument_message(tensor(metrics_with(4, Vec3(1, -2, 3).asDiagonal())));
  EXPECT_NE(indefinite.find("vertex 5"), std::string::npos) << indefinite;
  EXPECT_NE(indefinite.find("positive definite"), std::string::npos) << indefinite;
  Metric skew = Metric::Identity();
  skew(0, 1) = 0.5;
  const std::string asym = invalid_argument_message(tensor(metrics_with(1, skew)));
  EXPECT_NE(asym.find("vertex 2"), std::string::npos) << asym;
  EXPECT_NE(asym.find("not symmetric"), std::string::npos) << asym;
  Metric bad = Metric::Identity();
  bad(2, 2) = nan;
  EXPECT_NE(invalid_argument_message(tensor(metrics_with(3, bad))).find("vertex 4"), std::string::npos);
  EXPECT_NE(invalid_argument_message(tensor(metrics_with(3, Metric::Zero()))).find("vertex 4"), std::string::npos);
  EXPECT_NE(invalid_argument_message(tensor(std::vector<Metric>(9, Metric::Identity()))).find("9 metrics"),
            std::string::npos);

  mesh::TetMesh broken = m;
  broken.tet2verts[2][1] = 8;
  EXPECT_THROW(BackgroundField(broken, std::vector<double>(8, 1.0)), std::invalid_argument);
  EXPECT_THROW(BackgroundField(mesh::TetMesh{}, std::vector<double>{}), std::invalid_argument);

  EXPECT_THROW(grade_sizes(m, std::vector<double>(8, 1.0), 0.9), std::invalid_argument);
  EXPECT_THROW(grade_sizes(m, std::vector<double>(8, 1.0), nan), std::invalid_argument);
  EXPECT_THROW(grade_metrics(m, std::vector<Metric>(8, Metric::Identity()), inf), std::invalid_argument);
  EXPECT_NE(invalid_argument_message([&] { grade_sizes(m, sizes_with(5, -2), 1.2); }).find("vertex 6"),
            std::string::npos);
  EXPECT_NE(invalid_argument_message([&] { grade_metrics(m, metrics_with(5, -Metric::Identity()), 1.2); })
                .find("vertex 6"),
            std::string::npos);

  const BackgroundField ok(m, std::vector<double>(8, 1.0));
  EXPECT_THROW(ok.size(Vec3(nan, 0, 0)), std::domain_error);
}

TEST(GradeSizes, BoundHoldsOnEveryEdgeAndMatchesRelaxation) {
  std::mt19937 rng(7);
  const Vec3 lo(0, 0, 0), hi(1, 2, 1);
  const std::array<int, 3> n{6, 5, 4};
  mesh::TetMesh m = mesh::make_box_mesh(n, lo, hi, false);
  jitter_interior(m, n, lo, hi, 0.2, rng);
  std::vector<double> h0;
  std::uniform_real_distribution<double> u(std::log(0.01), 0);
  for (std::size_t v = 0; v < m.num_verts(); ++v) h0.push_back(std::exp(u(rng)));
  const double hgrad = 1.2;
  const auto h = grade_sizes(m, h0, hgrad);
  ASSERT_EQ(h.size(), h0.size());
  const auto edges = mesh_edges(m);
  for (const auto& [a, b] : edges) {
    const double len = (m.coords[a] - m.coords[b]).norm();
    EXPECT_LE(h[b], (h[a] + (hgrad - 1) * len) * (1 + 1e-14));
    EXPECT_LE(h[a], (h[b] + (hgrad - 1) * len) * (1 + 1e-14));
  }
  std::size_t lowered = 0;
  for (std::size_t v = 0; v < h.size(); ++v) {
    EXPECT_LE(h[v], h0[v]);
    lowered += h[v] < h0[v];
  }
  EXPECT_GT(lowered, h.size() / 4);
  // An independent fixpoint: relax every edge until nothing changes.
  std::vector<double> r = h0;
  for (bool changed = true; changed;) {
    changed = false;
    for (const auto& [a, b] : edges) {
      const double w = (hgrad - 1) * (m.coords[a] - m.coords[b]).norm();
      if (r[a] + w < r[b]) r[b] = r[a] + w, changed = true;
      if (r[b] + w < r[a]) r[a] = r[b] + w, changed = true;
    }
  }
  for (std::size_t v = 0; v < h.size(); ++v) EXPECT_NEAR(h[v], r[v], 1e-12 * r[v]);
}

TEST(GradeSizes, SingleSmallSizeSpreadsAlongEdges) {
  const int n = 8;
  const mesh::TetMesh m = unit_cube_mesh(n);
  const double h0 = 0.01, hmax = 1, hgrad = 1.5;
  std::vector<double> h(m.num_verts(), hmax);
  ASSERT_EQ(m.coords[0], Vec3(0, 0, 0));
  h[0] = h0;
  const auto g = grade_sizes(m, h, hgrad);
  auto expected_on_straight_path = [&](const Vec3& x) { return std::min(hmax, h0 + (hgrad - 1) * x.norm()); };
  for (VertId v = 0; v < m.num_verts(); ++v) {
    const Vec3& x = m.coords[v];
    // The x axis and the cube diagonal from the corner are edge paths (the
    // Kuhn tets of every cell share its main diagonal): there the graph
    // distance is the Euclidean one.
    const bool straight = (x.y() == 0 && x.z() == 0) || (x.x() == x.y() && x.y() == x.z());
    if (straight)
      EXPECT_NEAR(g[v], expected_on_straight_path(x), 1e-12) << x.transpose();
    else
      EXPECT_GE(g[v], expected_on_straight_path(x) - 1e-12) << x.transpose();
    EXPECT_LE(g[v], hmax);
  }
}

TEST(GradeSizes, HgradOneGivesTheMinimumEverywhere) {
  const mesh::TetMesh m = unit_cube_mesh(3);
  std::vector<double> h(m.num_verts());
  for (std::size_t v = 0; v < h.size(); ++v) h[v] = 1 + static_cast<double>(v % 7);
  h[17] = 0.25;
  for (double x : grade_sizes(m, h, 1.0)) EXPECT_EQ(x, 0.25);
}

TEST(GradeMetrics, LowersOnlyAndBoundsEveryEdge) {
  std::mt19937 rng(8);
  const Vec3 lo(0, 0, 0), hi(1, 1, 1);
  const std::array<int, 3> n{5, 5, 5};
  mesh::TetMesh m = mesh::make_box_mesh(n, lo, hi, false);
  jitter_interior(m, n, lo, hi, 0.2, rng);
  std::vector<Metric> m0;
  for (std::size_t v = 0; v < m.num_verts(); ++v) m0.push_back(random_metric(rng, 0.005, 0.5));
  const double hgrad = 1.3;
  const auto g = grade_metrics(m, m0, hgrad);
  ASSERT_EQ(g.size(), m0.size());
  std::size_t changed = 0;
  for (std::size_t v = 0; v < g.size(); ++v) {
    ASSERT_TRUE(is_metric(g[v])) << v;
    EXPECT_LE(excess(m0[v], g[v]), 1 + 1e-9) << "vertex " << v << " was coarsened";
    changed += relative_difference(g[v], m0[v]) > 1e-6;
  }
  EXPECT_GT(changed, g.size() / 4);
  for (const auto& [a, b] : mesh_edges(m))
    for (const auto& [p, q] : {std::pair{a, b}, std::pair{b, a}}) {
      const double eta = 1 + (hgrad - 1) * metric_length(g[p], m.coords[p], m.coords[q]);
      EXPECT_LE(excess(g[p] / (eta * eta), g[q]), 1 + 1e-6) << "edge " << p << " -> " << q;
    }
}

TEST(GradeMetrics, IsotropicMetricsMatchGradeSizes) {
  std::mt19937 rng(9);
  const mesh::TetMesh m = unit_cube_mesh(4);
  std::vector<double> h;
  std::vector<Metric> ms;
  std::uniform_real_distribution<double> u(std::log(0.01), 0);
  for (std::size_t v = 0; v < m.num_verts(); ++v) {
    h.push_back(std::exp(u(rng)));
    ms.push_back(isotropic_metric(h.back()));
  }
  const auto gh = grade_sizes(m, h, 1.4);
  const auto gm = grade_metrics(m, ms, 1.4);
  for (std::size_t v = 0; v < h.size(); ++v) {
    const Vec3 s = metric_sizes(gm[v]);
    EXPECT_NEAR(s[0], gh[v], 1e-9 * gh[v]);
    EXPECT_NEAR(s[2], gh[v], 1e-9 * gh[v]);
  }
}

TEST(BackgroundField, LocatesTheRightTetAmong200kTetsInParallel) {
  std::mt19937 rng(10);
  const Vec3 lo(0, 0, 0), hi(3, 3.2, 3.5);
  const std::array<int, 3> n{30, 32, 35};
  mesh::TetMesh m = mesh::make_box_mesh(n, lo, hi, false);
  jitter_interior(m, n, lo, hi, 0.15, rng);
  ASSERT_TRUE(all_positive(m));
  ASSERT_GE(m.num_tets(), 200000u);
  auto h = [](const Vec3& x) { return 0.1 + x.x() * x.x() + x.y(); };

  const auto t0 = std::chrono::steady_clock::now();
  const BackgroundField field(m, at_vertices(m, h));
  const auto t1 = std::chrono::steady_clock::now();

  const std::size_t num_points = 100000;
  std::vector<Vec3> points(num_points);
  for (Vec3& x : points) x = random_point(rng, lo, hi);
  std::vector<BackgroundField::Location> parallel(num_points), serial(num_points);
  const auto t2 = std::chrono::steady_clock::now();
  tbb::parallel_for(std::size_t{0}, num_points, [&](std::size_t i) { parallel[i] = field.locate(points[i]); });
  const auto t3 = std::chrono::steady_clock::now();
  for (std::size_t i = 0; i < num_points; ++i) serial[i] = field.locate(points[i]);
  const auto t4 = std::chrono::steady_clock::now();

  auto seconds = [](auto a, auto b) { return std::chrono::duration<double>(b - a).count(); };
  std::cout << "BackgroundField on " << field.num_tets() << " tets: build " << seconds(t0, t1) << " s, "
            << num_points / seconds(t3, t4) << " points/s serial, " << num_points / seconds(t2, t3)
            << " points/s parallel\n";

  for (std::size_t i = 0; i < num_points; ++i) {
    const auto& loc = parallel[i];
    ASSERT_EQ(loc.tet, serial[i].tet) << i;
    ASSERT_EQ(loc.bary, serial[i].bary) << i;
    ASSERT_NE(loc.tet, kNone);
    EXPECT_EQ(loc.distance, 0.0);
    // Non-negative weights summing to 1 that reproduce x: x is in the tet.
    Vec3 y = Vec3::Zero();
    double sum = 0;
    for (int k = 0; k < 4; ++k) {
      EXPECT_GE(loc.bary[k], 0.0);
      sum += loc.bary[k];
      y += loc.bary[k] * m.coords[m.tet2verts[loc.tet][k]];
    }
    EXPECT_NEAR(sum, 1, 1e-14);
    ASSERT_LT((y - points[i]).norm(), 1e-12) << i;
  }

  // Brute force on a sample: every tet whose box holds the point is tested.
  std::vector<std::array<Vec3, 2>> boxes;
  for (const auto& tv : m.tet2verts) {
    Vec3 a = m.coords[tv[0]], b = a;
    for (VertId v : tv) a = a.cwiseMin(m.coords[v]), b = b.cwiseMax(m.coords[v]);
    boxes.push_back({a, b});
  }
  for (std::size_t i = 0; i < 1000; ++i) {
    const Vec3& x = points[i];
    std::vector<TetId> containing;
    for (TetId t = 0; t < m.num_tets(); ++t) {
      if ((x.array() < boxes[t][0].array()).any() || (x.array() > boxes[t][1].array()).any()) continue;
      const auto& tv = m.tet2verts[t];
      Mat3 e;
      for (int k = 0; k < 3; ++k) e.col(k) = m.coords[tv[k + 1]] - m.coords[tv[0]];
      const Vec3 l = e.partialPivLu().solve(x - m.coords[tv[0]]);
      if (l.minCoeff() >= -1e-12 && 1 - l.sum() >= -1e-12) containing.push_back(t);
    }
    ASSERT_FALSE(containing.empty()) << i;
    EXPECT_NE(std::find(containing.begin(), containing.end(), parallel[i].tet), containing.end())
        << "point " << i << " located in tet " << parallel[i].tet << ", brute force finds " << containing.front();
  }

  // Values and points outside, in parallel too.
  std::vector<double> sizes(1000);
  std::vector<Vec3> outside(1000);
  for (Vec3& x : outside) x = random_point(rng, lo - Vec3(1, 1, 1), hi + Vec3(1, 1, 1));
  tbb::parallel_for(std::size_t{0}, outside.size(), [&](std::size_t i) { sizes[i] = field.size(outside[i]); });
  for (std::size_t i = 0; i < outside.size(); ++i) {
    const Vec3 c = clamp_to_box(outside[i], lo, hi);
    // The field is linear per tet, h is not: compare with the field at c.
    EXPECT_NEAR(sizes[i], field.size(c), 1e-12);
  }
  const auto t5 = std::chrono::steady_clock::now();
  std::vector<double> far(num_points);
  tbb::parallel_for(std::size_t{0}, num_points, [&](std::size_t i) {
    const Vec3 x = points[i] + Vec3(5, 0, 0);  // beyond the +x side
    far[i] = field.locate(x).distance;
  });
  const auto t6 = std::chrono::steady_clock::now();
  std::cout << "  outside points: " << num_points / seconds(t5, t6) << " points/s parallel\n";
}
