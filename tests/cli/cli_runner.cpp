#include "cli_runner.hpp"

#include <sys/wait.h>

#include <array>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <vector>

namespace cm::test {

RunResult run_command(const std::string& command_line) {
  RunResult r;
  const std::string cmd = command_line + " 2>&1";
  FILE* pipe = popen(cmd.c_str(), "r");
  if (!pipe) throw std::runtime_error("popen failed: " + command_line);
  std::array<char, 4096> buf;
  std::size_t n;
  while ((n = fread(buf.data(), 1, buf.size(), pipe)) > 0) r.output.append(buf.data(), n);
  const int status = pclose(pipe);
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  return r;
}

RunResult run_cli(const std::string& args) { return run_command(std::string(CM_CLI_EXECUTABLE) + " " + args); }

std::string make_temp_dir(const std::string& label) {
  namespace fs = std::filesystem;
  std::string templ = (fs::temp_directory_path() / ("curvemesh_" + label + "_XXXXXX")).string();
  if (!mkdtemp(templ.data())) throw std::runtime_error("mkdtemp failed");
  static std::vector<std::string> to_remove;
  if (to_remove.empty()) std::atexit([] {
      for (const auto& d : to_remove) std::filesystem::remove_all(d);
    });
  to_remove.push_back(templ);
  return templ;
}

std::string read_text(const std::string& path) {
  std::ifstream in(path);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

}  // namespace cm::test
