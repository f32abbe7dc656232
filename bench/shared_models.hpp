#pragma once
// Where the benchmarks find the shared CAD models: $CM_MODELS_DIR, by default
// ../../shared/models next to this source file (../shared beside the project).
#include <algorithm>
#include <cstdlib>
#include <filesystem>
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

}  // namespace cm::bench
