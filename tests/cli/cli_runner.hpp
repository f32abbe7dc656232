#pragma once
// Runs the curvemesh executable (or gmsh) as a user would and captures what it prints.
#include <string>

namespace cm::test {

struct RunResult {
  int exit_code = -1;
  std::string output;  ///< stdout and stderr interleaved
};

/// Runs a shell command line; stderr is merged into the captured output.
RunResult run_command(const std::string& command_line);
/// Runs `curvemesh ARGS`.
RunResult run_cli(const std::string& args);
/// A fresh empty directory under the system temp dir, removed at exit.
std::string make_temp_dir(const std::string& label);
std::string read_text(const std::string& path);

}  // namespace cm::test
