// Closed-form curves and surfaces of the analytic model. Closest points are
// computed by reducing the probe to the shape's own frame, where each shape
// is a circle, a line or a plane in a meridian half-plane, so no iteration
// (and no hint) is needed; the hint only decides ties that the geometry
// leaves open (a probe on an axis, a parameter on a seam).
#include "curvemesh/geom/analytic_shapes.hpp"

#include <algorithm>
#include <cmath>

namespace cm::geom::analytic {

namespace {

/// Angular distance (radians) from a seam within which a projected
/// parameter may be moved onto the seam side the caller's hint asks for.
constexpr double kSeamSnap = 1e-12;

/// t shifted by whole periods into [lo, lo + 2π).
double wrap_into(double t, double lo) {
  double a = std::fmod(t - lo, kTwoPi);
  if (a < 0) a += kTwoPi;
  return lo + a;
}

/// The parameter to report when every parameter is equally close (probe on
/// the axis or at the centre): the hint if it is usable, otherwise `fallback`.
double tie_parameter(std::optional<double> hint, double lo, double hi, bool periodic,
                     double fallback) {
  if (!hint || !std::isfinite(*hint)) return fallback;
  if (periodic) return wrap_into(*hint, lo);
  return std::clamp(*hint, lo, hi);
}

std::optional<double> hint_u(const std::optional<Vec2>& hint) {
  if (!hint) return std::nullopt;
  return hint->x();
}
std::optional<double> hint_v(const std::optional<Vec2>& hint) {
  if (!hint) return std::nullopt;
  return hint->y();
}

/// Box of c + r (cos t a + sin t b), t in [t0, t1]: per coordinate the
/// function is c_i + r A_i cos(t - φ_i), so its extremes are the end points
/// and the phases φ_i, φ_i + π that fall inside the range.
BoundingBox arc_box(const Vec3& c, const Vec3& a, const Vec3& b, double r, double t0, double t1) {
  BoundingBox box;
  const auto at = [&](double t) { return Vec3(c + r * (std::cos(t) * a + std::sin(t) * b)); };
  box.add(at(t0));
  box.add(at(t1));
  const bool full = t1 - t0 >= kTwoPi;
  for (int i = 0; i < 3; ++i) {
    const double amplitude = r * std::hypot(a[i], b[i]);
    const double phase = std::atan2(b[i], a[i]);
    if (full || wrap_into(phase, t0) <= t1) box.max[i] = std::max(box.max[i], c[i] + amplitude);
    if (full || wrap_into(phase + kPi, t0) <= t1) box.min[i] = std::min(box.min[i], c[i] - amplitude);
  }
  return box;
}

Projection make_projection(const Vec3& x, const Vec3& point, const Vec2& param) {
  return {point, param, (x - point).norm()};
}

}  // namespace

Vec3 reference_x_direction(const Vec3& axis) {
  const Vec3 a = axis.normalized();
  int least = 0;
  for (int i = 1; i < 3; ++i)
    if (std::abs(a[i]) < std::abs(a[least])) least = i;
  const Vec3 e = Vec3::Unit(least);
  return (e - e.dot(a) * a).normalized();
}

Frame make_axis_frame(const Vec3& origin, const Vec3& axis) {
  Frame f;
  f.origin = origin;
  f.z = axis.normalized();
  f.x = reference_x_direction(f.z);
  f.y = f.z.cross(f.x);
  return f;
}

double angle_from(double y, double x, double lo) {
  double a = std::atan2(y, x);
  while (a < lo) a += kTwoPi;
  while (a > lo + kTwoPi) a -= kTwoPi;
  return a;
}

double pick_seam_side(double a, double lo, std::optional<double> hint) {
  const double hi = lo + kTwoPi;
  if (!hint || !std::isfinite(*hint)) return a == hi ? lo : a;
  // A probe on the seam comes out of atan2 a few ulps to either side of it;
  // within kSeamSnap (a 3D move of 1e-12 × radius) it is taken as on the
  // seam so that the hint, not the rounding, picks the side.
  const bool hint_on_high_side = *hint > lo + kPi;
  if (hint_on_high_side && a - lo <= kSeamSnap) return hi;
  if (!hint_on_high_side && hi - a <= kSeamSnap) return lo;
  return a;
}

// --- CircleArc ---------------------------------------------------------------

CircleArc::CircleArc(const Frame& frame, double radius, double t0, double t1)
    : frame_(frame), radius_(radius), t0_(t0), t1_(std::min(t1, t0 + kTwoPi)) {}

ParamRange CircleArc::range() const {
  ParamRange r;
  r.u0 = t0_;
  r.u1 = t1_;
  if (is_full()) {
    r.periodic_u = true;
    r.period_u = kTwoPi;
  }
  return r;
}

CurveDerivatives CircleArc::derivatives(double t) const {
  const double c = std::cos(t), s = std::sin(t);
  const Vec3 radial = c * frame_.x + s * frame_.y;
  const Vec3 tangent = -s * frame_.x + c * frame_.y;
  return {frame_.origin + radius_ * radial, radius_ * tangent, -radius_ * radial};
}

Projection CircleArc::project(const Vec3& x, std::optional<double> hint) const {
  const Vec3 l = frame_.to_local(x);
  double t;
  if (l.x() == 0.0 && l.y() == 0.0) {
    t = tie_parameter(hint, t0_, t1_, is_full(), t0_);
  } else {
    t = angle_from(l.y(), l.x(), t0_);
    if (is_full()) {
      t = pick_seam_side(t, t0_, hint);
    } else if (t > t1_) {
      // Outside the arc the distance grows with the angular gap, so the
      // answer is the nearer end point.
      const double d0 = (derivatives(t0_).point - x).squaredNorm();
      const double d1 = (derivatives(t1_).point - x).squaredNorm();
      t = d1 < d0 ? t1_ : t0_;
    }
  }
  return make_projection(x, derivatives(t).point, Vec2(t, 0.0));
}

BoundingBox CircleArc::box() const {
  return arc_box(frame_.origin, frame_.x, frame_.y, radius_, t0_, t1_);
}

// --- Segment -----------------------------------------------------------------

Segment::Segment(const Vec3& origin, const Vec3& unit_dir, double t0, double t1)
    : origin_(origin), dir_(unit_dir), t0_(t0), t1_(t1) {}

ParamRange Segment::range() const {
  ParamRange r;
  r.u0 = t0_;
  r.u1 = t1_;
  return r;
}

CurveDerivatives Segment::derivatives(double t) const {
  return {origin_ + t * dir_, dir_, Vec3::Zero()};
}

Projection Segment::project(const Vec3& x, std::optional<double>) const {
  const double t = std::clamp((x - origin_).dot(dir_), t0_, t1_);
  return make_projection(x, derivatives(t).point, Vec2(t, 0.0));
}

BoundingBox Segment::box() const {
  BoundingBox b;
  b.add(derivatives(t0_).point);
  b.add(derivatives(t1_).point);
  return b;
}

// --- CollapsedCurve ----------------------------------------------------------

ParamRange CollapsedCurve::range() const {
  ParamRange r;
  r.u0 = t0_;
  r.u1 = t1_;
  return r;
}

CurveDerivatives CollapsedCurve::derivatives(double) const {
  return {point_, Vec3::Zero(), Vec3::Zero()};
}

Projection CollapsedCurve::project(const Vec3& x, std::optional<double> hint) const {
  const double t = tie_parameter(hint, t0_, t1_, false, t0_);
  return make_projection(x, point_, Vec2(t, 0.0));
}

BoundingBox CollapsedCurve::box() const {
  BoundingBox b;
  b.add(point_);
  return b;
}

// --- SphereSurface -----------------------------------------------------------

ParamRange SphereSurface::range() const {
  ParamRange r;
  r.u0 = 0.0;
  r.u1 = kTwoPi;
  r.v0 = -0.5 * kPi;
  r.v1 = 0.5 * kPi;
  r.periodic_u = true;
  r.period_u = kTwoPi;
  return r;
}

SurfaceDerivatives SphereSurface::derivatives(const Vec2& uv) const {
  const double cu = std::cos(uv.x()), su = std::sin(uv.x());
  const double cv = std::cos(uv.y()), sv = std::sin(uv.y());
  const double r = radius_;
  const Vec3 radial = cu * frame_.x + su * frame_.y;   // unit, in the equator plane
  const Vec3 east = -su * frame_.x + cu * frame_.y;    // d(radial)/du
  const Vec3 up = frame_.z;
  SurfaceDerivatives d;
  d.point = frame_.origin + r * (cv * radial + sv * up);
  d.du = r * cv * east;
  d.dv = r * (-sv * radial + cv * up);
  d.duu = -r * cv * radial;
  d.duv = -r * sv * east;
  d.dvv = -r * (cv * radial + sv * up);
  return d;
}

Vec3 SphereSurface::normal(const Vec2& uv) const {
  const double cv = std::cos(uv.y()), sv = std::sin(uv.y());
  return cv * (std::cos(uv.x()) * frame_.x + std::sin(uv.x()) * frame_.y) + sv * frame_.z;
}

Curvatures SphereSurface::curvatures(const Vec2& uv) const {
  const double cu = std::cos(uv.x()), su = std::sin(uv.x());
  const double cv = std::cos(uv.y()), sv = std::sin(uv.y());
  Curvatures k;
  k.k1 = k.k2 = 1.0 / radius_;
  // Unit east and north: well defined even at the poles, where du vanishes.
  k.dir1 = -su * frame_.x + cu * frame_.y;
  k.dir2 = -sv * (cu * frame_.x + su * frame_.y) + cv * frame_.z;
  return k;
}

Projection SphereSurface::project(const Vec3& x, std::optional<Vec2> hint) const {
  const Vec3 l = frame_.to_local(x);
  const double rho = std::hypot(l.x(), l.y());
  double u, v;
  if (rho == 0.0 && l.z() == 0.0) {
    u = tie_parameter(hint_u(hint), 0.0, kTwoPi, true, 0.0);
    v = tie_parameter(hint_v(hint), -0.5 * kPi, 0.5 * kPi, false, 0.0);
  } else {
    u = rho == 0.0 ? tie_parameter(hint_u(hint), 0.0, kTwoPi, true, 0.0)
                   : pick_seam_side(angle_from(l.y(), l.x(), 0.0), 0.0, hint_u(hint));
    v = std::atan2(l.z(), rho);
  }
  return make_projection(x, derivatives({u, v}).point, {u, v});
}

bool SphereSurface::contains(const Vec2& uv, double tolerance) const {
  const double slack = tolerance / radius_;
  return std::isfinite(uv.x()) && uv.y() >= -0.5 * kPi - slack && uv.y() <= 0.5 * kPi + slack;
}

BoundingBox SphereSurface::box() const {
  BoundingBox b;
  b.add(frame_.origin - Vec3::Constant(radius_));
  b.add(frame_.origin + Vec3::Constant(radius_));
  return b;
}

// --- CylinderSurface ---------------------------------------------------------

ParamRange CylinderSurface::range() const {
  ParamRange r;
  r.u0 = 0.0;
  r.u1 = kTwoPi;
  r.v0 = 0.0;
  r.v1 = height_;
  r.periodic_u = true;
  r.period_u = kTwoPi;
  return r;
}

SurfaceDerivatives CylinderSurface::derivatives(const Vec2& uv) const {
  const double cu = std::cos(uv.x()), su = std::sin(uv.x());
  const Vec3 radial = cu * frame_.x + su * frame_.y;
  const Vec3 east = -su * frame_.x + cu * frame_.y;
  SurfaceDerivatives d;
  d.point = frame_.origin + radius_ * radial + uv.y() * frame_.z;
  d.du = radius_ * east;
  d.dv = frame_.z;
  d.duu = -radius_ * radial;
  d.duv = Vec3::Zero();
  d.dvv = Vec3::Zero();
  return d;
}

Vec3 CylinderSurface::normal(const Vec2& uv) const {
  return std::cos(uv.x()) * frame_.x + std::sin(uv.x()) * frame_.y;
}

Curvatures CylinderSurface::curvatures(const Vec2& uv) const {
  Curvatures k;
  k.k1 = 1.0 / radius_;
  k.k2 = 0.0;
  k.dir1 = -std::sin(uv.x()) * frame_.x + std::cos(uv.x()) * frame_.y;
  k.dir2 = frame_.z;
  return k;
}

Projection CylinderSurface::project(const Vec3& x, std::optional<Vec2> hint) const {
  const Vec3 l = frame_.to_local(x);
  // u and v decouple: the squared distance is (rho - R)² + (z - v)², so the
  // trimmed answer just clamps v.
  const double u = (l.x() == 0.0 && l.y() == 0.0)
                       ? tie_parameter(hint_u(hint), 0.0, kTwoPi, true, 0.0)
                       : pick_seam_side(angle_from(l.y(), l.x(), 0.0), 0.0, hint_u(hint));
  const double v = std::clamp(l.z(), 0.0, height_);
  return make_projection(x, derivatives({u, v}).point, {u, v});
}

bool CylinderSurface::contains(const Vec2& uv, double tolerance) const {
  return std::isfinite(uv.x()) && uv.y() >= -tolerance && uv.y() <= height_ + tolerance;
}

BoundingBox CylinderSurface::box() const {
  BoundingBox b = arc_box(frame_.origin, frame_.x, frame_.y, radius_, 0.0, kTwoPi);
  const BoundingBox top =
      arc_box(frame_.origin + height_ * frame_.z, frame_.x, frame_.y, radius_, 0.0, kTwoPi);
  b.add(top.min);
  b.add(top.max);
  return b;
}

// --- DiskSurface -------------------------------------------------------------

ParamRange DiskSurface::range() const {
  ParamRange r;
  r.u0 = r.v0 = -radius_;
  r.u1 = r.v1 = radius_;
  return r;
}

SurfaceDerivatives DiskSurface::derivatives(const Vec2& uv) const {
  SurfaceDerivatives d;
  d.point = frame_.origin + uv.x() * frame_.x + uv.y() * frame_.y;
  d.du = frame_.x;
  d.dv = frame_.y;
  d.duu = d.duv = d.dvv = Vec3::Zero();
  return d;
}

Curvatures DiskSurface::curvatures(const Vec2&) const {
  Curvatures k;
  k.k1 = k.k2 = 0.0;
  k.dir1 = frame_.x;
  k.dir2 = frame_.y;
  return k;
}

Projection DiskSurface::project(const Vec3& x, std::optional<Vec2>) const {
  const Vec3 l = frame_.to_local(x);
  Vec2 uv(l.x(), l.y());
  const double rho = uv.norm();
  if (rho > radius_) {
    uv *= radius_ / rho;
    // The rescaling may overshoot by an ulp; keep the parameter in range.
    uv = uv.cwiseMax(-radius_).cwiseMin(radius_);
  }
  return make_projection(x, derivatives(uv).point, uv);
}

bool DiskSurface::contains(const Vec2& uv, double tolerance) const {
  return std::hypot(uv.x(), uv.y()) <= radius_ + tolerance;
}

BoundingBox DiskSurface::box() const {
  return arc_box(frame_.origin, frame_.x, frame_.y, radius_, 0.0, kTwoPi);
}

// --- TorusSurface ------------------------------------------------------------

ParamRange TorusSurface::range() const {
  ParamRange r;
  r.u0 = r.v0 = 0.0;
  r.u1 = r.v1 = kTwoPi;
  r.periodic_u = r.periodic_v = true;
  r.period_u = r.period_v = kTwoPi;
  return r;
}

SurfaceDerivatives TorusSurface::derivatives(const Vec2& uv) const {
  const double cu = std::cos(uv.x()), su = std::sin(uv.x());
  const double cv = std::cos(uv.y()), sv = std::sin(uv.y());
  const Vec3 radial = cu * frame_.x + su * frame_.y;
  const Vec3 east = -su * frame_.x + cu * frame_.y;
  const Vec3& up = frame_.z;
  const double ring = major_ + minor_ * cv;  // distance to the axis
  SurfaceDerivatives d;
  d.point = frame_.origin + ring * radial + minor_ * sv * up;
  d.du = ring * east;
  d.dv = minor_ * (-sv * radial + cv * up);
  d.duu = -ring * radial;
  d.duv = -minor_ * sv * east;
  d.dvv = -minor_ * (cv * radial + sv * up);
  return d;
}

Vec3 TorusSurface::normal(const Vec2& uv) const {
  const double cv = std::cos(uv.y()), sv = std::sin(uv.y());
  return cv * (std::cos(uv.x()) * frame_.x + std::sin(uv.x()) * frame_.y) + sv * frame_.z;
}

Curvatures TorusSurface::curvatures(const Vec2& uv) const {
  const double cu = std::cos(uv.x()), su = std::sin(uv.x());
  const double cv = std::cos(uv.y()), sv = std::sin(uv.y());
  Curvatures k;
  // Around the tube the section is a circle of radius r, convex outward.
  // Along a parallel, Meusnier: the parallel's curvature 1/(R + r cos v)
  // projected on the normal, which changes sign on the inner half.
  k.k1 = 1.0 / minor_;
  k.k2 = cv / (major_ + minor_ * cv);
  k.dir1 = -sv * (cu * frame_.x + su * frame_.y) + cv * frame_.z;
  k.dir2 = su * frame_.x - cu * frame_.y;  // minus east, so dir1 × dir2 = normal
  return k;
}

Projection TorusSurface::project(const Vec3& x, std::optional<Vec2> hint) const {
  const Vec3 l = frame_.to_local(x);
  const double rho = std::hypot(l.x(), l.y());
  // The nearest point lies in the meridian half-plane through the probe; in
  // that half-plane the torus is the circle of radius r around (R, 0).
  const double u = rho == 0.0 ? tie_parameter(hint_u(hint), 0.0, kTwoPi, true, 0.0)
                              : pick_seam_side(angle_from(l.y(), l.x(), 0.0), 0.0, hint_u(hint));
  const double dr = rho - major_;
  const double v = (dr == 0.0 && l.z() == 0.0)
                       ? tie_parameter(hint_v(hint), 0.0, kTwoPi, true, 0.0)
                       : pick_seam_side(angle_from(l.z(), dr, 0.0), 0.0, hint_v(hint));
  return make_projection(x, derivatives({u, v}).point, {u, v});
}

bool TorusSurface::contains(const Vec2& uv, double) const {
  return std::isfinite(uv.x()) && std::isfinite(uv.y());
}

BoundingBox TorusSurface::box() const {
  // Support function along a world axis e: R |e projected on the equator
  // plane| + r, since the tube circle can always turn fully towards e.
  BoundingBox b;
  Vec3 extent;
  for (int i = 0; i < 3; ++i) {
    const double axial = frame_.z[i];
    extent[i] = major_ * std::sqrt(std::max(0.0, 1.0 - axial * axial)) + minor_;
  }
  b.add(frame_.origin - extent);
  b.add(frame_.origin + extent);
  return b;
}

}  // namespace cm::geom::analytic
