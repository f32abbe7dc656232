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
// Cusp tips (geom/cusps.hpp): an edge with an end at a tip vertex gets its
// first node there on the tip's sphere, and the metric places the others
// from that node on. At a wedge span's vertex (two cusp pairs) the first
// node is put at the span's radius only when the metric would put it nearer.
#include <array>
#include <vector>

#include "curvemesh/geom/cusps.hpp"
#include "curvemesh/geom/model.hpp"
#include "curvemesh/size/size_field.hpp"

namespace cm::generate {

struct EdgeMesh {
  int edge = 0;
  std::array<int, 2> vertices{0, 0};  ///< model vertex tags at u0 and u1 (0: none)
  bool degenerate = false;            ///< a pole: all nodes at one point
  std::vector<double> params;         ///< increasing, params.front() = u0, params.back() = u1
  std::vector<Vec3> points;           ///< on the edge at params
  double metric_length = 0;           ///< L above, between the tip nodes if any
};

struct EdgeMeshOptions {
  double hmin = 0;                ///< an edge shorter than this gets one segment
  int max_table_depth = 12;       ///< bisections of the integration table
  double table_tolerance = 0.05;  ///< metric length per table interval at most this
};

/// A tip ends where the strip between its cusp edges is this times the
/// local size wide: its cross edges are then about the size, and the
/// triangles along it fair.
inline constexpr double kTipWidth = 0.9;

/// One edge. `min_segments` >= 1 (see above for how the caller chooses it);
/// `tip_radius` (at u0, at u1; 0: none) puts the first node at that chord
/// distance from the end, if the edge gets that far from it; `min_first`
/// (same order; 0: none) moves the first node out to that distance if the
/// metric put it nearer.
EdgeMesh discretize_edge(const geom::Model& model, int edge, const size::SizeField& size,
                         const EdgeMeshOptions& options, int min_segments = 1, std::array<double, 2> tip_radius = {},
                         std::array<double, 2> min_first = {});

/// The model's cusp tips for this size field: each ends where the strip
/// between its edges is kTipWidth times the size wide.
std::vector<geom::CuspTip> cusp_tips(const geom::Model& model, const size::SizeField& size);

/// Every edge of the model, in parallel; result[e - 1] is edge e.
std::vector<EdgeMesh> discretize_edges(const geom::Model& model, const size::SizeField& size,
                                       const EdgeMeshOptions& options, const std::vector<geom::CuspTip>& tips = {},
                                       const std::vector<geom::WedgeSpan>& spans = {});

}  // namespace cm::generate
