#include "curving.hpp"

#include <fmt/format.h>

namespace cm::cli {

curved::CurveOptions CurvingFlags::options() const {
  curved::CurveOptions o;
  o.order = order;
  o.repair.acceptance.min_measure = min_measure;
  o.repair.acceptance.min_scaled_jacobian = min_scaled_jacobian;
  o.repair_enabled = !no_repair;
  return o;
}

void add_curving_flags(CLI::App* cmd, CurvingFlags& flags, int default_order) {
  flags.order = default_order;
  cmd->add_option("--order", flags.order,
                  default_order == 1 ? "Element order: 1 (straight), 2 or 3 (curved on the model, certified valid)"
                                     : "Element order: 2 or 3")
      ->check(default_order == 1 ? CLI::IsMember({1, 2, 3}) : CLI::IsMember({2, 3}))
      ->capture_default_str();
  cmd->add_option("--min-jacobian-ratio", flags.min_measure,
                  "Curved elements: least acceptable measure I of the seed's eq. (3.5) (least det J at the "
                  "integration points over its mean)")
      ->check(CLI::Range(0.0, 1.0))
      ->capture_default_str();
  cmd->add_option("--min-scaled-jacobian", flags.min_scaled_jacobian,
                  "Curved elements: least acceptable certified min det J / max det J")
      ->check(CLI::Range(0.0, 1.0))
      ->capture_default_str();
  cmd->add_flag("--no-repair", flags.no_repair,
                "Curved elements: place the nodes and report, without repairing (the output may be invalid)");
}

nlohmann::json curve_report_json(const curved::CurveReport& r) {
  const curved::RepairStats& s = r.repair;
  // Vertex ids are those of the mesh before the repair (it may renumber).
  nlohmann::json listed = nlohmann::json::array();
  for (const curved::ProblemEntities& p : s.problems)
    listed.push_back({{"tet_vertices", p.tet},
                      {"score", p.score},
                      {"least_det_j_at", p.at},
                      {"curved_edges", p.curved_edges},
                      {"case", p.too_far ? "too far from straight" : "too close"}});
  return {{"order", r.order},
          {"nodes", {{"edges_on_model_edges", r.placement.edges_on_model_edges},
                     {"edges_on_model_faces", r.placement.edges_on_model_faces},
                     {"triangles", r.placement.faces}}},
          {"before", {{"invalid", r.invalid_before},
                      {"unacceptable", r.unacceptable_before},
                      {"min_scaled_jacobian", r.min_scaled_jacobian_before},
                      {"min_measure", r.min_measure_before}}},
          {"after", {{"invalid", r.after.invalid.size()},
                     {"undetermined", r.after.undetermined},
                     {"unacceptable", r.after.unacceptable.size()},
                     {"min_scaled_jacobian", r.after.min_scaled_jacobian},
                     {"mean_scaled_jacobian", r.after.mean_scaled_jacobian},
                     {"min_measure", r.after.min_measure}}},
          {"problems", {{"too_far_from_straight", s.too_far}, {"too_close", s.too_close}, {"listed", listed}}},
          {"operations", {{"edge_removals", s.edge_removals},
                          {"face_swaps", s.face_swaps},
                          {"boundary_swaps", s.boundary_swaps},
                          {"deletions", s.deletions},
                          {"splits", s.splits},
                          {"collapses", s.collapses},
                          {"relocations", s.relocations},
                          {"interior_edges_curved", s.interior_edges_curved},
                          {"boundary_edges_straightened", s.edges_straightened},
                          {"boundary_triangles_straightened", s.faces_straightened},
                          {"passes", s.passes}}},
          {"geometric_error", {{"straight_max", r.error_straight.max},
                               {"straight_mean", r.error_straight.mean},
                               {"curved_max", r.error_curved.max},
                               {"curved_mean", r.error_curved.mean},
                               {"samples", r.error_curved.samples}}},
          {"seconds", {{"nodes", r.place_seconds},
                       {"check", r.check_seconds},
                       {"repair", s.seconds},
                       {"geometric_error", r.error_seconds}}}};
}

void print_curve_report(const curved::CurveReport& r) {
  const curved::RepairStats& s = r.repair;
  fmt::print("curving: order {}; nodes on {} model-edge and {} model-face edges{}\n", r.order,
             r.placement.edges_on_model_edges, r.placement.edges_on_model_faces,
             r.order == 3 ? fmt::format(" and {} triangles", r.placement.faces) : "");
  fmt::print("  before repair: {} certified invalid, {} unacceptable; min scaled Jacobian {:.4f}, min I {:.4f}\n",
             r.invalid_before, r.unacceptable_before, r.min_scaled_jacobian_before, r.min_measure_before);
  if (r.unacceptable_before > 0)
    fmt::print("  problems: {} curved entities too far from the straight element, {} too close to another; "
               "repair: {} edge removals, {} face swaps, {} boundary swaps, {} deletions, {} splits, {} collapses, {} "
               "relocations, {} interior edges curved, {} boundary edges straightened, in {} passes\n",
               s.too_far, s.too_close, s.edge_removals, s.face_swaps, s.boundary_swaps, s.deletions, s.splits,
               s.collapses, s.relocations, s.interior_edges_curved, s.edges_straightened, s.passes);
  fmt::print("  after: {} certified invalid, {} unacceptable; scaled Jacobian min {:.4f} mean {:.4f}; I min {:.4f}\n",
             r.after.invalid.size(), r.after.unacceptable.size(), r.after.min_scaled_jacobian,
             r.after.mean_scaled_jacobian, r.after.min_measure);
  fmt::print("  geometric error (boundary to model, {} samples): straight max {:.4g} mean {:.4g}, curved max {:.4g} "
             "mean {:.4g}\n",
             r.error_curved.samples, r.error_straight.max, r.error_straight.mean, r.error_curved.max,
             r.error_curved.mean);
  fmt::print("  time: nodes {:.2f} s, checks {:.2f} s, repair {:.2f} s, geometric error {:.2f} s\n", r.place_seconds,
             r.check_seconds, s.seconds, r.error_seconds);
}

bool curve_report_ok(const curved::CurveReport& r) {
  return r.after.invalid.empty() && r.after.unacceptable.empty();
}

}  // namespace cm::cli
