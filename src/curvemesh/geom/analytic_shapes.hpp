#pragma once
// Internal to the geom module: closed-form curves and surfaces that
// AnalyticModel assembles into solids. Each shape knows its own trimmed
// parameter range, so closest points and bounding boxes are exact (to
// rounding) and need no iteration. Not part of the public API.
//
// Every shape is immutable after construction, which is what makes the
// model's queries thread-safe without locks.
#include <numbers>
#include <optional>

#include "curvemesh/geom/model.hpp"

namespace cm::geom::analytic {

inline constexpr double kPi = std::numbers::pi;
inline constexpr double kTwoPi = 2.0 * std::numbers::pi;

/// Right-handed orthonormal frame: x, y, z unit and x × y = z.
struct Frame {
  Vec3 origin = Vec3::Zero();
  Vec3 x = Vec3::UnitX();
  Vec3 y = Vec3::UnitY();
  Vec3 z = Vec3::UnitZ();

  /// Coordinates of p in this frame.
  Vec3 to_local(const Vec3& p) const {
    const Vec3 d = p - origin;
    return {d.dot(x), d.dot(y), d.dot(z)};
  }
};

/// Unit vector perpendicular to `axis` (which need not be unit): the world
/// axis least aligned with `axis`, with its `axis` component removed. Gives
/// +X for a +Z axis, like OpenCASCADE's gp_Ax2 default.
Vec3 reference_x_direction(const Vec3& axis);

/// Frame with z along `axis` and x = reference_x_direction(axis).
Frame make_axis_frame(const Vec3& origin, const Vec3& axis);

/// The representative of a periodic angle `a` (already in [lo, lo + 2π]) to
/// report: on the seam (within 1e-12 rad of lo or lo + 2π) both ends name the
/// same point, so pick the end on the hint's side (lo without a hint).
double pick_seam_side(double a, double lo, std::optional<double> hint);

/// `atan2(y, x)` mapped to [lo, lo + 2π].
double angle_from(double y, double x, double lo);

// --- curves ----------------------------------------------------------------

class Curve {
 public:
  virtual ~Curve() = default;
  virtual ShapeType type() const = 0;
  virtual ParamRange range() const = 0;
  /// Derivatives of the underlying (untrimmed) curve at t.
  virtual CurveDerivatives derivatives(double t) const = 0;
  /// Unsigned curvature 1 / radius; 0 for a line or a collapsed curve.
  virtual double curvature(double t) const = 0;
  /// Exact closest point on the trimmed curve. `hint` only breaks ties
  /// (a probe equidistant to several points, a seam parameter).
  virtual Projection project(const Vec3& x, std::optional<double> hint) const = 0;
  virtual BoundingBox box() const = 0;
  virtual double length() const = 0;
};

/// p(t) = c + r (cos t x + sin t y), t in [t0, t1], t1 - t0 <= 2π. A range
/// of exactly 2π is a full, periodic circle.
class CircleArc final : public Curve {
 public:
  CircleArc(const Frame& frame, double radius, double t0, double t1);
  ShapeType type() const override { return ShapeType::kCircle; }
  ParamRange range() const override;
  CurveDerivatives derivatives(double t) const override;
  double curvature(double) const override { return 1.0 / radius_; }
  Projection project(const Vec3& x, std::optional<double> hint) const override;
  BoundingBox box() const override;
  double length() const override { return radius_ * (t1_ - t0_); }

 private:
  bool is_full() const { return t1_ - t0_ >= kTwoPi; }
  Frame frame_;
  double radius_, t0_, t1_;
};

/// p(t) = o + t d with |d| = 1, t in [t0, t1].
class Segment final : public Curve {
 public:
  Segment(const Vec3& origin, const Vec3& unit_dir, double t0, double t1);
  ShapeType type() const override { return ShapeType::kLine; }
  ParamRange range() const override;
  CurveDerivatives derivatives(double t) const override;
  double curvature(double) const override { return 0.0; }
  Projection project(const Vec3& x, std::optional<double> hint) const override;
  BoundingBox box() const override;
  double length() const override { return t1_ - t0_; }

 private:
  Vec3 origin_, dir_;
  double t0_, t1_;
};

/// A degenerate edge: every t in [t0, t1] maps to the same point (a pole).
class CollapsedCurve final : public Curve {
 public:
  CollapsedCurve(const Vec3& point, double t0, double t1) : point_(point), t0_(t0), t1_(t1) {}
  ShapeType type() const override { return ShapeType::kPoint; }
  ParamRange range() const override;
  CurveDerivatives derivatives(double t) const override;
  double curvature(double) const override { return 0.0; }
  Projection project(const Vec3& x, std::optional<double> hint) const override;
  BoundingBox box() const override;
  double length() const override { return 0.0; }

 private:
  Vec3 point_;
  double t0_, t1_;
};

// --- surfaces --------------------------------------------------------------

class Surface {
 public:
  virtual ~Surface() = default;
  virtual ShapeType type() const = 0;
  virtual ParamRange range() const = 0;
  /// Derivatives of the underlying (untrimmed) surface at uv.
  virtual SurfaceDerivatives derivatives(const Vec2& uv) const = 0;
  /// Unit normal along du × dv, extended by continuity where du × dv = 0.
  virtual Vec3 normal(const Vec2& uv) const = 0;
  /// Principal curvatures signed with respect to normal(uv) (positive where
  /// the surface bends away from it), with dir1 × dir2 = normal(uv).
  virtual Curvatures curvatures(const Vec2& uv) const = 0;
  /// Exact closest point on the trimmed surface; `hint` only breaks ties.
  virtual Projection project(const Vec3& x, std::optional<Vec2> hint) const = 0;
  /// Whether uv lies in the trimmed domain, widened by `tolerance` (a 3D
  /// distance); periodic parameters are taken modulo their period.
  virtual bool contains(const Vec2& uv, double tolerance) const = 0;
  virtual BoundingBox box() const = 0;
  virtual double area() const = 0;
};

/// p(u, v) = c + R (cos v cos u x + cos v sin u y + sin v z),
/// u in [0, 2π] periodic (longitude), v in [-π/2, π/2] (latitude).
class SphereSurface final : public Surface {
 public:
  SphereSurface(const Frame& frame, double radius) : frame_(frame), radius_(radius) {}
  ShapeType type() const override { return ShapeType::kSphere; }
  ParamRange range() const override;
  SurfaceDerivatives derivatives(const Vec2& uv) const override;
  Vec3 normal(const Vec2& uv) const override;
  Curvatures curvatures(const Vec2& uv) const override;
  Projection project(const Vec3& x, std::optional<Vec2> hint) const override;
  bool contains(const Vec2& uv, double tolerance) const override;
  BoundingBox box() const override;
  double area() const override { return 4.0 * kPi * radius_ * radius_; }

 private:
  Frame frame_;
  double radius_;
};

/// p(u, v) = c + R (cos u x + sin u y) + v z, u in [0, 2π] periodic,
/// v in [0, H].
class CylinderSurface final : public Surface {
 public:
  CylinderSurface(const Frame& frame, double radius, double height)
      : frame_(frame), radius_(radius), height_(height) {}
  ShapeType type() const override { return ShapeType::kCylinder; }
  ParamRange range() const override;
  SurfaceDerivatives derivatives(const Vec2& uv) const override;
  Vec3 normal(const Vec2& uv) const override;
  Curvatures curvatures(const Vec2& uv) const override;
  Projection project(const Vec3& x, std::optional<Vec2> hint) const override;
  bool contains(const Vec2& uv, double tolerance) const override;
  BoundingBox box() const override;
  double area() const override { return kTwoPi * radius_ * height_; }

 private:
  Frame frame_;
  double radius_, height_;
};

/// The plane p(u, v) = c + u x + v y trimmed to the disk u² + v² <= R².
class DiskSurface final : public Surface {
 public:
  DiskSurface(const Frame& frame, double radius) : frame_(frame), radius_(radius) {}
  ShapeType type() const override { return ShapeType::kPlane; }
  ParamRange range() const override;
  SurfaceDerivatives derivatives(const Vec2& uv) const override;
  Vec3 normal(const Vec2&) const override { return frame_.z; }
  Curvatures curvatures(const Vec2& uv) const override;
  Projection project(const Vec3& x, std::optional<Vec2> hint) const override;
  bool contains(const Vec2& uv, double tolerance) const override;
  BoundingBox box() const override;
  double area() const override { return kPi * radius_ * radius_; }

 private:
  Frame frame_;
  double radius_;
};

/// p(u, v) = c + (R + r cos v)(cos u x + sin u y) + r sin v z, u and v in
/// [0, 2π], both periodic; requires R > r > 0 (a ring torus).
class TorusSurface final : public Surface {
 public:
  TorusSurface(const Frame& frame, double major_radius, double minor_radius)
      : frame_(frame), major_(major_radius), minor_(minor_radius) {}
  ShapeType type() const override { return ShapeType::kTorus; }
  ParamRange range() const override;
  SurfaceDerivatives derivatives(const Vec2& uv) const override;
  Vec3 normal(const Vec2& uv) const override;
  Curvatures curvatures(const Vec2& uv) const override;
  Projection project(const Vec3& x, std::optional<Vec2> hint) const override;
  bool contains(const Vec2& uv, double tolerance) const override;
  BoundingBox box() const override;
  double area() const override { return 4.0 * kPi * kPi * major_ * minor_; }

 private:
  Frame frame_;
  double major_, minor_;
};

}  // namespace cm::geom::analytic
