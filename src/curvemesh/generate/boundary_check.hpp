#pragma once
// Checks a boundary mesh against its model (seed paper 1, §2: a geometric
// triangulation is topologically compatible and geometrically similar) and
// measures it against the size field.
#include <string>
#include <vector>

#include "curvemesh/geom/model.hpp"
#include "curvemesh/mesh/tet_mesh.hpp"
#include "curvemesh/size/size_field.hpp"

namespace cm::generate {

struct BoundaryReport {
  // Geometric similarity.
  double max_vertex_distance = 0;   ///< from a vertex to its entity at its parameters, relative to tolerance
  std::size_t vertices_off_entity = 0;
  std::size_t folded_triangles = 0; ///< normal against the surface normal at the centroid
  std::size_t crossing_pairs = 0;   ///< pairs of triangles that cross each other (crossing_triangles)
  // Topological compatibility.
  std::size_t open_region_edges = 0;     ///< region boundary edges not used exactly twice, oppositely
  std::size_t unmeshed_faces = 0;
  // Size and quality.
  std::size_t edges = 0, edges_in_range = 0;  ///< length / size in [0.7, 1.4]
  std::size_t triangles = 0;
  double min_quality = 1, mean_quality = 0;
  std::size_t good_triangles = 0;       ///< mean ratio >= 0.6
  std::size_t poor_triangles = 0;       ///< mean ratio < 0.1, away from sharp model corners
  std::size_t poor_at_sharp_corners = 0;///< mean ratio < 0.1 with a corner where model edges meet at < 30°
  /// mean ratio < 0.1 with an edge under a tenth of the size: a model feature
  /// (a sliver face, a tiny edge) below hmin, which the mesh cannot resolve
  std::size_t poor_at_small_features = 0;
  std::vector<std::string> problems;    ///< first few failures, human-readable

  bool valid() const { return vertices_off_entity == 0 && folded_triangles == 0 && crossing_pairs == 0 && open_region_edges == 0 && unmeshed_faces == 0; }
};

BoundaryReport check_boundary(const geom::Model& model, const mesh::TetMesh& mesh, const size::SizeField& size);

}  // namespace cm::generate
