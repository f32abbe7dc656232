#include "curvemesh/quality/statistics.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace cm::quality {

double sorted_percentile(std::span<const double> sorted, double q) {
  if (sorted.empty()) return std::numeric_limits<double>::quiet_NaN();
  const double pos = std::clamp(q, 0.0, 100.0) / 100.0 * static_cast<double>(sorted.size() - 1);
  const auto below = static_cast<std::size_t>(std::floor(pos));
  const std::size_t above = std::min(below + 1, sorted.size() - 1);
  const double frac = pos - static_cast<double>(below);
  // Equal neighbours (including infinite ones) must not produce inf - inf.
  if (frac == 0 || sorted[below] == sorted[above]) return sorted[below];
  return sorted[below] + frac * (sorted[above] - sorted[below]);
}

Statistics compute_statistics(std::span<const double> values) {
  Statistics s;
  std::vector<double> sorted;
  sorted.reserve(values.size());
  for (double v : values) {
    if (std::isnan(v))
      ++s.nan_count;
    else
      sorted.push_back(v);
  }
  s.count = sorted.size();
  if (sorted.empty()) {
    const double nan = std::numeric_limits<double>::quiet_NaN();
    s.min = s.max = s.mean = s.p1 = s.p5 = s.p50 = s.p95 = s.p99 = nan;
    return s;
  }
  std::sort(sorted.begin(), sorted.end());
  s.min = sorted.front();
  s.max = sorted.back();
  // Summing in ascending order keeps the rounding error small for the
  // positive, similar-sized values typical of quality measures.
  double sum = 0;
  for (double v : sorted) sum += v;
  s.mean = sum / static_cast<double>(sorted.size());
  s.p1 = sorted_percentile(sorted, 1);
  s.p5 = sorted_percentile(sorted, 5);
  s.p50 = sorted_percentile(sorted, 50);
  s.p95 = sorted_percentile(sorted, 95);
  s.p99 = sorted_percentile(sorted, 99);
  return s;
}

std::size_t Histogram::total() const {
  std::size_t n = below + above;
  for (std::size_t c : counts) n += c;
  return n;
}

Histogram make_histogram(std::span<const double> values, double lo, double hi, int bins) {
  if (bins < 1 || !(lo < hi))
    throw std::invalid_argument(
        fmt::format("histogram needs bins >= 1 and lo < hi (got {}, [{}, {}])", bins, lo, hi));
  Histogram h;
  h.lo = lo;
  h.hi = hi;
  h.counts.assign(static_cast<std::size_t>(bins), 0);
  for (double v : values) {
    if (std::isnan(v)) {
      ++h.nan_count;
    } else if (v < lo) {
      ++h.below;
    } else if (v > hi) {
      ++h.above;
    } else {
      const double n = static_cast<double>(h.counts.size());
      auto i = static_cast<std::size_t>(std::min(std::floor((v - lo) / (hi - lo) * n), n - 1));
      // The guess may be one bin off next to a bound; the bounds reported by
      // bin_lower/bin_upper are authoritative.
      while (i > 0 && v < h.bin_lower(i)) --i;
      while (i + 1 < h.counts.size() && v >= h.bin_upper(i)) ++i;
      ++h.counts[i];
    }
  }
  return h;
}

Histogram make_quality_histogram(std::span<const double> values) {
  return make_histogram(values, 0.0, 1.0, 10);
}

Histogram make_angle_histogram(std::span<const double> degrees) {
  return make_histogram(degrees, 0.0, 180.0, 18);
}

std::string render_histogram(const Histogram& h, int bar_width, int decimals) {
  std::size_t largest = std::max(h.below, h.above);
  for (std::size_t c : h.counts) largest = std::max(largest, c);
  std::size_t count_width = fmt::formatted_size("{}", largest);
  const auto bar = [&](std::size_t c) {
    if (c == 0 || largest == 0) return std::string();
    const auto len = static_cast<std::size_t>(
        std::llround(static_cast<double>(c) * bar_width / static_cast<double>(largest)));
    return std::string(std::max<std::size_t>(len, 1), '#');
  };
  std::vector<std::string> labels;
  for (std::size_t i = 0; i < h.counts.size(); ++i) {
    const char close = i + 1 == h.counts.size() ? ']' : ')';
    labels.push_back(fmt::format("[{:.{}f}, {:.{}f}{}", h.bin_lower(i), decimals, h.bin_upper(i),
                                 decimals, close));
  }
  const std::string below_label = fmt::format("< {:.{}f}", h.lo, decimals);
  const std::string above_label = fmt::format("> {:.{}f}", h.hi, decimals);
  std::size_t label_width = std::max(below_label.size(), above_label.size());
  for (const auto& l : labels) label_width = std::max(label_width, l.size());
  count_width = std::max(count_width, fmt::formatted_size("{}", h.nan_count));

  std::string out;
  const auto line = [&](const std::string& label, std::size_t c) {
    const std::string b = bar(c);
    fmt::format_to(std::back_inserter(out), "{:<{}} {:>{}}{}{}\n", label, label_width, c,
                   count_width, b.empty() ? "" : " ", b);
  };
  if (h.below > 0) line(below_label, h.below);
  for (std::size_t i = 0; i < h.counts.size(); ++i) line(labels[i], h.counts[i]);
  if (h.above > 0) line(above_label, h.above);
  if (h.nan_count > 0)
    fmt::format_to(std::back_inserter(out), "{:<{}} {:>{}}\n", "NaN", label_width, h.nan_count,
                   count_width);
  return out;
}

}  // namespace cm::quality
