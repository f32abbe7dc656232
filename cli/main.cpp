// curvemesh command-line entry point: parses the subcommand, runs it, and
// turns every error into one message on stderr and a documented exit code.
#include <cstdio>
#include <exception>
#include <new>

#include <fmt/format.h>

#include "commands.hpp"
#include "curvemesh/core/error.hpp"
#include "exit_codes.hpp"

namespace {
int report(const char* kind, const std::exception& e, int code) {
  std::fprintf(stderr, "curvemesh: %s%s\n", kind, e.what());
  return code;
}
}  // namespace

int main(int argc, char** argv) {
  using namespace cm::cli;
  CLI::App app{"curvemesh: curved tetrahedral meshes of CAD models, certified valid"};
  app.require_subcommand(1);
  app.set_version_flag("--version", "curvemesh 0.1.0");
  Runner runner;
  add_check_command(app, runner);
  add_convert_command(app, runner);
  add_info_command(app, runner);
  add_size_command(app, runner);
  add_mesh_command(app, runner);
  add_optimize_command(app, runner);
  add_curve_command(app, runner);
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForAllHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForVersion& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    app.exit(e);
    return kExitBadInput;
  }
  try {
    return runner();
  } catch (const cm::InputError& e) {
    return report("error: ", e, kExitBadInput);
  } catch (const cm::GeometryError& e) {
    return report("error: ", e, kExitBadInput);
  } catch (const cm::InternalError& e) {
    return report("", e, kExitInternal);
  } catch (const std::bad_alloc&) {
    std::fprintf(stderr, "curvemesh: error: out of memory\n");
    return kExitInternal;
  } catch (const std::invalid_argument& e) {
    return report("error: ", e, kExitBadInput);
  } catch (const std::exception& e) {
    // Output files that cannot be written land here (std::runtime_error).
    return report("error: ", e, kExitBadInput);
  }
}
