#include "curvemesh/size/build.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <stdexcept>

#include <fmt/format.h>
#include <tbb/parallel_for.h>

#include "curvemesh/core/error.hpp"
#include "curvemesh/core/timer.hpp"

namespace cm::size {

namespace {

const char* entity_name(int dim) {
  static const char* const kNames[] = {"vertex", "edge", "face", "region"};
  return dim >= 0 && dim <= 3 ? kNames[dim] : "entity";
}

/// h inside a region and on its boundary, no request (+inf) elsewhere: what
/// the octree evaluates at its corners and centres to honour a size on a
/// region. The corners of every octant inside the region get h, so its
/// interior is at most h there; an octant the boundary crosses is covered by
/// the boundary's own samples (sample_entity_size).
///
/// A point-in-solid test near a CAD boundary costs tens of microseconds, and
/// the octree asks for hundreds of thousands of points. But a box that meets
/// none of the region's face boxes holds no boundary, so it is inside or
/// outside as a whole (uniform_in), and the octree then asks once for all
/// the octants such boxes join into; the classifier is left with the octants
/// along the boundary.
class RegionSizeField final : public BoxSizeField {
 public:
  RegionSizeField(const geom::Model& model, int region, double h) : model_(model), region_(region), h_(h) {
    // Padded: the boxes only spare classifier calls away from the boundary,
    // and a face box found by sampling may be a little tight.
    const geom::BoundingBox b = model.bounding_box({3, region});
    const double pad = 1e-3 * b.diagonal() + model.tolerance({3, region});
    lo_ = b.min - Vec3::Constant(pad);
    hi_ = b.max + Vec3::Constant(pad);
    for (const geom::OrientedUse& use : model.region_faces(region)) {
      const geom::BoundingBox f = model.bounding_box({2, use.tag});
      const double face_pad = pad + 1e-2 * f.diagonal();
      face_boxes_.push_back({f.min - Vec3::Constant(face_pad), f.max + Vec3::Constant(face_pad)});
    }
  }

  double size(const Vec3& x, const SizeHint& = {}) const override {
    if (outside_box(x, x)) return kNone;
    try {
      return model_.classify_point(region_, x) != geom::Containment::kOutside ? h_ : kNone;
    } catch (const GeometryError&) {
      // The CAD classifier found no usable ray here. A finer size than
      // needed is harmless; failing the whole field for one point is not.
      return h_;
    }
  }

  bool uniform_in(const Vec3& lo, const Vec3& hi) const override {
    if (outside_box(lo, hi)) return true;
    for (const auto& [flo, fhi] : face_boxes_)
      if ((lo.array() <= fhi.array()).all() && (hi.array() >= flo.array()).all()) return false;
    return true;
  }

 private:
  static constexpr double kNone = std::numeric_limits<double>::infinity();
  bool outside_box(const Vec3& lo, const Vec3& hi) const {
    return (hi.array() < lo_.array()).any() || (lo.array() > hi_.array()).any();
  }

  const geom::Model& model_;
  int region_;
  double h_;
  Vec3 lo_, hi_;
  std::vector<std::pair<Vec3, Vec3>> face_boxes_;
};

}  // namespace

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
    if (e.dim < 0 || e.dim > 3)
      throw std::invalid_argument(fmt::format("size on an entity of dimension {}: a size goes on a vertex, an edge, "
                                              "a face or a region (dimension 0-3)",
                                              e.dim));
    if (e.tag < 1 || e.tag > model.count(e.dim)) {
      const int n = model.count(e.dim);
      throw std::invalid_argument(
          fmt::format("size on {} {}: the model has no such entity ({})", entity_name(e.dim), e.tag,
                      n == 0 ? fmt::format("it has no {}", entity_name(e.dim))
                             : fmt::format("{} tags are 1..{}", entity_name(e.dim), n)));
    }
    if (!(h > 0) || !std::isfinite(h))
      throw std::invalid_argument(fmt::format("size on entity {}:{} must be finite and > 0", e.dim, e.tag));
  }

  Timer timer;
  SamplingOptions so = o.sampling;
  so.rule = o.curvature;
  so.hmin = r.hmin;
  so.hmax = r.hmax;
  r.samples = sample_model_curvature(model, so, &r.stats);
  r.curvature_seconds = timer.seconds();
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
    tbb::parallel_for(1, nf + 1, [&](int f) { per[f - 1] = sample_thin_closed_face(model, f, r.hmin); });
    for (const auto& v : per) r.samples.insert(r.samples.end(), v.begin(), v.end());
    const double hmin = r.hmin;
    for (const geom::CuspTip& tip : geom::cusp_tips(model, [hmin](const Vec3&) { return hmin; })) {
      const std::vector<SizeSample> strip = sample_cusp_strips(model, tip, kCuspStripFloor * r.hmin, r.hmax);
      r.samples.insert(r.samples.end(), strip.begin(), strip.end());
    }
  }
  r.sampling_seconds = timer.seconds();

  Timer octree_timer;
  OctreeOptions oo;
  oo.hmin = r.hmin;
  oo.cusp_min = kCuspStripFloor * r.hmin;
  oo.hmax = r.hmax;
  oo.hgrad = o.hgrad;
  oo.max_depth = o.max_depth;
  r.octree = std::make_shared<SizeOctree>(box, oo);
  for (const SizeSample& sm : r.samples)
    if (sm.size < r.hmax) r.octree->insert(sm.point, sm.size, sm.source);
  for (const auto& f : o.fields) r.octree->insert_field(f);
  for (const auto& [e, h] : o.entity_sizes)
    if (e.dim == 3) r.octree->insert_field(std::make_shared<RegionSizeField>(model, e.tag, h));
  r.octree->build();
  r.octree_seconds = octree_timer.seconds();

  r.field = std::make_shared<ModelSizeField>(model, o, r.hmin, r.hmax, r.octree, oo.cusp_min);
  return r;
}

ModelSizeField::ModelSizeField(const geom::Model& model, const SizeOptions& o, double hmin, double hmax,
                               std::shared_ptr<const SizeOctree> octree, double octree_min)
    : model_(model),
      octree_(std::move(octree)),
      metric_(o.metric),
      rule_(o.curvature),
      directional_(o.directional && o.curvature.enabled()),
      hmin_(hmin),
      hmax_(hmax),
      octree_min_(octree_min > 0 ? std::min(octree_min, hmin) : hmin),
      vertex_size_(model.count(0) + 1, std::numeric_limits<double>::infinity()),
      edge_size_(model.count(1) + 1, std::numeric_limits<double>::infinity()),
      face_size_(model.count(2) + 1, std::numeric_limits<double>::infinity()),
      region_size_(model.count(3) + 1, std::numeric_limits<double>::infinity()) {
  const auto lower = [](double& to, double h) { to = std::min(to, h); };
  for (const auto& [e, h] : o.entity_sizes) {
    switch (e.dim) {
      case 0: lower(vertex_size_[e.tag], h); break;
      case 1: lower(edge_size_[e.tag], h); break;
      case 2: lower(face_size_[e.tag], h); break;
      case 3: {
        // A size inside a region holds on its closure: a boundary point
        // queried with its face, edge or vertex as hint gets it too.
        lower(region_size_[e.tag], h);
        for (const geom::OrientedUse& face : model.region_faces(e.tag)) {
          lower(face_size_[face.tag], h);
          for (const geom::Loop& loop : model.face_loops(face.tag))
            for (const geom::OrientedUse& edge : loop.edges) {
              lower(edge_size_[edge.tag], h);
              for (const int v : model.edge_vertices(edge.tag))
                if (v > 0) lower(vertex_size_[v], h);
            }
        }
        break;
      }
      default: break;
    }
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
  } else if (e.dim == 0 && e.tag >= 1 && e.tag <= model_.count(0)) {
    h = vertex_size_[e.tag];
  } else if (e.dim == 3 && e.tag >= 1 && e.tag <= model_.count(3)) {
    h = region_size_[e.tag];
  }
  return h;
}

// The octree may hold cusp strip sizes below hmin (its own floor); every
// other source is clamped to [hmin, hmax].
double ModelSizeField::octree_size(const Vec3& x) const { return std::clamp(octree_->size(x), octree_min_, hmax_); }

double ModelSizeField::size(const Vec3& x, const SizeHint& hint) const {
  double h = hint_size(hint);
  if (metric_) h = std::min(h, metric_->size(x, hint));
  return std::min(octree_size(x), std::clamp(h, hmin_, hmax_));
}

Metric ModelSizeField::metric(const Vec3& x, const SizeHint& hint) const {
  if (!anisotropic()) return isotropic_metric(size(x, hint));
  Metric m = isotropic_metric(std::min(octree_size(x), std::clamp(hint_size(hint), hmin_, hmax_)));
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
