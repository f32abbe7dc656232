#include "curvemesh/size/size_field.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <fmt/format.h>

namespace cm::size {

UniformSizeField::UniformSizeField(double h) : h_(h) {
  if (!(h > 0) || !std::isfinite(h)) throw std::invalid_argument("uniform size must be finite and > 0");
}

AnalyticSizeField::AnalyticSizeField(std::function<double(const Vec3&)> h) : h_(std::move(h)) {}

double AnalyticSizeField::size(const Vec3& x, const SizeHint&) const {
  const double h = h_(x);
  if (!(h > 0) || !std::isfinite(h))
    throw std::domain_error(
        fmt::format("size function gives {} at ({}, {}, {}); sizes must be finite and > 0", h, x.x(), x.y(), x.z()));
  return h;
}

void MinSizeField::add(std::shared_ptr<const SizeField> field) {
  if (!field) throw std::invalid_argument("MinSizeField::add: null field");
  fields_.push_back(std::move(field));
}

double MinSizeField::size(const Vec3& x, const SizeHint& hint) const {
  if (fields_.empty()) throw std::logic_error("MinSizeField: no field added");
  double h = std::numeric_limits<double>::infinity();
  for (const auto& f : fields_) h = std::min(h, f->size(x, hint));
  return h;
}

Metric MinSizeField::metric(const Vec3& x, const SizeHint& hint) const {
  if (!anisotropic()) return isotropic_metric(size(x, hint));
  Metric m = fields_.front()->metric(x, hint);
  for (std::size_t i = 1; i < fields_.size(); ++i) m = intersect(m, fields_[i]->metric(x, hint));
  return m;
}

bool MinSizeField::anisotropic() const {
  return std::any_of(fields_.begin(), fields_.end(), [](const auto& f) { return f->anisotropic(); });
}

ClampedSizeField::ClampedSizeField(std::shared_ptr<const SizeField> field, double hmin, double hmax)
    : field_(std::move(field)), hmin_(hmin), hmax_(hmax) {
  if (!field_) throw std::invalid_argument("ClampedSizeField: null field");
  if (!(hmin > 0) || !(hmax >= hmin) || !std::isfinite(hmin))
    throw std::invalid_argument(fmt::format("need 0 < hmin <= hmax (got hmin {}, hmax {})", hmin, hmax));
}

double ClampedSizeField::size(const Vec3& x, const SizeHint& hint) const {
  return std::clamp(field_->size(x, hint), hmin_, hmax_);
}

Metric ClampedSizeField::metric(const Vec3& x, const SizeHint& hint) const {
  if (!field_->anisotropic()) return isotropic_metric(size(x, hint));
  Mat3 dirs;
  Vec3 h = metric_sizes(field_->metric(x, hint), &dirs);
  for (int i = 0; i < 3; ++i) h[i] = std::clamp(h[i], hmin_, hmax_);
  return metric_from_sizes({dirs.col(0), dirs.col(1), dirs.col(2)}, h);
}

}  // namespace cm::size
