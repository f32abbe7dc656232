// `curvemesh check`: validity of a mesh (DESIGN.md "valid mesh", as far as it
// can be checked without the model) and its quality.
#include <algorithm>
#include <fstream>
#include <limits>
#include <map>

#include <fmt/format.h>
#include <nlohmann/json.hpp>
#include <tbb/parallel_for.h>

#include "commands.hpp"
#include "curvemesh/core/progress.hpp"
#include "curvemesh/core/timer.hpp"
#include "curvemesh/io/mesh_io.hpp"
#include "curvemesh/mesh/validate.hpp"
#include "curvemesh/quality/bezier_jacobian.hpp"
#include "curvemesh/quality/measures.hpp"
#include "curvemesh/quality/shape_measure.hpp"
#include "curvemesh/quality/statistics.hpp"
#include "exit_codes.hpp"
#include "json_output.hpp"

namespace cm::cli {

namespace {

struct CheckOptions {
  std::string input;
  std::string json_path;
  std::size_t max_listed = 20;
  bool quiet = false;
};

// Per-element results of the curved-element certification.
struct CurvedReport {
  std::vector<TetId> invalid;
  std::vector<TetId> undetermined;
  std::vector<double> scaled_jacobian;  // certified lower bound per tet
  std::vector<double> measure_i;        // seed eq. (3.5) per tet
};

CurvedReport certify_curved(const mesh::TetMesh& m) {
  CurvedReport r;
  const std::size_t nt = m.num_tets();
  std::vector<quality::Validity> verdict(nt);
  r.scaled_jacobian.resize(nt);
  r.measure_i.resize(nt);
  // Chunks keep the progress bar moving without touching it from worker threads.
  Progress progress("certifying curved elements", static_cast<std::int64_t>(nt));
  constexpr std::size_t kChunk = 1 << 15;
  for (std::size_t begin = 0; begin < nt; begin += kChunk) {
    const std::size_t end = std::min(nt, begin + kChunk);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(begin, end), [&](const tbb::blocked_range<std::size_t>& range) {
      for (std::size_t t = range.begin(); t != range.end(); ++t) {
        const auto v = quality::certify_tet(m, static_cast<TetId>(t));
        verdict[t] = v.verdict;
        r.scaled_jacobian[t] = v.scaled_jacobian_lower;
        r.measure_i[t] = quality::shape_measure(m, static_cast<TetId>(t)).measure;
      }
    });
    progress.update(static_cast<std::int64_t>(end));
  }
  progress.finish();
  for (std::size_t t = 0; t < nt; ++t) {
    if (verdict[t] == quality::Validity::kInvalid) r.invalid.push_back(static_cast<TetId>(t));
    if (verdict[t] == quality::Validity::kUndetermined) r.undetermined.push_back(static_cast<TetId>(t));
  }
  return r;
}

nlohmann::json stats_json(const quality::Statistics& s) {
  return {{"count", s.count}, {"min", s.min}, {"max", s.max}, {"mean", s.mean},
          {"p1", s.p1},       {"p5", s.p5},   {"p50", s.p50}, {"p95", s.p95}, {"p99", s.p99}};
}

nlohmann::json histogram_json(const quality::Histogram& h) {
  return {{"lo", h.lo}, {"hi", h.hi}, {"counts", h.counts}, {"below", h.below}, {"above", h.above}};
}

std::string id_list(const std::vector<TetId>& ids, std::size_t max_listed) {
  std::string s;
  for (std::size_t i = 0; i < std::min(ids.size(), max_listed); ++i) s += fmt::format("{}{}", i ? " " : "", ids[i]);
  if (ids.size() > max_listed) s += fmt::format(" ... (+{})", ids.size() - max_listed);
  return s;
}

int run_check(const CheckOptions& o) {
  Timer timer;
  mesh::TetMesh m = io::read_mesh(o.input);
  const double read_s = timer.seconds();
  timer.reset();
  const auto report = mesh::validate(m, mesh::Level::kFull);
  const double validate_s = timer.seconds();

  // Straight-sided shape measures of every tet.
  timer.reset();
  const std::size_t nt = m.num_tets();
  std::vector<double> mean_ratio(nt), min_dihedral(nt), max_dihedral(nt), radius_ratio(nt);
  std::vector<double> edge_length;
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nt), [&](const tbb::blocked_range<std::size_t>& range) {
    for (std::size_t t = range.begin(); t != range.end(); ++t) {
      const auto q = quality::evaluate_tet(m, static_cast<TetId>(t));
      mean_ratio[t] = q.mean_ratio;
      min_dihedral[t] = q.min_dihedral;
      max_dihedral[t] = q.max_dihedral;
      radius_ratio[t] = q.radius_ratio;
    }
  });
  {
    std::vector<std::pair<VertId, VertId>> edges;
    edges.reserve(6 * nt);
    for (const auto& tv : m.tet2verts)
      for (const auto& e : mesh::kTetEdges) edges.push_back(std::minmax(tv[e[0]], tv[e[1]]));
    std::sort(edges.begin(), edges.end());
    edges.erase(std::unique(edges.begin(), edges.end()), edges.end());
    edge_length.reserve(edges.size());
    for (const auto& [a, b] : edges) edge_length.push_back((m.coords[a] - m.coords[b]).norm());
  }
  const auto mr_stats = quality::compute_statistics(mean_ratio);
  const auto mr_hist = quality::make_quality_histogram(mean_ratio);
  const auto dmin_stats = quality::compute_statistics(min_dihedral);
  const auto dmax_stats = quality::compute_statistics(max_dihedral);
  const auto dihedral_hist = quality::make_angle_histogram(min_dihedral);
  const auto rr_stats = quality::compute_statistics(radius_ratio);
  const auto len_stats = quality::compute_statistics(edge_length);

  const int order = m.high_order.order();
  CurvedReport curved;
  if (order > 1) curved = certify_curved(m);
  const double quality_s = timer.seconds();

  const bool valid = report.valid() && curved.invalid.empty() && curved.undetermined.empty();
  std::map<int, int> entity_count;
  for (const auto& e : m.entities) ++entity_count[e.dim];

  if (!o.quiet) {
    fmt::print("mesh: {}\n", o.input);
    fmt::print("  {} vertices, {} tets (order {}), {} boundary triangles, {} classified edges\n", m.num_verts(), nt,
               order, m.tris.size(), m.edges.size());
    fmt::print("  model entities: {} regions, {} faces, {} edges, {} vertices\n", entity_count[3], entity_count[2],
               entity_count[1], entity_count[0]);
    fmt::print("validity: {}\n", valid ? "VALID" : "INVALID");
    fmt::print("  inverted tets: {}\n", report.num_inverted);
    fmt::print("  flat tets: {}\n", report.num_flat);
    fmt::print("  non-conforming: {}\n", report.num_nonconforming);
    fmt::print("  classification errors: {}\n", report.num_classification);
    std::size_t shown = 0;
    for (const auto& issue : report.issues) {
      if (shown++ == o.max_listed) {
        fmt::print("    ... {} more\n", report.num_issues - o.max_listed);
        break;
      }
      fmt::print("    {}\n", issue.message);
    }
    if (order > 1) {
      const auto sj = quality::compute_statistics(curved.scaled_jacobian);
      const auto mi = quality::compute_statistics(curved.measure_i);
      fmt::print("  curved elements (certified Bezier bounds of det J):\n");
      fmt::print("    invalid (det J <= 0 somewhere): {}{}\n", curved.invalid.size(),
                 curved.invalid.empty() ? "" : fmt::format("  tets: {}", id_list(curved.invalid, o.max_listed)));
      if (!curved.undetermined.empty())
        fmt::print("    undetermined: {}  tets: {}\n", curved.undetermined.size(), id_list(curved.undetermined, o.max_listed));
      fmt::print("    min scaled Jacobian (certified lower bound): {:.4g}   mean {:.4g}\n", sj.min, sj.mean);
      fmt::print("    measure I of eq. (3.5): min {:.4g}   mean {:.4g}\n", mi.min, mi.mean);
    }
    fmt::print("quality (straight-sided):\n");
    fmt::print("  mean ratio: min {:.4f}  p1 {:.4f}  p5 {:.4f}  median {:.4f}  mean {:.4f}\n", mr_stats.min, mr_stats.p1,
               mr_stats.p5, mr_stats.p50, mr_stats.mean);
    fmt::print("  dihedral angle: min {:.2f} deg  max {:.2f} deg\n", dmin_stats.min, dmax_stats.max);
    fmt::print("  radius ratio Q (1 = regular): max {:.4g}  mean {:.4g}\n", rr_stats.max, rr_stats.mean);
    fmt::print("  edge length: min {:.4g}  mean {:.4g}  max {:.4g}\n", len_stats.min, len_stats.mean, len_stats.max);
    fmt::print("  mean ratio histogram:\n{}", quality::render_histogram(mr_hist));
    fmt::print("time: read {:.2f} s, validate {:.2f} s, quality {:.2f} s\n", read_s, validate_s, quality_s);
  }

  if (!o.json_path.empty()) {
    nlohmann::json j;
    j["file"] = o.input;
    j["valid"] = valid;
    j["counts"] = {{"vertices", m.num_verts()}, {"tets", nt},         {"order", order},
                   {"triangles", m.tris.size()}, {"edges", m.edges.size()}};
    j["model_entities"] = {{"regions", entity_count[3]}, {"faces", entity_count[2]}, {"edges", entity_count[1]},
                           {"vertices", entity_count[0]}};
    nlohmann::json issues = nlohmann::json::array();
    for (const auto& issue : report.issues)
      issues.push_back({{"kind", mesh::to_string(issue.kind)}, {"entity", issue.entity}, {"message", issue.message}});
    j["validity"] = {{"inverted", report.num_inverted},
                     {"flat", report.num_flat},
                     {"nonconforming", report.num_nonconforming},
                     {"classification", report.num_classification},
                     {"issues", issues}};
    std::vector<TetId> inverted;
    for (const auto& issue : report.issues)
      if (issue.kind == mesh::ValidationIssue::Kind::kInverted) inverted.push_back(static_cast<TetId>(issue.entity));
    j["validity"]["inverted_tets"] = inverted;
    if (order > 1) {
      j["curved"] = {{"invalid", curved.invalid.size()},
                     {"invalid_tets", curved.invalid},
                     {"undetermined_tets", curved.undetermined},
                     {"scaled_jacobian", stats_json(quality::compute_statistics(curved.scaled_jacobian))},
                     {"measure_i", stats_json(quality::compute_statistics(curved.measure_i))}};
    }
    j["quality"] = {{"mean_ratio", stats_json(mr_stats)},
                    {"mean_ratio_histogram", histogram_json(mr_hist)},
                    {"min_dihedral_deg", stats_json(dmin_stats)},
                    {"max_dihedral_deg", stats_json(dmax_stats)},
                    {"min_dihedral_histogram", histogram_json(dihedral_hist)},
                    {"radius_ratio", stats_json(rr_stats)},
                    {"edge_length", stats_json(len_stats)}};
    j["seconds"] = {{"read", read_s}, {"validate", validate_s}, {"quality", quality_s}};
    write_json(j, o.json_path);
  }
  return valid ? kExitOk : kExitInvalidMesh;
}

}  // namespace

void add_check_command(CLI::App& app, Runner& runner) {
  auto opts = std::make_shared<CheckOptions>();
  CLI::App* cmd = app.add_subcommand("check", "Check a mesh's validity and report its quality");
  cmd->add_option("mesh", opts->input, "Mesh file (.msh 2.2/4.1, .mesh, .meshb)")->required();
  cmd->add_option("--json", opts->json_path, "Also write the full report as JSON to this file");
  cmd->add_option("--max-listed", opts->max_listed, "How many offending entities to list")->capture_default_str();
  cmd->add_flag("-q,--quiet", opts->quiet, "Print nothing; the exit code tells");
  cmd->footer(
      "Exit codes: 0 valid, 1 invalid mesh, 2 bad usage or unreadable input, 3 internal error.\n"
      "Checks: exact positive orientation, conformity (an interior face has two tets, a boundary face one),\n"
      "classification consistency, and for order >= 2 certified Bezier bounds of det J per element.\n"
      "Examples:\n  curvemesh check part.msh\n  curvemesh check part_p2.msh --json report.json");
  cmd->callback([&runner, opts] { runner = [opts] { return run_check(*opts); }; });
}

}  // namespace cm::cli
