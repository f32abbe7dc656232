#pragma once
// Subcommands of the curvemesh CLI. Each registers its options on the app
// and returns the exit code (exit_codes.hpp) when run. Errors are thrown as
// cm::InputError / cm::GeometryError / cm::InternalError and mapped to exit
// codes in main.cpp.
#include <functional>

#include <CLI/CLI.hpp>

namespace cm::cli {

using Runner = std::function<int()>;

/// `curvemesh check MESH [--json FILE]`
void add_check_command(CLI::App& app, Runner& runner);
/// `curvemesh info MODEL [--json FILE]` 
void add_info_command(CLI::App& app, Runner& runner);
/// `curvemesh size MODEL [-o size.vtu]`
void add_size_command(CLI::App& app, Runner& runner);
/// `curvemesh mesh MODEL --dim 2 -o OUT`
void add_mesh_command(CLI::App& app, Runner& runner);
/// `curvemesh convert IN OUT`
void add_convert_command(CLI::App& app, Runner& runner);
/// `curvemesh optimize IN -o OUT [--sol S] [--aniso]`
void add_optimize_command(CLI::App& app, Runner& runner);
/// `curvemesh curve MESH --model MODEL --order 2|3 -o OUT`
void add_curve_command(CLI::App& app, Runner& runner);

}  // namespace cm::cli
