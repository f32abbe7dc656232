// Predicate throughput (items_per_second = calls per second) on random inputs,
// where the floating-point filter decides, and on near-degenerate inputs
// (rounded constructions of collinear / coplanar / cocircular / cospherical
// points), where most calls go to the exact stage, and on small-integer grid
// points, whose many exact degeneracies reach the exact stage with short
// expansions. The counter exact_fraction
// reports the share of calls that did. Run with --benchmark_format=json for a
// machine-readable record.
#include <benchmark/benchmark.h>

#include <cmath>
#include <random>
#include <vector>

#include "curvemesh/core/predicates.hpp"

namespace {

using cm::predicates::exact_stats;
using cm::predicates::ExactStats;

enum class Inputs { kRandom, kNearDegenerate, kIntegerGrid };

constexpr int kTuples = 1024;  // a power of two, cycled through by the loop

// kTuples tuples of K points in dimension D, stored flat (K * D doubles each).
template <int D, int K>
std::vector<double> make_tuples(Inputs inputs, bool on_sphere) {
  std::mt19937_64 rng(20240601);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  std::vector<double> data(static_cast<std::size_t>(kTuples) * K * D);
  for (int t = 0; t < kTuples; ++t) {
    double* p = &data[static_cast<std::size_t>(t) * K * D];
    for (int i = 0; i < K * D; ++i) p[i] = unit(rng);
    if (inputs == Inputs::kRandom) continue;
    if (inputs == Inputs::kIntegerGrid) {
      for (int i = 0; i < K * D; ++i) p[i] = std::floor(2.0 * (p[i] + 1.0));  // 0..3
      continue;
    }
    if (on_sphere) {
      // Every point at distance 1 from the origin, rounded.
      for (int i = 0; i < K; ++i) {
        double norm2 = 0.0;
        for (int k = 0; k < D; ++k) norm2 += p[i * D + k] * p[i * D + k];
        for (int k = 0; k < D; ++k) p[i * D + k] /= std::sqrt(norm2);
      }
    } else {
      // The last point an affine combination of the first D, rounded.
      double* last = p + (K - 1) * D;
      for (int k = 0; k < D; ++k) last[k] = p[k];
      for (int j = 1; j < D; ++j) {
        const double weight = unit(rng);
        for (int k = 0; k < D; ++k) last[k] += weight * (p[j * D + k] - p[k]);
      }
    }
  }
  return data;
}

template <int D, int K, class Call>
void run(benchmark::State& state, Inputs inputs, bool on_sphere, Call call,
         long long ExactStats::*counter) {
  const std::vector<double> data = make_tuples<D, K>(inputs, on_sphere);
  exact_stats() = {};
  int tuple = 0;
  int sum = 0;
  for (auto _ : state) {
    sum += call(&data[static_cast<std::size_t>(tuple) * K * D]);
    tuple = (tuple + 1) & (kTuples - 1);
  }
  benchmark::DoNotOptimize(sum);
  state.SetItemsProcessed(state.iterations());
  state.counters["exact_fraction"] =
      static_cast<double>(exact_stats().*counter) / static_cast<double>(state.iterations());
}

void bm_orient2d(benchmark::State& state, Inputs inputs) {
  run<2, 3>(
      state, inputs, false,
      [](const double* p) { return cm::predicates::orient2d(p, p + 2, p + 4); },
      &ExactStats::orient2d);
}

void bm_orient3d(benchmark::State& state, Inputs inputs) {
  run<3, 4>(
      state, inputs, false,
      [](const double* p) { return cm::predicates::orient3d(p, p + 3, p + 6, p + 9); },
      &ExactStats::orient3d);
}

void bm_incircle(benchmark::State& state, Inputs inputs) {
  run<2, 4>(
      state, inputs, true,
      [](const double* p) { return cm::predicates::incircle(p, p + 2, p + 4, p + 6); },
      &ExactStats::incircle);
}

void bm_insphere(benchmark::State& state, Inputs inputs) {
  run<3, 5>(
      state, inputs, true,
      [](const double* p) { return cm::predicates::insphere(p, p + 3, p + 6, p + 9, p + 12); },
      &ExactStats::insphere);
}

// The unfiltered determinant, as the cost floor of orient3d.
void bm_orient3d_fast(benchmark::State& state, Inputs inputs) {
  run<3, 4>(
      state, inputs, false,
      [](const double* p) {
        return cm::predicates::orient3d_fast(p, p + 3, p + 6, p + 9) > 0.0 ? 1 : -1;
      },
      &ExactStats::orient3d);
}

BENCHMARK_CAPTURE(bm_orient2d, random, Inputs::kRandom);
BENCHMARK_CAPTURE(bm_orient3d, random, Inputs::kRandom);
BENCHMARK_CAPTURE(bm_incircle, random, Inputs::kRandom);
BENCHMARK_CAPTURE(bm_insphere, random, Inputs::kRandom);
BENCHMARK_CAPTURE(bm_orient3d_fast, random, Inputs::kRandom);
BENCHMARK_CAPTURE(bm_orient2d, near_degenerate, Inputs::kNearDegenerate);
BENCHMARK_CAPTURE(bm_orient3d, near_degenerate, Inputs::kNearDegenerate);
BENCHMARK_CAPTURE(bm_incircle, near_degenerate, Inputs::kNearDegenerate);
BENCHMARK_CAPTURE(bm_insphere, near_degenerate, Inputs::kNearDegenerate);
BENCHMARK_CAPTURE(bm_orient2d, integer_grid, Inputs::kIntegerGrid);
BENCHMARK_CAPTURE(bm_orient3d, integer_grid, Inputs::kIntegerGrid);
BENCHMARK_CAPTURE(bm_incircle, integer_grid, Inputs::kIntegerGrid);
BENCHMARK_CAPTURE(bm_insphere, integer_grid, Inputs::kIntegerGrid);

}  // namespace

BENCHMARK_MAIN();
