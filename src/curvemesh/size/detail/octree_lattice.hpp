#pragma once
// Lattice helpers shared by the files of the size octree (octree.cpp: the
// tree, its refinement and queries; octree_grading.cpp: corner sizes,
// gradation and conformity). Internal to the size module.
#include <array>
#include <cstdint>
#include <limits>
#include <vector>

namespace cm::size::detail {

inline constexpr std::uint32_t kNone32 = std::numeric_limits<std::uint32_t>::max();

// Corner b of an octant: bit 0 -> +x, bit 1 -> +y, bit 2 -> +z.
inline constexpr std::array<std::array<int, 3>, 8> kCorner = {
    {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0}, {0, 0, 1}, {1, 0, 1}, {0, 1, 1}, {1, 1, 1}}};

// Hanging-corner candidates of an octant in half-side units: the 12 edge
// midpoints with their 2 end corners and the 6 face centres with their 4.
struct Midpoint {
  std::array<int, 3> at;           // 0, 1 or 2 half-sides along each axis
  std::array<int, 4> corners;      // -1 pads the edge case
};
const std::vector<Midpoint>& midpoints();

// Position on the Morton (Z-order) curve of a lattice point: the bits of x,
// y and z interleaved, x lowest, so that the children of an octant, numbered
// bx + 2by + 4bz, follow each other along the curve and every octant covers
// one contiguous range of it.
std::uint64_t morton(std::uint64_t ix, std::uint64_t iy, std::uint64_t iz);

}  // namespace cm::size::detail
