#include "curvemesh/generate/spatial_sort.hpp"

#include <algorithm>
#include <cmath>
#include <random>

namespace cm::generate {

std::uint64_t hilbert_key(std::uint32_t x, std::uint32_t y, std::uint32_t z, int bits) {
  // Skilling, "Programming the Hilbert curve" (2004): axes -> transposed index.
  std::uint32_t X[3] = {x, y, z};
  const std::uint32_t M = 1u << (bits - 1);
  for (std::uint32_t Q = M; Q > 1; Q >>= 1) {
    const std::uint32_t P = Q - 1;
    for (int i = 0; i < 3; ++i) {
      if (X[i] & Q) {
        X[0] ^= P;
      } else {
        const std::uint32_t t = (X[0] ^ X[i]) & P;
        X[0] ^= t;
        X[i] ^= t;
      }
    }
  }
  for (int i = 1; i < 3; ++i) X[i] ^= X[i - 1];
  std::uint32_t t = 0;
  for (std::uint32_t Q = M; Q > 1; Q >>= 1)
    if (X[2] & Q) t ^= Q - 1;
  for (auto& c : X) c ^= t;
  std::uint64_t key = 0;
  for (int b = bits - 1; b >= 0; --b)
    for (int i = 0; i < 3; ++i) key = (key << 1) | ((X[i] >> b) & 1u);
  return key;
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
  std::vector<std::uint64_t> keys(n);
  for (std::size_t i = 0; i < n; ++i) {
    const Vec3 q = (points[i] - lo) * scale;
    keys[i] = hilbert_key(static_cast<std::uint32_t>(q.x()), static_cast<std::uint32_t>(q.y()),
                          static_cast<std::uint32_t>(q.z()), kBits);
  }
  std::mt19937_64 rng(seed);
  std::shuffle(order.begin(), order.end(), rng);
  // Rounds of growing size: ..., n/8, n/4, n/2 (the first one at least 1000).
  std::vector<std::size_t> ends;
  for (std::size_t end = n; end > 0;) {
    ends.push_back(end);
    if (end <= 1000) break;
    end /= 2;
  }
  std::size_t begin = 0;
  for (auto it = ends.rbegin(); it != ends.rend(); ++it) {
    std::sort(order.begin() + static_cast<std::ptrdiff_t>(begin), order.begin() + static_cast<std::ptrdiff_t>(*it),
              [&](std::uint32_t a, std::uint32_t b) { return keys[a] < keys[b] || (keys[a] == keys[b] && a < b); });
    begin = *it;
  }
  return order;
}

}  // namespace cm::generate
