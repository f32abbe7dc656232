// `curvemesh curve MESH --model MODEL --order 2|3 -o OUT`: raises a
// classified tet mesh to curved elements on its model and repairs it until
// every element is certified valid and acceptable (seed paper 1, §3).
#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "commands.hpp"
#include "curvemesh/core/error.hpp"
#include "curvemesh/core/timer.hpp"
#include "curvemesh/curved/element_check.hpp"
#include "curvemesh/generate/classify_on_model.hpp"
#include "curvemesh/geom_occ/load.hpp"
#include "curvemesh/io/mesh_io.hpp"
#include "curvemesh/mesh/adjacency.hpp"
#include "curvemesh/mesh/validate.hpp"
#include "classification_report.hpp"
#include "curving.hpp"
#include "exit_codes.hpp"
#include "json_output.hpp"
#include "size_options.hpp"

namespace cm::cli {

namespace {

struct CurveCliOptions {
  std::string input, output, model, json_path;
  CurvingFlags curving;
  ModelFlags model_flags;
  bool quiet = false;
};

int run_curve(const CurveCliOptions& o) {
  Timer total, step;
  mesh::TetMesh m = io::read_mesh(o.input);
  const double read_s = step.seconds();
  step.reset();
  mesh::build_adjacency(m);
  // The curved mesh is only as valid as its straight-sided skeleton, which
  // the repair keeps valid and falls back to.
  const auto straight = mesh::validate(m, mesh::Level::kFull);
  if (!straight.valid())
    throw InputError(o.input, 0, -1, fmt::format("the straight-sided mesh is not valid ({} inverted, {} flat, {} "
                                             "non-conforming tets, {} classification errors); run curvemesh check",
                                             straight.num_inverted, straight.num_flat, straight.num_nonconforming,
                                             straight.num_classification));
  // What the input's own high-order nodes give, for the summary.
  const int input_order = m.high_order.order();
  std::size_t input_invalid = 0, input_unacceptable = 0;
  double input_min_sj = 1;
  if (input_order > 1) {
    const curved::MeshCheck c = curved::check_mesh(m, o.curving.options().repair.acceptance);
    input_invalid = c.invalid.size();
    input_unacceptable = c.unacceptable.size();
    input_min_sj = c.min_scaled_jacobian;
  }
  const double check_s = step.seconds();
  step.reset();
  const auto model = geom_occ::load_model(o.model, o.model_flags.load_options());
  const double load_s = step.seconds();
  // Whatever made the mesh, its boundary is classified on the model by
  // geometry (a mesh of another model, or in other units, is refused here).
  const generate::ModelClassification classified = generate::classify_on_model(m, *model, {o.input});
  const auto recheck = mesh::validate(m, mesh::Level::kFull, 1);
  if (!recheck.valid())
    throw InputError(o.input, -1, -1,
                     fmt::format("its classification on the model {} is not consistent ({}{})", o.model,
                                 recheck.issues.empty() ? "" : recheck.issues.front().message,
                                 classified.problems.empty() ? "" : "; " + classified.problems.front()));
  step.reset();
  const curved::CurveReport r = curved::curve_mesh(m, *model, o.curving.options());
  const double curve_s = step.seconds();
  step.reset();
  const bool ok = curve_report_ok(r);
  if (!o.output.empty()) io::write_mesh(m, o.output);
  const double write_s = step.seconds();

  nlohmann::json j;
  j["input"] = o.input;
  j["model"] = o.model;
  j["input_order"] = input_order;
  if (input_order > 1)
    j["input_curved"] = {{"invalid", input_invalid},
                         {"unacceptable", input_unacceptable},
                         {"min_scaled_jacobian", input_min_sj}};
  j["counts"] = {{"vertices", m.num_verts()}, {"tets", m.num_tets()}, {"boundary_triangles", m.tris.size()}};
  j["classification"] = classification_json(classified);
  j["curving"] = curve_report_json(r);
  j["valid"] = ok;
  j["seconds"] = {{"read", read_s},        {"check_input", check_s}, {"load_model", load_s},
                  {"classify", classified.seconds}, {"curving", curve_s}, {"write", write_s},
                  {"total", total.seconds()}};
  if (!o.json_path.empty()) write_json(j, o.json_path);
  if (!o.quiet) {
    fmt::print("mesh: {}  ({} tets, order {})  model: {}\n", o.input, m.num_tets(), input_order, o.model);
    if (input_order > 1)
      fmt::print("input's own nodes: {} certified invalid, {} unacceptable, min scaled Jacobian {:.4f} (replaced)\n",
                 input_invalid, input_unacceptable, input_min_sj);
    fmt::print("{}", render_classification(classified));
    print_curve_report(r);
    fmt::print("check: {}\n", ok ? "every element certified valid and acceptable" : "INVALID or unacceptable elements remain");
    fmt::print("time: read {:.2f} s, check input {:.2f} s, load model {:.2f} s, classify {:.2f} s, curving {:.2f} s, "
               "write {:.2f} s, total {:.2f} s\n",
               read_s, check_s, load_s, classified.seconds, curve_s, write_s, total.seconds());
    if (!o.output.empty()) fmt::print("wrote {}\n", o.output);
  }
  return ok ? kExitOk : kExitInvalidMesh;
}

}  // namespace

void add_curve_command(CLI::App& app, Runner& runner) {
  auto o = std::make_shared<CurveCliOptions>();
  CLI::App* cmd = app.add_subcommand("curve", "Curve a classified tet mesh on its model (order 2 or 3), certified valid");
  cmd->add_option("mesh", o->input, "Input mesh (.msh 4.1 with its classification, .mesh, .meshb)")->required();
  cmd->add_option("--model", o->model, "The CAD model of the mesh (STEP/IGES/BREP or builtin:NAME)")->required();
  cmd->add_option("-o,--output", o->output, "Output mesh (.msh: 10/20-node tets, .vtu: Lagrange cells)");
  cmd->add_option("--json", o->json_path, "Write the summary as JSON");
  add_curving_flags(cmd, o->curving, 2);
  add_model_flags(cmd, o->model_flags);
  cmd->add_flag("-q,--quiet", o->quiet, "Print nothing on success");
  cmd->footer(
      "The straight-sided mesh must be valid; any tool's mesh of the model will do (its boundary is\n"
      "classified on the model by geometry first). High-order nodes it has are replaced by nodes on the\n"
      "model.\n"
      "Exit code 0 when every element is certified valid (det J > 0 everywhere, Bezier bounds) and\n"
      "acceptable, 1 when some are not (written anyway; only with --no-repair), 2 on bad input, 3 on an\n"
      "internal error.\n"
      "\nExamples:\n  curvemesh curve part.msh --model part.step --order 2 -o part_p2.msh\n"
      "  curvemesh curve part.msh --model part.step --order 3 -o part_p3.vtu --json report.json");
  cmd->callback([&runner, o] { runner = [o] { return run_curve(*o); }; });
}

}  // namespace cm::cli
