#pragma once
// Basic index and vector types shared by every module.
#include <cstdint>
#include <limits>

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace cm {

/// 0-based index of a vertex, tet, face or edge in the compact mesh arrays.
using Index = std::uint32_t;
using VertId = Index;
using TetId = Index;
/// "No entity" marker (a missing neighbour, an unset seed tet).
inline constexpr Index kNone = std::numeric_limits<Index>::max();

using Vec2 = Eigen::Vector2d;
using Vec3 = Eigen::Vector3d;
using Mat3 = Eigen::Matrix3d;

}  // namespace cm
