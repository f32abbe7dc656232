// Adjacency construction rate and memory per tet of the compact mesh arrays.
#include <benchmark/benchmark.h>

#include "curvemesh/mesh/adjacency.hpp"
#include "curvemesh/mesh/structured.hpp"

using namespace cm;

static void BM_BuildAdjacency(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  mesh::TetMesh m = mesh::make_box_mesh({n, n, n}, Vec3(0, 0, 0), Vec3(1, 1, 1), false);
  for (auto _ : state) {
    mesh::build_adjacency(m);
    benchmark::DoNotOptimize(m.tet2adj.data());
  }
  state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(m.num_tets()));
  state.counters["tets"] = static_cast<double>(m.num_tets());
  state.counters["bytes_per_tet"] = static_cast<double>(m.memory_bytes()) / static_cast<double>(m.num_tets());
}
BENCHMARK(BM_BuildAdjacency)->Arg(20)->Arg(56)->Unit(benchmark::kMillisecond);

static void BM_Ball(benchmark::State& state) {
  mesh::TetMesh m = mesh::make_box_mesh({30, 30, 30}, Vec3(0, 0, 0), Vec3(1, 1, 1), false);
  mesh::build_adjacency(m);
  std::vector<TetId> ball;
  VertId v = 0;
  for (auto _ : state) {
    mesh::collect_ball(m, v, ball);
    benchmark::DoNotOptimize(ball.data());
    v = (v + 7919) % static_cast<VertId>(m.num_verts());
  }
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_Ball);

BENCHMARK_MAIN();
