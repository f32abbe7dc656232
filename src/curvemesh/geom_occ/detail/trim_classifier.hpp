#pragma once
// Internal to geom_occ, but free of OpenCASCADE: the trimming loops of a face
// as closed polygons in its (u, v) plane, bucketed in a uniform grid, for the
// fast path of OccModel::contains_param. OCC's trimmed-face classifier costs
// tens of microseconds per point and serializes its callers (it is not
// thread-safe); it was a sixth to a quarter of a whole meshing run on CAD
// parts. Crossing parity on the polygons answers in well under a microsecond
// for every point outside a band around them; inside the band (where the
// polygon and the true loops may disagree) the caller asks OCC.
//
// Immutable after construction, so queries are thread-safe.
#include <cstdint>
#include <optional>
#include <vector>

#include "curvemesh/core/types.hpp"

namespace cm::geom_occ::detail {

class TrimClassifier {
 public:
  /// `loops`: closed polygons (the last point joins the first), any
  /// orientation, together bounding the region by even-odd parity (outer
  /// loops and holes alike). `band` >= 0: points closer than this to a
  /// polygon edge are undecided. Loops with fewer than 2 points are ignored.
  /// O(S) for S segments (cells are about one segment each).
  TrimClassifier(const std::vector<std::vector<Vec2>>& loops, double band);

  bool empty() const { return segments_.empty(); }
  std::size_t segments() const { return segments_.size(); }
  double band() const { return band_; }

  /// Whether uv is inside the polygons; nullopt within the band of one of
  /// them. Outside the polygons' box (widened by the band): false.
  /// O(segments in the point's grid row right of it), about sqrt(S).
  std::optional<bool> inside(const Vec2& uv) const;

 private:
  struct Segment {
    Vec2 a, b;
  };
  int column(double u) const;
  int row(double v) const;

  std::vector<Segment> segments_;
  double band_ = 0;
  Vec2 lo_ = Vec2::Zero(), hi_ = Vec2::Zero();
  int nu_ = 1, nv_ = 1;
  double cell_u_ = 1, cell_v_ = 1;
  // Segments per cell (row-major), compressed: cell c holds
  // cell_segments_[cell_start_[c] .. cell_start_[c + 1]).
  std::vector<std::uint32_t> cell_start_;
  std::vector<std::uint32_t> cell_segments_;
};

}  // namespace cm::geom_occ::detail
