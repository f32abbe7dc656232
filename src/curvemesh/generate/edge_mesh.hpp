#pragma once
// Discretization of model edges to the size field (the first step of the
// boundary mesh, seed paper 1 §2): every model vertex is one mesh vertex and
// every model edge a chain of mesh edges, discretized once however many
// faces it bounds.
//
// Node placement: the metric length of the edge, L = ∫ |γ'(u)|_M du with
// |t|_M = sqrt(tᵀ M(γ(u)) t) (= |γ'|/h for isotropic sizes), is integrated
// on an adaptively bisected table; the edge gets n = round(L) segments (at
// least 1; at least 3 for a closed edge, at least 2 when another edge joins
// the same two vertices, so no two mesh edges share both end points) and node
// k sits where the integral reaches k·L/n. The size field is queried with the
// edge and parameter as hint, so curvature is evaluated at the node itself.
//
// Cusps: where two edges leave a model vertex tangent to each other (a face
// tapering to a point between them), the width between them grows as the
// square of the distance from the vertex, so the triangle at the tip has a
// quality proportional to the length of its two edges there. The segment
// at such an end gets kCuspStretch times the metric length of the others
// (when the others keep at least 0.8 of the mean): a better tip triangle
// and the same count.
#include <array>
#include <vector>

#include "curvemesh/geom/model.hpp"
#include "curvemesh/size/size_field.hpp"

namespace cm::generate {

struct EdgeMesh {
  int edge = 0;
  std::array<int, 2> vertices{0, 0};  ///< model vertex tags at u0 and u1 (0: none)
  bool degenerate = false;            ///< a pole: all nodes at one point
  std::vector<double> params;         ///< increasing, params.front() = u0, params.back() = u1
  std::vector<Vec3> points;           ///< on the edge at params
  double metric_length = 0;           ///< L above
};

struct EdgeMeshOptions {
  double hmin = 0;                ///< an edge shorter than this gets one segment
  int max_table_depth = 12;       ///< bisections of the integration table
  double table_tolerance = 0.05;  ///< metric length per table interval at most this
};

inline constexpr double kCuspStretch = 1.25;
/// Two edges leaving a vertex at less than this angle form a cusp.
inline constexpr double kCuspDegrees = 10;

/// One edge. `min_segments` >= 1 (see above for how the caller chooses it);
/// `cusp` marks the ends (at u0, at u1) that are cusps.
EdgeMesh discretize_edge(const geom::Model& model, int edge, const size::SizeField& size,
                         const EdgeMeshOptions& options, int min_segments = 1, std::array<bool, 2> cusp = {});

/// Per edge (index edge - 1), which of its ends are cusps (see above).
std::vector<std::array<bool, 2>> cusp_ends(const geom::Model& model);

/// Every edge of the model, in parallel; result[e - 1] is edge e.
std::vector<EdgeMesh> discretize_edges(const geom::Model& model, const size::SizeField& size,
                                       const EdgeMeshOptions& options);

}  // namespace cm::generate
