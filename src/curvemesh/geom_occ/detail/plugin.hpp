#pragma once
// Internal to geom_occ: the OpenCASCADE toolkits that only some inputs need
// live in plugins, shared modules loaded on first use. Binding a toolkit's
// symbols is what a process of ours spends before main(): all of them took
// 0.032 s, the ones every model needs (geometry, topology, healing,
// tessellation) 0.011 s. STEP (TKSTEP*, TKXSBase), IGES (TKIGES), the
// built-in shapes (TKPrim, TKBool, TKFillet) and the general fuse of several
// solids (TKBO) are each a plugin, so `curvemesh check` on a mesh file or a
// .brep model loads none of them.
//
// A plugin is built in the same build as the program (same compiler, same
// OpenCASCADE), so its table uses C++ types; only the entry point has C
// linkage, to be found by name. Plugins throw cm::InputError and
// cm::GeometryError as the code they came from did: they carry their own copy
// of the error classes, and the C++ runtime matches exception types across
// shared objects by name.
#include <string>
#include <vector>

#include <TopoDS_Shape.hxx>
#include <TopoDS_Solid.hxx>

#include "curvemesh/geom_occ/detail/occ_shapes.hpp"

namespace cm::geom_occ::detail {

/// Bumped whenever PluginTable changes, so a stale plugin is refused.
inline constexpr int kPluginAbi = 1;

/// What a plugin provides; the entries it does not are null.
struct PluginTable {
  int abi = kPluginAbi;
  /// Reads a file whose header was already checked (STEP, IGES).
  ReadShape (*read_file)(const std::string& path) = nullptr;
  /// Builds "builtin:NAME[:k=v,...]" (see builtin_catalog.hpp).
  ReadShape (*make_builtin)(const std::string& spec) = nullptr;
  /// General fuse of two or more closed solids with the given fuzzy value:
  /// a compound of the solids' pieces, their shared faces merged. Throws
  /// cm::GeometryError naming `source` when the fuse fails.
  TopoDS_Shape (*fuse_solids)(const std::vector<TopoDS_Solid>& solids, double fuzz,
                              const std::string& source) = nullptr;
};

enum class Plugin { kStep, kIges, kBuiltin, kFuse };

/// The plugin's table, loading it on first use (thread-safe). Searched in
/// $CURVEMESH_PLUGIN_DIR when that is set (only there), otherwise in
/// `plugins/` beside the executable, then in the build tree's plugins/.
/// Throws cm::InternalError naming the paths tried when it cannot be loaded.
const PluginTable& plugin(Plugin which);

}  // namespace cm::geom_occ::detail

/// The one symbol every plugin exports: CM_OCC_PLUGIN(.read_file = read_step)
/// defines it, returning a table with those entries.
#define CM_OCC_PLUGIN_ENTRY_NAME "curvemesh_occ_plugin"
#define CM_OCC_PLUGIN(...)                                                        \
  extern "C" const cm::geom_occ::detail::PluginTable* curvemesh_occ_plugin() {     \
    static const cm::geom_occ::detail::PluginTable table{__VA_ARGS__};             \
    return &table;                                                                  \
  }
