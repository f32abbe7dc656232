// `curvemesh optimize IN -o OUT`: quality optimization of an existing tet
// mesh (paper 2): isotropic shape, or shape and lengths in a size map or a
// metric field given per vertex.
#include <algorithm>
#include <cmath>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Eigenvalues>
#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "commands.hpp"
#include "curvemesh/core/error.hpp"
#include "curvemesh/core/timer.hpp"
#include "curvemesh/generate/classify_on_model.hpp"
#include "curvemesh/geom_occ/load.hpp"
#include "curvemesh/io/atomic_file.hpp"
#include "curvemesh/io/formats.hpp"
#include "curvemesh/io/mesh_io.hpp"
#include "curvemesh/mesh/validate.hpp"
#include "curvemesh/optimize/adapt.hpp"
#include "curvemesh/optimize/boundary_limit.hpp"
#include "curvemesh/optimize/improve.hpp"
#include "curvemesh/optimize/metric_field.hpp"
#include "curvemesh/size/expression.hpp"
#include "classification_report.hpp"
#include "exit_codes.hpp"
#include "improve_report.hpp"
#include "json_output.hpp"

namespace cm::cli {

namespace {

struct OptimizeCliOptions {
  std::string input, output, json_path, model, sol, sol_out, size_expr, metric_expr;
  double hmin = 0, hmax = 0, hgrad = 1.3;
  bool aniso = false, binary = false, quiet = false;
  int passes = 8;
  // Higher than `mesh`'s 0.3: an optimize run is asked for quality, and the
  // fair tets (0.3-0.6) are where most of the mean is won, for little time.
  // In an anisotropic metric 0.9 (see optimize::AdaptOptions::threshold)
  // unless given.
  double threshold = 0.6;
  bool threshold_given = false;
  bool flat_boundary = false;
};

bool has_size_spec(const OptimizeCliOptions& o) {
  return !o.sol.empty() || !o.size_expr.empty() || !o.metric_expr.empty() || o.hmin > 0 || o.hmax > 0 || o.aniso;
}

// A size function clamped to [hmin, hmax] (a bound <= 0 is not applied), as
// clamp_sizes clamps the values sampled at the vertices.
class ClampedField final : public size::SizeField {
 public:
  ClampedField(std::shared_ptr<const size::SizeField> inner, double hmin, double hmax)
      : inner_(std::move(inner)), hmin_(hmin > 0 ? hmin : 0), hmax_(hmax > 0 ? hmax : HUGE_VAL) {}
  double size(const Vec3& x, const size::SizeHint& hint = {}) const override {
    return std::clamp(inner_->size(x, hint), hmin_, hmax_);
  }
  size::Metric metric(const Vec3& x, const size::SizeHint& hint = {}) const override {
    if (!inner_->anisotropic()) return size::isotropic_metric(size(x, hint));
    const Eigen::SelfAdjointEigenSolver<size::Metric> eig(inner_->metric(x, hint));
    Vec3 l = eig.eigenvalues();
    for (int k = 0; k < 3; ++k) l[k] = std::clamp(l[k], 1 / (hmax_ * hmax_), 1 / (hmin_ * hmin_));
    return eig.eigenvectors() * l.asDiagonal() * eig.eigenvectors().transpose();
  }
  bool anisotropic() const override { return inner_->anisotropic(); }

 private:
  std::shared_ptr<const size::SizeField> inner_;
  double hmin_, hmax_;
};

// Sizes along x, y and z: the metric diag(1/hx², 1/hy², 1/hz²).
class AxisSizeField final : public size::SizeField {
 public:
  explicit AxisSizeField(std::array<std::shared_ptr<const size::SizeField>, 3> axes) : axes_(std::move(axes)) {}
  double size(const Vec3& x, const size::SizeHint& hint = {}) const override {
    return std::min({axes_[0]->size(x, hint), axes_[1]->size(x, hint), axes_[2]->size(x, hint)});
  }
  size::Metric metric(const Vec3& x, const size::SizeHint& hint = {}) const override {
    size::Metric m = size::Metric::Zero();
    for (int k = 0; k < 3; ++k) {
      const double h = axes_[static_cast<std::size_t>(k)]->size(x, hint);
      m(k, k) = 1 / (h * h);
    }
    return m;
  }
  bool anisotropic() const override { return true; }

 private:
  std::array<std::shared_ptr<const size::SizeField>, 3> axes_;
};

std::shared_ptr<const size::SizeField> parse_metric_expr(const std::string& text) {
  std::vector<std::string> parts;
  for (std::size_t begin = 0;;) {
    const std::size_t end = text.find(';', begin);
    parts.push_back(text.substr(begin, end == std::string::npos ? end : end - begin));
    if (end == std::string::npos) break;
    begin = end + 1;
  }
  if (parts.size() != 3)
    throw InputError("--metric-expr", -1, -1,
                     fmt::format("needs three sizes 'hx; hy; hz', got {} expression(s)", parts.size()));
  std::array<std::shared_ptr<const size::SizeField>, 3> axes;
  for (std::size_t k = 0; k < 3; ++k) {
    try {
      axes[k] = size::make_expression_field(parts[k]);
    } catch (const std::exception& e) {
      throw InputError("--metric-expr", -1, -1, fmt::format("size along {}: {}", "xyz"[k], e.what()));
    }
  }
  return std::make_shared<AxisSizeField>(std::move(axes));
}

struct SizeSpec {
  optimize::MetricField field;
  /// The analytic function behind it (clamped), when there is one.
  std::shared_ptr<const size::SizeField> analytic;
};

// The size specification at the input's vertices, or nothing (isotropic
// shape only). Errors name the option or file at fault.
std::optional<SizeSpec> make_metric(const OptimizeCliOptions& o, const mesh::TetMesh& m) {
  if (!has_size_spec(o)) return std::nullopt;
  if (o.hmin > 0 && o.hmax > 0 && o.hmin > o.hmax)
    throw InputError("--hmin/--hmax", -1, -1, fmt::format("hmin {} is larger than hmax {}", o.hmin, o.hmax));
  SizeSpec spec;
  optimize::MetricField& field = spec.field;
  if (!o.sol.empty()) {
    const io::SolField sol = io::read_sol(io::read_file_bytes(o.sol), o.sol);
    try {
      const int components = sol.type == io::SolField::Type::kScalar ? 1 : 6;
      field = optimize::metric_field_from_values(sol.values, components, m.num_verts());
    } catch (const std::invalid_argument& e) {
      throw InputError(o.sol, -1, -1, fmt::format("{} ({})", e.what(), o.input));
    }
  } else if (!o.size_expr.empty() || !o.metric_expr.empty()) {
    std::shared_ptr<const size::SizeField> expr;
    try {
      expr = o.metric_expr.empty() ? size::make_expression_field(o.size_expr) : parse_metric_expr(o.metric_expr);
    } catch (const InputError&) {
      throw;
    } catch (const std::exception& e) {
      throw InputError("--size-expr", -1, -1, e.what());
    }
    spec.analytic = std::make_shared<ClampedField>(expr, o.hmin, o.hmax);
    try {
      field = optimize::metric_field_from_size_field(m, *spec.analytic);
    } catch (const std::exception& e) {
      throw InputError(o.metric_expr.empty() ? "--size-expr" : "--metric-expr", -1, -1, e.what());
    }
  } else if (o.aniso) {
    field = optimize::metric_field_from_mesh_shape(m);
  } else {
    field = optimize::metric_field_from_mesh_sizes(m);
  }
  if (o.aniso && !field.anisotropic()) {
    std::vector<size::Metric> ms(field.size());
    for (VertId v = 0; v < ms.size(); ++v) ms[v] = field.metric(v);
    field = optimize::MetricField::from_tensors(std::move(ms));
  }
  try {
    optimize::clamp_sizes(field, o.hmin, o.hmax);
  } catch (const std::invalid_argument& e) {
    throw InputError("--hmin/--hmax", -1, -1, e.what());
  }
  optimize::grade(field, m, o.hgrad);
  return spec;
}

nlohmann::json summary_json(const optimize::MeshSummary& s, bool metric) {
  nlohmann::json j = {{"vertices", s.verts},
                      {"tets", s.tets},
                      {"inverted", s.inverted},
                      {"mean_ratio_min", s.min_mean_ratio},
                      {"mean_ratio_mean", s.mean_mean_ratio},
                      {"min_dihedral_deg", s.min_dihedral},
                      {"max_dihedral_deg", s.max_dihedral},
                      {"volume", s.volume}};
  if (metric) {
    j["metric_quality_min"] = s.min_metric_quality;
    j["metric_quality_mean"] = s.mean_metric_quality;
  }
  return j;
}

nlohmann::json lengths_json(const optimize::LengthStats& l) {
  return {{"edges", l.edges},         {"min", l.min},
          {"max", l.max},             {"mean", l.mean},
          {"in_0_7_1_4", l.in_range}, {"percent_in_0_7_1_4", l.percent_in_range()},
          {"too_short", l.too_short}, {"too_long", l.too_long},
          {"histogram_bin_0_25", l.histogram}};
}

nlohmann::json limit_json(const optimize::BoundaryLimit& l) {
  nlohmann::json worst = nlohmann::json::array();
  for (const auto& w : l.worst)
    worst.push_back({{"min_dihedral_deg", w.dihedral},
                     {"mean_ratio", w.mean_ratio},
                     {"why", optimize::to_string(w.why)},
                     {"cap_deg", w.cap},
                     {"mean_ratio_at_target", w.price},
                     {"boundary_vertices", w.boundary_verts},
                     {"boundary_faces", w.boundary_faces},
                     {"centroid", {w.centroid.x(), w.centroid.y(), w.centroid.z()}}});
  return {{"target_deg", l.target},
          {"pinned", l.pinned},
          {"pinned_by_two_faces", l.by_two_faces},
          {"pinned_by_wedge", l.by_wedge},
          {"pinned_min_dihedral_deg", l.pinned_min_dihedral},
          {"pinned_min_mean_ratio", l.pinned_min_mean_ratio},
          {"pinned_min_cap_deg", l.pinned_min_cap},
          {"free_below_target", l.free_below},
          {"held_by_thin_face", l.held_by_thin_face},
          {"held_min_mean_ratio_at_target", l.min_price},
          {"free_min_dihedral_deg", l.free_min_dihedral},
          {"free_min_mean_ratio", l.free_min_mean_ratio},
          {"worst", worst}};
}

std::string render_limit(const optimize::BoundaryLimit& l) {
  std::string s = fmt::format(
      "below {:g} deg: {} tets pinned by the boundary ({} with two boundary faces, {} by a boundary wedge)", l.target,
      l.pinned, l.by_two_faces, l.by_wedge);
  if (l.pinned)
    s += fmt::format(": min dihedral {:.2f} deg, min mean ratio {:.4f}, the boundary allows {:.2f} deg at best",
                     l.pinned_min_dihedral, l.pinned_min_mean_ratio, l.pinned_min_cap);
  s += fmt::format("; {} free", l.free_below);
  if (l.held_by_thin_face)
    s += fmt::format(" ({} on a thin boundary face, where a tet at {:g} deg has mean ratio {:.4f} at best)",
                     l.held_by_thin_face, l.target, l.min_price);
  s += fmt::format("; free tets min dihedral {:.2f} deg, min mean ratio {:.4f}\n", l.free_min_dihedral,
                   l.free_min_mean_ratio);
  for (const auto& w : l.worst) {
    s += fmt::format("    {:6.2f} deg  mean ratio {:.4f}  {:<18}  cap {:6.2f} deg", w.dihedral, w.mean_ratio,
                     optimize::to_string(w.why), w.cap);
    if (w.price < 1) s += fmt::format("  at {:g} deg {:.4f}", l.target, w.price);
    s += fmt::format("  at ({:.6g}, {:.6g}, {:.6g})\n", w.centroid.x(), w.centroid.y(), w.centroid.z());
  }
  return s;
}

std::string render_lengths(const optimize::LengthStats& l) {
  std::string s;
  const std::size_t top = std::max<std::size_t>(1, *std::max_element(l.histogram.begin(), l.histogram.end()));
  for (std::size_t b = 0; b < l.histogram.size(); ++b) {
    const std::string label =
        b + 1 < l.histogram.size() ? fmt::format("[{:.2f},{:.2f})", 0.25 * b, 0.25 * (b + 1)) : "[3.00, inf)";
    s += fmt::format("    {:<12} {:>9} {}\n", label, l.histogram[b], std::string(40 * l.histogram[b] / top, '#'));
  }
  return s;
}

std::string boundary_policy(bool adapt, bool model, bool flat) {
  if (!model && adapt && flat)
    return "kept as a surface (boundary edges split at their midpoints; boundary vertices moved and collapsed only "
           "where it is exactly flat)";
  if (!model) return adapt ? "kept (boundary vertices fixed; boundary edges split at their midpoints)"
                           : "kept (boundary vertices and triangles unchanged)";
  return adapt ? "on the model (boundary vertices moved, split onto and collapsed along it; poor tets on it deleted)"
               : "on the model (boundary vertices moved on their model face or edge, collapsed along it; poor tets "
                 "on it deleted)";
}

int run_optimize(const OptimizeCliOptions& o) {
  Timer total, step;
  if (o.flat_boundary && !has_size_spec(o))
    throw InputError("--move-flat-boundary", -1, -1,
                     "needs a size specification (--sol, --size-expr, --metric-expr, --hmin/--hmax or --aniso)");
  mesh::TetMesh m = io::read_mesh(o.input);
  if (m.high_order.order() > 1)
    throw InputError(o.input, -1, -1,
                     fmt::format("optimize works on linear meshes; this one has order {} (curve it after)",
                                 m.high_order.order()));
  // A flat tet (exactly zero volume) is what optimization is for; anything
  // else that makes the mesh invalid is not ours to repair.
  const auto input_check = mesh::validate(m, mesh::Level::kFull, 5);
  if (input_check.num_issues > input_check.num_flat) {
    std::string first;
    for (const auto& issue : input_check.issues)
      if (issue.kind != mesh::ValidationIssue::Kind::kFlat) {
        first = issue.message;
        break;
      }
    throw InputError(o.input, -1, -1,
                     fmt::format("the input mesh is not valid ({} inverted tets, {} non-conforming faces, {} "
                                 "classification errors; first: {}); run `curvemesh check` on it",
                                 input_check.num_inverted, input_check.num_nonconforming,
                                 input_check.num_classification, first));
  }
  std::unique_ptr<geom::Model> model;
  if (!o.model.empty()) model = geom_occ::load_model(o.model, {});
  const double read_s = step.seconds();

  // The mesh's own tags need not be the model's (another tool's mesh of
  // it): the model's classification is found by geometry.
  std::optional<generate::ModelClassification> classified;
  if (model) {
    classified = generate::classify_on_model(m, *model, {o.input});
    const auto recheck = mesh::validate(m, mesh::Level::kFull, 1);
    if (!recheck.valid())
      throw InputError(o.input, -1, -1,
                       fmt::format("its classification on the model {} is not consistent ({}{}); optimize it "
                                   "without --model to keep its boundary as it is",
                                   o.model, recheck.issues.empty() ? "" : recheck.issues.front().message,
                                   classified->problems.empty() ? "" : "; " + classified->problems.front()));
  }
  const double classify_s = classified ? classified->seconds : 0;

  step.reset();
  std::optional<SizeSpec> spec = make_metric(o, m);
  // Adaptation adds and removes vertices and keeps the field attached to them.
  const optimize::MetricField* metric = spec ? &spec->field : nullptr;
  const double metric_s = step.seconds();
  const optimize::MeshSummary before = optimize::summarize_mesh(m, metric);

  step.reset();
  optimize::ImproveStats iso;
  optimize::AdaptStats adapt;
  if (metric) {
    optimize::AdaptOptions ao;
    ao.passes = o.passes;
    ao.threshold = o.threshold_given || !spec->field.anisotropic() ? o.threshold : 0.9;
    ao.flat_boundary = o.flat_boundary;
    ao.model = model.get();
    ao.sizes = spec->analytic.get();
    adapt = optimize::adapt_to_metric(m, spec->field, ao);
  } else {
    optimize::ImproveOptions io_;
    io_.passes = o.passes;
    io_.threshold = o.threshold;
    io_.model = model.get();
    iso = optimize::improve_quality(m, io_);
  }
  const double optimize_s = step.seconds();

  step.reset();
  const auto check = mesh::validate(m, mesh::Level::kFull);
  const optimize::MeshSummary after = optimize::summarize_mesh(m, metric);
  // The isotropic angle target the issue sets (10 degrees): which tets the
  // surface keeps below it.
  const optimize::BoundaryLimit limit = optimize::classify_boundary_limit(m, 10.0, 5);
  const double check_s = step.seconds();

  step.reset();
  io::WriteOptions wo;
  wo.binary = o.binary;
  io::write_mesh(m, o.output, wo);
  if (!o.sol_out.empty()) {
    if (!metric) throw InputError("--sol-out", -1, -1, "needs a size specification (--sol, --size-expr, --hmin/--hmax or --aniso)");
    io::SolField sol;
    sol.type = metric->anisotropic() ? io::SolField::Type::kTensor : io::SolField::Type::kScalar;
    sol.values = optimize::metric_field_values(*metric);
    io::write_sol(sol, o.sol_out, io::format_from_path(o.sol_out) == io::FileFormat::kSolBinary);
  }
  const double write_s = step.seconds();
  const bool ok = check.valid();
  const char* mode = !metric ? "isotropic" : metric->anisotropic() ? "anisotropic" : "size map";

  nlohmann::json j;
  j["input"] = o.input;
  j["output"] = o.output;
  j["mode"] = mode;
  j["move_flat_boundary"] = o.flat_boundary;
  j["valid"] = ok;
  j["before"] = summary_json(before, metric != nullptr);
  j["after"] = summary_json(after, metric != nullptr);
  j["check"] = {{"issues", check.num_issues},
                {"inverted", check.num_inverted},
                {"flat", check.num_flat},
                {"nonconforming", check.num_nonconforming},
                {"classification", check.num_classification}};
  double op_seconds = 0;
  if (metric) {
    j["operators"] = {{"edge_removals", adapt.edge_removals},
                      {"face_swaps", adapt.face_swaps},
                      {"relocations", adapt.relocations},
                      {"splits", adapt.splits},
                      {"collapses", adapt.collapses},
                      {"insertions", adapt.insertions},
                      {"deletions", adapt.deletions},
                      {"passes", adapt.passes},
                      {"seconds",
                       {{"splits", adapt.split_seconds},
                        {"collapses", adapt.collapse_seconds},
                        {"swaps", adapt.swap_seconds},
                        {"relocation", adapt.relocation_seconds},
                        {"insertion", adapt.insertion_seconds}}}};
    j["lengths_before"] = lengths_json(adapt.lengths_before);
    j["lengths_after"] = lengths_json(adapt.lengths_after);
    op_seconds = adapt.seconds;
  } else {
    j["operators"] = {{"edge_removals", iso.edge_removals},
                      {"face_swaps", iso.face_swaps},
                      {"relocations", iso.relocations},
                      {"boundary_relocations", iso.boundary_relocations},
                      {"searched_relocations", iso.searched_relocations},
                      {"insertions", iso.insertions},
                      {"deletions", iso.deletions},
                      {"collapses", iso.collapses},
                      {"passes", iso.passes},
                      {"seconds",
                       {{"swaps", iso.swap_seconds},
                        {"relocation", iso.relocation_seconds},
                        {"insertion", iso.insertion_seconds},
                        {"deletion", iso.deletion_seconds},
                        {"collapse", iso.collapse_seconds}}}};
    op_seconds = iso.seconds;
  }
  if (classified) j["classification"] = classification_json(*classified);
  j["boundary"] = boundary_policy(metric != nullptr, model != nullptr, o.flat_boundary);
  j["boundary_limit"] = limit_json(limit);
  j["seconds"] = {{"read", read_s},   {"classify", classify_s}, {"metric", metric_s}, {"optimize", optimize_s},
                  {"check", check_s}, {"write", write_s},       {"total", total.seconds()}};
  if (!o.json_path.empty()) write_json(j, o.json_path);

  if (!o.quiet) {
    fmt::print("mesh: {}  ({} mode{})\n", o.input, mode, model ? fmt::format(", model {}", o.model) : "");
    if (classified) fmt::print("{}", render_classification(*classified));
    auto line = [&](const char* label, const optimize::MeshSummary& s) {
      fmt::print("  {:<7} {:>8} vertices {:>9} tets  mean ratio min {:.4f} mean {:.4f}  dihedral min {:6.2f} max "
                 "{:6.2f} deg",
                 label, s.verts, s.tets, s.min_mean_ratio, s.mean_mean_ratio, s.min_dihedral, s.max_dihedral);
      if (metric && metric->anisotropic())
        fmt::print("  metric quality min {:.4f} mean {:.4f}", s.min_metric_quality, s.mean_metric_quality);
      fmt::print("\n");
    };
    line("before", before);
    line("after", after);
    if (metric) {
      fmt::print("operators: {} splits, {} collapses, {} edge removals, {} face swaps, {} relocations, {} "
                 "insertions, {} deletions in {} passes (splits {:.2f} s, collapses {:.2f} s, swaps {:.2f} s, "
                 "relocation {:.2f} s, insertion {:.2f} s)\n",
                 adapt.splits, adapt.collapses, adapt.edge_removals, adapt.face_swaps, adapt.relocations,
                 adapt.insertions, adapt.deletions, adapt.passes, adapt.split_seconds, adapt.collapse_seconds, adapt.swap_seconds,
                 adapt.relocation_seconds, adapt.insertion_seconds);
      fmt::print("lengths in the metric: {:.1f}% of {} edges in [0.7, 1.4] before, {:.1f}% after (min {:.3f} max "
                 "{:.3f} mean {:.3f})\n",
                 adapt.lengths_before.percent_in_range(), adapt.lengths_before.edges,
                 adapt.lengths_after.percent_in_range(), adapt.lengths_after.min, adapt.lengths_after.max,
                 adapt.lengths_after.mean);
      fmt::print("{}", render_lengths(adapt.lengths_after));
    } else {
      fmt::print("operators: {}\n", improve_operator_counts(iso, true));
    }
    fmt::print("{}", render_limit(limit));
    fmt::print("volume: {:.10g} -> {:.10g}; boundary: {}\n", before.volume, after.volume,
               boundary_policy(metric != nullptr, model != nullptr, o.flat_boundary));
    fmt::print("check: {}", ok ? "valid" : "INVALID");
    if (!ok) fmt::print(" ({} inverted, {} flat, {} other issues)", check.num_inverted, check.num_flat,
                        check.num_issues - check.num_inverted - check.num_flat);
    fmt::print("\n");
    fmt::print("time: read {:.2f} s, classify {:.2f} s, metric {:.2f} s, optimize {:.2f} s (operators {:.2f} s), "
               "check {:.2f} s, write {:.2f} s, total {:.2f} s\n",
               read_s, classify_s, metric_s, optimize_s, op_seconds, check_s, write_s, total.seconds());
    fmt::print("wrote {}\n", o.output);
  }
  return ok ? kExitOk : kExitInvalidMesh;
}

}  // namespace

void add_optimize_command(CLI::App& app, Runner& runner) {
  auto o = std::make_shared<OptimizeCliOptions>();
  CLI::App* cmd = app.add_subcommand("optimize", "Improve the quality of a tet mesh (isotropic, size map or metric)");
  cmd->add_option("mesh", o->input, "Input mesh (.msh 2.2/4.1, .mesh, .meshb)")->required();
  cmd->add_option("-o,--output", o->output, "Output mesh (.msh, .mesh/.meshb, .vtu)")->required();
  cmd->add_option("--model", o->model, "The CAD model of the mesh (STEP/IGES/BREP)");
  auto* sol = cmd->add_option("--sol", o->sol,
                              "Sizes (scalar) or metric tensors (6 values, MMG order m11 m12 m22 m13 m23 m33) at "
                              "the input's vertices (.sol/.solb)");
  auto* expr = cmd->add_option("--size-expr", o->size_expr, "Size as a function of x, y, z, e.g. '0.1 + 0.05*x'");
  sol->excludes(expr);
  auto* metric_expr = cmd->add_option(
      "--metric-expr", o->metric_expr,
      "Anisotropic metric from three sizes along x, y and z, 'hx; hy; hz' (each as --size-expr)");
  metric_expr->excludes(sol);
  metric_expr->excludes(expr);
  cmd->add_option("--hmin", o->hmin, "Smallest size: clamps the size map (alone: the mesh's own sizes)")
      ->check(CLI::PositiveNumber);
  cmd->add_option("--hmax", o->hmax, "Largest size: clamps the size map (alone: the mesh's own sizes)")
      ->check(CLI::PositiveNumber);
  cmd->add_option("--hgrad", o->hgrad, "Gradation of the size map, MMG's rule; <= 0: none")->capture_default_str();
  cmd->add_flag("--aniso", o->aniso,
                "Measure in an anisotropic metric: the --sol tensors, or without them the mesh's own stretching");
  cmd->add_option("--passes", o->passes, "Passes over the bad tets")->capture_default_str()->check(CLI::Range(0, 1000));
  cmd->add_option("--threshold", o->threshold,
                  "Tets with mean ratio (in the metric) below this are worked on (0.9 in an anisotropic metric)")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 1.0))
      ->each([o](const std::string&) { o->threshold_given = true; });
  cmd->add_flag("--move-flat-boundary", o->flat_boundary,
                "With a size map or metric and no --model: boundary vertices may move and go where the surface is "
                "exactly flat (and straight along model edges), keeping the surface and volume");
  cmd->add_option("--sol-out", o->sol_out, "Write the size map / metric used at the output's vertices (.sol/.solb)");
  cmd->add_flag("--binary", o->binary, "Binary MSH 4.1 output");
  cmd->add_option("--json", o->json_path, "Write the summary as JSON");
  cmd->add_flag("-q,--quiet", o->quiet, "Print nothing on success");
  cmd->footer(
      "Without --model the boundary surface, its classification and reference tags, and the enclosed\n"
      "volume are kept: boundary vertices never move and boundary triangles are never swapped; with a\n"
      "size map or a metric, edges are split and collapsed toward unit length in it ([0.7, 1.4]),\n"
      "boundary edges split at their midpoints and boundary vertices never removed; with\n"
      "--move-flat-boundary they also move and go within faces that are exactly flat (and along model\n"
      "edges that are exactly straight), as on a box, so the surface is the same point set. With --model the\n"
      "mesh is first classified on the model by geometry (a mesh made from that model by any tool, e.g.\n"
      "Gmsh, whatever its own tags; the output carries the model's tags), then boundary vertices move on\n"
      "their model face or edge, new boundary points go onto the model and boundary vertices may\n"
      "collapse along it. A mesh whose boundary is not on the model is refused (exit code 2).\n"
      "--hgrad <= 0 turns gradation off (default 1.3, applied to any size map).\n"
      "Exit codes: 0 the optimized mesh is valid, 1 it is not (written anyway), 2 bad usage or\n"
      "unreadable input (including an input mesh with inverted tets, or a .sol whose count differs\n"
      "from the mesh's vertices), 3 internal error.\n"
      "Examples:\n  curvemesh optimize part.msh -o part_opt.msh\n"
      "  curvemesh optimize part.mesh --sol sizes.sol -o part_opt.mesh --json report.json\n"
      "  curvemesh optimize part.mesh --sol metric.sol --aniso -o part_opt.mesh\n"
      "  curvemesh optimize box.msh --metric-expr '0.02 + 0.2*abs(x - 0.5); 0.1; 0.1' -o box_aniso.msh");
  cmd->callback([&runner, o] { runner = [o] { return run_optimize(*o); }; });
}

}  // namespace cm::cli
