#pragma once
// Exit codes of the curvemesh command (documented in README.md).
namespace cm::cli {
inline constexpr int kExitOk = 0;            ///< success; for `check`: the mesh is valid
inline constexpr int kExitInvalidMesh = 1;   ///< `check`: the mesh is invalid
inline constexpr int kExitBadInput = 2;      ///< bad usage or unreadable input
inline constexpr int kExitInternal = 3;      ///< internal error (a bug)
}  // namespace cm::cli
