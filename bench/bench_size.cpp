// The size field per shared model with the default options (hmax = diagonal
// / 20, hmin = hmax / 100, alpha = 0.04, hgrad = 1.3): curvature samples per
// second, and the time to build the whole field (sampling + octree). The
// share of meshing time spent on curvature (the seed reports 1.35%, ours
// must stay under 5%) is reported by the volume-mesh benchmark once the
// mesher exists; no Gmsh counterpart is timed here because Gmsh builds its
// curvature sizes inside surface meshing, not as a separate field.
// Models are read from $CM_MODELS_DIR, by default ../../shared/models.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "curvemesh/geom_occ/load.hpp"
#include "shared_models.hpp"
#include "curvemesh/size/build.hpp"

namespace {

namespace fs = std::filesystem;

void BM_SizeField(benchmark::State& state, const std::string& path) {
  const auto model = cm::geom_occ::load_model(path);
  cm::size::SizeOptions options;
  double sampling = 0, curvature = 0, octree = 0;
  std::size_t evaluations = 0, samples = 0, leaves = 0;
  for (auto _ : state) {
    const cm::size::SizeFieldResult r = cm::size::build_size_field(*model, options);
    sampling += r.sampling_seconds;
    curvature += r.curvature_seconds;
    octree += r.octree_seconds;
    evaluations += r.stats.evaluations;
    samples = r.samples.size();
    leaves = r.octree->num_leaves();
  }
  const double n = static_cast<double>(state.iterations());
  state.counters["curv_samples_per_s"] = curvature > 0 ? evaluations / curvature : 0;
  state.counters["evaluations"] = evaluations / n;
  state.counters["kept_samples"] = static_cast<double>(samples);
  state.counters["sampling_ms"] = 1e3 * sampling / n;
  state.counters["curvature_ms"] = 1e3 * curvature / n;
  state.counters["octree_ms"] = 1e3 * octree / n;
  state.counters["leaves"] = static_cast<double>(leaves);
}

const int kRegistered = [] {
  const std::vector<fs::path> files = cm::bench::model_files();
  for (const fs::path& f : files)
    benchmark::RegisterBenchmark(("BM_SizeField/" + f.filename().string()).c_str(), BM_SizeField, f.string())
        ->Unit(benchmark::kMillisecond)
        ->Iterations(2)
        ->UseRealTime();
  return static_cast<int>(files.size());
}();

}  // namespace

BENCHMARK_MAIN();
