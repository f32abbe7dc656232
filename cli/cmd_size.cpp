// `curvemesh size`: builds the size field of a model (curvature, entity
// sizes, background and analytic fields, gradation) and shows it: a summary,
// the octree cells as .vtu (where the mesh will be fine and which source made
// it so), the curvature samples as a point cloud.
#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <optional>
#include <regex>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "commands.hpp"
#include "curvemesh/core/error.hpp"
#include "curvemesh/core/timer.hpp"
#include "curvemesh/geom_occ/load.hpp"
#include "curvemesh/io/atomic_file.hpp"
#include "curvemesh/io/formats.hpp"
#include "curvemesh/io/mesh_io.hpp"
#include "curvemesh/size/background_field.hpp"
#include "curvemesh/size/build.hpp"
#include "curvemesh/size/expression.hpp"
#include "exit_codes.hpp"

namespace cm::cli {

namespace {

struct SizeCliOptions {
  std::string model;
  std::string vtu_path, samples_path, json_path;
  double hmax = 0, hmin = 0, hgrad = 1.3;
  std::optional<double> curv_eps, curv_alpha;
  bool no_curvature = false;
  bool directional = false;
  std::vector<std::string> entity_sizes;
  std::vector<std::string> expressions;
  std::string background_mesh, background_sol;
  double heal_tolerance = 0;
  bool no_heal = false;
  bool quiet = false;
};

// "face:3=0.5", "edge:12=0.1", "vertex:4=0.01" or "2:3=0.5".
std::pair<geom::EntityRef, double> parse_entity_size(const std::string& spec) {
  static const std::regex re(R"(^\s*(vertex|edge|face|0|1|2)\s*:\s*(\d+)\s*=\s*([^\s]+)\s*$)");
  std::smatch m;
  if (!std::regex_match(spec, m, re))
    throw InputError("--size", -1, -1,
                     fmt::format("'{}': expected DIM:TAG=H with DIM vertex, edge or face (or 0, 1, 2), e.g. face:3=0.5",
                                 spec));
  static const std::map<std::string, int> dims = {{"vertex", 0}, {"edge", 1}, {"face", 2}, {"0", 0}, {"1", 1}, {"2", 2}};
  double h = 0;
  try {
    std::size_t used = 0;
    h = std::stod(m[3].str(), &used);
    if (used != m[3].str().size()) throw std::invalid_argument("trailing");
  } catch (const std::exception&) {
    throw InputError("--size", -1, -1, fmt::format("'{}': '{}' is not a number", spec, m[3].str()));
  }
  if (!(h > 0) || !std::isfinite(h))
    throw InputError("--size", -1, -1, fmt::format("'{}': the size must be finite and > 0", spec));
  return {{dims.at(m[1].str()), std::stoi(m[2].str())}, h};
}

std::shared_ptr<const size::SizeField> read_background(const SizeCliOptions& o, double hgrad,
                                                       std::shared_ptr<const size::SizeField>* metric) {
  mesh::TetMesh bg = io::read_mesh(o.background_mesh);
  const io::SolField sol = io::read_sol(io::read_file_bytes(o.background_sol), o.background_sol);
  if (sol.num_verts() != bg.num_verts())
    throw InputError(o.background_sol, -1, -1,
                     fmt::format("{} values for the {} vertices of {}", sol.num_verts(), bg.num_verts(),
                                 o.background_mesh));
  try {
    if (sol.type == io::SolField::Type::kScalar) {
      // Graded with every other isotropic source in the octree.
      return std::make_shared<size::BackgroundField>(std::move(bg), sol.values);
    }
    std::vector<size::Metric> ms(sol.num_verts());
    for (std::size_t v = 0; v < ms.size(); ++v) {
      const double* t = &sol.values[6 * v];  // MMG order m11 m12 m22 m13 m23 m33
      ms[v] << t[0], t[1], t[3], t[1], t[2], t[4], t[3], t[4], t[5];
    }
    ms = size::grade_metrics(bg, std::move(ms), hgrad);
    *metric = std::make_shared<size::BackgroundField>(std::move(bg), std::move(ms));
    return nullptr;
  } catch (const std::invalid_argument& e) {
    throw InputError(o.background_sol, -1, -1, e.what());
  }
}

void write_octree_vtu(const size::SizeOctree& tree, const std::string& path) {
  constexpr std::uint8_t kVtkVoxel = 11;  // corners x fastest, then y, then z: the octree's order
  const auto leaves = tree.leaves();
  io::VtuGrid g;
  g.points.reserve(8 * leaves.size());
  io::VtuGrid::Field size{"size", 1, {}}, min_size{"min_size", 1, {}}, level{"level", 1, {}},
      source{"source", 1, {}};
  for (const auto& l : leaves) {
    for (int c = 0; c < 8; ++c) {
      g.connectivity.push_back(static_cast<std::int64_t>(g.points.size()));
      g.points.push_back(l.lo + l.side * Vec3(c & 1, (c >> 1) & 1, (c >> 2) & 1));
    }
    g.offsets.push_back(static_cast<std::int64_t>(g.connectivity.size()));
    g.types.push_back(kVtkVoxel);
    size.values.push_back(l.size);
    min_size.values.push_back(l.min_size);
    level.values.push_back(l.level);
    source.values.push_back(static_cast<int>(l.source));
  }
  g.cell_fields = {size, min_size, level, source};
  io::write_vtu_grid(g, path);
}

void write_samples_vtu(const std::vector<size::SizeSample>& samples, const std::string& path) {
  constexpr std::uint8_t kVtkVertex = 1;
  io::VtuGrid g;
  io::VtuGrid::Field size{"size", 1, {}}, k1{"k1", 1, {}}, k2{"k2", 1, {}}, source{"source", 1, {}},
      dim{"entity_dim", 1, {}}, tag{"entity_tag", 1, {}}, dir{"dir1", 3, {}};
  for (const auto& s : samples) {
    g.connectivity.push_back(static_cast<std::int64_t>(g.points.size()));
    g.offsets.push_back(static_cast<std::int64_t>(g.connectivity.size()));
    g.types.push_back(kVtkVertex);
    g.points.push_back(s.point);
    size.values.push_back(s.size);
    k1.values.push_back(s.k1);
    k2.values.push_back(s.k2);
    source.values.push_back(static_cast<int>(s.source));
    dim.values.push_back(s.entity.dim);
    tag.values.push_back(s.entity.tag);
    for (int a = 0; a < 3; ++a) dir.values.push_back(s.dir1[a]);
  }
  g.point_fields = {size, k1, k2, source, dim, tag, dir};
  io::write_vtu_grid(g, path);
}

int run_size(const SizeCliOptions& o) {
  Timer timer;
  size::SizeOptions so;
  so.hmax = o.hmax;
  so.hmin = o.hmin;
  so.hgrad = o.hgrad;
  so.directional = o.directional;
  if (o.no_curvature)
    so.curvature = size::CurvatureRule::off();
  else if (o.curv_eps)
    so.curvature = size::CurvatureRule::chord_deviation(*o.curv_eps);
  else if (o.curv_alpha)
    so.curvature = size::CurvatureRule::relative_deviation(*o.curv_alpha);
  for (const auto& spec : o.entity_sizes) so.entity_sizes.push_back(parse_entity_size(spec));
  for (const auto& e : o.expressions) so.fields.push_back(size::make_expression_field(e));
  if (!o.background_mesh.empty()) {
    if (auto iso = read_background(o, o.hgrad, &so.metric)) so.fields.push_back(iso);
  }

  geom_occ::LoadOptions lo;
  lo.heal = !o.no_heal;
  lo.heal_tolerance = o.heal_tolerance;
  const auto model = geom_occ::load_model(o.model, lo);
  const double load_s = timer.seconds();
  const size::SizeFieldResult r = size::build_size_field(*model, so);

  // Curvature samples only: entity sizes are the user's own numbers.
  double smin = std::numeric_limits<double>::infinity(), smax = 0;
  std::size_t curvature_kept = 0;
  for (const auto& s : r.samples)
    if (s.source == size::SizeSource::kFaceCurvature || s.source == size::SizeSource::kEdgeCurvature) {
      smin = std::min(smin, s.size);
      smax = std::max(smax, s.size);
      ++curvature_kept;
    }
  std::map<size::SizeSource, std::size_t> by_source;
  for (const auto& l : r.octree->leaves()) ++by_source[l.source];
  const double rate = r.sampling_seconds > 0 ? double(r.stats.evaluations) / r.sampling_seconds : 0;

  nlohmann::json j;
  j["model"] = o.model;
  j["units"] = model->units();
  j["hmin"] = r.hmin;
  j["hmax"] = r.hmax;
  j["hgrad"] = o.hgrad;
  j["curvature"] = so.curvature.kind == size::CurvatureRule::Kind::kOff ? "off"
                   : so.curvature.kind == size::CurvatureRule::Kind::kChordDeviation
                       ? fmt::format("eps={}", so.curvature.value)
                       : fmt::format("alpha={}", so.curvature.value);
  j["samples"] = {{"evaluations", r.stats.evaluations}, {"kept", curvature_kept},
                  {"outside_trim", r.stats.outside}, {"revisited", r.stats.revisited},
                  {"subdivided_cells", r.stats.subdivided}, {"per_second", rate}};
  if (curvature_kept > 0) j["samples"]["size_range"] = {smin, smax};
  j["octree"] = {{"leaves", r.octree->num_leaves()}, {"corners", r.octree->num_corners()},
                 {"depth", r.octree->depth()}, {"root_side", r.octree->root_side()},
                 {"rounds", r.octree->build_rounds()}};
  nlohmann::json sources;
  for (const auto& [s, n] : by_source) sources[size::to_string(s)] = n;
  j["octree"]["leaves_by_source"] = sources;
  j["seconds"] = {{"load", load_s}, {"sampling", r.sampling_seconds}, {"octree", r.octree_seconds},
                  {"total", timer.seconds()}};

  if (!o.vtu_path.empty()) write_octree_vtu(*r.octree, o.vtu_path);
  if (!o.samples_path.empty()) write_samples_vtu(r.samples, o.samples_path);
  if (!o.json_path.empty()) {
    io::AtomicFile out(o.json_path);
    out.write(j.dump(2));
    out.write("\n");
    out.commit();
  }
  if (!o.quiet) {
    fmt::print("model: {}  (units: {})\n", o.model, model->units().empty() ? "unknown" : model->units());
    fmt::print("  hmin {:.6g}  hmax {:.6g}  hgrad {}  curvature {}\n", r.hmin, r.hmax, o.hgrad,
               j["curvature"].get<std::string>());
    fmt::print("  curvature samples: {} evaluated ({:.3g}/s), {} ask for < hmax", r.stats.evaluations, rate,
               curvature_kept);
    if (curvature_kept > 0) fmt::print(" (sizes {:.4g} .. {:.4g})", smin, smax);
    fmt::print("\n  octree: {} leaves, depth {}, {} rounds\n", r.octree->num_leaves(), r.octree->depth(),
               r.octree->build_rounds());
    for (const auto& [s, n] : by_source) fmt::print("    {:>8} leaves set by {}\n", n, size::to_string(s));
    fmt::print("time: load {:.2f} s, sampling {:.2f} s, octree {:.2f} s, total {:.2f} s\n", load_s,
               r.sampling_seconds, r.octree_seconds, timer.seconds());
    if (!o.vtu_path.empty()) fmt::print("wrote {}\n", o.vtu_path);
    if (!o.samples_path.empty()) fmt::print("wrote {}\n", o.samples_path);
  }
  return kExitOk;
}

}  // namespace

void add_size_command(CLI::App& app, Runner& runner) {
  auto o = std::make_shared<SizeCliOptions>();
  CLI::App* cmd = app.add_subcommand("size", "Build a model's size field (curvature, sizes, gradation) and show it");
  cmd->add_option("model", o->model, "STEP/IGES/BREP file or builtin:NAME[:key=value,...]")->required();
  cmd->add_option("-o,--output", o->vtu_path, "Write the octree cells (size, source, level) to this .vtu");
  cmd->add_option("--samples-out", o->samples_path, "Write the curvature samples (point cloud) to this .vtu");
  cmd->add_option("--json", o->json_path, "Write the summary as JSON");
  cmd->add_option("--hmax", o->hmax, "Largest size (default: bounding-box diagonal / 20)")->check(CLI::PositiveNumber);
  cmd->add_option("--hmin", o->hmin, "Smallest size (default: hmax / 100)")->check(CLI::PositiveNumber);
  cmd->add_option("--hgrad", o->hgrad, "Gradation: sizes grow at most by (hgrad-1) per unit length")
      ->capture_default_str()
      ->check(CLI::Range(1.0, 1e6));
  auto* eps = cmd->add_option("--curv-eps", o->curv_eps,
                              "Curvature: constant chord deviation eps (seed eq. 4.3), a length")
                  ->check(CLI::PositiveNumber);
  auto* alpha = cmd->add_option("--curv-alpha", o->curv_alpha,
                                "Curvature: deviation alpha times the edge length (eq. 4.5), in (0, 0.5]; "
                                "default 0.04")
                    ->check(CLI::Range(1e-12, 0.5));
  auto* off = cmd->add_flag("--no-curvature", o->no_curvature, "No curvature-based sizes");
  eps->excludes(alpha)->excludes(off);
  alpha->excludes(off);
  cmd->add_flag("--directional", o->directional,
                "Sizes along each principal direction on faces (anisotropic surface metric)");
  cmd->add_option("--size", o->entity_sizes, "Size on a model entity: DIM:TAG=H, e.g. face:3=0.5 (repeatable)");
  cmd->add_option("--size-expr", o->expressions,
                  "Size as a function of x, y, z, e.g. '0.1 + 0.05*sqrt(x^2+y^2)' (repeatable)");
  auto* bg = cmd->add_option("--background", o->background_mesh, "Background tet mesh for --background-sol");
  auto* bgs = cmd->add_option("--background-sol", o->background_sol,
                              "Sizes (scalar) or metrics (tensor) at the background mesh's vertices (.sol/.solb)");
  bg->needs(bgs);
  bgs->needs(bg);
  cmd->add_option("--heal-tolerance", o->heal_tolerance, "Healing/sewing tolerance (0: from the model)");
  cmd->add_flag("--no-heal", o->no_heal, "Do not run shape healing on import");
  cmd->add_flag("-q,--quiet", o->quiet, "Print nothing on success");
  cmd->footer(
      "Sources are combined by taking the finest, then graded by --hgrad and clamped to [hmin, hmax].\n"
      "Cell field 'source' in the .vtu: 0 hmax, 1 face curvature, 2 edge curvature, 3 entity size,\n"
      "4 size field, 5 gradation, 6 hmin.\n"
      "\nExamples:\n  curvemesh size part.step -o size.vtu\n"
      "  curvemesh size builtin:torus --curv-eps 0.01 --hgrad 1.2 -o size.vtu --samples-out samples.vtu\n"
      "  curvemesh size part.step --size face:3=0.5 --size-expr '0.2 + 0.1*abs(z)'");
  cmd->callback([&runner, o] { runner = [o] { return run_size(*o); }; });
}

}  // namespace cm::cli
