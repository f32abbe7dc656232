#pragma once
// Gmsh meshes of the shared models for tests that compare with, or start
// from, what Gmsh makes (its path is CM_GMSH_EXECUTABLE, empty when it is
// not installed).
#include <filesystem>
#include <map>
#include <string>

#include <fmt/format.h>

#include "../cli/cli_runner.hpp"
#include "curvemesh/geom/model.hpp"

namespace cm::test {

inline bool have_gmsh() { return std::string(CM_GMSH_EXECUTABLE).size() > 0; }

/// Gmsh reads STEP in millimetres; curvemesh keeps the file's unit.
inline std::string gmsh_unit_option(const std::string& units) {
  static const std::map<std::string, std::string> kOcc = {{"cm", "CM"}, {"m", "M"}, {"inch", "INCH"}, {"ft", "FT"}};
  const auto it = kOcc.find(units);
  return it == kOcc.end() ? "" : " -setstring Geometry.OCCTargetUnit " + it->second;
}

/// Gmsh's order-2 mesh of `input` (the model file, or a .geo merging it) at
/// about the model's diagonal / 15 with MeshSizeFromCurvature 12, finer
/// when its volume mesher fails at that size (it does on some models); the
/// size used in h. Empty when every try failed.
inline std::string gmsh_order2_mesh(const std::string& input, const geom::Model& model, const std::string& dir,
                                    double& h) {
  h = model.bounding_box().diagonal() / 15;
  for (int attempt = 0; attempt < 4; ++attempt, h /= 2) {
    const std::string out = dir + "/gmsh.msh";
    std::filesystem::remove(out);
    const auto r = run_command(fmt::format(
        "{} -3 -nt 1 -order 2{} -setnumber Mesh.MeshSizeFromCurvature 12 -setnumber Mesh.MeshSizeMax {} '{}' -o '{}' "
        "-format msh41",
        CM_GMSH_EXECUTABLE, gmsh_unit_option(model.units()), h, input, out));
    if (r.exit_code == 0 && std::filesystem::exists(out)) return out;
  }
  return "";
}

}  // namespace cm::test
