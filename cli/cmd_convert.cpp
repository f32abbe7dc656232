#include <fmt/format.h>

#include "commands.hpp"
#include "curvemesh/core/timer.hpp"
#include "curvemesh/io/mesh_io.hpp"
#include "exit_codes.hpp"

namespace cm::cli {

namespace {
struct ConvertOptions {
  std::string input;
  std::string output;
  bool binary = false;
  bool quiet = false;
};
}  // namespace

void add_convert_command(CLI::App& app, Runner& runner) {
  auto opts = std::make_shared<ConvertOptions>();
  CLI::App* cmd = app.add_subcommand("convert", "Convert a mesh between formats, chosen by extension");
  cmd->add_option("input", opts->input, "Input mesh (.msh 2.2/4.1, .mesh, .meshb)")->required();
  cmd->add_option("output", opts->output, "Output mesh (.msh 4.1, .mesh, .meshb, .vtu)")->required();
  cmd->add_flag("--binary", opts->binary, "Write MSH 4.1 in binary");
  cmd->add_flag("-q,--quiet", opts->quiet, "Print nothing on success");
  cmd->footer(
      "Examples:\n  curvemesh convert part.msh part.mesh\n  curvemesh convert part.mesh part.vtu\n"
      "  curvemesh convert big.msh big.msh --binary");
  cmd->callback([&runner, opts] {
    runner = [opts] {
      Timer timer;
      mesh::TetMesh m = io::read_mesh(opts->input);
      const double read_s = timer.seconds();
      timer.reset();
      io::WriteOptions w;
      w.binary = opts->binary;
      io::write_mesh(m, opts->output, w);
      if (!opts->quiet)
        fmt::print("{} -> {}: {} vertices, {} tets, {} boundary triangles (read {:.2f} s, write {:.2f} s)\n",
                   opts->input, opts->output, m.num_verts(), m.num_tets(), m.tris.size(), read_s, timer.seconds());
      return kExitOk;
    };
  });
}

}  // namespace cm::cli
