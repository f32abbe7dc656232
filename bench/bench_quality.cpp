// Throughput of the quality measures: straight-tet shape measures, and the
// certified validity of curved P2/P3 tets. Run with --benchmark_format=json
// for machine-readable records; items_per_second is tets per second.
#include <benchmark/benchmark.h>

#include <Eigen/Geometry>
#include <random>
#include <vector>

#include "curvemesh/core/error.hpp"
#include "curvemesh/mesh/high_order.hpp"
#include "curvemesh/quality/bezier_jacobian.hpp"
#include "curvemesh/quality/measures.hpp"
#include "curvemesh/quality/shape_measure.hpp"

namespace {

using cm::Vec3;
namespace q = cm::quality;

constexpr int kTets = 1024;

std::array<Vec3, 4> random_tet(std::mt19937& rng) {
  std::uniform_real_distribution<double> u(-0.15, 0.15);
  std::normal_distribution<double> n01;
  Eigen::Quaterniond rot(n01(rng), n01(rng), n01(rng), n01(rng));
  rot.normalize();
  const std::array<Vec3, 4> reg{Vec3(1, 1, 1), Vec3(1, -1, -1), Vec3(-1, -1, 1), Vec3(-1, 1, -1)};
  std::array<Vec3, 4> v;
  for (int k = 0; k < 4; ++k) v[k] = rot * (0.5 * reg[k] + Vec3(u(rng), u(rng), u(rng)));
  return v;
}

// kTets order-p tets whose edge/face nodes are moved by up to `magnitude`
// (relative to an edge length ~1.4), kept only if certified valid: the
// workload of checking a freshly curved mesh.
std::vector<std::vector<Vec3>> curved_valid_tets(int p, double magnitude) {
  std::mt19937 rng(42);
  std::uniform_real_distribution<double> u(-1, 1);
  const auto idx = cm::mesh::tet_node_indices(p);
  std::vector<std::vector<Vec3>> out;
  while (out.size() < kTets) {
    const auto v = random_tet(rng);
    std::vector<Vec3> nodes;
    for (const auto& a : idx) {
      Vec3 x = Vec3::Zero();
      for (int k = 0; k < 4; ++k) x += (static_cast<double>(a[k]) / p) * v[k];
      if (*std::max_element(a.begin(), a.end()) < p) x += magnitude * Vec3(u(rng), u(rng), u(rng));
      nodes.push_back(x);
    }
    if (q::certify_jacobian(p, nodes).verdict == q::Validity::kValid)
      out.push_back(std::move(nodes));
  }
  return out;
}

// Mean ratio and dihedral angles: Arg 0 the range of angles (a mesh
// summary's), 1 the smallest alone (the optimizer's measure).
void BM_MeanRatioAndDihedral(benchmark::State& state) {
  std::mt19937 rng(1);
  std::vector<std::array<Vec3, 4>> tets;
  for (int i = 0; i < kTets; ++i) tets.push_back(random_tet(rng));
  const bool min_only = state.range(0) == 1;
  for (auto _ : state) {
    double acc = 0;
    for (const auto& t : tets) {
      acc += q::tet_mean_ratio(t[0], t[1], t[2], t[3]);
      acc += min_only ? q::tet_min_dihedral(t[0], t[1], t[2], t[3]) : q::tet_dihedral_range(t[0], t[1], t[2], t[3]).min;
    }
    benchmark::DoNotOptimize(acc);
  }
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations()) * kTets);
}
BENCHMARK(BM_MeanRatioAndDihedral)->Arg(0)->Arg(1);

void BM_CertifyValid(benchmark::State& state) {
  const int p = static_cast<int>(state.range(0));
  const double magnitude = static_cast<double>(state.range(1)) / 100.0;
  const auto tets = curved_valid_tets(p, magnitude);
  long long splits = 0;
  for (auto _ : state) {
    for (const auto& nodes : tets) {
      const q::ValidityReport r = q::certify_jacobian(p, nodes);
      splits += r.splits;
      benchmark::DoNotOptimize(r.min_lower);
    }
  }
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations()) * kTets);
  state.counters["splits_per_tet"] =
      static_cast<double>(splits) / (static_cast<double>(state.iterations()) * kTets);
}
// (order, node displacement in hundredths): mild and strong curving.
BENCHMARK(BM_CertifyValid)->Args({2, 3})->Args({2, 15})->Args({3, 3})->Args({3, 15});

void BM_ShapeMeasure(benchmark::State& state) {
  const int p = static_cast<int>(state.range(0));
  const auto tets = curved_valid_tets(p, 0.03);
  for (auto _ : state) {
    double acc = 0;
    for (const auto& nodes : tets) acc += q::shape_measure(p, nodes).measure;
    benchmark::DoNotOptimize(acc);
  }
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations()) * kTets);
}
BENCHMARK(BM_ShapeMeasure)->Arg(2)->Arg(3);

// The same measure from det J's Bézier coefficients, as the curving check
// computes it after the certification.
void BM_ShapeMeasureFromBezier(benchmark::State& state) {
  const int p = static_cast<int>(state.range(0));
  std::vector<std::vector<double>> coefs;
  for (const auto& nodes : curved_valid_tets(p, 0.03)) coefs.push_back(q::jacobian_bezier_coefficients(p, nodes));
  for (auto _ : state) {
    double acc = 0;
    for (const auto& c : coefs) acc += q::shape_measure_from_bezier(p, c).measure;
    benchmark::DoNotOptimize(acc);
  }
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations()) * kTets);
}
BENCHMARK(BM_ShapeMeasureFromBezier)->Arg(2)->Arg(3);

}  // namespace

BENCHMARK_MAIN();
