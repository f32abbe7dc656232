#pragma once
// check_element is a pure function of a tet's nodes (and the order and the
// acceptance, fixed for a run). The repair judges the same tets over and
// over: the "before" of every candidate around a tet, the ring tets of the
// edge-removal dynamic program for each of a tet's edges, the same
// candidates again on the next pass. Results are remembered keyed by the
// nodes themselves, compared exactly, so a temporary node override, a
// scratch vertex reusing an id or a moved vertex can never hit a stale one.
// Candidates are ranked by their scores, not by where they fail, so an
// invalid one is not located further (check_element's locate_minimum).
#include <span>

#include "curvemesh/curved/element_check.hpp"

namespace cm::curved::detail {

class CheckMemo {
 public:
  CheckMemo(int order, const Acceptance& acceptance) : table_(order), acceptance_(acceptance) {}

  ElementCheck operator()(std::span<const Vec3> nodes) {
    if (const ElementCheck* known = table_.find(nodes)) {
      ++hits_;
      return *known;
    }
    ++misses_;
    const ElementCheck c = check_element(table_.order(), nodes, acceptance_, false, false);
    // A bounded memory: start afresh rather than track ages.
    if (table_.size() >= kMaxEntries) table_.clear();
    table_.add(nodes, c);
    return c;
  }
  std::size_t hits() const { return hits_; }
  std::size_t misses() const { return misses_; }

 private:
  static constexpr std::size_t kMaxEntries = 1 << 18;
  CheckCache table_;
  Acceptance acceptance_;
  std::size_t hits_ = 0, misses_ = 0;
};

}  // namespace cm::curved::detail
