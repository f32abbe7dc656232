#pragma once
// Internal to geom_occ (includes OpenCASCADE): the geom::Model over a compound
// of conformal solids. Never include this header outside geom_occ.
//
// Thread safety. Every table is filled by the constructor and only read
// afterwards. Shape queries evaluate the Geom_Surface / Geom_Curve /
// Geom2d_Curve handles directly: since OCCT 7.0 the B-spline span cache lives
// in GeomAdaptor_* (mutable, per adaptor, NOT thread-safe) and no longer in
// Geom_BSplineSurface/Curve, whose D0..D3 are const and read-only; offset,
// revolution and extrusion surfaces built from Geom handles evaluate through
// GeomEvaluator_* holding Geom handles, equally read-only. No query touches
// a shared adaptor: B-spline surfaces and 3D curves are evaluated through
// adaptors of the calling thread (detail/occ_evaluator.hpp). The one shared OCC object with hidden mutable
// state is the trimmed-face classifier, which is locked per face (see
// FaceData::classifier); the solid classifiers of classify_point are worse
// (every Perform mutates them) and are lent out one per caller from a
// per-region pool (RegionData::classifiers), behind a tessellation that
// answers for points away from the boundary (RegionMesh, built on first use
// from a copy of the solid, so the model's faces never get a triangulation
// attached). Results never depend on which thread asks, so
// answers are bitwise the same serially and in parallel. Handle reference
// counts are atomic in OCCT. Mass properties are computed once on first use
// (Lazy, std::call_once).
//
// Tags: index in TopExp::MapShapes of the final shape, per dimension.
// Orientation: each face is stored as oriented in its first (lowest-tag)
// region, so face_normal, face_loops and the p-curves agree with that
// region's outward normal; region_faces marks a use forward when the region
// sees the face that way.
#include <cstdint>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include <BRepClass3d_SolidClassifier.hxx>
#include <BRepTopAdaptor_FClass2d.hxx>
#include <Geom2d_Curve.hxx>
#include <Geom_Curve.hxx>
#include <Geom_Surface.hxx>
#include <TopoDS_Edge.hxx>
#include <TopoDS_Face.hxx>
#include <TopoDS_Shape.hxx>
#include <TopoDS_Solid.hxx>
#include <TopTools_IndexedMapOfShape.hxx>

#include "curvemesh/geom/model.hpp"
#include "curvemesh/geom_occ/detail/occ_evaluator.hpp"
#include "curvemesh/geom_occ/detail/triangle_classifier.hpp"
#include "curvemesh/geom_occ/detail/trim_classifier.hpp"

namespace cm::geom_occ::detail {

/// A value computed on first use, exactly once, whichever thread asks first
/// (mass properties are costly and only needed for validation).
template <class T>
class Lazy {
 public:
  template <class Compute>
  const T& get(Compute&& compute) const {
    std::call_once(flag_, [&] { value_ = compute(); });
    return value_;
  }

 private:
  mutable std::once_flag flag_;
  mutable T value_{};
};

struct MassProperties {
  double mass = 0;
  Vec3 center = Vec3::Zero();
};

struct VertexData {
  Vec3 point = Vec3::Zero();
  double tolerance = 0;
  std::vector<int> edges;
};

struct EdgeData {
  TopoDS_Edge edge;  // FORWARD
  Handle(Geom_Curve) curve;  // global coordinates, trimming wrappers removed; null if degenerate
  CurveEvaluator eval;       // of curve: what queries evaluate it through
  double first = 0, last = 0;
  bool degenerate = false;
  geom::ShapeType type = geom::ShapeType::kOtherCurve;
  std::array<int, 2> vertices{0, 0};
  geom::ParamRange range;
  double length = 0;
  double tolerance = 0;  // BRep tolerance, raised to the measured curve / p-curve gap
  geom::BoundingBox box;
  std::vector<int> faces;
  // Seeds of the global closest-point search: parameters and their points.
  std::vector<double> sample_params;
  std::vector<Vec3> sample_points;
};

/// The p-curve of one use of an edge in a face (seams have two uses).
struct PCurveUse {
  int edge = 0;
  bool forward = true;
  Handle(Geom2d_Curve) curve;
};

struct FaceData {
  TopoDS_Face face;  // oriented as in its first region
  Handle(Geom_Surface) surface;  // global coordinates, trimming wrappers removed
  SurfaceEvaluator eval;         // of surface: what queries evaluate it through
  bool flip_normal = false;  // du x dv points into the first region
  geom::ShapeType type = geom::ShapeType::kOtherSurface;
  geom::ParamRange range;  // UV bounds of the trimmed face
  // Box the projection's Newton iteration stays in (surface bounds in the
  // non-periodic directions, open in the periodic ones).
  double box_u0 = 0, box_u1 = 0, box_v0 = 0, box_v1 = 0;
  // BRepTopAdaptor_FClass2d::Perform is const but NOT safe to call from two
  // threads at once: its polygons live in NCollection_Sequence members, whose
  // const Value() moves a mutable "current node" cursor. Every use goes
  // through face_contains, which holds classifier_mutex.
  std::unique_ptr<BRepTopAdaptor_FClass2d> classifier;
  std::unique_ptr<std::mutex> classifier_mutex = std::make_unique<std::mutex>();
  // The fast path in front of it (occ_trim.cpp): the loops as polygons;
  // null where they could not be built or disagreed with the classifier.
  std::unique_ptr<TrimClassifier> trim;
  std::vector<geom::Loop> loops;
  std::vector<int> edges;  // boundary edges, each once
  std::vector<PCurveUse> pcurves;
  std::vector<int> regions;
  double tolerance = 0;
  geom::BoundingBox box;  // edges' exact boxes and the padded sample grid
  // Seeds of the global closest-point search, inside the trimmed face: the
  // first grid_samples from a UV grid, then points of the boundary.
  std::vector<Vec2> sample_params;
  std::vector<Vec3> sample_points;
  std::size_t grid_samples = 0;
  Vec2 grid_step = Vec2::Zero();
  // Parametric tolerance of the classifier (its ON band): the face's and its
  // edges' 3D tolerance through the surface's resolution, and at least the
  // largest gap between consecutive p-curves of a loop.
  double uv_tolerance = 0;
  double uv_loop_gap = 0;
};

/// Solid classifiers of one region, for classify_point. Perform is not
/// const in any sense: the solid explorer inside moves member iterators over
/// the shells and faces and caches one curve-surface intersector per face.
/// So a classifier serves one caller at a time; building one is the costly
/// part (those intersectors), so idle ones are kept for the next caller.
/// The pool grows to the number of concurrent callers and no further.
struct ClassifierPool {
  std::mutex mutex;
  std::vector<std::unique_ptr<BRepClass3d_SolidClassifier>> idle;
};

/// The fast paths of classify_point (occ_classify.cpp): the region's
/// boundary tessellated, each triangle with the band around it inside which
/// the tessellation's side of a point may differ from the solid's (its
/// measured deviation from its face, doubled, plus the tolerances). Null
/// surface: no usable tessellation, every point goes to the exact classifier.
struct RegionMesh {
  std::unique_ptr<TriangleClassifier> surface;
  double band = 0;       ///< the widest triangle band
  double tolerance = 0;  ///< largest tolerance of the region's faces, edges and vertices
};

struct RegionData {
  TopoDS_Solid solid;
  std::vector<geom::OrientedUse> faces;
  double tolerance = 0;
  geom::BoundingBox box;  // union of its faces' boxes
  std::unique_ptr<ClassifierPool> classifiers = std::make_unique<ClassifierPool>();
};

/// contains_param on a face's data: the polygons first, OCC's classifier
/// within their band (occ_trim.cpp).
bool face_contains(const FaceData& face, Vec2 uv);
/// OCC's classifier alone (uv in the face's periodic range).
bool occ_face_contains(const FaceData& face, const Vec2& uv);
/// The polygons of the face's loops, checked against OCC's classifier just
/// outside their band; nullptr when a p-curve is missing or a check fails.
/// Needs the face's loops, p-curves and uv tolerances.
std::unique_ptr<TrimClassifier> build_trim_classifier(const FaceData& face, const std::vector<EdgeData>& edges);
/// What `trim` (the face's polygons) says of uv as face_contains would ask
/// it (periodic parameters brought into range, shifts by a period tried);
/// nullopt where OCC's classifier must decide.
std::optional<bool> trim_face_contains(const FaceData& face, const TrimClassifier& trim, const Vec2& uv);

/// Adds to `box` the interior maxima and minima of each coordinate over the
/// trimmed face (occ_bounds.cpp); the boundary is the edges' business.
void add_interior_extremes(const FaceData& face, geom::BoundingBox& box);

/// The entity maps of the final shape: tag = index in these maps.
struct ShapeMaps {
  TopTools_IndexedMapOfShape vertices, edges, faces, solids;
};

class OccModel final : public geom::Model {
 public:
  /// `solids`: a shape whose solids are conformal (see make_conformal_solids).
  OccModel(const TopoDS_Shape& solids, std::string units);

  int count(int dim) const override;
  geom::ShapeType type(geom::EntityRef e) const override;
  geom::BoundingBox bounding_box(geom::EntityRef e) const override;
  geom::BoundingBox bounding_box() const override { return box_; }
  std::vector<geom::OrientedUse> region_faces(int region) const override;
  std::vector<geom::Loop> face_loops(int face) const override;
  std::array<int, 2> edge_vertices(int edge) const override;
  bool is_degenerate(int edge) const override;
  std::vector<int> upward(geom::EntityRef e) const override;
  double tolerance(geom::EntityRef e) const override;
  std::string units() const override { return units_; }

  geom::ParamRange param_range(geom::EntityRef e) const override;
  Vec3 vertex_point(int vertex) const override;
  geom::CurveDerivatives edge_derivatives(int edge, double u) const override;
  geom::SurfaceDerivatives face_derivatives(int face, const Vec2& uv) const override;
  Vec3 face_normal(int face, const Vec2& uv) const override;
  geom::Curvatures face_curvatures(int face, const Vec2& uv) const override;
  geom::SurfaceGeometry face_geometry(int face, const Vec2& uv) const override;
  double edge_curvature(int edge, double u) const override;
  geom::Projection closest_point(geom::EntityRef e, const Vec3& x,
                                 std::optional<Vec2> hint = {}) const override;
  Vec2 edge_param_on_face(int edge, int face, double u, bool forward = true) const override;
  bool contains_param(int face, const Vec2& uv) const override;
  std::optional<bool> contains_param_quick(int face, const Vec2& uv) const override;
  geom::Containment classify_point(int region, const Vec3& x) const override;

  /// Faces whose contains_param has the polygon fast path (for tests and
  /// benchmarks: the rest always ask OCC's classifier).
  int faces_with_trim_polygons() const;
  /// contains_param by OCC's classifier alone, without the fast path.
  bool contains_param_by_occ(int face, const Vec2& uv) const;

  double area(int face) const override;
  double length(int edge) const override;
  double volume(int region) const override;
  Vec3 center_of_mass(int region) const override;

 private:
  const VertexData& vertex_at(int tag) const;
  const EdgeData& edge_at(int tag) const;
  const FaceData& face_at(int tag) const;
  const RegionData& region_at(int tag) const;

  // Construction steps (occ_model.cpp).
  void build_vertices(const TopoDS_Shape& shape, const ShapeMaps& maps);
  void build_edges(const TopoDS_Shape& shape, const ShapeMaps& maps);
  void build_regions(const ShapeMaps& maps);
  void build_faces(const TopoDS_Shape& shape, const ShapeMaps& maps);
  void build_face_loops(FaceData& face, const ShapeMaps& maps);
  void build_face_samples(FaceData& face);

  // Closest point (occ_projection.cpp).
  geom::Projection project_on_edge(const EdgeData& edge, const Vec3& x,
                                   std::optional<double> hint) const;
  geom::Projection project_on_face(const FaceData& face, const Vec3& x,
                                   std::optional<Vec2> hint) const;
  geom::Projection project_on_face_boundary(const FaceData& face, const Vec3& x,
                                            const Vec2& near_uv) const;
  static Vec2 pcurve_point(const PCurveUse& use, double u);

  // Point in solid (occ_classify.cpp).
  RegionMesh build_region_mesh(int region) const;
  std::optional<geom::Containment> classify_near_faces(const RegionData& region, const RegionMesh& mesh,
                                                       const Vec3& x) const;

  std::vector<VertexData> vertices_;
  std::vector<EdgeData> edges_;
  std::vector<FaceData> faces_;
  std::vector<RegionData> regions_;
  std::unique_ptr<Lazy<double>[]> face_areas_;
  std::unique_ptr<Lazy<MassProperties>[]> region_mass_;
  std::unique_ptr<Lazy<RegionMesh>[]> region_meshes_;
  geom::BoundingBox box_;
  double scale_ = 1;  // model bounding-box diagonal: the length scale of iteration tolerances
  std::uint64_t serial_ = 0;  // distinct for every model made in the process (edge_curvature's memo)
  std::string units_;
};

}  // namespace cm::geom_occ::detail
