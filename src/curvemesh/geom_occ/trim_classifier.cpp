// TrimClassifier: segments bucketed by the cells their band-widened boxes
// overlap; a query checks its own cell for a segment within the band, then
// counts crossings of the ray toward +u along its grid row.
#include "curvemesh/geom_occ/detail/trim_classifier.hpp"

#include <algorithm>
#include <cmath>

namespace cm::geom_occ::detail {

namespace {

constexpr int kMaxCells = 512;  // per direction

double segment_distance(const Vec2& p, const Vec2& a, const Vec2& b) {
  const Vec2 ab = b - a;
  const double len2 = ab.squaredNorm();
  const double t = len2 > 0 ? std::clamp((p - a).dot(ab) / len2, 0.0, 1.0) : 0.0;
  return (p - (a + t * ab)).norm();
}

}  // namespace

TrimClassifier::TrimClassifier(const std::vector<std::vector<Vec2>>& loops, double band) : band_(std::max(band, 0.0)) {
  for (const auto& loop : loops) {
    if (loop.size() < 2) continue;
    for (std::size_t k = 0; k < loop.size(); ++k) segments_.push_back({loop[k], loop[(k + 1) % loop.size()]});
  }
  if (segments_.empty()) return;
  lo_ = hi_ = segments_.front().a;
  for (const Segment& s : segments_) {
    lo_ = lo_.cwiseMin(s.a).cwiseMin(s.b);
    hi_ = hi_.cwiseMax(s.a).cwiseMax(s.b);
  }
  lo_ -= Vec2(band_, band_);
  hi_ += Vec2(band_, band_);
  // About one segment per cell, cells shaped like the box.
  const double w = hi_.x() - lo_.x(), h = hi_.y() - lo_.y();
  const double n = static_cast<double>(segments_.size());
  const double aspect = h > 0 ? w / h : 1.0;
  nu_ = static_cast<int>(std::clamp(std::round(std::sqrt(n * aspect)), 1.0, double(kMaxCells)));
  nv_ = static_cast<int>(std::clamp(std::round(n / nu_), 1.0, double(kMaxCells)));
  cell_u_ = w > 0 ? w / nu_ : 1.0;
  cell_v_ = h > 0 ? h / nv_ : 1.0;

  // Two passes (count, then fill) into compressed rows.
  std::vector<std::uint32_t> count(static_cast<std::size_t>(nu_) * nv_ + 1, 0);
  auto for_cells = [&](const Segment& s, auto&& fn) {
    const Vec2 a = s.a.cwiseMin(s.b) - Vec2(band_, band_), b = s.a.cwiseMax(s.b) + Vec2(band_, band_);
    const int i0 = column(a.x()), i1 = column(b.x()), j0 = row(a.y()), j1 = row(b.y());
    for (int j = j0; j <= j1; ++j)
      for (int i = i0; i <= i1; ++i) fn(static_cast<std::size_t>(j) * nu_ + i);
  };
  for (const Segment& s : segments_) for_cells(s, [&](std::size_t c) { ++count[c + 1]; });
  for (std::size_t c = 1; c < count.size(); ++c) count[c] += count[c - 1];
  cell_start_ = count;
  cell_segments_.resize(count.back());
  for (std::uint32_t k = 0; k < segments_.size(); ++k)
    for_cells(segments_[k], [&](std::size_t c) { cell_segments_[count[c]++] = k; });
}

int TrimClassifier::column(double u) const {
  return std::clamp(static_cast<int>(std::floor((u - lo_.x()) / cell_u_)), 0, nu_ - 1);
}

int TrimClassifier::row(double v) const {
  return std::clamp(static_cast<int>(std::floor((v - lo_.y()) / cell_v_)), 0, nv_ - 1);
}

std::optional<bool> TrimClassifier::inside(const Vec2& p) const {
  if (segments_.empty()) return std::nullopt;
  if (!(p.x() >= lo_.x() && p.x() <= hi_.x() && p.y() >= lo_.y() && p.y() <= hi_.y())) return false;
  const int i0 = column(p.x()), j = row(p.y());
  const std::size_t row_start = static_cast<std::size_t>(j) * nu_;
  // Every segment within the band of p has its widened box over p's cell.
  for (std::uint32_t k = cell_start_[row_start + i0]; k < cell_start_[row_start + i0 + 1]; ++k) {
    const Segment& s = segments_[cell_segments_[k]];
    if (segment_distance(p, s.a, s.b) <= band_) return std::nullopt;
  }
  // A crossing of the ray is counted in the cell that holds its u only, so a
  // segment listed in several cells of the row counts once. Half-open in v,
  // so a polygon vertex on the ray's line counts once for its two segments.
  bool in = false;
  for (int i = i0; i < nu_; ++i) {
    for (std::uint32_t k = cell_start_[row_start + i]; k < cell_start_[row_start + i + 1]; ++k) {
      const Segment& s = segments_[cell_segments_[k]];
      if ((s.a.y() > p.y()) == (s.b.y() > p.y())) continue;
      const double uc = s.a.x() + (p.y() - s.a.y()) * (s.b.x() - s.a.x()) / (s.b.y() - s.a.y());
      if (uc > p.x() && column(uc) == i) in = !in;
    }
  }
  return in;
}

}  // namespace cm::geom_occ::detail
