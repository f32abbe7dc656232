#pragma once
// The operator counts of an isotropic optimization run, one wording for
// every command that optimizes (`mesh`, `optimize`).
#include <string>

#include "curvemesh/optimize/improve.hpp"

namespace cm::cli {

/// "N edge removals, ..., N collapses in N passes", with the operators'
/// times appended when `with_times`.
std::string improve_operator_counts(const optimize::ImproveStats& s, bool with_times);

}  // namespace cm::cli
