// Finding and loading the OpenCASCADE plugins (detail/plugin.hpp).
#include <dlfcn.h>
#include <unistd.h>

#include <array>
#include <cstdlib>
#include <filesystem>
#include <mutex>
#include <string>
#include <vector>

#include "curvemesh/core/error.hpp"
#include "curvemesh/geom_occ/detail/plugin.hpp"

#ifndef CURVEMESH_PLUGIN_BUILD_DIR
#error "CURVEMESH_PLUGIN_BUILD_DIR must name the build tree's plugin directory"
#endif

namespace cm::geom_occ::detail {

namespace {

namespace fs = std::filesystem;

struct Named {
  const char* file;
  const char* what;  // for the error message
};

constexpr std::array<Named, 4> kPlugins = {{
    {"libcurvemesh_occ_step.so", "the STEP reader"},
    {"libcurvemesh_occ_iges.so", "the IGES reader"},
    {"libcurvemesh_occ_builtin.so", "the built-in shapes"},
    {"libcurvemesh_occ_fuse.so", "the fuse of several solids"},
}};

fs::path executable_dir() {
  std::error_code ec;
  const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  return ec ? fs::path() : exe.parent_path();
}

std::vector<fs::path> search_dirs() {
  if (const char* env = std::getenv("CURVEMESH_PLUGIN_DIR"); env && *env) return {fs::path(env)};
  std::vector<fs::path> dirs;
  if (const fs::path exe = executable_dir(); !exe.empty()) dirs.push_back(exe / "plugins");
  dirs.emplace_back(CURVEMESH_PLUGIN_BUILD_DIR);
  return dirs;
}

struct Loaded {
  const PluginTable* table = nullptr;
  std::string error;
};

Loaded load(const Named& named) {
  Loaded out;
  std::string tried;
  for (const fs::path& dir : search_dirs()) {
    const fs::path file = dir / named.file;
    std::error_code ec;
    if (!fs::exists(file, ec)) {
      tried += fmt::format("{}{} (missing)", tried.empty() ? "" : ", ", file.string());
      continue;
    }
    // Never unloaded: OpenCASCADE registers types and statics it keeps for
    // the life of the process.
    void* handle = dlopen(file.c_str(), RTLD_NOW | RTLD_LOCAL | RTLD_NODELETE);
    if (!handle) {
      tried += fmt::format("{}{} ({})", tried.empty() ? "" : ", ", file.string(), dlerror());
      continue;
    }
    using Entry = const PluginTable* (*)();
    const auto entry = reinterpret_cast<Entry>(dlsym(handle, CM_OCC_PLUGIN_ENTRY_NAME));
    const PluginTable* table = entry ? entry() : nullptr;
    if (!table || table->abi != kPluginAbi) {
      tried += fmt::format("{}{} (not a plugin of this build)", tried.empty() ? "" : ", ", file.string());
      continue;
    }
    out.table = table;
    return out;
  }
  out.error = fmt::format("cannot load {}: tried {} (CURVEMESH_PLUGIN_DIR names the directory of the "
                          "curvemesh plugins, build/plugins in a build tree)",
                          named.what, tried);
  return out;
}

}  // namespace

const PluginTable& plugin(Plugin which) {
  static std::array<std::once_flag, kPlugins.size()> once;
  static std::array<Loaded, kPlugins.size()> loaded;
  const auto i = static_cast<std::size_t>(which);
  std::call_once(once[i], [i] { loaded[i] = load(kPlugins[i]); });
  if (!loaded[i].table) throw InternalError(loaded[i].error);
  return *loaded[i].table;
}

}  // namespace cm::geom_occ::detail
