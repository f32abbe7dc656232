// `curvemesh size`: builds the size field of a model (curvature, entity
// sizes, background and analytic fields, gradation) and shows it: a summary,
// the octree cells as .vtu (where the mesh will be fine and which source made
// it so), the curvature samples as a point cloud.
#include <algorithm>
#include <cmath>
#include <limits>
#include <map>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "commands.hpp"
#include "curvemesh/core/timer.hpp"
#include "curvemesh/geom_occ/load.hpp"
#include "curvemesh/io/formats.hpp"
#include "curvemesh/size/build.hpp"
#include "exit_codes.hpp"
#include "json_output.hpp"
#include "size_options.hpp"

namespace cm::cli {

namespace {

struct SizeCliOptions {
  std::string model;
  std::string vtu_path, samples_path, json_path;
  SizeFlags size;
  ModelFlags model_flags;
  bool quiet = false;
};

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
  const size::SizeOptions so = make_size_options(o.size);
  const auto model = geom_occ::load_model(o.model, o.model_flags.load_options());
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
  const double rate = r.curvature_seconds > 0 ? double(r.stats.evaluations) / r.curvature_seconds : 0;

  nlohmann::json j;
  j["model"] = o.model;
  j["units"] = model->units();
  j["hmin"] = r.hmin;
  j["hmax"] = r.hmax;
  j["hgrad"] = so.hgrad;
  j["curvature"] = describe(so.curvature);
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
  j["seconds"] = {{"load", load_s}, {"sampling", r.sampling_seconds}, {"curvature", r.curvature_seconds},
                  {"octree", r.octree_seconds},
                  {"total", timer.seconds()}};

  if (!o.vtu_path.empty()) write_octree_vtu(*r.octree, o.vtu_path);
  if (!o.samples_path.empty()) write_samples_vtu(r.samples, o.samples_path);
  if (!o.json_path.empty()) {
    write_json(j, o.json_path);
  }
  if (!o.quiet) {
    fmt::print("model: {}  (units: {})\n", o.model, model->units().empty() ? "unknown" : model->units());
    fmt::print("  hmin {:.6g}  hmax {:.6g}  hgrad {}  curvature {}\n", r.hmin, r.hmax, so.hgrad,
               j["curvature"].get<std::string>());
    fmt::print("  curvature samples: {} evaluated ({:.3g}/s), {} ask for < hmax", r.stats.evaluations, rate,
               curvature_kept);
    if (curvature_kept > 0) fmt::print(" (sizes {:.4g} .. {:.4g})", smin, smax);
    fmt::print("\n  octree: {} leaves, depth {}, {} rounds\n", r.octree->num_leaves(), r.octree->depth(),
               r.octree->build_rounds());
    for (const auto& [s, n] : by_source) fmt::print("    {:>8} leaves set by {}\n", n, size::to_string(s));
    fmt::print("time: load {:.2f} s, sampling {:.2f} s (curvature {:.2f} s), octree {:.2f} s, total {:.2f} s\n",
               load_s, r.sampling_seconds, r.curvature_seconds, r.octree_seconds, timer.seconds());
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
  add_size_flags(cmd, o->size);
  add_model_flags(cmd, o->model_flags);
  cmd->add_flag("-q,--quiet", o->quiet, "Print nothing on success");
  cmd->footer(
      "Sources are combined by taking the finest, then graded by --hgrad and clamped to [hmin, hmax]\n"
      "(except along a face tapering to a cusp narrower than hmin and on a face closed around in under\n"
      "3 hmin: down to hmin / 10).\n"
      "Cell field 'source' in the .vtu: 0 hmax, 1 face curvature, 2 edge curvature, 3 entity size,\n"
      "4 size field, 5 gradation, 6 hmin, 7 short edge, 8 narrow face, 9 cusp strip, 10 thin closed face.\n"
      "\nExamples:\n  curvemesh size part.step -o size.vtu\n"
      "  curvemesh size builtin:torus --curv-eps 0.01 --hgrad 1.2 -o size.vtu --samples-out samples.vtu\n"
      "  curvemesh size part.step --size face:3=0.5 --size-expr '0.2 + 0.1*abs(z)'\n"
      "  curvemesh size assembly.step --size region:2=1.5 -o size.vtu");
  cmd->callback([&runner, o] { runner = [o] { return run_size(*o); }; });
}

}  // namespace cm::cli
