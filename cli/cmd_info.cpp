// `curvemesh info`: what a geometric model holds — topology, units, sizes and
// the range of curvature of each face, as the size field will see it.
#include <algorithm>
#include <cmath>
#include <limits>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "commands.hpp"
#include "curvemesh/core/timer.hpp"
#include "curvemesh/geom_occ/load.hpp"
#include "exit_codes.hpp"
#include "json_output.hpp"

namespace cm::cli {

namespace {

struct InfoOptions {
  std::string model;
  std::string json_path;
  int samples = 16;
  double heal_tolerance = 0;
  bool no_heal = false;
};

struct CurvatureRange {
  double k_min = std::numeric_limits<double>::infinity();
  double k_max = -std::numeric_limits<double>::infinity();
  int samples = 0;
};

// Principal curvatures at the corners and centres of an n x n grid over the
// face's parameter box (corners catch extremes on the box boundary, e.g. a
// torus's inner equator), keeping only points inside the trimmed face.
CurvatureRange sample_curvature(const geom::Model& g, int face, int n) {
  CurvatureRange r;
  const geom::ParamRange pr = g.param_range({2, face});
  for (int i = 0; i <= 2 * n; ++i)
    for (int j = 0; j <= 2 * n; ++j) {
      if ((i + j) % 2 != 0) continue;  // even: corner (both even) or centre (both odd)
      const Vec2 uv(pr.u0 + (pr.u1 - pr.u0) * i / (2.0 * n), pr.v0 + (pr.v1 - pr.v0) * j / (2.0 * n));
      if (!g.contains_param(face, uv)) continue;
      const geom::Curvatures c = g.face_curvatures(face, uv);
      if (!std::isfinite(c.k1) || !std::isfinite(c.k2)) continue;
      r.k_min = std::min(r.k_min, c.k2);
      r.k_max = std::max(r.k_max, c.k1);
      ++r.samples;
    }
  return r;
}

nlohmann::json box_json(const geom::BoundingBox& b) {
  return {{"min", {b.min.x(), b.min.y(), b.min.z()}}, {"max", {b.max.x(), b.max.y(), b.max.z()}}};
}

int run_info(const InfoOptions& o) {
  Timer timer;
  geom_occ::LoadOptions lo;
  lo.heal = !o.no_heal;
  lo.heal_tolerance = o.heal_tolerance;
  const auto model = geom_occ::load_model(o.model, lo);
  const geom::Model& g = *model;
  const double load_s = timer.seconds();

  nlohmann::json j;
  j["model"] = o.model;
  j["units"] = g.units();
  j["counts"] = {{"regions", g.count(3)}, {"faces", g.count(2)}, {"edges", g.count(1)}, {"vertices", g.count(0)}};
  j["bounding_box"] = box_json(g.bounding_box());
  double volume = 0, area = 0;
  nlohmann::json regions = nlohmann::json::array();
  for (int r = 1; r <= g.count(3); ++r) {
    const double v = g.volume(r);
    volume += v;
    const Vec3 c = g.center_of_mass(r);
    regions.push_back({{"tag", r}, {"volume", v}, {"faces", g.region_faces(r).size()}, {"center_of_mass", {c.x(), c.y(), c.z()}}});
  }
  nlohmann::json faces = nlohmann::json::array();
  for (int f = 1; f <= g.count(2); ++f) {
    const double a = g.area(f);
    area += a;
    const CurvatureRange k = sample_curvature(g, f, o.samples);
    nlohmann::json fj = {{"tag", f}, {"type", geom::to_string(g.type({2, f}))}, {"area", a}, {"loops", g.face_loops(f).size()}};
    // "+ 0.0" turns a plane's -0 curvature into 0 so users do not read a sign into it.
    if (k.samples > 0) fj["curvature"] = {{"min", k.k_min + 0.0}, {"max", k.k_max + 0.0}, {"samples", k.samples}};
    faces.push_back(fj);
  }
  nlohmann::json edges = nlohmann::json::array();
  for (int e = 1; e <= g.count(1); ++e)
    edges.push_back({{"tag", e}, {"type", geom::to_string(g.type({1, e}))}, {"length", g.length(e)}, {"degenerate", g.is_degenerate(e)}});
  j["volume"] = volume;
  j["area"] = area;
  j["regions"] = regions;
  j["faces"] = faces;
  j["edges"] = edges;
  j["seconds"] = {{"load", load_s}, {"total", timer.seconds()}};

  const auto& bb = g.bounding_box();
  fmt::print("model: {}  (units: {})\n", o.model, g.units().empty() ? "unknown" : g.units());
  fmt::print("  {} regions, {} faces, {} edges, {} vertices\n", g.count(3), g.count(2), g.count(1), g.count(0));
  fmt::print("  bounding box: ({:.6g}, {:.6g}, {:.6g}) - ({:.6g}, {:.6g}, {:.6g})\n", bb.min.x(), bb.min.y(), bb.min.z(),
             bb.max.x(), bb.max.y(), bb.max.z());
  fmt::print("  volume {:.8g}   area {:.8g}\n", volume, area);
  fmt::print("faces:\n");
  for (const auto& f : faces) {
    fmt::print("  {:5d} {:<22} area {:<12.6g}", f["tag"].get<int>(), f["type"].get<std::string>(), f["area"].get<double>());
    if (f.contains("curvature"))
      fmt::print(" curvature [{:.4g}, {:.4g}]", f["curvature"]["min"].get<double>(), f["curvature"]["max"].get<double>());
    fmt::print("\n");
  }
  fmt::print("edges:\n");
  for (const auto& e : edges)
    fmt::print("  {:5d} {:<14} length {:.6g}{}\n", e["tag"].get<int>(), e["type"].get<std::string>(),
               e["length"].get<double>(), e["degenerate"].get<bool>() ? "  (degenerate)" : "");
  fmt::print("time: load {:.2f} s, total {:.2f} s\n", load_s, timer.seconds());

  if (!o.json_path.empty()) {
    write_json(j, o.json_path);
  }
  return kExitOk;
}

}  // namespace

void add_info_command(CLI::App& app, Runner& runner) {
  auto opts = std::make_shared<InfoOptions>();
  CLI::App* cmd = app.add_subcommand("info", "Describe a geometric model: topology, units, sizes, curvature");
  cmd->add_option("model", opts->model, "STEP/IGES/BREP file or builtin:NAME[:key=value,...]")->required();
  cmd->add_option("--json", opts->json_path, "Also write the description as JSON to this file");
  cmd->add_option("--samples", opts->samples, "Curvature grid cells per parameter direction of each face (samples at corners and centres)")
      ->capture_default_str()
      ->check(CLI::Range(1, 1000));
  cmd->add_option("--heal-tolerance", opts->heal_tolerance, "Healing/sewing tolerance (0: from the model)");
  cmd->add_flag("--no-heal", opts->no_heal, "Do not run shape healing on import");
  cmd->footer("Built-in models:\n" + geom_occ::builtin_help() +
              "\nExamples:\n  curvemesh info part.step\n  curvemesh info builtin:torus:R=3,r=1 --json torus.json");
  cmd->callback([&runner, opts] { runner = [opts] { return run_info(*opts); }; });
}

}  // namespace cm::cli
