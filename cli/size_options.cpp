#include "size_options.hpp"

#include <charconv>
#include <cmath>
#include <map>
#include <regex>

#include <fmt/format.h>

#include "curvemesh/core/error.hpp"
#include "curvemesh/io/atomic_file.hpp"
#include "curvemesh/io/formats.hpp"
#include "curvemesh/io/mesh_io.hpp"
#include "curvemesh/size/background_field.hpp"
#include "curvemesh/size/expression.hpp"

namespace cm::cli {

namespace {

// "face:3=0.5", "edge:12=0.1", "vertex:4=0.01", "region:2=1.5" or "2:3=0.5".
// Whether the tag exists is build_size_field's check, once the model is read.
std::pair<geom::EntityRef, double> parse_entity_size(const std::string& spec) {
  static const std::regex re(R"(^\s*(vertex|edge|face|region|0|1|2|3)\s*:\s*(\d+)\s*=\s*([^\s]+)\s*$)");
  std::smatch m;
  if (!std::regex_match(spec, m, re))
    throw InputError("--size", -1, -1,
                     fmt::format("'{}': expected DIM:TAG=H with DIM vertex, edge, face or region (or 0-3), "
                                 "e.g. face:3=0.5",
                                 spec));
  static const std::map<std::string, int> dims = {{"vertex", 0}, {"edge", 1}, {"face", 2}, {"region", 3},
                                                  {"0", 0},      {"1", 1},    {"2", 2},    {"3", 3}};
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
  int tag = 0;
  const std::string digits = m[2].str();
  const auto [end, ec] = std::from_chars(digits.data(), digits.data() + digits.size(), tag);
  if (ec != std::errc() || end != digits.data() + digits.size() || tag < 1)
    throw InputError("--size", -1, -1, fmt::format("'{}': the tag must be an integer >= 1", spec));
  return {{dims.at(m[1].str()), tag}, h};
}

std::shared_ptr<const size::SizeField> read_background(const SizeFlags& o, double hgrad,
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

}  // namespace

geom_occ::LoadOptions ModelFlags::load_options() const {
  geom_occ::LoadOptions lo;
  lo.heal = !no_heal;
  lo.heal_tolerance = heal_tolerance;
  return lo;
}

void add_model_flags(CLI::App* cmd, ModelFlags& f) {
  cmd->add_option("--heal-tolerance", f.heal_tolerance, "Healing/sewing tolerance (0: from the model)");
  cmd->add_flag("--no-heal", f.no_heal, "Do not run shape healing on import");
}

void add_size_flags(CLI::App* cmd, SizeFlags& f) {
  cmd->add_option("--hmax", f.hmax, "Largest size (default: bounding-box diagonal / 20)")->check(CLI::PositiveNumber);
  cmd->add_option("--hmin", f.hmin, "Smallest size (default: hmax / 100; a face tapering to a cusp may go to a tenth of it)")->check(CLI::PositiveNumber);
  cmd->add_option("--hgrad", f.hgrad, "Gradation: sizes grow at most by (hgrad-1) per unit length")
      ->capture_default_str()
      ->check(CLI::Range(1.0, 1e6));
  auto* eps = cmd->add_option("--curv-eps", f.curv_eps,
                              "Curvature: constant chord deviation eps (seed eq. 4.3), a length")
                  ->check(CLI::PositiveNumber);
  auto* alpha = cmd->add_option("--curv-alpha", f.curv_alpha,
                                "Curvature: deviation alpha times the edge length (eq. 4.5), in (0, 0.5]; "
                                "default 0.04")
                    ->check(CLI::Range(1e-12, 0.5));
  auto* off = cmd->add_flag("--no-curvature", f.no_curvature, "No curvature-based sizes");
  eps->excludes(alpha)->excludes(off);
  alpha->excludes(off);
  cmd->add_flag("--directional", f.directional,
                "Sizes along each principal direction on faces (anisotropic surface metric)");
  cmd->add_option("--size", f.entity_sizes,
                  "Size on a model entity: DIM:TAG=H with DIM vertex, edge, face or region, e.g. face:3=0.5; "
                  "a region gets H everywhere inside it and on its boundary (repeatable)");
  cmd->add_option("--size-expr", f.expressions,
                  "Size as a function of x, y, z, e.g. '0.1 + 0.05*sqrt(x^2+y^2)' (repeatable)");
  auto* bg = cmd->add_option("--background", f.background_mesh, "Background tet mesh for --background-sol");
  auto* bgs = cmd->add_option("--background-sol", f.background_sol,
                              "Sizes (scalar) or metrics (tensor) at the background mesh's vertices (.sol/.solb)");
  bg->needs(bgs);
  bgs->needs(bg);
}

size::SizeOptions make_size_options(const SizeFlags& f) {
  size::SizeOptions so;
  so.hmax = f.hmax;
  so.hmin = f.hmin;
  so.hgrad = f.hgrad;
  so.directional = f.directional;
  if (f.no_curvature)
    so.curvature = size::CurvatureRule::off();
  else if (f.curv_eps)
    so.curvature = size::CurvatureRule::chord_deviation(*f.curv_eps);
  else if (f.curv_alpha)
    so.curvature = size::CurvatureRule::relative_deviation(*f.curv_alpha);
  for (const auto& spec : f.entity_sizes) so.entity_sizes.push_back(parse_entity_size(spec));
  for (const auto& e : f.expressions) so.fields.push_back(size::make_expression_field(e));
  if (!f.background_mesh.empty()) {
    if (auto iso = read_background(f, f.hgrad, &so.metric)) so.fields.push_back(iso);
  }
  return so;
}

std::string describe(const size::CurvatureRule& rule) {
  switch (rule.kind) {
    case size::CurvatureRule::Kind::kOff: return "off";
    case size::CurvatureRule::Kind::kChordDeviation: return fmt::format("eps={}", rule.value);
    case size::CurvatureRule::Kind::kRelativeDeviation: return fmt::format("alpha={}", rule.value);
  }
  return "?";
}

}  // namespace cm::cli
