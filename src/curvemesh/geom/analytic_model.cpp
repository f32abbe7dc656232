// AnalyticModel: topology tables (vertices, edges, faces with their loops of
// edge uses and p-curves, one region) over the closed-form shapes of
// analytic_shapes.hpp, plus the three factories that fill them the way
// OpenCASCADE's primitives are built (see analytic_model.hpp).
#include "curvemesh/geom/analytic_model.hpp"

#include <algorithm>
#include <cmath>
#include <functional>
#include <stdexcept>
#include <utility>

#include <fmt/format.h>

#include "curvemesh/core/error.hpp"
#include "curvemesh/geom/analytic_shapes.hpp"

namespace cm::geom {

namespace {

using analytic::Curve;
using analytic::Frame;
using analytic::kPi;
using analytic::kTwoPi;
using analytic::Surface;

/// Image of an edge in a face's parameter plane: a straight line
/// uv = origin + a t (on the periodic faces) or a circle
/// uv = origin + a cos t + b sin t (a circle edge on a plane face).
struct PCurve {
  bool circular = false;
  Vec2 origin = Vec2::Zero();
  Vec2 a = Vec2::Zero();
  Vec2 b = Vec2::Zero();

  Vec2 at(double t) const {
    if (circular) return origin + a * std::cos(t) + b * std::sin(t);
    return origin + a * t;
  }
};

PCurve line_pcurve(const Vec2& origin, const Vec2& direction) {
  return {false, origin, direction, Vec2::Zero()};
}
PCurve circle_pcurve(double radius) {
  return {true, Vec2::Zero(), Vec2(radius, 0.0), Vec2(0.0, radius)};
}

struct EdgeUse {
  int edge = 0;
  bool forward = true;
  PCurve pcurve;
};

struct FaceLoop {
  std::vector<EdgeUse> uses;
  bool outer = true;
};

struct EdgeRecord {
  std::unique_ptr<Curve> curve;
  std::array<int, 2> vertices{0, 0};
  bool degenerate = false;
};

struct FaceRecord {
  std::unique_ptr<Surface> surface;
  std::vector<FaceLoop> loops;
};

struct RegionRecord {
  std::vector<OrientedUse> faces;
  double volume = 0.0;
  Vec3 center_of_mass = Vec3::Zero();
  /// Exact signed Euclidean distance to the solid's boundary, negative
  /// inside: comparing it with the tolerance gives classify_point's answer
  /// with the same "on" band as every other query of the model.
  std::function<double(const Vec3&)> signed_distance;
};

/// Relative size of the model tolerance: far above rounding (1e-16) so exact
/// answers are always "on" their entity, far below any mesh size.
constexpr double kRelativeTolerance = 1e-9;

class AnalyticModel final : public Model {
 public:
  AnalyticModel(std::vector<Vec3> vertices, std::vector<EdgeRecord> edges,
                std::vector<FaceRecord> faces, std::vector<RegionRecord> regions);

  int count(int dim) const override;
  ShapeType type(EntityRef e) const override;
  BoundingBox bounding_box(EntityRef e) const override;
  BoundingBox bounding_box() const override { return box_; }
  std::vector<OrientedUse> region_faces(int region) const override;
  std::vector<Loop> face_loops(int face) const override;
  std::array<int, 2> edge_vertices(int edge) const override { return edge_record(edge).vertices; }
  bool is_degenerate(int edge) const override { return edge_record(edge).degenerate; }
  std::vector<int> upward(EntityRef e) const override;
  double tolerance(EntityRef e) const override;
  std::string units() const override { return ""; }

  ParamRange param_range(EntityRef e) const override;
  Vec3 vertex_point(int vertex) const override;
  CurveDerivatives edge_derivatives(int edge, double u) const override;
  SurfaceDerivatives face_derivatives(int face, const Vec2& uv) const override;
  Vec3 face_normal(int face, const Vec2& uv) const override;
  Curvatures face_curvatures(int face, const Vec2& uv) const override;
  double edge_curvature(int edge, double u) const override;
  Projection closest_point(EntityRef e, const Vec3& x, std::optional<Vec2> hint) const override;
  Vec2 edge_param_on_face(int edge, int face, double u, bool forward) const override;
  bool contains_param(int face, const Vec2& uv) const override;
  Containment classify_point(int region, const Vec3& x) const override;

  double area(int face) const override { return face_record(face).surface->area(); }
  double length(int edge) const override { return edge_record(edge).curve->length(); }
  double volume(int region) const override { return region_record(region).volume; }
  Vec3 center_of_mass(int region) const override { return region_record(region).center_of_mass; }

 private:
  void check_tag(EntityRef e) const;
  const EdgeRecord& edge_record(int tag) const;
  const FaceRecord& face_record(int tag) const;
  const RegionRecord& region_record(int tag) const;
  void check_pcurves() const;

  std::vector<Vec3> vertices_;
  std::vector<EdgeRecord> edges_;
  std::vector<FaceRecord> faces_;
  std::vector<RegionRecord> regions_;
  /// Per face: whether its first region uses it reversed, i.e. whether the
  /// outward normal is -(du × dv).
  std::vector<bool> face_reversed_;
  /// upward_[d][tag - 1]: sorted tags of dimension d + 1 bounded by the entity.
  std::array<std::vector<std::vector<int>>, 3> upward_;
  BoundingBox box_;
  double tolerance_ = 0.0;
};

AnalyticModel::AnalyticModel(std::vector<Vec3> vertices, std::vector<EdgeRecord> edges,
                             std::vector<FaceRecord> faces, std::vector<RegionRecord> regions)
    : vertices_(std::move(vertices)),
      edges_(std::move(edges)),
      faces_(std::move(faces)),
      regions_(std::move(regions)) {
  upward_[0].resize(vertices_.size());
  upward_[1].resize(edges_.size());
  upward_[2].resize(faces_.size());
  for (std::size_t e = 0; e < edges_.size(); ++e)
    for (int v : edges_[e].vertices)
      if (v > 0) upward_[0][static_cast<std::size_t>(v - 1)].push_back(static_cast<int>(e + 1));
  for (std::size_t f = 0; f < faces_.size(); ++f)
    for (const FaceLoop& loop : faces_[f].loops)
      for (const EdgeUse& use : loop.uses)
        upward_[1][static_cast<std::size_t>(use.edge - 1)].push_back(static_cast<int>(f + 1));
  face_reversed_.assign(faces_.size(), false);
  std::vector<bool> face_seen(faces_.size(), false);
  for (std::size_t r = 0; r < regions_.size(); ++r) {
    for (const OrientedUse& use : regions_[r].faces) {
      const auto f = static_cast<std::size_t>(use.tag - 1);
      upward_[2][f].push_back(static_cast<int>(r + 1));
      if (!face_seen[f]) face_reversed_[f] = !use.forward;
      face_seen[f] = true;
    }
  }
  for (auto& per_dim : upward_) {
    for (std::vector<int>& up : per_dim) {
      std::sort(up.begin(), up.end());
      up.erase(std::unique(up.begin(), up.end()), up.end());
    }
  }
  for (const FaceRecord& face : faces_) {
    const BoundingBox b = face.surface->box();
    box_.add(b.min);
    box_.add(b.max);
  }
  tolerance_ = kRelativeTolerance * box_.diagonal();
  check_pcurves();
}

/// The tables are written by hand in the factories below; a p-curve that
/// does not map onto its edge would silently break every mesher, so check
/// each use at both ends and the middle once, at construction.
void AnalyticModel::check_pcurves() const {
  for (std::size_t f = 0; f < faces_.size(); ++f) {
    for (const FaceLoop& loop : faces_[f].loops) {
      for (const EdgeUse& use : loop.uses) {
        const EdgeRecord& edge = edges_[static_cast<std::size_t>(use.edge - 1)];
        const ParamRange r = edge.curve->range();
        for (double t : {r.u0, 0.5 * (r.u0 + r.u1), r.u1}) {
          const Vec3 on_edge = edge.curve->derivatives(t).point;
          const Vec3 on_face = faces_[f].surface->derivatives(use.pcurve.at(t)).point;
          CM_ASSERT_OP((on_edge - on_face).norm(), <=, tolerance_);
        }
      }
    }
  }
}

void AnalyticModel::check_tag(EntityRef e) const {
  if (e.dim < 0 || e.dim > 3 || e.tag < 1 || e.tag > count(e.dim))
    throw std::out_of_range(fmt::format("analytic model: no entity of dimension {} with tag {}", e.dim, e.tag));
}

const EdgeRecord& AnalyticModel::edge_record(int tag) const {
  check_tag({1, tag});
  return edges_[static_cast<std::size_t>(tag - 1)];
}

const FaceRecord& AnalyticModel::face_record(int tag) const {
  check_tag({2, tag});
  return faces_[static_cast<std::size_t>(tag - 1)];
}

const RegionRecord& AnalyticModel::region_record(int tag) const {
  check_tag({3, tag});
  return regions_[static_cast<std::size_t>(tag - 1)];
}

int AnalyticModel::count(int dim) const {
  switch (dim) {
    case 0: return static_cast<int>(vertices_.size());
    case 1: return static_cast<int>(edges_.size());
    case 2: return static_cast<int>(faces_.size());
    case 3: return static_cast<int>(regions_.size());
    default: return 0;
  }
}

ShapeType AnalyticModel::type(EntityRef e) const {
  check_tag(e);
  switch (e.dim) {
    case 0: return ShapeType::kPoint;
    case 1: return edge_record(e.tag).curve->type();
    case 2: return face_record(e.tag).surface->type();
    default: return ShapeType::kSolid;
  }
}

BoundingBox AnalyticModel::bounding_box(EntityRef e) const {
  check_tag(e);
  switch (e.dim) {
    case 0: {
      BoundingBox b;
      b.add(vertex_point(e.tag));
      return b;
    }
    case 1: return edge_record(e.tag).curve->box();
    case 2: return face_record(e.tag).surface->box();
    default: return box_;
  }
}

std::vector<OrientedUse> AnalyticModel::region_faces(int region) const {
  return region_record(region).faces;
}

std::vector<Loop> AnalyticModel::face_loops(int face) const {
  std::vector<Loop> loops;
  for (const FaceLoop& record : face_record(face).loops) {
    Loop loop;
    loop.outer = record.outer;
    for (const EdgeUse& use : record.uses) loop.edges.push_back({use.edge, use.forward});
    loops.push_back(std::move(loop));
  }
  return loops;
}

std::vector<int> AnalyticModel::upward(EntityRef e) const {
  check_tag(e);
  if (e.dim == 3) return {};
  return upward_[static_cast<std::size_t>(e.dim)][static_cast<std::size_t>(e.tag - 1)];
}

double AnalyticModel::tolerance(EntityRef e) const {
  check_tag(e);
  return tolerance_;
}

ParamRange AnalyticModel::param_range(EntityRef e) const {
  check_tag(e);
  if (e.dim == 1) return edge_record(e.tag).curve->range();
  if (e.dim == 2) return face_record(e.tag).surface->range();
  return {};
}

Vec3 AnalyticModel::vertex_point(int vertex) const {
  check_tag({0, vertex});
  return vertices_[static_cast<std::size_t>(vertex - 1)];
}

CurveDerivatives AnalyticModel::edge_derivatives(int edge, double u) const {
  return edge_record(edge).curve->derivatives(u);
}

SurfaceDerivatives AnalyticModel::face_derivatives(int face, const Vec2& uv) const {
  return face_record(face).surface->derivatives(uv);
}

Vec3 AnalyticModel::face_normal(int face, const Vec2& uv) const {
  const Vec3 n = face_record(face).surface->normal(uv);
  return face_reversed_[static_cast<std::size_t>(face - 1)] ? Vec3(-n) : n;
}

Curvatures AnalyticModel::face_curvatures(int face, const Vec2& uv) const {
  const Curvatures k = face_record(face).surface->curvatures(uv);
  if (!face_reversed_[static_cast<std::size_t>(face - 1)]) return k;
  // Flipping the normal negates both curvatures, which swaps their order;
  // swapping the directions keeps dir1 × dir2 along the (flipped) normal.
  Curvatures flipped;
  flipped.k1 = -k.k2;
  flipped.k2 = -k.k1;
  flipped.dir1 = k.dir2;
  flipped.dir2 = k.dir1;
  return flipped;
}

double AnalyticModel::edge_curvature(int edge, double u) const {
  return edge_record(edge).curve->curvature(u);
}

Projection AnalyticModel::closest_point(EntityRef e, const Vec3& x, std::optional<Vec2> hint) const {
  check_tag(e);
  switch (e.dim) {
    case 0: {
      const Vec3 p = vertex_point(e.tag);
      return {p, Vec2::Zero(), (x - p).norm()};
    }
    case 1: {
      std::optional<double> t;
      if (hint) t = hint->x();
      return edge_record(e.tag).curve->project(x, t);
    }
    case 2: return face_record(e.tag).surface->project(x, hint);
    default:
      throw std::invalid_argument(
          fmt::format("analytic model: closest_point is defined on vertices, edges and faces, not on region {}", e.tag));
  }
}

Vec2 AnalyticModel::edge_param_on_face(int edge, int face, double u, bool forward) const {
  check_tag({1, edge});
  const EdgeUse* found = nullptr;
  for (const FaceLoop& loop : face_record(face).loops) {
    for (const EdgeUse& use : loop.uses) {
      if (use.edge != edge) continue;
      // A seam has two uses with different p-curves; any other edge has one
      // and `forward` does not matter.
      if (!found || use.forward == forward) found = &use;
    }
  }
  if (!found)
    throw std::invalid_argument(fmt::format("analytic model: edge {} does not bound face {}", edge, face));
  return found->pcurve.at(u);
}

bool AnalyticModel::contains_param(int face, const Vec2& uv) const {
  return face_record(face).surface->contains(uv, tolerance_);
}

Containment AnalyticModel::classify_point(int region, const Vec3& x) const {
  const RegionRecord& r = region_record(region);
  if (!x.allFinite())
    throw std::invalid_argument(fmt::format("analytic model: classify_point at a non-finite point ({}, {}, {})",
                                            x.x(), x.y(), x.z()));
  const double d = r.signed_distance(x);
  if (d < -tolerance_) return Containment::kInside;
  if (d > tolerance_) return Containment::kOutside;
  return Containment::kOn;
}

// --- factories ---------------------------------------------------------------

bool is_finite(const Vec3& v) { return v.allFinite(); }

void require(bool ok, const std::string& what) {
  if (!ok) throw GeometryError("analytic model: " + what);
}

Vec3 checked_axis(const Vec3& axis_dir) {
  require(is_finite(axis_dir) && axis_dir.norm() > 0.0,
          fmt::format("the axis direction ({}, {}, {}) must be finite and non-zero", axis_dir.x(),
                      axis_dir.y(), axis_dir.z()));
  return axis_dir.normalized();
}

void require_positive(double value, const char* name) {
  require(std::isfinite(value) && value > 0.0, fmt::format("the {} ({}) must be finite and positive", name, value));
}

/// The same frame with its origin moved along z, for the parallel circles
/// and caps of the cylinder.
Frame shifted(const Frame& f, double along_z) {
  Frame g = f;
  g.origin = f.origin + along_z * f.z;
  return g;
}

/// Frame of a meridian circle: x in the equator, y along the axis.
Frame meridian_frame(const Frame& f, const Vec3& center) {
  Frame g;
  g.origin = center;
  g.x = f.x;
  g.y = f.z;
  g.z = f.x.cross(f.z);
  return g;
}

EdgeRecord make_edge(std::unique_ptr<Curve> curve, int v0, int v1, bool degenerate = false) {
  EdgeRecord e;
  e.curve = std::move(curve);
  e.vertices = {v0, v1};
  e.degenerate = degenerate;
  return e;
}

/// The loop shared by the three periodic faces (OpenCASCADE's order): the
/// v = v1 boundary backwards, the u = 0 side of the seam downwards, the
/// v = v0 boundary forwards, the u = 2π side upwards — counter-clockwise in
/// (u, v), i.e. the face on the left seen along du × dv.
FaceLoop rectangle_loop(int top_edge, int seam_edge, int bottom_edge, double v0, double v1) {
  FaceLoop loop;
  loop.uses = {
      {top_edge, false, line_pcurve({0.0, v1}, {1.0, 0.0})},
      {seam_edge, false, line_pcurve({0.0, 0.0}, {0.0, 1.0})},
      {bottom_edge, true, line_pcurve({0.0, v0}, {1.0, 0.0})},
      {seam_edge, true, line_pcurve({kTwoPi, 0.0}, {0.0, 1.0})},
  };
  return loop;
}

}  // namespace

Vec3 analytic_reference_direction(const Vec3& axis_dir) {
  return analytic::reference_x_direction(checked_axis(axis_dir));
}

std::unique_ptr<Model> make_analytic_sphere(const Vec3& center, double radius) {
  require(is_finite(center), "the sphere centre must be finite");
  require_positive(radius, "sphere radius");
  Frame frame;
  frame.origin = center;
  const Vec3 north = center + radius * frame.z;
  const Vec3 south = center - radius * frame.z;

  std::vector<EdgeRecord> edges;
  edges.push_back(make_edge(std::make_unique<analytic::CollapsedCurve>(north, 0.0, kTwoPi), 1, 1, true));
  edges.push_back(make_edge(
      std::make_unique<analytic::CircleArc>(meridian_frame(frame, center), radius, -0.5 * kPi, 0.5 * kPi), 2, 1));
  edges.push_back(make_edge(std::make_unique<analytic::CollapsedCurve>(south, 0.0, kTwoPi), 2, 2, true));

  std::vector<FaceRecord> faces(1);
  faces[0].surface = std::make_unique<analytic::SphereSurface>(frame, radius);
  faces[0].loops.push_back(rectangle_loop(1, 2, 3, -0.5 * kPi, 0.5 * kPi));

  std::vector<RegionRecord> regions(1);
  regions[0].faces = {{1, true}};
  regions[0].volume = 4.0 / 3.0 * kPi * radius * radius * radius;
  regions[0].center_of_mass = center;
  regions[0].signed_distance = [center, radius](const Vec3& x) { return (x - center).norm() - radius; };
  return std::make_unique<AnalyticModel>(std::vector<Vec3>{north, south}, std::move(edges),
                                         std::move(faces), std::move(regions));
}

std::unique_ptr<Model> make_analytic_cylinder(const Vec3& base_center, const Vec3& axis_dir,
                                              double radius, double height) {
  require(is_finite(base_center), "the cylinder base centre must be finite");
  const Vec3 axis = checked_axis(axis_dir);
  require_positive(radius, "cylinder radius");
  require_positive(height, "cylinder height");
  const Frame bottom = analytic::make_axis_frame(base_center, axis);
  const Frame top = shifted(bottom, height);
  const Vec3 top_vertex = top.origin + radius * top.x;
  const Vec3 bottom_vertex = bottom.origin + radius * bottom.x;

  std::vector<EdgeRecord> edges;
  edges.push_back(make_edge(std::make_unique<analytic::CircleArc>(top, radius, 0.0, kTwoPi), 1, 1));
  edges.push_back(make_edge(std::make_unique<analytic::Segment>(bottom_vertex, bottom.z, 0.0, height), 2, 1));
  edges.push_back(make_edge(std::make_unique<analytic::CircleArc>(bottom, radius, 0.0, kTwoPi), 2, 2));

  std::vector<FaceRecord> faces(3);
  faces[0].surface = std::make_unique<analytic::CylinderSurface>(bottom, radius, height);
  faces[0].loops.push_back(rectangle_loop(1, 2, 3, 0.0, height));
  faces[1].surface = std::make_unique<analytic::DiskSurface>(top, radius);
  faces[1].loops.push_back({{{1, true, circle_pcurve(radius)}}, true});
  // Both caps share the axis as plane normal; the bottom one is used reversed,
  // so its loop runs clockwise in (u, v) and counter-clockwise about -axis.
  faces[2].surface = std::make_unique<analytic::DiskSurface>(bottom, radius);
  faces[2].loops.push_back({{{3, false, circle_pcurve(radius)}}, true});

  std::vector<RegionRecord> regions(1);
  regions[0].faces = {{1, true}, {2, true}, {3, false}};
  regions[0].volume = kPi * radius * radius * height;
  regions[0].center_of_mass = base_center + 0.5 * height * axis;
  regions[0].signed_distance = [bottom, radius, height](const Vec3& x) {
    // Distance to the box |radial| <= R, 0 <= axial <= H in the (radial,
    // axial) half-plane: outside, the distance to the nearest of the lateral
    // face, a cap or their rim; inside, minus the distance to the nearest face.
    const Vec3 l = bottom.to_local(x);
    const double radial = std::hypot(l.x(), l.y()) - radius;
    const double axial = std::max(-l.z(), l.z() - height);
    return std::min(std::max(radial, axial), 0.0) + std::hypot(std::max(radial, 0.0), std::max(axial, 0.0));
  };
  return std::make_unique<AnalyticModel>(std::vector<Vec3>{top_vertex, bottom_vertex}, std::move(edges),
                                         std::move(faces), std::move(regions));
}

std::unique_ptr<Model> make_analytic_torus(const Vec3& center, const Vec3& axis_dir,
                                           double major_radius, double minor_radius) {
  require(is_finite(center), "the torus centre must be finite");
  const Vec3 axis = checked_axis(axis_dir);
  require_positive(minor_radius, "torus minor radius");
  require(std::isfinite(major_radius) && major_radius > minor_radius,
          fmt::format("the torus major radius ({}) must exceed the minor radius ({})", major_radius,
                      minor_radius));
  const Frame frame = analytic::make_axis_frame(center, axis);
  const Vec3 vertex = center + (major_radius + minor_radius) * frame.x;

  std::vector<EdgeRecord> edges;
  edges.push_back(make_edge(
      std::make_unique<analytic::CircleArc>(frame, major_radius + minor_radius, 0.0, kTwoPi), 1, 1));
  edges.push_back(make_edge(std::make_unique<analytic::CircleArc>(
                                meridian_frame(frame, center + major_radius * frame.x), minor_radius, 0.0, kTwoPi),
                            1, 1));

  std::vector<FaceRecord> faces(1);
  faces[0].surface = std::make_unique<analytic::TorusSurface>(frame, major_radius, minor_radius);
  faces[0].loops.push_back(rectangle_loop(1, 2, 1, 0.0, kTwoPi));

  std::vector<RegionRecord> regions(1);
  regions[0].faces = {{1, true}};
  regions[0].volume = 2.0 * kPi * kPi * major_radius * minor_radius * minor_radius;
  regions[0].center_of_mass = center;
  regions[0].signed_distance = [frame, major_radius, minor_radius](const Vec3& x) {
    const Vec3 l = frame.to_local(x);
    return std::hypot(std::hypot(l.x(), l.y()) - major_radius, l.z()) - minor_radius;
  };
  return std::make_unique<AnalyticModel>(std::vector<Vec3>{vertex}, std::move(edges), std::move(faces),
                                         std::move(regions));
}

}  // namespace cm::geom
