#pragma once
// Where the size sources are evaluated (seed paper 1, §4): curvature at
// points of a uniform grid in each face's parameter space, at the cell
// corners *and* centroids (Fig. 4.1), skipping points outside the trimmed
// face and points already sampled; the same along each model edge from the
// curve's own curvature; and points covering an entity that carries a
// user-given size.
//
// The grid spacing comes from the face's extent in 3D and hmax; a cell whose
// samples ask for a length smaller than the cell itself is subdivided (new
// corners and centroids) so that a region of fast-varying curvature is
// resolved where it is first seen; where the cell's samples agree, only
// while the cell is more than twice the length they ask for. A centroid
// between four corners inside the trimmed face is taken as inside without
// asking the (costly) trimming test, and each sample is one face_geometry
// evaluation. A curvature peak narrower than the grid
// spacing that no sample touches stays unseen; the grid is what bounds it.
#include <cstddef>
#include <vector>

#include "curvemesh/geom/cusps.hpp"
#include "curvemesh/geom/model.hpp"
#include "curvemesh/size/curvature_size.hpp"

namespace cm::size {

/// What set the size at a point; also the cell field "source" in size.vtu.
enum class SizeSource : int {
  kHmax = 0,            ///< nothing asked for less than hmax
  kFaceCurvature = 1,
  kEdgeCurvature = 2,
  kEntitySize = 3,      ///< --size on a model entity
  kField = 4,           ///< analytic or background field
  kGradation = 5,       ///< a finer size nearby, spread by --hgrad
  kHmin = 6,            ///< clamped up to hmin
  kShortEdge = 7,       ///< a model edge shorter than the size around it
  kProximity = 8,       ///< two boundary edges of a narrow face close to each other
  kCuspStrip = 9,       ///< the width of a face tapering to a cusp (may be below hmin)
  kThinClosedFace = 10, ///< a closed face too thin around for three segments at hmin (may be below hmin)
};
const char* to_string(SizeSource s);

struct SizeSample {
  Vec3 point;
  double size = 0;  ///< requested edge length at the point
  SizeSource source = SizeSource::kFaceCurvature;
  geom::EntityRef entity;
  Vec2 param = Vec2::Zero();
  /// Faces: principal curvatures and first direction; edges: κ, 0, tangent.
  double k1 = 0, k2 = 0;
  Vec3 dir1 = Vec3::Zero();
};

struct SamplingOptions {
  CurvatureRule rule;
  double hmin = 0;   ///< sizes below are clamped up; subdivision stops at cells this small
  double hmax = 0;   ///< samples asking for >= hmax are not kept
  bool centroids = true;      ///< corners + centroids (seed Fig. 4.1); false: corners only
  int grid_cells = 0;         ///< cells per direction; 0: from the face's extent and hmax
  int max_grid_cells = 128;   ///< cap per direction for the automatic grid
  bool adaptive = true;       ///< subdivide cells whose samples ask for less than the cell
  int max_depth = 6;          ///< levels of subdivision below the grid
};

struct SamplingStats {
  std::size_t evaluations = 0;     ///< curvature queries made
  std::size_t outside = 0;         ///< grid points outside the trimmed face
  std::size_t revisited = 0;       ///< points skipped because already sampled
  std::size_t subdivided = 0;      ///< cells subdivided
  SamplingStats& operator+=(const SamplingStats& o);
};

/// Curvature samples of one face (those asking for less than hmax). Planes
/// and lines are not sampled: they ask for nothing.
std::vector<SizeSample> sample_face_curvature(const geom::Model& model, int face, const SamplingOptions& opt,
                                              SamplingStats* stats = nullptr);
/// Curvature samples of one edge (none for a degenerate edge).
std::vector<SizeSample> sample_edge_curvature(const geom::Model& model, int edge, const SamplingOptions& opt,
                                              SamplingStats* stats = nullptr);
/// Every face and edge, in parallel; deterministic order (edges, then faces, by tag).
std::vector<SizeSample> sample_model_curvature(const geom::Model& model, const SamplingOptions& opt,
                                               SamplingStats* stats = nullptr);

/// Narrow faces: points along each boundary edge of `face` asking for their
/// distance to the nearest other boundary edge of the face that shares no
/// vertex with it, where that distance is below hmax (so a strip between two
/// nearly parallel edges gets elements as small as it is wide).
std::vector<SizeSample> sample_face_proximity(const geom::Model& model, int face, double hmin, double hmax);

/// Cusp strips (geom/cusps.hpp): points along each edge of the tip's pairs,
/// from its sphere on, asking for the strip's width there (at least
/// `floor`), spaced half that apart, until the strip is hmax wide. The tip
/// itself asks for nothing: it will hold no point. Where the tip's ball is
/// cut short by the model around it, the strip ends narrower than hmin, and
/// the needles at the tip are fair only if the sizes there follow it down:
/// these are the one request allowed below hmin, to kCuspStripFloor hmin.
std::vector<SizeSample> sample_cusp_strips(const geom::Model& model, const geom::CuspTip& tip, double floor,
                                           double hmax);
inline constexpr double kCuspStripFloor = 0.1;

/// A face closed around (its parameter range one whole period, as a hole's
/// cylinder) whose way around is shorter than three times hmin would get
/// fewer than three segments around, and its mesh would close on itself:
/// a wire 5 um across in a KiCad valve model left the volume mesh invalid.
/// For such a face, points covering it and its edges asking for a fifth of
/// the way around, at least kCuspStripFloor hmin; none for any other face,
/// nor where that floor still leaves fewer than three segments around or
/// the points would be more than `max_points`.
std::vector<SizeSample> sample_thin_closed_face(const geom::Model& model, int face, double hmin,
                                                std::size_t max_points = 200'000);

/// Points covering a vertex, edge or face, or the boundary of a region (its
/// faces and their edges), with spacing <= h/2 and at most
/// max_points_per_direction per parameter direction, each with size h and
/// the vertex, edge or face it lies on. A region's interior is not sampled:
/// build_size_field covers it with a field (see build.hpp).
std::vector<SizeSample> sample_entity_size(const geom::Model& model, geom::EntityRef entity, double h,
                                           int max_points_per_direction = 1024);

}  // namespace cm::size
