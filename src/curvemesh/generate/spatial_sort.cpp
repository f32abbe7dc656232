#include "curvemesh/generate/spatial_sort.hpp"

#include <algorithm>
#include <cmath>
#include <random>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

namespace cm::generate {

namespace {

// Spreads the low 21 bits of x so that bit b lands on bit 3b.
std::uint64_t spread3(std::uint64_t x) {
  x &= 0x1FFFFFu;
  x = (x | x << 32) & 0x001F00000000FFFFull;
  x = (x | x << 16) & 0x001F0000FF0000FFull;
  x = (x | x << 8) & 0x100F00F00F00F00Full;
  x = (x | x << 4) & 0x10C30C30C30C30C3ull;
  x = (x | x << 2) & 0x1249249249249249ull;
  return x;
}

}  // namespace

std::uint64_t hilbert_key(std::uint32_t x, std::uint32_t y, std::uint32_t z, int bits) {
  // Skilling, "Programming the Hilbert curve" (2004): axes -> transposed
  // index. Written without data-dependent branches (they mispredict half the
  // time on random points): `set` is all ones when bit Q of X[i] is.
  std::uint32_t X[3] = {x, y, z};
  for (int q = bits - 1; q > 0; --q) {
    const std::uint32_t P = (1u << q) - 1;
    for (int i = 0; i < 3; ++i) {
      const std::uint32_t set = 0u - ((X[i] >> q) & 1u);
      // Bit set: invert the low bits of X[0]; clear: exchange them with X[i]'s.
      const std::uint32_t t = (X[0] ^ X[i]) & P & ~set;
      X[0] ^= t ^ (P & set);
      X[i] ^= t;
    }
  }
  for (int i = 1; i < 3; ++i) X[i] ^= X[i - 1];
  std::uint32_t t = 0;
  for (int q = bits - 1; q > 0; --q) t ^= ((1u << q) - 1) & (0u - ((X[2] >> q) & 1u));
  for (auto& c : X) c ^= t;
  // Interleave, most significant bit first: X[0]'s bit b goes to 3b + 2.
  return spread3(X[0]) << 2 | spread3(X[1]) << 1 | spread3(X[2]);
}

std::vector<std::uint32_t> brio_order(std::span<const Vec3> points, std::uint64_t seed) {
  const std::size_t n = points.size();
  std::vector<std::uint32_t> order(n);
  for (std::size_t i = 0; i < n; ++i) order[i] = static_cast<std::uint32_t>(i);
  if (n < 2) return order;
  Vec3 lo = points[0], hi = points[0];
  for (const Vec3& p : points) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  constexpr int kBits = 20;
  const double ext = std::max((hi - lo).maxCoeff(), 1e-300);
  const double scale = ((1u << kBits) - 1) / ext;
  // Keys travel with their index, so sorting reads contiguous memory.
  struct Keyed {
    std::uint64_t key;
    std::uint32_t index;
  };
  std::vector<Keyed> items(n);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 4096), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t i = r.begin(); i != r.end(); ++i) {
      const Vec3 q = (points[i] - lo) * scale;
      items[i] = {hilbert_key(static_cast<std::uint32_t>(q.x()), static_cast<std::uint32_t>(q.y()),
                              static_cast<std::uint32_t>(q.z()), kBits),
                  static_cast<std::uint32_t>(i)};
    }
  });
  std::mt19937_64 rng(seed);
  std::shuffle(items.begin(), items.end(), rng);
  // Rounds of growing size: ..., n/8, n/4, n/2 (the first one at least 1000).
  std::vector<std::size_t> ends;
  for (std::size_t end = n; end > 0;) {
    ends.push_back(end);
    if (end <= 1000) break;
    end /= 2;
  }
  std::size_t begin = 0;
  for (auto it = ends.rbegin(); it != ends.rend(); ++it) {
    // A total order (indices are distinct): any sort gives the same result.
    tbb::parallel_sort(items.begin() + static_cast<std::ptrdiff_t>(begin),
                       items.begin() + static_cast<std::ptrdiff_t>(*it),
                       [](const Keyed& a, const Keyed& b) { return a.key < b.key || (a.key == b.key && a.index < b.index); });
    begin = *it;
  }
  for (std::size_t i = 0; i < n; ++i) order[i] = items[i].index;
  return order;
}

}  // namespace cm::generate
