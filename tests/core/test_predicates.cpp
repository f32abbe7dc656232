// Every predicate is compared with the sign of the same determinant computed in
// exact rational arithmetic (GMP), on random inputs and on inputs built to be
// exactly or nearly degenerate, where the floating-point filter must give up and
// the exact stage decide. Each case also checks antisymmetry under every
// transposition of the arguments.
#include <fmt/format.h>
#include <gmpxx.h>
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdint>
#include <iostream>
#include <limits>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include "curvemesh/core/predicates.hpp"

namespace cm::predicates {
namespace {

template <int D>
using Point = std::array<double, D>;
template <int D, int K>
using Tuple = std::array<Point<D>, K>;

// ---------------------------------------------------------------------------
// The predicate under test, its exact-stage counter and its rational reference,
// chosen by the shape of the argument tuple.

int evaluate(const Tuple<2, 3>& p) { return orient2d(p[0].data(), p[1].data(), p[2].data()); }
int evaluate(const Tuple<2, 4>& p) {
  return incircle(p[0].data(), p[1].data(), p[2].data(), p[3].data());
}
int evaluate(const Tuple<3, 4>& p) {
  return orient3d(p[0].data(), p[1].data(), p[2].data(), p[3].data());
}
int evaluate(const Tuple<3, 5>& p) {
  return insphere(p[0].data(), p[1].data(), p[2].data(), p[3].data(), p[4].data());
}

long long exact_count(const Tuple<2, 3>&) { return exact_stats().orient2d; }
long long exact_count(const Tuple<2, 4>&) { return exact_stats().incircle; }
long long exact_count(const Tuple<3, 4>&) { return exact_stats().orient3d; }
long long exact_count(const Tuple<3, 5>&) { return exact_stats().insphere; }

using Rational = mpq_class;  // mpq_class(double) is exact

Rational det3(const std::array<std::array<Rational, 3>, 3>& m) {
  return m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) -
         m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) +
         m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
}

Rational det4(const std::array<std::array<Rational, 4>, 4>& m) {
  Rational sum = 0;
  for (int col = 0; col < 4; ++col) {
    std::array<std::array<Rational, 3>, 3> minor;
    for (int r = 1; r < 4; ++r) {
      for (int c = 0, k = 0; c < 4; ++c) {
        if (c != col) minor[r - 1][k++] = m[r][c];
      }
    }
    const Rational term = m[0][col] * det3(minor);
    if (col % 2 == 0) {
      sum += term;
    } else {
      sum -= term;
    }
  }
  return sum;
}

// The definitions of the header, translated literally.
int reference(const Tuple<2, 3>& p) {  // det[b-a, c-a]
  const Rational ux = Rational(p[1][0]) - p[0][0], uy = Rational(p[1][1]) - p[0][1];
  const Rational vx = Rational(p[2][0]) - p[0][0], vy = Rational(p[2][1]) - p[0][1];
  return sgn(Rational(ux * vy - uy * vx));
}
int reference(const Tuple<3, 4>& p) {  // det[b-a, c-a, d-a]
  std::array<std::array<Rational, 3>, 3> m;
  for (int i = 0; i < 3; ++i) {
    for (int k = 0; k < 3; ++k) m[i][k] = Rational(p[i + 1][k]) - p[0][k];
  }
  return sgn(det3(m));
}
int reference(const Tuple<2, 4>& p) {  // det[[p-d, |p-d|^2]]
  std::array<std::array<Rational, 3>, 3> m;
  for (int i = 0; i < 3; ++i) {
    m[i][0] = Rational(p[i][0]) - p[3][0];
    m[i][1] = Rational(p[i][1]) - p[3][1];
    m[i][2] = m[i][0] * m[i][0] + m[i][1] * m[i][1];
  }
  return sgn(det3(m));
}
int reference(const Tuple<3, 5>& p) {  // -det[[p-e, |p-e|^2]]
  std::array<std::array<Rational, 4>, 4> m;
  for (int i = 0; i < 4; ++i) {
    m[i][3] = 0;
    for (int k = 0; k < 3; ++k) {
      m[i][k] = Rational(p[i][k]) - p[4][k];
      m[i][3] += m[i][k] * m[i][k];
    }
  }
  return -sgn(det4(m));
}

template <class PointTuple>
std::string describe(const PointTuple& p) {
  std::string s;
  for (const auto& point : p) {
    s += "(";
    for (std::size_t k = 0; k < point.size(); ++k) {
      s += fmt::format("{}{:a}", k ? ", " : "", point[k]);
    }
    s += ") ";
  }
  return s;
}

// ---------------------------------------------------------------------------
// Running a group of cases.

struct Tally {
  long cases = 0;
  long zeros = 0;
  long exact = 0;  // primary calls decided by the exact stage
  long wrong = 0;
  long not_antisymmetric = 0;
  std::string first_failures;

  void note_failure(const std::string& what) {
    if (wrong + not_antisymmetric <= 5) first_failures += what + "\n";
  }
};

template <int D, int K>
void check_case(const Tuple<D, K>& p, Tally& tally) {
  const int expected = reference(p);
  const long long before = exact_count(p);
  const int got = evaluate(p);
  tally.exact += exact_count(p) - before;
  ++tally.cases;
  tally.zeros += expected == 0;
  if (got != expected) {
    ++tally.wrong;
    tally.note_failure(fmt::format("got {} expected {} for {}", got, expected, describe(p)));
  }
  for (int i = 0; i < K; ++i) {
    for (int j = i + 1; j < K; ++j) {
      Tuple<D, K> swapped = p;
      std::swap(swapped[i], swapped[j]);
      if (evaluate(swapped) != -expected) {
        ++tally.not_antisymmetric;
        tally.note_failure(fmt::format("swap {} {} not negated for {}", i, j, describe(p)));
      }
    }
  }
}

template <int D, int K, class Make>
Tally run_group(const std::string& name, int count, Make&& make) {
  Tally tally;
  for (int i = 0; i < count; ++i) check_case<D, K>(make(), tally);
  std::cout << fmt::format("  {:<34} cases {:>6}  zero {:>6}  exact {:>6}\n", name, tally.cases,
                           tally.zeros, tally.exact);
  EXPECT_EQ(tally.wrong, 0) << name << "\n" << tally.first_failures;
  EXPECT_EQ(tally.not_antisymmetric, 0) << name << "\n" << tally.first_failures;
  return tally;
}

// ---------------------------------------------------------------------------
// Input generators. Everything is seeded, so every run sees the same cases.

class Generator {
 public:
  explicit Generator(std::uint64_t seed) : rng_(seed) {}

  double uniform(double lo, double hi) { return std::uniform_real_distribution<>(lo, hi)(rng_); }
  int integer(int lo, int hi) { return std::uniform_int_distribution<>(lo, hi)(rng_); }
  bool coin() { return integer(0, 1) == 1; }

  // +-[1, 2) * 2^e with e in [lo, hi]: a full 53-bit significand.
  double magnitude(int lo, int hi) {
    const double x = std::ldexp(uniform(1.0, 2.0), integer(lo, hi));
    return coin() ? x : -x;
  }

  // Coordinates of widely different magnitudes, between about 1e-30 and 1e30.
  double wide() { return integer(0, 19) == 0 ? 0.0 : magnitude(-99, 98); }

  // Moves one coordinate of one point by 1 or 2 ulps. A zero would become a
  // subnormal, outside the predicates' precondition; it becomes +-2^-100, the
  // smallest magnitude they accept, instead.
  template <class PointTuple>
  PointTuple perturb(PointTuple p) {
    auto& point = p[integer(0, static_cast<int>(p.size()) - 1)];
    double& x = point[integer(0, static_cast<int>(point.size()) - 1)];
    if (x == 0.0) {
      x = coin() ? 0x1p-100 : -0x1p-100;
      return p;
    }
    const double toward =
        coin() ? std::numeric_limits<double>::infinity() : -std::numeric_limits<double>::infinity();
    for (int steps = integer(1, 2); steps > 0; --steps) x = std::nextafter(x, toward);
    return p;
  }

  template <int D, int K, class Coordinate>
  Tuple<D, K> tuple(Coordinate&& coordinate) {
    Tuple<D, K> p;
    for (auto& point : p) {
      for (auto& x : point) x = coordinate();
    }
    return p;
  }

  // Points offset + scale * i with integer |i| <= n (exact by construction).
  template <int D, int K>
  Tuple<D, K> grid(int n, double scale, double offset) {
    return tuple<D, K>([&] { return offset + scale * integer(-n, n); });
  }

  // A random power of two to scale a whole exact configuration without
  // changing whether it is degenerate.
  double power_of_two(int lo, int hi) { return std::ldexp(1.0, integer(lo, hi)); }

  template <int D>
  Point<D> random_direction() {
    Point<D> v;
    double norm2 = 0.0;
    do {
      norm2 = 0.0;
      for (auto& x : v) {
        x = uniform(-1.0, 1.0);
        norm2 += x * x;
      }
    } while (norm2 < 0.01 || norm2 > 1.0);
    for (auto& x : v) x /= std::sqrt(norm2);
    return v;
  }

 private:
  std::mt19937_64 rng_;
};

// Integer points with |p|^2 == radius2.
template <int D>
std::vector<Point<D>> lattice_sphere(int radius2) {
  std::vector<Point<D>> points;
  const int r = static_cast<int>(std::sqrt(radius2)) + 1;
  for (int x = -r; x <= r; ++x) {
    for (int y = -r; y <= r; ++y) {
      if constexpr (D == 2) {
        if (x * x + y * y == radius2) points.push_back({{double(x), double(y)}});
      } else {
        for (int z = -r; z <= r; ++z) {
          if (x * x + y * y + z * z == radius2) {
            points.push_back({{double(x), double(y), double(z)}});
          }
        }
      }
    }
  }
  return points;
}

// K distinct points of one lattice circle/sphere, translated by an integer
// vector and scaled by a power of two: exactly cocircular/cospherical.
template <int D, int K>
Tuple<D, K> on_lattice_sphere(Generator& g, const std::vector<std::vector<Point<D>>>& spheres) {
  const auto& sphere = spheres[g.integer(0, static_cast<int>(spheres.size()) - 1)];
  std::array<int, K> picked;
  for (int i = 0; i < K; ++i) {
    bool fresh = false;
    while (!fresh) {
      picked[i] = g.integer(0, static_cast<int>(sphere.size()) - 1);
      fresh = true;
      for (int j = 0; j < i; ++j) fresh = fresh && picked[j] != picked[i];
    }
  }
  Point<D> shift;
  for (auto& x : shift) x = g.integer(-1000, 1000);
  const double scale = g.power_of_two(-60, 60);
  Tuple<D, K> p;
  for (int i = 0; i < K; ++i) {
    for (int k = 0; k < D; ++k) p[i][k] = (sphere[picked[i]][k] + shift[k]) * scale;
  }
  return p;
}

// o + s u + t v with small integers s, t (exactly coplanar; collinear in 2D
// when only u is used). o is dyadic so that all sums stay exact.
template <int D, int K>
Tuple<D, K> on_lattice_plane(Generator& g, int directions) {
  Point<D> o;
  std::array<Point<D>, 2> dir;
  for (auto& x : o) x = std::ldexp(g.integer(-(1 << 20), 1 << 20), -10);
  for (auto& v : dir) {
    for (auto& x : v) x = g.integer(-5, 5);
  }
  Tuple<D, K> p;
  for (auto& point : p) {
    const int s = g.integer(-10, 10);
    const int t = directions > 1 ? g.integer(-10, 10) : 0;
    for (int k = 0; k < D; ++k) point[k] = o[k] + s * dir[0][k] + t * dir[1][k];
  }
  return p;
}

// ---------------------------------------------------------------------------
// Groups shared by all predicates.

constexpr int kRandomCases = 10000;
constexpr int kDegenerateCases = 5000;

template <int D, int K>
void check_random_groups(std::uint64_t seed) {
  Generator g(seed);
  const Tally uniform = run_group<D, K>("uniform [-1,1]", kRandomCases, [&] {
    return g.tuple<D, K>([&] { return g.uniform(-1.0, 1.0); });
  });
  // The filter should settle nearly every random case.
  EXPECT_LE(uniform.exact, kRandomCases / 100);
  run_group<D, K>("magnitudes 1e-30..1e30", kRandomCases,
                  [&] { return g.tuple<D, K>([&] { return g.wide(); }); });
  run_group<D, K>("clustered near 1e6", kRandomCases,
                  [&] { return g.tuple<D, K>([&] { return 1e6 + g.uniform(-1e-6, 1e-6); }); });
}

template <int D, int K>
void check_grid_groups(std::uint64_t seed) {
  Generator g(seed);
  auto expect_degenerate = [](const Tally& t) {
    EXPECT_GT(t.zeros, t.cases / 50);
    EXPECT_GE(t.exact, t.zeros);  // the filter can never answer 0
  };
  expect_degenerate(run_group<D, K>("integer grid [-2,2]", kDegenerateCases,
                                    [&] { return g.grid<D, K>(2, 1.0, 0.0); }));
  expect_degenerate(run_group<D, K>("fine grid 1 + i 2^-40", kDegenerateCases,
                                    [&] { return g.grid<D, K>(3, 0x1p-40, 1.0); }));
  expect_degenerate(run_group<D, K>("grid offset by 2^40", kDegenerateCases,
                                    [&] { return g.grid<D, K>(3, 1.0, 0x1p40); }));
  expect_degenerate(run_group<D, K>("grid scaled 2^-99..2^96", kDegenerateCases,
                                    [&] { return g.grid<D, K>(2, g.power_of_two(-99, 96), 0.0); }));
  const Tally decimal = run_group<D, K>("decimal grid i/10", kDegenerateCases, [&] {
    return g.tuple<D, K>([&] { return g.integer(-10, 10) * 0.1; });
  });
  EXPECT_GT(decimal.exact, 0);
  const Tally perturbed = run_group<D, K>("integer grid, 1-2 ulp moved", kDegenerateCases,
                                          [&] { return g.perturb(g.grid<D, K>(2, 1.0, 0.0)); });
  EXPECT_GT(perturbed.exact, perturbed.cases / 20);
}

// ---------------------------------------------------------------------------
// orient2d

TEST(Orient2d, KnownValues) {
  const double a[2] = {0, 0}, b[2] = {1, 0}, c[2] = {0, 1}, m[2] = {0.5, 0};
  EXPECT_EQ(orient2d(a, b, c), 1);
  EXPECT_EQ(orient2d(a, c, b), -1);
  EXPECT_EQ(orient2d(a, b, m), 0);
  // Collinear in exact arithmetic although the naive evaluation is not zero.
  const double p[2] = {0.1, 0.1}, q[2] = {0.3, 0.3}, r[2] = {0.7, 0.7};
  EXPECT_EQ(orient2d(p, q, r), reference(Tuple<2, 3>{{{0.1, 0.1}, {0.3, 0.3}, {0.7, 0.7}}}));
}

TEST(Orient2d, MatchesRationalOnRandomInputs) { check_random_groups<2, 3>(101); }
TEST(Orient2d, MatchesRationalOnGrids) { check_grid_groups<2, 3>(102); }

TEST(Orient2d, MatchesRationalOnNearCollinearInputs) {
  Generator g(103);
  const Tally collinear = run_group<2, 3>("exactly collinear", kDegenerateCases,
                                          [&] { return on_lattice_plane<2, 3>(g, 1); });
  EXPECT_EQ(collinear.zeros, collinear.cases);
  run_group<2, 3>("collinear, 1-2 ulp moved", kDegenerateCases,
                  [&] { return g.perturb(on_lattice_plane<2, 3>(g, 1)); });
  const Tally rounded = run_group<2, 3>("c = a + t (b - a) rounded", kDegenerateCases, [&] {
    Tuple<2, 3> p;
    const double scale = g.power_of_two(-60, 90);  // stays above 2^-100
    for (int k = 0; k < 2; ++k) {
      p[0][k] = g.uniform(-1, 1) * scale;
      p[1][k] = g.uniform(-1, 1) * scale;
    }
    const double t = g.uniform(-2, 3);
    for (int k = 0; k < 2; ++k) p[2][k] = p[0][k] + t * (p[1][k] - p[0][k]);
    return p;
  });
  EXPECT_GT(rounded.exact, rounded.cases / 2);
}

// ---------------------------------------------------------------------------
// orient3d

TEST(Orient3d, KnownValues) {
  const double o[3] = {0, 0, 0}, x[3] = {1, 0, 0}, y[3] = {0, 1, 0}, z[3] = {0, 0, 1};
  const double in_plane[3] = {0.25, 0.5, 0};
  EXPECT_EQ(orient3d(o, x, y, z), 1);  // d above the ccw triangle (o, x, y)
  EXPECT_EQ(orient3d(o, y, x, z), -1);
  EXPECT_EQ(orient3d(o, x, y, in_plane), 0);
  EXPECT_DOUBLE_EQ(orient3d_fast(o, x, y, z), 1.0);
  EXPECT_DOUBLE_EQ(orient3d_fast(o, y, x, z), -1.0);
}

TEST(Orient3d, MatchesRationalOnRandomInputs) { check_random_groups<3, 4>(201); }
TEST(Orient3d, MatchesRationalOnGrids) { check_grid_groups<3, 4>(202); }

TEST(Orient3d, MatchesRationalOnNearCoplanarInputs) {
  Generator g(203);
  const Tally coplanar = run_group<3, 4>("exactly coplanar", kDegenerateCases,
                                         [&] { return on_lattice_plane<3, 4>(g, 2); });
  EXPECT_EQ(coplanar.zeros, coplanar.cases);
  run_group<3, 4>("coplanar, 1-2 ulp moved", kDegenerateCases,
                  [&] { return g.perturb(on_lattice_plane<3, 4>(g, 2)); });
  run_group<3, 4>("grid scaled per axis", kDegenerateCases, [&] {
    Tuple<3, 4> p = g.grid<3, 4>(2, 1.0, 0.0);
    for (int k = 0; k < 3; ++k) {
      const double s = g.power_of_two(-99, 96);
      for (auto& point : p) point[k] *= s;
    }
    return p;
  });
  const Tally rounded = run_group<3, 4>("d = a + s(b-a) + t(c-a) rounded", kDegenerateCases, [&] {
    Tuple<3, 4> p;
    const double scale = g.power_of_two(-60, 60);
    for (int i = 0; i < 3; ++i) {
      for (int k = 0; k < 3; ++k) p[i][k] = g.uniform(-1, 1) * scale;
    }
    const double s = g.uniform(-1, 2), t = g.uniform(-1, 2);
    for (int k = 0; k < 3; ++k) {
      p[3][k] = p[0][k] + s * (p[1][k] - p[0][k]) + t * (p[2][k] - p[0][k]);
    }
    return p;
  });
  EXPECT_GT(rounded.exact, rounded.cases / 2);
}

TEST(Orient3dFast, AgreesWithExactSignWhenWellConditioned) {
  Generator g(204);
  int compared = 0;
  for (int i = 0; i < 10000; ++i) {
    const auto p = g.tuple<3, 4>([&] { return g.uniform(-1.0, 1.0); });
    const double v = orient3d_fast(p[0].data(), p[1].data(), p[2].data(), p[3].data());
    if (std::abs(v) < 1e-6) continue;
    ++compared;
    EXPECT_EQ(v > 0 ? 1 : -1, evaluate(p)) << describe(p);
  }
  EXPECT_GT(compared, 9000);
}

// ---------------------------------------------------------------------------
// incircle

TEST(Incircle, KnownValues) {
  const double a[2] = {0, 0}, b[2] = {1, 0}, c[2] = {0, 1};
  const double inside[2] = {0.25, 0.25}, on[2] = {1, 1}, outside[2] = {2, 2};
  EXPECT_EQ(incircle(a, b, c, inside), 1);
  EXPECT_EQ(incircle(a, b, c, on), 0);
  EXPECT_EQ(incircle(a, b, c, outside), -1);
  EXPECT_EQ(incircle(a, c, b, inside), -1);  // clockwise triangle flips the sign
}

TEST(Incircle, MatchesRationalOnRandomInputs) { check_random_groups<2, 4>(301); }
TEST(Incircle, MatchesRationalOnGrids) { check_grid_groups<2, 4>(302); }

TEST(Incircle, MatchesRationalOnNearCocircularInputs) {
  Generator g(303);
  const std::vector<std::vector<Point<2>>> circles = {lattice_sphere<2>(25), lattice_sphere<2>(625),
                                                      lattice_sphere<2>(4225)};
  ASSERT_EQ(circles[0].size(), 12u);
  const Tally cocircular = run_group<2, 4>("lattice circles", kDegenerateCases,
                                           [&] { return on_lattice_sphere<2, 4>(g, circles); });
  EXPECT_EQ(cocircular.zeros, cocircular.cases);
  run_group<2, 4>("lattice circles, 1-2 ulp moved", kDegenerateCases,
                  [&] { return g.perturb(on_lattice_sphere<2, 4>(g, circles)); });
  run_group<2, 4>("collinear", kDegenerateCases, [&] { return on_lattice_plane<2, 4>(g, 1); });
  const Tally rounded = run_group<2, 4>("center + r (cos, sin) rounded", kDegenerateCases, [&] {
    const double r = g.magnitude(-40, 40);
    const Point<2> center{{g.uniform(-1, 1) * r * 4, g.uniform(-1, 1) * r * 4}};
    Tuple<2, 4> p;
    for (auto& point : p) {
      const double angle = g.uniform(0, 6.283185307179586);
      point = {center[0] + r * std::cos(angle), center[1] + r * std::sin(angle)};
    }
    return p;
  });
  EXPECT_GT(rounded.exact, rounded.cases / 2);
}

// ---------------------------------------------------------------------------
// insphere

TEST(Insphere, KnownValues) {
  const double o[3] = {0, 0, 0}, x[3] = {1, 0, 0}, y[3] = {0, 1, 0}, z[3] = {0, 0, 1};
  const double inside[3] = {0.1, 0.1, 0.1}, on[3] = {1, 1, 1}, outside[3] = {1, 1, 1.5};
  ASSERT_EQ(orient3d(o, x, y, z), 1);
  EXPECT_EQ(insphere(o, x, y, z, inside), 1);
  EXPECT_EQ(insphere(o, x, y, z, on), 0);
  EXPECT_EQ(insphere(o, x, y, z, outside), -1);
  EXPECT_EQ(insphere(o, y, x, z, inside), -1);  // negative tet flips the sign
}

TEST(Insphere, MatchesRationalOnRandomInputs) { check_random_groups<3, 5>(401); }
TEST(Insphere, MatchesRationalOnGrids) { check_grid_groups<3, 5>(402); }

TEST(Insphere, MatchesRationalOnNearCosphericalInputs) {
  Generator g(403);
  // 3^2 = 1+4+4 = 9, 9^2 = 1+16+64 = 16+16+49 = ..., 13^2 = 9+16+144 = ...
  const std::vector<std::vector<Point<3>>> spheres = {lattice_sphere<3>(9), lattice_sphere<3>(81),
                                                      lattice_sphere<3>(169)};
  ASSERT_EQ(spheres[0].size(), 30u);  // permutations of (+-3,0,0) and (+-1,+-2,+-2)
  const Tally cospherical = run_group<3, 5>("lattice spheres", kDegenerateCases,
                                            [&] { return on_lattice_sphere<3, 5>(g, spheres); });
  EXPECT_EQ(cospherical.zeros, cospherical.cases);
  run_group<3, 5>("lattice spheres, 1-2 ulp moved", kDegenerateCases,
                  [&] { return g.perturb(on_lattice_sphere<3, 5>(g, spheres)); });
  run_group<3, 5>("coplanar", kDegenerateCases, [&] { return on_lattice_plane<3, 5>(g, 2); });
  const long long unsettled_before = exact_stats().insphere_unsettled;
  const Tally rounded = run_group<3, 5>("center + r u rounded", kDegenerateCases, [&] {
    const double r = g.magnitude(-20, 20);
    Point<3> center;
    for (auto& x : center) x = g.uniform(-1, 1) * r * 4;
    Tuple<3, 5> p;
    for (auto& point : p) {
      const Point<3> u = g.random_direction<3>();
      for (int k = 0; k < 3; ++k) point[k] = center[k] + r * u[k];
    }
    return p;
  });
  EXPECT_GT(rounded.exact, rounded.cases / 2);
  // Rounded onto a sphere, points are not cospherical: the first-order
  // stage settles nearly all of them, and the rational reference checks it.
  EXPECT_LT(exact_stats().insphere_unsettled - unsettled_before, rounded.exact / 10);
}

// ---------------------------------------------------------------------------
// The references' sign conventions against the geometric definitions:
// circumcenter computed exactly, then inside/outside by comparing distances.

template <int D>
int geometric_insphere(const Tuple<D, D + 2>& p, int orientation) {
  // Circumcenter c: 2 (p_i - p_0) . c = |p_i|^2 - |p_0|^2, solved by Cramer.
  std::array<std::array<Rational, D>, D> m;
  std::array<Rational, D> rhs;
  for (int i = 0; i < D; ++i) {
    rhs[i] = 0;
    for (int k = 0; k < D; ++k) {
      m[i][k] = 2 * (Rational(p[i + 1][k]) - p[0][k]);
      rhs[i] += Rational(p[i + 1][k]) * p[i + 1][k] - Rational(p[0][k]) * p[0][k];
    }
  }
  auto det = [](const std::array<std::array<Rational, D>, D>& a) {
    if constexpr (D == 2) {
      return Rational(a[0][0] * a[1][1] - a[0][1] * a[1][0]);
    } else {
      return det3(a);
    }
  };
  const Rational denominator = det(m);
  std::array<Rational, D> center;
  for (int k = 0; k < D; ++k) {
    auto replaced = m;
    for (int i = 0; i < D; ++i) replaced[i][k] = rhs[i];
    center[k] = det(replaced) / denominator;
  }
  Rational radius2 = 0, distance2 = 0;
  for (int k = 0; k < D; ++k) {
    radius2 += (p[0][k] - center[k]) * (p[0][k] - center[k]);
    distance2 += (p[D + 1][k] - center[k]) * (p[D + 1][k] - center[k]);
  }
  return orientation * sgn(Rational(radius2 - distance2));
}

TEST(ReferenceConventions, MatchCircumcircleAndCircumsphere) {
  Generator g(501);
  for (int i = 0; i < 2000; ++i) {
    const auto p2 = g.tuple<2, 4>([&] { return g.uniform(-1.0, 1.0); });
    const Tuple<2, 3> triangle{{p2[0], p2[1], p2[2]}};
    if (reference(triangle) == 0) continue;
    EXPECT_EQ(reference(p2), geometric_insphere<2>(p2, reference(triangle))) << describe(p2);

    const auto p3 = g.tuple<3, 5>([&] { return g.uniform(-1.0, 1.0); });
    const Tuple<3, 4> tet{{p3[0], p3[1], p3[2], p3[3]}};
    if (reference(tet) == 0) continue;
    EXPECT_EQ(reference(p3), geometric_insphere<3>(p3, reference(tet))) << describe(p3);
  }
}

// ---------------------------------------------------------------------------
// Threads.

TEST(ExactStats, CountsOnlyExactCallsOfTheCallingThread) {
  const double a[3] = {0, 0, 0}, b[3] = {1, 0, 0}, c[3] = {0, 1, 0}, d[3] = {0, 0, 1};
  const double in_plane[3] = {1, 1, 0};
  exact_stats() = {};
  EXPECT_EQ(orient3d(a, b, c, d), 1);
  EXPECT_EQ(exact_stats().orient3d, 0);  // decided by the filter
  EXPECT_EQ(orient3d(a, b, c, in_plane), 0);
  EXPECT_EQ(exact_stats().orient3d, 1);
  long long other_thread = -1;
  std::thread worker([&] {
    orient3d(a, b, c, in_plane);
    orient3d(a, b, c, in_plane);
    other_thread = exact_stats().orient3d;
  });
  worker.join();
  EXPECT_EQ(other_thread, 2);
  EXPECT_EQ(exact_stats().orient3d, 1);
}

TEST(Predicates, ConcurrentCallsGiveTheSequentialAnswers) {
  Generator g(601);
  std::vector<Tuple<3, 5>> cases;
  const std::vector<std::vector<Point<3>>> spheres = {lattice_sphere<3>(81)};
  for (int i = 0; i < 2000; ++i) cases.push_back(g.perturb(on_lattice_sphere<3, 5>(g, spheres)));
  std::vector<int> sequential;
  for (const auto& p : cases) sequential.push_back(evaluate(p));
  std::array<std::vector<int>, 2> parallel;
  std::vector<std::thread> threads;
  for (auto& out : parallel) {
    threads.emplace_back([&cases, &out] {
      for (const auto& p : cases) out.push_back(evaluate(p));
    });
  }
  for (auto& t : threads) t.join();
  EXPECT_EQ(parallel[0], sequential);
  EXPECT_EQ(parallel[1], sequential);
}

}  // namespace
}  // namespace cm::predicates
