#pragma once
// Local numbering of a tetrahedron, shared by every module (see docs/conventions.md).
//
//              3
//             /|\        Tet (0,1,2,3) is positive iff det[x1-x0, x2-x0, x3-x0] > 0.
//            / | \       Face f is the face opposite vertex f, listed so that its
//           /  |  \      normal (right-hand rule) points out of the tet.
//          0---|---2     Edge e joins kTetEdges[e][0] -> kTetEdges[e][1].
//           \  |  /
//            \ | /
//              1
#include <array>

namespace cm::mesh {

inline constexpr std::array<std::array<int, 3>, 4> kFaceVerts{{{1, 2, 3}, {0, 3, 2}, {0, 1, 3}, {0, 2, 1}}};
/// Edge order used by every high-order node array (same as VTK's quadratic tet).
inline constexpr std::array<std::array<int, 2>, 6> kTetEdges{{{0, 1}, {1, 2}, {2, 0}, {0, 3}, {1, 3}, {2, 3}}};
/// Triangle edges: edge e joins kTriEdges[e][0] -> kTriEdges[e][1].
inline constexpr std::array<std::array<int, 2>, 3> kTriEdges{{{0, 1}, {1, 2}, {2, 0}}};

}  // namespace cm::mesh
