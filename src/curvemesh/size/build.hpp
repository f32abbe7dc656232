#pragma once
// Assembles the size field a mesher queries from the user's options: global
// bounds, curvature of faces and edges (seed §4), sizes on model entities,
// and extra fields (analytic, background size); the isotropic part is stored
// in the graded octree, and an anisotropic background metric is intersected
// with it at query time. The order is fixed: sources first, gradation after
// all of them, the clamp to [hmin, hmax] on every value.
#include <memory>
#include <utility>
#include <vector>

#include "curvemesh/geom/model.hpp"
#include "curvemesh/size/octree.hpp"
#include "curvemesh/size/sampling.hpp"
#include "curvemesh/size/size_field.hpp"

namespace cm::size {

struct SizeOptions {
  double hmax = 0;   ///< 0: the model's bounding-box diagonal / 20
  double hmin = 0;   ///< 0: hmax / 100
  double hgrad = 1.3;
  /// Default: ε = αℓ with α = 0.04 (eq. 4.5), about 20 edges per circle.
  CurvatureRule curvature = CurvatureRule::relative_deviation(0.04);
  /// Sizes on model entities: (dim, tag) with dim 0-3 and h. A vertex, edge
  /// or face gets h at points sampled on it; a region gets h everywhere
  /// inside it and on its boundary (octree corners that classify_point puts
  /// inside or on, plus samples of its faces and edges), and so does every
  /// face, edge and vertex of its closure at hinted queries.
  std::vector<std::pair<geom::EntityRef, double>> entity_sizes;
  /// Isotropic (or the smallest size of anisotropic) sources, graded in the octree.
  std::vector<std::shared_ptr<const SizeField>> fields;
  /// An anisotropic metric (already graded), intersected with the octree.
  std::shared_ptr<const SizeField> metric;
  /// Curvature sampling pattern (centroids, grid, subdivision); its rule,
  /// hmin and hmax are set from the fields above.
  SamplingOptions sampling;
  int max_depth = 20;
  /// Directional variant (§4): on faces, sizes along each principal
  /// direction from its own κ. The octree then holds the coarser of the two
  /// so it does not undo the anisotropy, and metric() with a face hint
  /// intersects it with the surface metric.
  bool directional = false;
  /// A model edge shorter than hmax asks for its own length along it, so the
  /// sizes around it grade down to it instead of leaving slivers between it
  /// and its longer neighbours.
  bool short_edges = true;
  /// A face narrower than the size (two of its boundary edges that share no
  /// vertex closer than hmax) asks for its width there.
  bool narrow_faces = true;
};

/// The field meshers query: the graded octree everywhere; at a point given
/// with a hint (the model face or edge it lies on, with its parameters) also
/// the curvature evaluated exactly there and any size set on that entity
/// (seed §4 step 1: "obtain principal curvature at each node point generated
/// on the model face"), so sizes on the boundary are the formulas' values,
/// not an interpolation of them. Sizes on entities (SizeOptions::entity_sizes)
/// apply at hints on a vertex, edge or face (parameters then unused for a
/// vertex), and a region's size at hints on the region itself or on any
/// entity of its closure. The model must outlive the field.
class ModelSizeField final : public SizeField {
 public:
  /// `octree_min`: the octree's own floor (OctreeOptions::cusp_min; 0: hmin).
  ModelSizeField(const geom::Model& model, const SizeOptions& options, double hmin, double hmax,
                 std::shared_ptr<const SizeOctree> octree, double octree_min = 0);
  double size(const Vec3& x, const SizeHint& hint = {}) const override;
  Metric metric(const Vec3& x, const SizeHint& hint = {}) const override;
  bool anisotropic() const override { return directional_ || (metric_ && metric_->anisotropic()); }

 private:
  double hint_size(const SizeHint& hint) const;
  double octree_size(const Vec3& x) const;

  const geom::Model& model_;
  std::shared_ptr<const SizeOctree> octree_;
  std::shared_ptr<const SizeField> metric_;
  CurvatureRule rule_;
  bool directional_;
  double hmin_, hmax_, octree_min_;
  // User sizes per tag (+inf: none), a region's included on its closure.
  std::vector<double> vertex_size_, edge_size_, face_size_, region_size_;
};

struct SizeFieldResult {
  std::shared_ptr<SizeOctree> octree;
  std::shared_ptr<const ModelSizeField> field;  ///< what meshers query
  std::vector<SizeSample> samples;         ///< curvature and entity samples (size < hmax)
  SamplingStats stats;
  double hmin = 0, hmax = 0;
  /// Sampling: every source's samples; of it, curvature: the curvature
  /// sampling of faces and edges alone (the seed's measure of its cost).
  double sampling_seconds = 0, curvature_seconds = 0, octree_seconds = 0;
};

/// Throws std::invalid_argument for inconsistent options (hmin > hmax,
/// hgrad < 1, a size on an entity that does not exist, ...). A size on a
/// region costs one Model::classify_point per octree corner and centre in
/// the region's box, per refinement round.
SizeFieldResult build_size_field(const geom::Model& model, const SizeOptions& options);

}  // namespace cm::size
