#pragma once
// The geometric model interface (seed paper 1, §2): topological entities of
// dimension 0..3 with stable integer tags and their adjacencies, and the shape
// reached only through point-wise interrogations. Backends: AnalyticModel
// (closed-form sphere, cylinder, torus) and geom_occ's OpenCASCADE model.
//
// Contract shared by every backend:
// - Entities are addressed by EntityRef{dim, tag}; tags are >= 1, dense per
//   dimension (1..count) and stable: the same input gives the same tags.
// - All query methods are const and thread-safe: any number of threads may
//   query one model concurrently.
// - Parameters: u on an edge, (u, v) on a face, in the backend's native
//   parametrization; ranges and periodicity are reported, never assumed.
// - Errors: queries on a tag that does not exist throw std::out_of_range;
//   loading failures throw cm::InputError (file problems) or
//   cm::GeometryError (unusable geometry), naming the entity.
#include <array>
#include <optional>
#include <string>
#include <vector>

#include "curvemesh/core/types.hpp"

namespace cm::geom {

struct EntityRef {
  int dim = -1;
  int tag = 0;
  friend bool operator==(const EntityRef&, const EntityRef&) = default;
  friend auto operator<=>(const EntityRef&, const EntityRef&) = default;
};

/// Geometric type of a face or edge, as the CAD kernel names it.
enum class ShapeType {
  kPoint,
  kLine, kCircle, kEllipse, kBSplineCurve, kBezierCurve, kOtherCurve,
  kPlane, kCylinder, kCone, kSphere, kTorus, kBSplineSurface, kBezierSurface,
  kSurfaceOfRevolution, kSurfaceOfExtrusion, kOffsetSurface, kOtherSurface,
  kSolid,
};
std::string to_string(ShapeType t);

struct BoundingBox {
  Vec3 min = Vec3::Constant(std::numeric_limits<double>::infinity());
  Vec3 max = Vec3::Constant(-std::numeric_limits<double>::infinity());
  void add(const Vec3& p) { min = min.cwiseMin(p); max = max.cwiseMax(p); }
  Vec3 size() const { return max - min; }
  double diagonal() const { return (max - min).norm(); }
};

/// An edge used by a face loop or a face used by a region shell, with the
/// orientation of the use (true: same sense as the entity).
struct OrientedUse {
  int tag = 0;
  bool forward = true;
};

/// One loop of a face: its edge uses in order. Seam edges of periodic faces
/// appear twice (once each way); degenerate edges (a pole) are flagged.
/// Followed in order, the uses' p-curves (edge_param_on_face) form a closed
/// curve in the face's (u, v) plane, and the face lies on the left of each
/// use seen from the side face_normal points to: an outer loop runs
/// counter-clockwise in (u, v) when face_normal is along du × dv and
/// clockwise when the region uses the face reversed (OpenCASCADE's wire
/// order on a face as it sits in its shell).
struct Loop {
  std::vector<OrientedUse> edges;
  bool outer = true;
};

/// Parameter range of an entity: [u0, u1] (x [v0, v1] for faces).
struct ParamRange {
  double u0 = 0, u1 = 0, v0 = 0, v1 = 0;
  bool periodic_u = false, periodic_v = false;
  double period_u = 0, period_v = 0;
};

struct SurfaceDerivatives {
  Vec3 point, du, dv, duu, duv, dvv;
};
struct CurveDerivatives {
  Vec3 point, d1, d2;
};

/// Principal curvatures k1 >= k2 and their unit directions in 3D. Sign: with
/// n = face_normal (out of the material), the normal curvature along a unit
/// tangent t is k(t) = -n · γ''(s) for a unit-speed curve γ on the face with
/// γ'(s) = t; it is positive where the face bends away from n. So the outer
/// surface of a convex solid has k >= 0 (sphere of radius R: k1 = k2 = 1/R),
/// a hole or a concave fillet negative (inner equator of a torus:
/// -1/(R - r)). dir1 and dir2 are orthogonal tangents with dir1 × dir2 = n.
struct Curvatures {
  double k1 = 0, k2 = 0;
  Vec3 dir1 = Vec3::UnitX(), dir2 = Vec3::UnitY();
};

/// Everything a face evaluation gives at one (u, v): see Model::face_geometry.
struct SurfaceGeometry {
  SurfaceDerivatives derivatives;
  /// Set only where `regular`; see Curvatures for signs and directions.
  Curvatures curvatures;
  /// du × dv does not vanish: |du × dv| > 1e-12 |du| |dv|.
  bool regular = false;
};

/// Where a point lies with respect to a region (classify_point).
enum class Containment {
  kOutside,
  kOn,      ///< within the region's tolerance of its boundary
  kInside,
};

/// Result of a closest-point query.
struct Projection {
  Vec3 point;      ///< on the entity
  Vec2 param;      ///< u (x) on an edge, (u,v) on a face
  double distance; ///< from the query point
};

class Model {
 public:
  virtual ~Model() = default;

  // --- topology -----------------------------------------------------------
  /// Number of entities of dimension dim (tags are 1..count).
  virtual int count(int dim) const = 0;
  virtual ShapeType type(EntityRef e) const = 0;
  virtual BoundingBox bounding_box(EntityRef e) const = 0;
  virtual BoundingBox bounding_box() const = 0;
  /// Region -> its shells' faces with orientation (outward = forward).
  virtual std::vector<OrientedUse> region_faces(int region) const = 0;
  /// Face -> its loops of oriented edges.
  virtual std::vector<Loop> face_loops(int face) const = 0;
  /// Edge -> (start vertex, end vertex); a closed edge has both equal; an
  /// edge without vertices (a full circle in some kernels) returns {0, 0}.
  virtual std::array<int, 2> edge_vertices(int edge) const = 0;
  /// Edge degenerated to a point (a pole of a sphere or cone apex).
  virtual bool is_degenerate(int edge) const = 0;
  /// Upward adjacency: the entities of dimension dim+1 that e bounds.
  virtual std::vector<int> upward(EntityRef e) const = 0;
  /// Model tolerance of an entity (distance within which a point is "on" it).
  virtual double tolerance(EntityRef e) const = 0;
  /// Length unit of the model, e.g. "mm"; "" if unknown.
  virtual std::string units() const = 0;

  // --- shape queries ------------------------------------------------------
  virtual ParamRange param_range(EntityRef e) const = 0;
  virtual Vec3 vertex_point(int vertex) const = 0;
  virtual CurveDerivatives edge_derivatives(int edge, double u) const = 0;
  virtual SurfaceDerivatives face_derivatives(int face, const Vec2& uv) const = 0;
  Vec3 edge_point(int edge, double u) const { return edge_derivatives(edge, u).point; }
  Vec3 face_point(int face, const Vec2& uv) const { return face_derivatives(face, uv).point; }
  /// Unit normal of a face at (u, v), pointing out of the material of the
  /// region(s) the face bounds as oriented in its first region's shell.
  virtual Vec3 face_normal(int face, const Vec2& uv) const = 0;
  virtual Curvatures face_curvatures(int face, const Vec2& uv) const = 0;
  /// Point, derivatives and (where regular) principal curvatures at (u, v),
  /// the curvatures equal to face_curvatures(face, uv) there. Samplers that
  /// need all three call this once: the default asks face_derivatives and
  /// face_curvatures, and a backend whose evaluation is expensive overrides
  /// it to evaluate the surface once.
  virtual SurfaceGeometry face_geometry(int face, const Vec2& uv) const {
    SurfaceGeometry g;
    g.derivatives = face_derivatives(face, uv);
    const SurfaceDerivatives& d = g.derivatives;
    const double scale = d.du.norm() * d.dv.norm();
    g.regular = scale > 0 && d.du.cross(d.dv).norm() > 1e-12 * scale;
    if (g.regular) g.curvatures = face_curvatures(face, uv);
    return g;
  }
  /// Curvature (1 / radius) of an edge at u; 0 for a line.
  virtual double edge_curvature(int edge, double u) const = 0;
  /// Closest point on an edge or face; `hint` (parameters near the answer)
  /// starts a Newton iteration, with a global fallback if it fails.
  virtual Projection closest_point(EntityRef e, const Vec3& x, std::optional<Vec2> hint = {}) const = 0;
  /// (u, v) on `face` of the point at parameter u of `edge` (the p-curve).
  /// For a seam edge, `forward` picks which side: the p-curve of the use
  /// with that orientation in face_loops(face). Throws std::invalid_argument
  /// if the edge does not bound the face.
  virtual Vec2 edge_param_on_face(int edge, int face, double u, bool forward = true) const = 0;
  /// Whether (u, v) is inside the trimmed face (on its boundary counts as in).
  virtual bool contains_param(int face, const Vec2& uv) const = 0;
  /// The same test for callers that may take a point very near the face's
  /// boundary as on it (a curvature sampler, whose sample there reads the
  /// surface the face is cut from): the answer where it is quick to tell,
  /// nullopt in a narrow band along the trimming loops (a few thousandths of
  /// the parameter extent at most) where only contains_param can. The
  /// default gives contains_param's answer everywhere.
  virtual std::optional<bool> contains_param_quick(int face, const Vec2& uv) const { return contains_param(face, uv); }
  /// Where x lies with respect to the closed solid `region`: kOn within
  /// tolerance({3, region}) of its boundary (so a point of a face two
  /// regions share is kOn for both), else kInside or kOutside. Exact to
  /// rounding on analytic models, O(1). On CAD models a few microseconds per
  /// call on average, up to milliseconds for points close to a corner
  /// (geom_occ/load.hpp); the first call on a region also prepares it (tens
  /// to hundreds of milliseconds). Throws std::out_of_range for a
  /// region that does not exist and std::invalid_argument for a non-finite x.
  virtual Containment classify_point(int region, const Vec3& x) const = 0;

  // --- global properties (validation) -----------------------------------
  virtual double area(int face) const = 0;
  virtual double length(int edge) const = 0;
  virtual double volume(int region) const = 0;
  virtual Vec3 center_of_mass(int region) const = 0;
};

}  // namespace cm::geom
