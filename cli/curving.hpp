#pragma once
// Options and summary shared by the commands that curve a mesh (`mesh
// --order`, `curve`): the flags, their translation into curved::CurveOptions,
// and the printed and JSON report of a curving run.
#include <string>

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include "curvemesh/curved/curve.hpp"

namespace cm::cli {

struct CurvingFlags {
  int order = 1;  ///< 1: no curving
  double min_measure = curved::Acceptance{}.min_measure;
  double min_scaled_jacobian = curved::Acceptance{}.min_scaled_jacobian;
  bool no_repair = false;
  curved::CurveOptions options() const;
};

/// Registers --order (with `default_order` as its default: 1 for `mesh`,
/// 2 for `curve`), --min-jacobian-ratio, --min-scaled-jacobian, --no-repair.
void add_curving_flags(CLI::App* cmd, CurvingFlags& flags, int default_order);

nlohmann::json curve_report_json(const curved::CurveReport& r);
void print_curve_report(const curved::CurveReport& r);
/// Every element certified valid and acceptable.
bool curve_report_ok(const curved::CurveReport& r);

}  // namespace cm::cli
