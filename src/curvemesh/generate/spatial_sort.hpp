#pragma once
// Insertion order for incremental Delaunay: BRIO (biased randomized insertion
// order, Amenta–Choi–Rote) with each round sorted along a Hilbert curve. The
// randomized rounds keep the expected cost of Bowyer–Watson optimal; the
// Hilbert order inside a round makes consecutive points close, so the walk
// from the last inserted tet to the next point is short.
#include <cstdint>
#include <span>
#include <vector>

#include "curvemesh/core/types.hpp"

namespace cm::generate {

/// 3D Hilbert index of a point with integer coordinates in [0, 2^bits),
/// bits <= 21.
std::uint64_t hilbert_key(std::uint32_t x, std::uint32_t y, std::uint32_t z, int bits);

/// Indices 0..points.size()-1 in BRIO + Hilbert order; deterministic for a
/// given seed.
std::vector<std::uint32_t> brio_order(std::span<const Vec3> points, std::uint64_t seed = 0x5EED);

}  // namespace cm::generate
