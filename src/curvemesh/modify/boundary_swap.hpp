#pragma once
// Boundary edge swap: the 2D flip of a face edge of the boundary surface,
// with the tets around it retriangulated. Edge (a, b) of two boundary
// triangles (a, b, c) and (b, a, d) of one model face goes; the triangles
// become (a, c, d) and (b, d, c) — the other diagonal of the quad a c b d —
// and the edge's open shell (the tets around (a, b), from one triangle to
// the other) is replaced by the best triangulation of its ring c = r0, r1,
// ..., rk = d joined to a and to b (ring_triangulation.hpp), whose base
// side (c, d) is the new face edge.
//
// The surface changes (from one piecewise-linear approximation of the face
// to another), so the operator needs the model: the new triangles must not
// turn against the old ones nor against the model face (the test
// generate::check_boundary applies, with its projection hint) and must stay
// as close to the face as the chord rule asks. It is what fixes a boundary
// triangle with an angle near 180° (two model edges tangent at a model
// vertex, a sliver against the surface) that no interior operator reaches.
//
// Applying keeps adjacency, vert2tet, orientation and region tags (through
// rebuild_open), m.tris (the two triangles replaced, orientation kept),
// m.edges (untouched: (a, b) is no model edge), and face marks (the new hull
// faces are marked). The editor's hook runs once the triangles are in.
#include <array>
#include <vector>

#include "curvemesh/geom/model.hpp"
#include "curvemesh/modify/cavity.hpp"
#include "curvemesh/modify/surface.hpp"

namespace cm::modify {

/// Quality of a would-be tet: > 0 for a strictly positive tet (higher is
/// better), <= 0 otherwise. nullptr: tet_quality (mean ratio, exact sign).
using SwapMeasure = double (*)(const mesh::TetMesh& m, const std::array<VertId, 4>& v, const void* context);

struct BoundarySwap {
  Refusal refusal = Refusal::kNone;
  VertId a = kNone, b = kNone;  ///< the face edge that goes
  VertId c = kNone, d = kNone;  ///< the face edge that comes
  std::int32_t face_tag = 0;
  /// The triangles that go and come, as m.tris lists (and orients) them.
  std::array<std::array<VertId, 3>, 2> removed{}, added{};
  /// Worst measure of the shell, and of the fill.
  double before = 0, after = 0;
  std::vector<NewTet> fill;
};

struct BoundarySwapOptions {
  /// Chord rule: the new triangles' centroids and the new edge's midpoint
  /// may lie at most this times the longest new edge from the model face,
  /// unless no farther than the old triangles' samples (as deletion).
  double max_relative_deviation = 0.04;
};

/// Plans swapping face edge (a, b); `start` is a live tet holding it. Fills
/// the cavity with the edge's shell; changes nothing. Refusals, in order:
/// - kConstrainedFace: no model, or the shell is closed (an interior
///   edge), or has one tet (that is a deletion) or more than kMaxRing - 1,
///   or a face through (a, b) inside the shell is a classified triangle (an
///   interface);
/// - kClassification: (a, b) is on a model edge, the two hull faces through
///   it are not triangles of one model face, or the shell mixes regions;
/// - kNonManifold: (c, d) is already an edge;
/// - kNotStarShaped: no triangulation of the ring gives only tets of
///   positive measure;
/// - kFoldedSurface: a new triangle turns against an old one or the model
///   face, or strays beyond the chord rule;
/// - kNoImprovement: a complete, applicable plan whose worst measure is no
///   better than the shell's (the caller may still apply it).
/// O(shell³) measure calls, a few closest-point queries.
BoundarySwap plan_boundary_edge_swap(MeshEditor& ed, Cavity& cavity, const BoundaryIndex& boundary, VertId a,
                                     VertId b, TetId start, const geom::Model* model, SwapMeasure measure = nullptr,
                                     const void* context = nullptr, const BoundarySwapOptions& options = {});

/// Applies a plan made with this cavity (no other use of it or edit of the
/// mesh in between). Precondition: plan.refusal == kNone.
std::span<const TetId> apply(MeshEditor& ed, Cavity& cavity, BoundaryIndex& boundary, const BoundarySwap& plan);

}  // namespace cm::modify
