#include "improve_report.hpp"

#include <fmt/format.h>

namespace cm::cli {

std::string improve_operator_counts(const optimize::ImproveStats& s, bool with_times) {
  std::string out = fmt::format(
      "{} edge removals, {} face swaps, {} relocations ({} on the boundary, {} searched), {} insertions, {} "
      "deletions, {} collapses in {} passes",
      s.edge_removals, s.face_swaps, s.relocations, s.boundary_relocations, s.searched_relocations, s.insertions,
      s.deletions, s.collapses, s.passes);
  if (with_times)
    out += fmt::format(" (swaps {:.2f} s, relocation {:.2f} s, insertion {:.2f} s, deletion {:.2f} s, collapse {:.2f} s)",
                       s.swap_seconds, s.relocation_seconds, s.insertion_seconds, s.deletion_seconds,
                       s.collapse_seconds);
  return out;
}

}  // namespace cm::cli
