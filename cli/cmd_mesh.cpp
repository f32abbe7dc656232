// `curvemesh mesh MODEL -o out.msh`: the volume mesh of a model (the main
// job), or with --dim 2 its classified boundary mesh; checked against the
// model and summarized.
#include <fmt/format.h>
#include <nlohmann/json.hpp>
#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>
#include <tbb/task_group.h>

#include "commands.hpp"
#include "curvemesh/core/timer.hpp"
#include "curvemesh/geom_occ/load.hpp"
#include "curvemesh/io/mesh_io.hpp"
#include "curvemesh/size/build.hpp"
#include "curvemesh/generate/boundary_check.hpp"
#include "curvemesh/generate/boundary_mesh.hpp"
#include "curvemesh/generate/volume_mesh.hpp"
#include "curvemesh/mesh/validate.hpp"
#include "curvemesh/optimize/improve.hpp"
#include "curvemesh/quality/measures.hpp"
#include "curvemesh/quality/statistics.hpp"
#include "curving.hpp"
#include "exit_codes.hpp"
#include "improve_report.hpp"
#include "json_output.hpp"
#include "size_options.hpp"

namespace cm::cli {

namespace {

struct MeshCliOptions {
  std::string model;
  std::string output, json_path;
  int dim = 3;
  SizeFlags size;
  ModelFlags model_flags;
  bool quiet = false;
  bool no_optimize = false;
  CurvingFlags curving;
};

// The model and its size field, loaded the same way for both dimensions.
struct Inputs {
  size::SizeOptions size_options;
  std::unique_ptr<geom::Model> model;
  size::SizeFieldResult size;
  double load_seconds = 0, size_seconds = 0;
};

Inputs load_inputs(const MeshCliOptions& o) {
  Inputs in;
  Timer step;
  in.size_options = make_size_options(o.size);
  in.model = geom_occ::load_model(o.model, o.model_flags.load_options());
  in.load_seconds = step.seconds();
  step.reset();
  in.size = size::build_size_field(*in.model, in.size_options);
  in.size_seconds = step.seconds();
  return in;
}

int run_volume(const MeshCliOptions& o);

int run_mesh(const MeshCliOptions& o) {
  if (o.dim == 3) return run_volume(o);
  Timer total;
  Timer step;
  const Inputs in = load_inputs(o);
  const size::SizeOptions& so = in.size_options;
  const geom::Model* model = in.model.get();
  const size::SizeFieldResult& sf = in.size;
  const double load_s = in.load_seconds, size_s = in.size_seconds;
  generate::BoundaryMeshStats st;
  const mesh::TetMesh m = generate::mesh_boundary(*model, *sf.field, {}, &st);
  step.reset();
  const generate::BoundaryReport rep = generate::check_boundary(*model, m, *sf.field);
  const double check_s = step.seconds();
  step.reset();
  if (!o.output.empty()) io::write_mesh(m, o.output);
  const double write_s = step.seconds();

  const double pct_size = rep.edges ? 100.0 * rep.edges_in_range / rep.edges : 0;
  const double pct_good = rep.triangles ? 100.0 * rep.good_triangles / rep.triangles : 0;
  nlohmann::json j;
  j["model"] = o.model;
  j["dim"] = o.dim;
  j["hmin"] = sf.hmin;
  j["hmax"] = sf.hmax;
  j["curvature"] = describe(so.curvature);
  j["counts"] = {{"vertices", m.num_verts()}, {"triangles", m.tris.size()}, {"edge_segments", st.edge_segments}};
  j["check"] = {{"valid", rep.valid()},
                {"vertices_off_entity", rep.vertices_off_entity},
                {"max_vertex_distance_over_tolerance", rep.max_vertex_distance},
                {"folded_triangles", rep.folded_triangles},
                {"crossing_triangle_pairs", rep.crossing_pairs},
                {"open_region_edges", rep.open_region_edges},
                {"unmeshed_faces", rep.unmeshed_faces},
                {"problems", rep.problems}};
  j["quality"] = {{"min", rep.min_quality},
                  {"mean", rep.mean_quality},
                  {"percent_at_least_0_6", pct_good},
                  {"below_0_1", rep.poor_triangles},
                  {"below_0_1_at_sharp_corners", rep.poor_at_sharp_corners},
                  {"below_0_1_at_small_features", rep.poor_at_small_features},
                  {"percent_edges_in_0_7_1_4", pct_size}};
  j["operations"] = {{"insertions", st.refinement_insertions}, {"flips", st.flips}, {"smoothing", st.smoothing_moves}};
  j["seconds"] = {{"load", load_s},          {"size_field", size_s},
                  {"curvature_sampling", sf.curvature_seconds},        {"edges", st.edges_seconds},
                  {"faces", st.faces_seconds}, {"assembly", st.assembly_seconds}, {"check", check_s},
                  {"write", write_s},        {"total", total.seconds()}};
  if (!o.json_path.empty()) {
    write_json(j, o.json_path);
  }
  if (!o.quiet) {
    fmt::print("model: {}  hmin {:.4g}  hmax {:.4g}  curvature {}\n", o.model, sf.hmin, sf.hmax,
               describe(so.curvature));
    fmt::print("surface mesh: {} vertices, {} triangles, {} edge segments\n", m.num_verts(), m.tris.size(),
               st.edge_segments);
    fmt::print("quality: min {:.3f}  mean {:.3f}  {:.1f}% >= 0.6  {} below 0.1 (+{} at sharp model corners, +{} at "
               "model features below hmin)\n",
               rep.min_quality, rep.mean_quality, pct_good, rep.poor_triangles, rep.poor_at_sharp_corners,
               rep.poor_at_small_features);
    fmt::print("sizes: {:.1f}% of edges within [0.7, 1.4] of the requested size\n", pct_size);
    fmt::print("check: {}", rep.valid() ? "valid" : "INVALID");
    if (!rep.valid())
      fmt::print(" ({} vertices off their entity, {} folded triangles, {} crossing triangle pairs, {} open region "
                 "edges, {} unmeshed faces)",
                 rep.vertices_off_entity, rep.folded_triangles, rep.crossing_pairs, rep.open_region_edges,
                 rep.unmeshed_faces);
    fmt::print("\n");
    for (const auto& p : rep.problems) fmt::print("  {}\n", p);
    fmt::print("time: load {:.2f} s, size field {:.2f} s, edges {:.2f} s, faces {:.2f} s, check {:.2f} s, "
               "write {:.2f} s, total {:.2f} s\n",
               load_s, size_s, st.edges_seconds, st.faces_seconds, check_s, write_s, total.seconds());
    if (!o.output.empty()) fmt::print("wrote {}\n", o.output);
  }
  return rep.valid() ? kExitOk : kExitInvalidMesh;
}

// Model volume (sum over regions) and mesh volume, for the summary.
double model_volume(const geom::Model& model) {
  double v = 0;
  for (int r = 1; r <= model.count(3); ++r) v += model.volume(r);
  return v;
}

double tets_volume(const mesh::TetMesh& m) {
  double v = 0;
  for (TetId t = 0; t < m.num_tets(); ++t) v += mesh::tet_volume(m, t);
  return v;
}

int run_volume(const MeshCliOptions& o) {
  Timer total;
  Timer step;
  const Inputs in = load_inputs(o);
  const size::SizeOptions& so = in.size_options;
  const geom::Model* model = in.model.get();
  const size::SizeFieldResult& sf = in.size;
  const double load_s = in.load_seconds, size_s = in.size_seconds;
  tbb::task_group background;
  double vol_model = 0;
  // Waited for on every path out, exceptions included: the task reads the model.
  struct Join {
    tbb::task_group& group;
    ~Join() { group.wait(); }
  } join{background};
  generate::VolumeMeshStats st;
  mesh::TetMesh m = generate::mesh_volume(*model, *sf.field, {}, &st);
  // The model's volume, for the report, by OpenCASCADE's integration (up
  // to a fifth of a second): computed meanwhile on the core the serial
  // optimizer leaves idle (the boundary meshing before uses both).
  background.run([&] { vol_model = model_volume(*model); });
  optimize::ImproveStats opt;
  if (!o.no_optimize) {
    // With the model, boundary vertices move on it: the worst tets of a
    // fresh mesh are mostly against the boundary, pinned there otherwise.
    optimize::ImproveOptions io;
    io.model = model;
    io.tips = st.tips;
    // Deletions move the surface: within the chord rule the sizes asked for.
    if (so.curvature.kind == size::CurvatureRule::Kind::kRelativeDeviation) io.chord_alpha = so.curvature.value;
    opt = optimize::improve_quality(m, io);
  }
  std::optional<curved::CurveReport> curving;
  double curve_s = 0;
  if (o.curving.order > 1) {
    step.reset();
    curving = curved::curve_mesh(m, *model, o.curving.options());
    curve_s = step.seconds();
  }
  step.reset();
  // The checks only read the mesh and the model: side by side.
  mesh::ValidationReport valid;
  generate::BoundaryReport rep;
  const std::size_t nt = m.num_tets();
  std::vector<double> q(nt), dmin(nt);
  double vol_mesh = 0;
  tbb::parallel_invoke([&] { valid = mesh::validate(m, mesh::Level::kFull); },
                       [&] { rep = generate::check_boundary(*model, m, *sf.field); },
                       [&] {
                         tbb::parallel_for(std::size_t{0}, nt, [&](std::size_t t) {
                           const auto e = quality::evaluate_tet(m, static_cast<TetId>(t));
                           q[t] = e.mean_ratio;
                           dmin[t] = e.min_dihedral;
                         });
                         vol_mesh = tets_volume(m);
                       });
  const auto qs = quality::compute_statistics(q);
  const auto ds = quality::compute_statistics(dmin);
  background.wait();
  const double check_s = step.seconds();
  step.reset();
  if (!o.output.empty()) io::write_mesh(m, o.output);
  const double write_s = step.seconds();
  // The boundary's whole check: a region boundary that is not a closed
  // manifold (an edge of two model faces' meshes that is no model edge) or
  // a model face left without triangles is a classification the tets'
  // validity does not see.
  const bool ok = valid.valid() && rep.valid() && (!curving || curve_report_ok(*curving));
  const std::size_t steiner = st.recovery.steiner_on_edges + st.recovery.steiner_on_faces;

  nlohmann::json j;
  j["model"] = o.model;
  j["dim"] = 3;
  j["hmin"] = sf.hmin;
  j["hmax"] = sf.hmax;
  j["curvature"] = describe(so.curvature);
  j["counts"] = {{"vertices", m.num_verts()},
                 {"tets", nt},
                 {"boundary_triangles", m.tris.size()},
                 {"boundary_vertices_initial", st.boundary_vertices},
                 {"interior_points", st.interior_points},
                 {"refused_points", st.refused_points}};
  j["recovery"] = {{"missing_edges", st.recovery.missing_edges_initial},
                   {"missing_triangles", st.recovery.missing_triangles_initial},
                   {"steiner_on_model_edges", st.recovery.steiner_on_edges},
                   {"steiner_on_model_faces", st.recovery.steiner_on_faces},
                   {"surface_flips", st.recovery.surface_flips},
                   {"volume_flips", st.recovery.volume_flips},
                   {"edges_by_volume_flips", st.recovery.edges_by_volume_flips},
                   {"triangles_by_volume_flips", st.recovery.triangles_by_volume_flips},
                   {"rounds", st.recovery.rounds},
                   {"region_conflicts", st.region_conflicts}};
  j["check"] = {{"valid", ok},
                {"issues", valid.num_issues},
                {"inverted", valid.num_inverted},
                {"flat", valid.num_flat},
                {"nonconforming", valid.num_nonconforming},
                {"classification", valid.num_classification},
                {"vertices_off_entity", rep.vertices_off_entity},
                {"folded_triangles", rep.folded_triangles},
                {"crossing_pairs", rep.crossing_pairs},
                {"open_region_edges", rep.open_region_edges},
                {"unmeshed_faces", rep.unmeshed_faces}};
  j["volume"] = {{"model", vol_model}, {"mesh", vol_mesh}};
  j["optimization"] = {{"edge_removals", opt.edge_removals},
                       {"face_swaps", opt.face_swaps},
                       {"relocations", opt.relocations},
                       {"boundary_relocations", opt.boundary_relocations},
                       {"searched_relocations", opt.searched_relocations},
                       {"insertions", opt.insertions},
                       {"deletions", opt.deletions},
                       {"collapses", opt.collapses},
                       {"passes", opt.passes},
                       {"min_dihedral_before", opt.min_dihedral_before},
                       {"mean_ratio_min_before", opt.min_before},
                       {"below_0_3_before", opt.below_before},
                       {"below_0_3_after", opt.below_after}};
  j["quality"] = {{"mean_ratio_min", qs.min},
                  {"mean_ratio_mean", qs.mean},
                  {"min_dihedral_deg", ds.min},
                  {"surface_min", rep.min_quality},
                  {"surface_mean", rep.mean_quality}};
  j["seconds"] = {{"load", load_s},
                  {"size_field", size_s},
                  {"curvature_sampling", sf.curvature_seconds},
                  {"boundary", st.boundary_seconds},
                  {"delaunay", st.delaunay_seconds},
                  {"recovery", st.recovery_seconds},
                  {"regions", st.classify_seconds},
                  {"interior", st.refine_seconds},
                  {"optimize", opt.seconds},
                  {"curving", curve_s},
                  {"check", check_s},
                  {"write", write_s},
                  {"total", total.seconds()}};
  if (curving) j["curving"] = curve_report_json(*curving);
  if (!o.json_path.empty()) write_json(j, o.json_path);
  if (!o.quiet) {
    fmt::print("model: {}  hmin {:.4g}  hmax {:.4g}  curvature {}\n", o.model, sf.hmin, sf.hmax,
               describe(so.curvature));
    fmt::print("mesh: {} vertices, {} tets, {} boundary triangles; {} interior points ({} refused)\n",
               m.num_verts(), nt, m.tris.size(), st.interior_points, st.refused_points);
    fmt::print("recovery: {} missing edges, {} missing triangles; {} Steiner points ({} on model edges, {} on model "
               "faces), {} surface flips, {} volume flips ({} edges, {} triangles recovered by them), in {} rounds\n",
               st.recovery.missing_edges_initial, st.recovery.missing_triangles_initial, steiner,
               st.recovery.steiner_on_edges, st.recovery.steiner_on_faces, st.recovery.surface_flips,
               st.recovery.volume_flips, st.recovery.edges_by_volume_flips, st.recovery.triangles_by_volume_flips,
               st.recovery.rounds);
    if (!o.no_optimize)
      fmt::print("optimization: {}; tets with mean ratio < 0.3: {} -> {}; min {:.3f} -> {:.3f}; min dihedral {:.2f} -> "
                 "{:.2f} deg\n",
                 improve_operator_counts(opt, false), opt.below_before, opt.below_after, opt.min_before,
                 opt.min_after, opt.min_dihedral_before, opt.min_dihedral_after);
    if (curving) print_curve_report(*curving);
    fmt::print("quality{}: mean ratio min {:.3f} mean {:.3f}; min dihedral {:.2f} deg\n",
               curving ? " (straight-sided)" : "", qs.min, qs.mean, ds.min);
    fmt::print("volume: mesh {:.6g}, model {:.6g} (relative difference {:.2e})\n", vol_mesh, vol_model,
               vol_model > 0 ? (vol_mesh - vol_model) / vol_model : 0.0);
    fmt::print("check: {}", ok ? "valid" : "INVALID");
    if (!ok)
      fmt::print(" ({} validity issues, {} vertices off their entity, {} folded boundary triangles, {} crossing "
                 "triangle pairs, {} open region edges, {} unmeshed faces)",
                 valid.num_issues, rep.vertices_off_entity, rep.folded_triangles, rep.crossing_pairs,
                 rep.open_region_edges, rep.unmeshed_faces);
    fmt::print("\n");
    for (std::size_t i = 0; i < std::min<std::size_t>(valid.issues.size(), 5); ++i)
      fmt::print("  {}\n", valid.issues[i].message);
    for (std::size_t i = 0; i < std::min<std::size_t>(rep.problems.size(), 5); ++i) fmt::print("  {}\n", rep.problems[i]);
    fmt::print("time: load {:.2f} s, size field {:.2f} s, boundary {:.2f} s, delaunay {:.2f} s, recovery {:.2f} s, "
               "regions {:.2f} s, interior {:.2f} s, optimize {:.2f} s, {}check {:.2f} s, write {:.2f} s, total {:.2f} "
               "s\n",
               load_s, size_s, st.boundary_seconds, st.delaunay_seconds, st.recovery_seconds, st.classify_seconds,
               st.refine_seconds, opt.seconds, curving ? fmt::format("curving {:.2f} s, ", curve_s) : "", check_s,
               write_s, total.seconds());
    fmt::print("curvature sampling: {:.3f} s of the size field, {:.1f}% of the total\n", sf.curvature_seconds,
               100 * sf.curvature_seconds / total.seconds());
    if (!o.output.empty()) fmt::print("wrote {}\n", o.output);
  }
  return ok ? kExitOk : kExitInvalidMesh;
}

}  // namespace

void add_mesh_command(CLI::App& app, Runner& runner) {
  auto o = std::make_shared<MeshCliOptions>();
  CLI::App* cmd = app.add_subcommand("mesh", "Mesh a model: the classified tetrahedral mesh (or --dim 2: its surface)");
  cmd->add_option("model", o->model, "STEP/IGES/BREP file or builtin:NAME[:key=value,...]")->required();
  cmd->add_option("-o,--output", o->output, "Output mesh (.msh, .mesh/.meshb, .vtu)");
  cmd->add_option("--dim", o->dim, "3 = volume mesh (default), 2 = boundary (surface) mesh only")
      ->check(CLI::IsMember({2, 3}));
  cmd->add_option("--json", o->json_path, "Write the summary as JSON");
  add_size_flags(cmd, o->size);
  add_model_flags(cmd, o->model_flags);
  cmd->add_flag("--no-optimize", o->no_optimize, "Volume mesh: skip the quality optimization (swaps, smoothing)");
  add_curving_flags(cmd, o->curving, 1);
  cmd->add_flag("-q,--quiet", o->quiet, "Print nothing on success");
  cmd->footer(
      "Exit code 0 when the mesh passes its checks (volume: every tet positive, conforming,\n"
      "classification consistent, boundary vertices on their model entities; surface: vertices on\n"
      "their entities, no folded triangle, every region closed), 1 when it does not, 2 on bad input,\n"
      "3 on an internal error.\n"
      "\nExamples:\n  curvemesh mesh part.step -o part.msh\n  curvemesh mesh part.step --dim 2 -o part_surface.msh\n"
      "  curvemesh mesh builtin:torus --dim 2 --curv-eps 0.01 -o torus.vtu\n"
      "  curvemesh mesh part.step --order 2 -o part_p2.msh");
  cmd->callback([&runner, o] { runner = [o] { return run_mesh(*o); }; });
}

}  // namespace cm::cli
