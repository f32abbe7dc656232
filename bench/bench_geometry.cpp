// The OpenCASCADE model: load time per shared model, the point-query
// throughput the mesher depends on (curvature and closest point) on the
// largest freeform (B-spline) face of t20_data.step, and classify_point (the
// point-in-solid test behind sizes on regions) on a few shared models, warm
// (the region's classifier already built) and cold (the first call on a
// freshly loaded model, which builds it). items_per_second is queries per
// second. Models are read from $CM_MODELS_DIR, by default
// ../../shared/models next to this source file. Run with
// --benchmark_format=json for machine-readable records.
#include <benchmark/benchmark.h>

#include <cstdlib>
#include <filesystem>
#include <map>
#include <memory>
#include <mutex>
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

// The region of largest volume (ring.brep's region 1 is a small ring).
int largest_region(const cm::geom::Model& model) {
  int best = 1;
  for (int r = 2; r <= model.count(3); ++r)
    if (model.volume(r) > model.volume(best)) best = r;
  return best;
}

// Uniform probes in the model's box: what the size octree asks.
std::vector<Vec3> box_probes(const cm::geom::Model& model, std::size_t n) {
  const cm::geom::BoundingBox b = model.bounding_box();
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> unit(0, 1);
  std::vector<Vec3> probes(n);
  for (Vec3& p : probes) p = b.min + Vec3(unit(rng), unit(rng), unit(rng)).cwiseProduct(b.size());
  return probes;
}

void BM_ClassifyPoint(benchmark::State& state, const std::string& path) {
  static std::mutex mutex;
  static std::map<std::string, std::unique_ptr<cm::geom::Model>> models;
  const cm::geom::Model* model = nullptr;
  {
    const std::lock_guard<std::mutex> lock(mutex);
    auto& slot = models[path];
    if (!slot) slot = cm::geom_occ::load_model(path);
    model = slot.get();
  }
  const std::vector<Vec3> probes = box_probes(*model, 4096);
  const int region = largest_region(*model);
  std::size_t i = static_cast<std::size_t>(state.thread_index()) * 331;
  model->classify_point(region, probes[i % probes.size()]);  // prepares the region, untimed
  std::size_t inside = 0;
  for (auto _ : state) {
    inside += model->classify_point(region, probes[i++ % probes.size()]) != cm::geom::Containment::kOutside;
  }
  state.SetItemsProcessed(state.iterations());
  state.counters["faces"] = benchmark::Counter(model->count(2), benchmark::Counter::kAvgThreads);
  state.counters["inside_fraction"] = benchmark::Counter(
      double(inside) / double(std::max<std::int64_t>(1, state.iterations())), benchmark::Counter::kAvgThreads);
}

void BM_ClassifyPointCold(benchmark::State& state, const std::string& path) {
  for (auto _ : state) {
    state.PauseTiming();
    const auto model = cm::geom_occ::load_model(path);
    const Vec3 centre = 0.5 * (model->bounding_box().min + model->bounding_box().max);
    const int region = largest_region(*model);
    state.ResumeTiming();
    benchmark::DoNotOptimize(model->classify_point(region, centre));
  }
}

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
  for (const char* name :
       {"t20_data.step", "Zylkopf.stp", "SampleCrankshaft4A.stp", "917_fusee.stp", "ring.brep", "dlr_f6.brep"}) {
    const fs::path f = cm::bench::models_dir() / name;
    if (!fs::exists(f)) continue;
    benchmark::RegisterBenchmark((std::string("BM_ClassifyPoint/") + name).c_str(), BM_ClassifyPoint, f.string())
        ->Unit(benchmark::kMicrosecond)
        ->ThreadRange(1, 2)
        ->UseRealTime();
    benchmark::RegisterBenchmark((std::string("BM_ClassifyPointCold/") + name).c_str(), BM_ClassifyPointCold,
                                 f.string())
        ->Unit(benchmark::kMillisecond)
        ->Iterations(2);
  }
  return static_cast<int>(files.size());
}();

}  // namespace

BENCHMARK_MAIN();
