#pragma once
// Summary statistics and fixed-bin histograms of per-element measures, for the
// `check` report and the benchmarks. Plain structs so that front ends can
// serialize the fields directly (the quality library itself has no JSON).
#include <cstddef>
#include <span>
#include <string>
#include <vector>

namespace cm::quality {

/// Summary of a list of values. NaN values are counted in `nan_count` and
/// otherwise ignored; infinities take part (so min/max/mean may be infinite).
/// With no finite-or-infinite value, min/max/mean/percentiles are NaN.
struct Statistics {
  std::size_t count = 0;      ///< values taken into account (NaN excluded)
  std::size_t nan_count = 0;  ///< NaN values skipped
  double min = 0;
  double max = 0;
  double mean = 0;
  /// Percentiles by linear interpolation between closest ranks: the q-th
  /// percentile of the sorted values x[0..n-1] is x at position q/100 (n-1).
  double p1 = 0;
  double p5 = 0;
  double p50 = 0;
  double p95 = 0;
  double p99 = 0;
};

/// O(n log n): sorts a copy of the values.
Statistics compute_statistics(std::span<const double> values);

/// q-th percentile (0 <= q <= 100) of values that are already sorted
/// ascending, with the interpolation rule of Statistics. NaN if empty.
double sorted_percentile(std::span<const double> sorted, double q);

/// Counts of values in `counts.size()` = n equal bins over [lo, hi]. Bin i
/// holds [b_i, b_(i+1)) with b_i = lo + (hi - lo) i / n (so that decimal bounds
/// such as 0.3 come out as written); the last bin is closed
/// so that a value equal to hi (a perfect element of quality 1, a dihedral
/// angle of 180) is counted. Values outside go to `below` / `above`; NaN to
/// `nan_count`.
struct Histogram {
  double lo = 0;
  double hi = 1;
  std::vector<std::size_t> counts;
  std::size_t below = 0;
  std::size_t above = 0;
  std::size_t nan_count = 0;

  double bin_width() const { return (hi - lo) / static_cast<double>(counts.size()); }
  double bin_lower(std::size_t i) const {
    return lo + (hi - lo) * static_cast<double>(i) / static_cast<double>(counts.size());
  }
  double bin_upper(std::size_t i) const { return i + 1 == counts.size() ? hi : bin_lower(i + 1); }
  std::size_t total() const;  ///< all counted values, including below/above
};

/// Precondition: bins >= 1 and lo < hi (throws std::invalid_argument otherwise).
Histogram make_histogram(std::span<const double> values, double lo, double hi, int bins);

/// Fixed histograms used by the reports: 10 bins over [0,1] for qualities in
/// (0,1], 18 bins of 10 degrees over [0,180] for dihedral angles.
Histogram make_quality_histogram(std::span<const double> values);
Histogram make_angle_histogram(std::span<const double> degrees);

/// Text rendering, one line per bin:
///   "[0.90, 1.00]     1234 ############"
/// Bars are scaled so the largest count has `bar_width` characters; a non-zero
/// count always shows at least one character. `decimals` digits are printed
/// for the bin bounds. Lines for below/above/NaN appear only when non-zero.
std::string render_histogram(const Histogram& h, int bar_width = 40, int decimals = 2);

}  // namespace cm::quality
