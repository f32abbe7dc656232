#pragma once
// Options shared by the commands that build a size field (`size`, `mesh`):
// the flags, their help, and their translation into size::SizeOptions.
#include <optional>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "curvemesh/geom_occ/load.hpp"
#include "curvemesh/size/build.hpp"

namespace cm::cli {

struct SizeFlags {
  double hmax = 0, hmin = 0, hgrad = 1.3;
  std::optional<double> curv_eps, curv_alpha;
  bool no_curvature = false;
  bool directional = false;
  std::vector<std::string> entity_sizes;
  std::vector<std::string> expressions;
  std::string background_mesh, background_sol;
};

struct ModelFlags {
  double heal_tolerance = 0;
  bool no_heal = false;
  geom_occ::LoadOptions load_options() const;
};

void add_size_flags(CLI::App* cmd, SizeFlags& flags);
void add_model_flags(CLI::App* cmd, ModelFlags& flags);
/// Parses --size and --size-expr, reads the background; throws cm::InputError
/// naming the option or file at fault.
size::SizeOptions make_size_options(const SizeFlags& flags);
/// "off", "eps=E" or "alpha=A".
std::string describe(const size::CurvatureRule& rule);

}  // namespace cm::cli
