// The OpenCASCADE model: load time per shared model, and the point-query
// throughput the mesher depends on (curvature and closest point) on the
// largest freeform (B-spline) face of t20_data.step. items_per_second is
// queries per second. Models are read from $CM_MODELS_DIR, by default
// ../../shared/models next to this source file. Run with
// --benchmark_format=json for machine-readable records.
#include <benchmark/benchmark.h>

#include <cstdlib>
#include <filesystem>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "curvemesh/geom_occ/load.hpp"
#include "shared_models.hpp"

namespace {

namespace fs = std::filesystem;
using cm::Vec2;
using cm::Vec3;

// t20_data.step with its largest B-spline face, loaded once for all cases.
struct FreeformFace {
  std::unique_ptr<cm::geom::Model> model;
  int face = 0;
  std::vector<Vec2> params;   // inside the trimmed face
  std::vector<Vec3> probes;   // near the face, made from `params`
};

const FreeformFace& freeform_face() {
  static const FreeformFace data = [] {
    FreeformFace d;
    d.model = cm::geom_occ::load_model((cm::bench::models_dir() / "t20_data.step").string());
    double best_area = 0;
    for (int f = 1; f <= d.model->count(2); ++f) {
      if (d.model->type({2, f}) != cm::geom::ShapeType::kBSplineSurface) continue;
      if (d.model->area(f) > best_area) {
        best_area = d.model->area(f);
        d.face = f;
      }
    }
    const cm::geom::ParamRange r = d.model->param_range({2, d.face});
    const double size = d.model->bounding_box({2, d.face}).diagonal();
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> unit(0, 1);
    std::normal_distribution<double> gauss;
    while (d.params.size() < 4096) {
      const Vec2 uv(r.u0 + unit(rng) * (r.u1 - r.u0), r.v0 + unit(rng) * (r.v1 - r.v0));
      if (!d.model->contains_param(d.face, uv)) continue;
      const Vec3 dir = Vec3(gauss(rng), gauss(rng), gauss(rng)).normalized();
      d.params.push_back(uv);
      d.probes.push_back(d.model->face_point(d.face, uv) + dir * (0.1 * size * unit(rng)));
    }
    return d;
  }();
  return data;
}

void BM_FaceCurvatures(benchmark::State& state) {
  const FreeformFace& d = freeform_face();
  std::size_t i = static_cast<std::size_t>(state.thread_index()) * 977;
  for (auto _ : state) {
    benchmark::DoNotOptimize(d.model->face_curvatures(d.face, d.params[i++ % d.params.size()]));
  }
  state.SetItemsProcessed(state.iterations());
}

void BM_FaceDerivatives(benchmark::State& state) {
  const FreeformFace& d = freeform_face();
  std::size_t i = 0;
  for (auto _ : state) {
    benchmark::DoNotOptimize(d.model->face_derivatives(d.face, d.params[i++ % d.params.size()]));
  }
  state.SetItemsProcessed(state.iterations());
}

void BM_ClosestPointGlobal(benchmark::State& state) {
  const FreeformFace& d = freeform_face();
  std::size_t i = static_cast<std::size_t>(state.thread_index()) * 977;
  for (auto _ : state) {
    benchmark::DoNotOptimize(d.model->closest_point({2, d.face}, d.probes[i++ % d.probes.size()]));
  }
  state.SetItemsProcessed(state.iterations());
}

// The mesher's usual case: the hint is the parameter the point came from.
void BM_ClosestPointWithHint(benchmark::State& state) {
  const FreeformFace& d = freeform_face();
  std::size_t i = 0;
  for (auto _ : state) {
    const std::size_t k = i++ % d.probes.size();
    benchmark::DoNotOptimize(d.model->closest_point({2, d.face}, d.probes[k], d.params[k]));
  }
  state.SetItemsProcessed(state.iterations());
}

void BM_ContainsParam(benchmark::State& state) {
  const FreeformFace& d = freeform_face();
  std::size_t i = 0;
  for (auto _ : state) {
    benchmark::DoNotOptimize(d.model->contains_param(d.face, d.params[i++ % d.params.size()]));
  }
  state.SetItemsProcessed(state.iterations());
}

BENCHMARK(BM_FaceCurvatures)->ThreadRange(1, 2)->UseRealTime();
BENCHMARK(BM_FaceDerivatives);
BENCHMARK(BM_ClosestPointGlobal)->ThreadRange(1, 2)->UseRealTime();
BENCHMARK(BM_ClosestPointWithHint);
BENCHMARK(BM_ContainsParam);

void BM_Load(benchmark::State& state, const std::string& path) {
  int faces = 0;
  for (auto _ : state) {
    const auto model = cm::geom_occ::load_model(path);
    faces = model->count(2);
  }
  state.counters["faces"] = faces;
}

// One load case per shared model, named after the file.
const int kRegistered = [] {
  const std::vector<fs::path> files = cm::bench::model_files();
  for (const fs::path& f : files) {
    benchmark::RegisterBenchmark(("BM_Load/" + f.filename().string()).c_str(), BM_Load, f.string())
        ->Unit(benchmark::kMillisecond)
        ->Iterations(2)
        ->UseRealTime();
  }
  return static_cast<int>(files.size());
}();

}  // namespace

BENCHMARK_MAIN();
