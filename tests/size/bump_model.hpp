#pragma once
// A test model with one freeform face: the height field
//   z = A exp(-|(u,v) - c|² / w²)  over (u,v) in [0,1]²,
// a smooth plate with one narrow curvature peak of height A and width w at c.
// Only what curvature sampling asks of a model is implemented.
#include <cmath>
#include <stdexcept>
#include <string>

#include <Eigen/Dense>

#include "curvemesh/geom/model.hpp"

namespace cm::test {

class BumpModel final : public geom::Model {
 public:
  BumpModel(double height, double width, Vec2 centre) : a_(height), w_(width), c_(centre) {}

  /// Largest |κ| (at the top): the second derivative of the Gaussian there.
  double peak_curvature() const { return 2 * a_ / (w_ * w_); }

  int count(int dim) const override { return dim == 2 ? 1 : dim == 3 ? 0 : 4; }
  geom::ShapeType type(geom::EntityRef e) const override {
    return e.dim == 2 ? geom::ShapeType::kBSplineSurface : geom::ShapeType::kLine;
  }
  geom::BoundingBox bounding_box(geom::EntityRef) const override { return bounding_box(); }
  geom::BoundingBox bounding_box() const override {
    geom::BoundingBox b;
    b.add(Vec3(0, 0, 0));
    b.add(Vec3(1, 1, a_));
    return b;
  }
  std::vector<geom::OrientedUse> region_faces(int) const override { return {}; }
  std::vector<geom::Loop> face_loops(int) const override { return {geom::Loop{{{1, true}, {2, true}, {3, true}, {4, true}}, true}}; }
  std::array<int, 2> edge_vertices(int e) const override { return {e, e % 4 + 1}; }
  bool is_degenerate(int) const override { return false; }
  std::vector<int> upward(geom::EntityRef) const override { return {1}; }
  double tolerance(geom::EntityRef) const override { return 1e-9; }
  std::string units() const override { return ""; }

  geom::ParamRange param_range(geom::EntityRef e) const override {
    geom::ParamRange r;
    r.u1 = 1;
    r.v1 = e.dim == 2 ? 1 : 0;
    return r;
  }
  Vec3 vertex_point(int v) const override { return corner(v); }
  geom::CurveDerivatives edge_derivatives(int e, double u) const override {
    const Vec3 a = corner(e), b = corner(e % 4 + 1);
    return {a + u * (b - a), b - a, Vec3::Zero()};
  }
  geom::SurfaceDerivatives face_derivatives(int, const Vec2& uv) const override {
    const Vec2 d = uv - c_;
    const double g = a_ * std::exp(-d.squaredNorm() / (w_ * w_));
    const double s = -2 / (w_ * w_);
    // z = g; z_u = s du g; z_uu = s g + s² du² g; z_uv = s² du dv g.
    const double zu = s * d.x() * g, zv = s * d.y() * g;
    const double zuu = s * g + s * s * d.x() * d.x() * g, zvv = s * g + s * s * d.y() * d.y() * g;
    const double zuv = s * s * d.x() * d.y() * g;
    return {Vec3(uv.x(), uv.y(), g), Vec3(1, 0, zu), Vec3(0, 1, zv), Vec3(0, 0, zuu), Vec3(0, 0, zuv),
            Vec3(0, 0, zvv)};
  }
  Vec3 face_normal(int f, const Vec2& uv) const override {
    const auto d = face_derivatives(f, uv);
    return d.du.cross(d.dv).normalized();
  }
  geom::Curvatures face_curvatures(int f, const Vec2& uv) const override {
    const auto d = face_derivatives(f, uv);
    const Vec3 n = d.du.cross(d.dv).normalized();
    Eigen::Matrix2d first, second;
    first << d.du.dot(d.du), d.du.dot(d.dv), d.du.dot(d.dv), d.dv.dot(d.dv);
    second << -n.dot(d.duu), -n.dot(d.duv), -n.dot(d.duv), -n.dot(d.dvv);
    const Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::Matrix2d> es(second, first);
    geom::Curvatures c;
    c.k1 = es.eigenvalues()[1];
    c.k2 = es.eigenvalues()[0];
    const Eigen::Vector2d p1 = es.eigenvectors().col(1), p2 = es.eigenvectors().col(0);
    c.dir1 = (p1.x() * d.du + p1.y() * d.dv).normalized();
    c.dir2 = (p2.x() * d.du + p2.y() * d.dv).normalized();
    return c;
  }
  double edge_curvature(int, double) const override { return 0; }
  geom::Projection closest_point(geom::EntityRef, const Vec3&, std::optional<Vec2>) const override {
    throw std::logic_error("BumpModel: closest_point not needed");
  }
  Vec2 edge_param_on_face(int, int, double, bool) const override {
    throw std::logic_error("BumpModel: p-curves not needed");
  }
  bool contains_param(int, const Vec2& uv) const override {
    return uv.x() >= 0 && uv.x() <= 1 && uv.y() >= 0 && uv.y() <= 1;
  }
  geom::Containment classify_point(int region, const Vec3&) const override {
    throw std::out_of_range("BumpModel: an open plate has no region " + std::to_string(region));
  }
  double area(int) const override { return 1; }
  double length(int) const override { return 1; }
  double volume(int) const override { return 0; }
  Vec3 center_of_mass(int) const override { return Vec3::Zero(); }

 private:
  static Vec3 corner(int v) {
    static const Vec3 c[4] = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(1, 1, 0), Vec3(0, 1, 0)};
    return c[(v - 1) % 4];
  }
  double a_, w_;
  Vec2 c_;
};

}  // namespace cm::test
