#pragma once
// The size-field interface every mesher step queries (DESIGN.md, `size`).
//
// Contract:
// - size(x) > 0 is the requested edge length at x; metric(x) the requested
//   metric (SPD; I/size² for isotropic fields).
// - A hint (the model entity the point lies on and its parameters) is
//   optional; fields that use it (directional curvature) fall back to a point
//   query without it, fields that do not ignore it.
// - Queries are const and thread-safe once the field is built.
// - Points outside the field's domain get the value at the nearest point of
//   the domain (the octree clamps to its cube, background meshes to their
//   nearest element).
#include <functional>
#include <limits>
#include <memory>
#include <vector>

#include "curvemesh/core/types.hpp"
#include "curvemesh/geom/model.hpp"
#include "curvemesh/size/metric.hpp"

namespace cm::size {

struct SizeHint {
  geom::EntityRef entity{};  ///< dim -1: no hint
  Vec2 param = Vec2::Constant(std::numeric_limits<double>::quiet_NaN());
};

class SizeField {
 public:
  virtual ~SizeField() = default;
  virtual double size(const Vec3& x, const SizeHint& hint = {}) const = 0;
  virtual Metric metric(const Vec3& x, const SizeHint& hint = {}) const {
    return isotropic_metric(size(x, hint));
  }
  /// Whether metric() may be anisotropic.
  virtual bool anisotropic() const { return false; }
};

/// The same size everywhere.
class UniformSizeField final : public SizeField {
 public:
  explicit UniformSizeField(double h);
  double size(const Vec3&, const SizeHint& = {}) const override { return h_; }

 private:
  double h_;
};

/// A user function of the position (must return a finite h > 0; checked).
class AnalyticSizeField final : public SizeField {
 public:
  explicit AnalyticSizeField(std::function<double(const Vec3&)> h);
  double size(const Vec3& x, const SizeHint& hint = {}) const override;

 private:
  std::function<double(const Vec3&)> h_;
};

/// The finest of several fields: the minimum size, and the intersection of
/// the metrics (seed/MMG convention for combining size sources).
class MinSizeField final : public SizeField {
 public:
  void add(std::shared_ptr<const SizeField> field);
  bool empty() const { return fields_.empty(); }
  double size(const Vec3& x, const SizeHint& hint = {}) const override;
  Metric metric(const Vec3& x, const SizeHint& hint = {}) const override;
  bool anisotropic() const override;

 private:
  std::vector<std::shared_ptr<const SizeField>> fields_;
};

/// Sizes clamped to [hmin, hmax]; metric eigenvalues clamped to match.
class ClampedSizeField final : public SizeField {
 public:
  ClampedSizeField(std::shared_ptr<const SizeField> field, double hmin, double hmax);
  double size(const Vec3& x, const SizeHint& hint = {}) const override;
  Metric metric(const Vec3& x, const SizeHint& hint = {}) const override;
  bool anisotropic() const override { return field_->anisotropic(); }

 private:
  std::shared_ptr<const SizeField> field_;
  double hmin_, hmax_;
};

}  // namespace cm::size
