#pragma once
// Raising a classified straight-sided mesh to order 2 or 3 on its model,
// with the guarantee of seed paper 1, §3: the result has no certified-invalid
// and no unacceptable element (nodes.hpp places the nodes, repair.hpp makes
// every element valid and acceptable), and a report of what that took.
#include <cstddef>

#include "curvemesh/curved/element_check.hpp"
#include "curvemesh/curved/nodes.hpp"
#include "curvemesh/curved/repair.hpp"
#include "curvemesh/geom/model.hpp"
#include "curvemesh/mesh/tet_mesh.hpp"

namespace cm::curved {

struct CurveOptions {
  int order = 2;  ///< 2 or 3
  RepairOptions repair;
  bool repair_enabled = true;  ///< false: place nodes and report only
};

/// How far the boundary triangles are from the model: the distance from
/// points of each triangle (its straight or its curved map) to the closest
/// point of its model face, sampled at points inside every triangle.
struct GeometricError {
  double max = 0, mean = 0;
  std::size_t samples = 0;
};

/// Samples boundary triangles of m (curved by m.high_order, or straight when
/// `straight`) and measures their distance to their model faces: 4 points
/// (the centroid and three points halfway to the corners) on every triangle,
/// or on every k-th one where that would be over 40 000 points. Parallel;
/// the result does not depend on the thread count.
GeometricError measure_geometric_error(const mesh::TetMesh& m, const geom::Model& model, bool straight);

struct CurveReport {
  int order = 2;
  PlacementStats placement;
  /// Right after placing the nodes, and at the end.
  std::size_t invalid_before = 0, unacceptable_before = 0;
  /// Minimum I before repair: a lower bound (I is computed where it decides
  /// acceptability, and bounded by the scaled Jacobian elsewhere).
  double min_scaled_jacobian_before = 1, min_measure_before = 1;
  MeshCheck after;
  RepairStats repair;
  GeometricError error_straight, error_curved;
  double place_seconds = 0, check_seconds = 0, error_seconds = 0;
};

/// Curves m (a valid straight-sided mesh, classified on `model` with
/// parameters, adjacency valid) to options.order and repairs it. Replaces
/// any high-order nodes m had. On return m is compact with adjacency valid;
/// unused vertices (left by collapses) are dropped. Throws
/// std::invalid_argument for an order other than 2 or 3.
CurveReport curve_mesh(mesh::TetMesh& m, const geom::Model& model, const CurveOptions& options = {});

}  // namespace cm::curved
