#pragma once
// Where the benchmarks find the shared CAD models: $CM_MODELS_DIR, by default
// ../../shared/models next to this source file (../shared beside the project).
#include <algorithm>
#include <cmath>
#include <tuple>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

namespace cm::bench {

inline std::filesystem::path models_dir() {
  if (const char* dir = std::getenv("CM_MODELS_DIR")) return dir;
  return std::filesystem::path(__FILE__).parent_path() / ".." / ".." / "shared" / "models";
}

/// The STEP and BREP files there, sorted by name (empty if the folder is missing).
inline std::vector<std::filesystem::path> model_files() {
  std::vector<std::filesystem::path> files;
  std::error_code ec;
  for (const auto& entry : std::filesystem::directory_iterator(models_dir(), ec)) {
    const std::string ext = entry.path().extension().string();
    if (ext == ".step" || ext == ".stp" || ext == ".brep") files.push_back(entry.path());
  }
  std::sort(files.begin(), files.end());
  return files;
}

/// The Gmsh option that makes it read a STEP or IGES file in `units` (what
/// geom::Model::units() reports): Gmsh converts such files to millimetres,
/// curvemesh keeps the file's own unit, and sizes given to both must mean
/// the same length. Empty for millimetres and for units OpenCASCADE's
/// converter does not name (B-rep files carry no unit: both read them as
/// they are).
inline std::string gmsh_unit_option(const std::string& units) {
  static const std::pair<const char*, const char*> kNames[] = {
      {"cm", "CM"}, {"m", "M"}, {"km", "KM"}, {"um", "UM"}, {"inch", "INCH"}, {"ft", "FT"}, {"mile", "MI"}, {"mil", "MIL"}};
  for (const auto& [ours, occ] : kNames)
    if (units == ours) return std::string(" -setstring Geometry.OCCTargetUnit ") + occ;
  return {};
}

/// Counts within this relative difference are comparable (issue 6: ±15%).
inline constexpr double kMatchedCount = 0.15;

/// Runs Gmsh (`run(factor)`, its sizes scaled by Mesh.MeshSizeFactor) at
/// factor 1, then rescales until its element count (`count(row)`) is within
/// kMatchedCount of `ours`, a few tries at most: element counts go as
/// 1/size^dim. Returns the first run and the last, with the factor used.
template <class Row, class Run, class Count>
std::tuple<Row, Row, double> run_matched(Run&& run, Count&& count, std::size_t ours, int dim) {
  Row first = run(1.0), matched = first;
  double factor = 1;
  for (int attempt = 0; attempt < 4 && matched.ok && count(matched) > 0 && ours > 0; ++attempt) {
    const double ratio = static_cast<double>(count(matched)) / static_cast<double>(ours);
    if (std::abs(ratio - 1) <= kMatchedCount) break;
    factor *= std::pow(ratio, 1.0 / dim);
    matched = run(factor);
  }
  return {first, matched, factor};
}

}  // namespace cm::bench
