#include "curvemesh/size/build.hpp"

#include <cmath>
#include <stdexcept>

#include <fmt/format.h>
#include <tbb/parallel_for.h>

#include "curvemesh/core/timer.hpp"

namespace cm::size {

SizeFieldResult build_size_field(const geom::Model& model, const SizeOptions& o) {
  SizeFieldResult r;
  const geom::BoundingBox box = model.bounding_box();
  const double diagonal = box.diagonal();
  if (!(diagonal > 0) || !std::isfinite(diagonal))
    throw std::invalid_argument("size field: the model's bounding box is empty");
  r.hmax = o.hmax > 0 ? o.hmax : diagonal / 20;
  r.hmin = o.hmin > 0 ? o.hmin : r.hmax / 100;
  if (!std::isfinite(r.hmax) || r.hmin > r.hmax)
    throw std::invalid_argument(fmt::format("hmin ({}) must not exceed hmax ({})", r.hmin, r.hmax));
  if (!(o.hgrad >= 1)) throw std::invalid_argument(fmt::format("hgrad must be >= 1 (got {})", o.hgrad));
  for (const auto& [e, h] : o.entity_sizes) {
    if (e.dim < 0 || e.dim > 2 || e.tag < 1 || e.tag > model.count(e.dim))
      throw std::invalid_argument(fmt::format("size on {} {}: the model has no such entity",
                                              e.dim == 0   ? "vertex"
                                              : e.dim == 1 ? "edge"
                                              : e.dim == 2 ? "face"
                                                           : "entity",
                                              e.tag));
    if (!(h > 0) || !std::isfinite(h))
      throw std::invalid_argument(fmt::format("size on entity {}:{} must be finite and > 0", e.dim, e.tag));
  }

  Timer timer;
  SamplingOptions so = o.sampling;
  so.rule = o.curvature;
  so.hmin = r.hmin;
  so.hmax = r.hmax;
  r.samples = sample_model_curvature(model, so, &r.stats);
  if (o.directional)
    for (SizeSample& sm : r.samples)
      if (sm.source == SizeSource::kFaceCurvature)
        sm.size = std::max(r.hmin, std::max(curvature_length(sm.k1, o.curvature), curvature_length(sm.k2, o.curvature)));
  {
    std::vector<std::vector<SizeSample>> per(o.entity_sizes.size());
    tbb::parallel_for(std::size_t{0}, per.size(), [&](std::size_t i) {
      per[i] = sample_entity_size(model, o.entity_sizes[i].first, o.entity_sizes[i].second);
    });
    for (const auto& v : per) r.samples.insert(r.samples.end(), v.begin(), v.end());
  }
  if (o.short_edges) {
    const int ne = model.count(1);
    std::vector<std::vector<SizeSample>> per(ne);
    tbb::parallel_for(1, ne + 1, [&](int e) {
      if (model.is_degenerate(e)) return;
      const double length = model.length(e);
      if (!(length < r.hmax)) return;
      per[e - 1] = sample_entity_size(model, {1, e}, std::max(length, r.hmin));
      for (SizeSample& s : per[e - 1]) s.source = SizeSource::kShortEdge;
    });
    for (const auto& v : per) r.samples.insert(r.samples.end(), v.begin(), v.end());
  }
  if (o.narrow_faces) {
    const int nf = model.count(2);
    std::vector<std::vector<SizeSample>> per(nf);
    tbb::parallel_for(1, nf + 1, [&](int f) { per[f - 1] = sample_face_proximity(model, f, r.hmin, r.hmax); });
    for (const auto& v : per) r.samples.insert(r.samples.end(), v.begin(), v.end());
  }
  r.sampling_seconds = timer.seconds();

  Timer octree_timer;
  OctreeOptions oo;
  oo.hmin = r.hmin;
  oo.hmax = r.hmax;
  oo.hgrad = o.hgrad;
  oo.max_depth = o.max_depth;
  r.octree = std::make_shared<SizeOctree>(box, oo);
  for (const SizeSample& sm : r.samples)
    if (sm.size < r.hmax) r.octree->insert(sm.point, sm.size, sm.source);
  for (const auto& f : o.fields) r.octree->insert_field(f);
  r.octree->build();
  r.octree_seconds = octree_timer.seconds();

  r.field = std::make_shared<ModelSizeField>(model, o, r.hmin, r.hmax, r.octree);
  return r;
}

ModelSizeField::ModelSizeField(const geom::Model& model, const SizeOptions& o, double hmin, double hmax,
                               std::shared_ptr<const SizeOctree> octree)
    : model_(model),
      octree_(std::move(octree)),
      metric_(o.metric),
      rule_(o.curvature),
      directional_(o.directional && o.curvature.enabled()),
      hmin_(hmin),
      hmax_(hmax),
      face_size_(model.count(2) + 1, std::numeric_limits<double>::infinity()),
      edge_size_(model.count(1) + 1, std::numeric_limits<double>::infinity()) {
  for (const auto& [e, h] : o.entity_sizes) {
    if (e.dim == 2) face_size_[e.tag] = std::min(face_size_[e.tag], h);
    if (e.dim == 1) edge_size_[e.tag] = std::min(edge_size_[e.tag], h);
  }
}

// The size the hint's entity asks for at the hint's parameters (+inf when
// there is no usable hint).
double ModelSizeField::hint_size(const SizeHint& hint) const {
  const geom::EntityRef e = hint.entity;
  double h = std::numeric_limits<double>::infinity();
  if (e.dim == 2 && e.tag >= 1 && e.tag <= model_.count(2) && hint.param.allFinite()) {
    h = face_size_[e.tag];
    if (rule_.enabled()) {
      geom::Curvatures c;
      if (usable_curvatures(model_, e.tag, hint.param, &c)) {
        // Directional: the isotropic size is the coarser principal length,
        // the finer one is in metric().
        const double l = directional_ ? std::max(curvature_length(c.k1, rule_), curvature_length(c.k2, rule_))
                                      : surface_curvature_length(c, rule_);
        h = std::min(h, l);
      }
    }
  } else if (e.dim == 1 && e.tag >= 1 && e.tag <= model_.count(1) && std::isfinite(hint.param.x())) {
    h = edge_size_[e.tag];
    if (rule_.enabled()) {
      const double k = model_.edge_curvature(e.tag, hint.param.x());
      if (std::isfinite(k)) h = std::min(h, curvature_length(k, rule_));
    }
  }
  return h;
}

double ModelSizeField::size(const Vec3& x, const SizeHint& hint) const {
  double h = std::min(octree_->size(x), hint_size(hint));
  if (metric_) h = std::min(h, metric_->size(x, hint));
  return std::clamp(h, hmin_, hmax_);
}

Metric ModelSizeField::metric(const Vec3& x, const SizeHint& hint) const {
  if (!anisotropic()) return isotropic_metric(size(x, hint));
  Metric m = isotropic_metric(std::clamp(std::min(octree_->size(x), hint_size(hint)), hmin_, hmax_));
  if (directional_ && hint.entity.dim == 2 && hint.entity.tag >= 1 && hint.entity.tag <= model_.count(2) &&
      hint.param.allFinite()) {
    geom::Curvatures c;
    if (usable_curvatures(model_, hint.entity.tag, hint.param, &c))
      m = intersect(m, surface_curvature_metric(c, model_.face_normal(hint.entity.tag, hint.param), rule_, hmin_,
                                                hmax_));
  }
  if (metric_) {
    // Clamp the background metric's sizes to [hmin, hmax] before combining.
    Mat3 dirs;
    Vec3 sizes = metric_sizes(metric_->metric(x, hint), &dirs);
    for (int i = 0; i < 3; ++i) sizes[i] = std::clamp(sizes[i], hmin_, hmax_);
    m = intersect(m, metric_from_sizes({dirs.col(0), dirs.col(1), dirs.col(2)}, sizes));
  }
  return m;
}

}  // namespace cm::size
