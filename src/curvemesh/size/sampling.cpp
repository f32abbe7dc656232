#include "curvemesh/size/sampling.hpp"

#include <algorithm>
#include <cmath>
#include <functional>
#include <unordered_map>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/partitioner.h>

namespace cm::size {

const char* to_string(SizeSource s) {
  switch (s) {
    case SizeSource::kHmax: return "hmax";
    case SizeSource::kFaceCurvature: return "face curvature";
    case SizeSource::kEdgeCurvature: return "edge curvature";
    case SizeSource::kEntitySize: return "entity size";
    case SizeSource::kField: return "size field";
    case SizeSource::kGradation: return "gradation";
    case SizeSource::kHmin: return "hmin";
    case SizeSource::kShortEdge: return "short edge";
    case SizeSource::kProximity: return "narrow face";
    case SizeSource::kCuspStrip: return "cusp strip";
    case SizeSource::kThinClosedFace: return "thin closed face";
  }
  return "?";
}

SamplingStats& SamplingStats::operator+=(const SamplingStats& o) {
  evaluations += o.evaluations;
  outside += o.outside;
  revisited += o.revisited;
  subdivided += o.subdivided;
  return *this;
}

namespace {

// Sample points live on an integer lattice: a grid cell is `res` lattice
// steps wide, fine enough for every corner and centroid down to max_depth,
// so a point met again (a corner shared by two cells, a parent's centroid
// that is its children's common corner) is recognized exactly.
std::int64_t lattice_resolution(const SamplingOptions& o) { return std::int64_t{2} << std::clamp(o.max_depth, 0, 20); }

int cells_for(double extent, double spacing, int lo, int hi) {
  if (!(spacing > 0) || !std::isfinite(extent / spacing)) return lo;
  return static_cast<int>(std::clamp(std::ceil(extent / spacing), double(lo), double(hi)));
}

double clamp_size(double l, const SamplingOptions& o) { return std::max(l, o.hmin); }

// Samples of one cell asking for lengths within this ratio agree (see
// FaceSampler::visit_cell), and such a cell is subdivided only while wider
// than kAgreeingCellRatio times that length.
constexpr double kAgreeingSizeRatio = 1.25;
constexpr double kAgreeingCellRatio = 2;

// 3D extent of a face along u (or v): the longest of three iso-parametric
// lines, each measured by a 16-segment polyline.
double face_extent(const geom::Model& m, int face, const geom::ParamRange& pr, bool along_u) {
  double longest = 0;
  for (const double t : {0.0, 0.5, 1.0}) {
    double len = 0;
    Vec3 prev;
    for (int k = 0; k <= 16; ++k) {
      const double s = k / 16.0;
      const Vec2 uv = along_u ? Vec2(pr.u0 + s * (pr.u1 - pr.u0), pr.v0 + t * (pr.v1 - pr.v0))
                              : Vec2(pr.u0 + t * (pr.u1 - pr.u0), pr.v0 + s * (pr.v1 - pr.v0));
      const Vec3 x = m.face_point(face, uv);
      if (k > 0) len += (x - prev).norm();
      prev = x;
    }
    longest = std::max(longest, len);
  }
  return longest;
}

class FaceSampler {
 public:
  FaceSampler(const geom::Model& m, int face, const SamplingOptions& o, SamplingStats& st)
      : m_(m),
        face_(face),
        o_(o),
        st_(st),
        pr_(m.param_range({2, face})),
        res_(lattice_resolution(o)),
        tolerance_(m.tolerance({2, face})) {}

  std::vector<SizeSample> run() {
    if (!(pr_.u1 > pr_.u0) || !(pr_.v1 > pr_.v0)) return {};
    const double spacing = 0.5 * o_.hmax;
    nu_ = o_.grid_cells > 0 ? o_.grid_cells : cells_for(face_extent(m_, face_, pr_, true), spacing, 2, o_.max_grid_cells);
    nv_ = o_.grid_cells > 0 ? o_.grid_cells : cells_for(face_extent(m_, face_, pr_, false), spacing, 2, o_.max_grid_cells);
    for (int i = 0; i < nu_; ++i)
      for (int j = 0; j < nv_; ++j) visit_cell(i * res_, j * res_, res_, 0, false);
    return std::move(out_);
  }

 private:
  struct Point {
    Vec3 x;
    double size;  // +inf where nothing is asked (outside the trim, flat)
    bool inside;  // in the trimmed face
  };

  Vec2 param(std::int64_t i, std::int64_t j) const {
    return {pr_.u0 + (pr_.u1 - pr_.u0) * double(i) / double(nu_ * res_),
            pr_.v0 + (pr_.v1 - pr_.v0) * double(j) / double(nv_ * res_)};
  }

  // `known_inside`: the caller vouches that (i, j) is in the trimmed face,
  // which spares the trimming test, the costliest part of a CAD sample.
  const Point& eval(std::int64_t i, std::int64_t j, bool known_inside = false) {
    const std::uint64_t key = (std::uint64_t(i) << 32) | std::uint64_t(j);
    if (const auto it = seen_.find(key); it != seen_.end()) {
      ++st_.revisited;
      return it->second;
    }
    const Vec2 uv = param(i, j);
    Point p{Vec3::Zero(), std::numeric_limits<double>::infinity(), false};
    // Near the trimming loops a sample counts as on the face: just off it,
    // it reads the curvature of the surface the face is cut from, next to
    // the face's own. Grid corners on the parameter box's edges are many,
    // and are exactly where telling in from out is slow.
    if (!known_inside && !m_.contains_param_quick(face_, uv).value_or(true)) {
      ++st_.outside;
      p.x = m_.face_point(face_, uv);
    } else {
      ++st_.evaluations;
      p.inside = true;
      // Point and curvatures from one evaluation of the surface.
      const geom::SurfaceGeometry g = m_.face_geometry(face_, uv);
      p.x = g.derivatives.point;
      // A pole or a singular point has no curvature to give.
      geom::Curvatures c;
      if (usable_curvatures(g, tolerance_, &c)) {
        p.size = clamp_size(surface_curvature_length(c, o_.rule), o_);
        if (p.size < o_.hmax)
          out_.push_back({p.x, p.size, SizeSource::kFaceCurvature, {2, face_}, uv, c.k1, c.k2, c.dir1});
      }
    }
    return seen_.emplace(key, p).first->second;
  }

  // `in_parent`: the four corners of the cell this one was cut from are in
  // the face, so this cell's points are taken as in it too.
  void visit_cell(std::int64_t i0, std::int64_t j0, std::int64_t s, int depth, bool in_parent) {
    // Copies: eval() may rehash the map.
    const Point c00 = eval(i0, j0, in_parent), c10 = eval(i0 + s, j0, in_parent), c01 = eval(i0, j0 + s, in_parent),
                c11 = eval(i0 + s, j0 + s, in_parent);
    double need = std::min({c00.size, c10.size, c01.size, c11.size});
    // A point between four corners in the face (the centroid, the points of
    // a subdivision) is taken as in it too: it is wrong only inside a hole
    // smaller than the cell, where the sample then reads the curvature of
    // the surface the hole was cut from, next to the face's own, which can
    // only make the field finer there. The trimming test is most of the cost
    // of a sample on CAD faces.
    const bool inside = c00.inside && c10.inside && c01.inside && c11.inside;
    if (o_.centroids) need = std::min(need, eval(i0 + s / 2, j0 + s / 2, inside).size);
    if (!o_.adaptive || depth >= o_.max_depth || s < 2 || !std::isfinite(need)) return;
    const double diameter = std::max((c11.x - c00.x).norm(), (c10.x - c01.x).norm());
    if (!(need < diameter) || diameter <= o_.hmin) return;
    // Where the samples agree, the curvature is resolved: finer samples
    // would repeat the same request, and a cell up to kAgreeingCellRatio
    // times the length it asks for leaves the octree between them within a
    // fraction of a gradation step of it (meshers take the exact size on the
    // boundary from the hint anyway). Disagreeing samples still subdivide
    // down to the length they ask for, which is what finds a narrow peak.
    double widest = need;
    for (const Point* p : {&c00, &c10, &c01, &c11})
      if (std::isfinite(p->size)) widest = std::max(widest, p->size);
    if (widest <= kAgreeingSizeRatio * need && diameter <= kAgreeingCellRatio * need) return;
    ++st_.subdivided;
    const std::int64_t h = s / 2;
    for (int a = 0; a < 2; ++a)
      for (int b = 0; b < 2; ++b) visit_cell(i0 + a * h, j0 + b * h, h, depth + 1, inside);
  }

  const geom::Model& m_;
  int face_;
  const SamplingOptions& o_;
  SamplingStats& st_;
  geom::ParamRange pr_;
  std::int64_t res_;
  double tolerance_;
  int nu_ = 0, nv_ = 0;
  std::unordered_map<std::uint64_t, Point> seen_;
  std::vector<SizeSample> out_;
};

class EdgeSampler {
 public:
  EdgeSampler(const geom::Model& m, int edge, const SamplingOptions& o, SamplingStats& st)
      : m_(m), edge_(edge), o_(o), st_(st), pr_(m.param_range({1, edge})), res_(lattice_resolution(o)) {}

  std::vector<SizeSample> run() {
    if (m_.is_degenerate(edge_) || !(pr_.u1 > pr_.u0)) return {};
    double len = 0;
    Vec3 prev = m_.edge_point(edge_, pr_.u0);
    for (int k = 1; k <= 32; ++k) {
      const Vec3 x = m_.edge_point(edge_, pr_.u0 + (pr_.u1 - pr_.u0) * k / 32.0);
      len += (x - prev).norm();
      prev = x;
    }
    n_ = o_.grid_cells > 0 ? o_.grid_cells : cells_for(len, 0.5 * o_.hmax, 4, 32 * o_.max_grid_cells);
    for (int i = 0; i < n_; ++i) visit(i * res_, res_, 0);
    return std::move(out_);
  }

 private:
  struct Point {
    Vec3 x;
    double size;
  };

  const Point& eval(std::int64_t i) {
    if (const auto it = seen_.find(i); it != seen_.end()) {
      ++st_.revisited;
      return it->second;
    }
    ++st_.evaluations;
    const double u = pr_.u0 + (pr_.u1 - pr_.u0) * double(i) / double(n_ * res_);
    const geom::CurveDerivatives d = m_.edge_derivatives(edge_, u);
    Point p{d.point, std::numeric_limits<double>::infinity()};
    const double k = m_.edge_curvature(edge_, u);
    if (std::isfinite(k)) {
      p.size = clamp_size(curvature_length(k, o_.rule), o_);
      if (p.size < o_.hmax) {
        const double speed = d.d1.norm();
        out_.push_back({p.x, p.size, SizeSource::kEdgeCurvature, {1, edge_}, Vec2(u, 0), k, 0,
                        speed > 0 ? Vec3(d.d1 / speed) : Vec3::Zero()});
      }
    }
    return seen_.emplace(i, p).first->second;
  }

  void visit(std::int64_t i0, std::int64_t s, int depth) {
    const Point a = eval(i0), b = eval(i0 + s), mid = eval(i0 + s / 2);
    const double need = std::min({a.size, b.size, mid.size});
    if (!o_.adaptive || depth >= o_.max_depth || s < 2 || !std::isfinite(need)) return;
    const double chord = (b.x - a.x).norm();
    if (!(need < chord) || chord <= o_.hmin) return;
    ++st_.subdivided;
    visit(i0, s / 2, depth + 1);
    visit(i0 + s / 2, s / 2, depth + 1);
  }

  const geom::Model& m_;
  int edge_;
  const SamplingOptions& o_;
  SamplingStats& st_;
  geom::ParamRange pr_;
  std::int64_t res_;
  int n_ = 0;
  std::unordered_map<std::int64_t, Point> seen_;
  std::vector<SizeSample> out_;
};

void check_options(const SamplingOptions& o) {
  if (!(o.hmax > 0) || !(o.hmin >= 0) || !(o.hmin <= o.hmax))
    throw std::invalid_argument("sampling needs 0 <= hmin <= hmax and hmax > 0");
}

}  // namespace

std::vector<SizeSample> sample_face_curvature(const geom::Model& model, int face, const SamplingOptions& opt,
                                              SamplingStats* stats) {
  check_options(opt);
  SamplingStats local;
  // A plane has no curvature to find: on CAD parts most faces are planes, and
  // their trimming tests were most of the sampling time.
  if (!opt.rule.enabled() || model.type({2, face}) == geom::ShapeType::kPlane) return {};
  auto out = FaceSampler(model, face, opt, local).run();
  if (stats) *stats += local;
  return out;
}

std::vector<SizeSample> sample_edge_curvature(const geom::Model& model, int edge, const SamplingOptions& opt,
                                              SamplingStats* stats) {
  check_options(opt);
  SamplingStats local;
  if (!opt.rule.enabled() || model.type({1, edge}) == geom::ShapeType::kLine) return {};
  auto out = EdgeSampler(model, edge, opt, local).run();
  if (stats) *stats += local;
  return out;
}

std::vector<SizeSample> sample_model_curvature(const geom::Model& model, const SamplingOptions& opt,
                                               SamplingStats* stats) {
  check_options(opt);
  const int ne = model.count(1), nf = model.count(2);
  std::vector<std::vector<SizeSample>> per(ne + nf);
  std::vector<SamplingStats> st(ne + nf);
  // One task per entity: a few large freeform faces can hold most of the
  // work, and chunks of neighbouring tags would leave a thread idle. Each
  // entity's samples land in its own slot, so the result is the same for
  // any number of threads.
  tbb::parallel_for(
      tbb::blocked_range<int>(0, ne + nf, 1),
      [&](const tbb::blocked_range<int>& range) {
        for (int k = range.begin(); k < range.end(); ++k)
          per[k] = k < ne ? sample_edge_curvature(model, k + 1, opt, &st[k])
                          : sample_face_curvature(model, k - ne + 1, opt, &st[k]);
      },
      tbb::simple_partitioner());
  std::vector<SizeSample> out;
  std::size_t total = 0;
  for (const auto& v : per) total += v.size();
  out.reserve(total);
  for (int k = 0; k < ne + nf; ++k) {
    out.insert(out.end(), per[k].begin(), per[k].end());
    if (stats) *stats += st[k];
  }
  return out;
}

std::vector<SizeSample> sample_face_proximity(const geom::Model& model, int face, double hmin, double hmax) {
  std::vector<int> edges;
  for (const geom::Loop& loop : model.face_loops(face))
    for (const geom::OrientedUse& use : loop.edges)
      if (!model.is_degenerate(use.tag)) edges.push_back(use.tag);
  std::sort(edges.begin(), edges.end());
  edges.erase(std::unique(edges.begin(), edges.end()), edges.end());
  std::vector<SizeSample> out;
  if (edges.size() < 2) return out;
  const auto touches = [&](int a, int b) {
    const auto va = model.edge_vertices(a), vb = model.edge_vertices(b);
    for (const int x : va)
      for (const int y : vb)
        if (x > 0 && x == y) return true;
    return false;
  };
  for (const int e : edges) {
    std::vector<int> others;
    for (const int e2 : edges)
      if (e2 != e && !touches(e, e2)) others.push_back(e2);
    if (others.empty()) continue;
    const geom::ParamRange r = model.param_range({1, e});
    const int n = cells_for(model.length(e), 0.25 * hmax, 4, 256);
    for (int i = 0; i <= n; ++i) {
      const double u = r.u0 + (r.u1 - r.u0) * i / n;
      const Vec3 x = model.edge_point(e, u);
      double d = hmax;
      for (const int e2 : others) {
        // Cheap rejection before the projection.
        const geom::BoundingBox b = model.bounding_box({1, e2});
        const Vec3 gap = (b.min - x).cwiseMax(x - b.max).cwiseMax(0.0);
        if (gap.norm() >= d) continue;
        d = std::min(d, model.closest_point({1, e2}, x).distance);
      }
      if (d < hmax)
        out.push_back({x, std::max(d, hmin), SizeSource::kProximity, {1, e}, Vec2(u, 0), 0, 0, Vec3::Zero()});
    }
  }
  return out;
}

std::vector<SizeSample> sample_cusp_strips(const geom::Model& model, const geom::CuspTip& tip, double floor,
                                           double hmax) {
  std::vector<SizeSample> out;
  constexpr int kMaxPerEdge = 4096;
  for (const auto& pair : tip.pairs)
    for (int k = 0; k < 2; ++k) {
      const int e = pair[k], other = pair[1 - k];
      const int side = model.edge_vertices(e)[0] == tip.vertex ? 0 : 1;
      const std::optional<double> start = geom::param_at_distance(model, e, side, tip.radius);
      if (!start) continue;
      const geom::ParamRange r = model.param_range({1, e});
      const double sense = side == 0 ? 1 : -1;
      double u = *start;
      for (int n = 0; n < kMaxPerEdge && u >= r.u0 && u <= r.u1; ++n) {
        const geom::CurveDerivatives d = model.edge_derivatives(e, u);
        const double w = model.closest_point({1, other}, d.point).distance;
        if (!(w < hmax)) break;
        const double h = std::max(w, floor);
        out.push_back({d.point, h, SizeSource::kCuspStrip, {1, e}, Vec2(u, 0), 0, 0, Vec3::Zero()});
        const double speed = d.d1.norm();
        if (!(speed > 0)) break;
        u += sense * 0.5 * h / speed;
      }
    }
  return out;
}

namespace {

// Grid points of a face's parameter box on the trimmed face, spacing <= h/2
// in 3D along each direction (the face's boundary is its edges' business).
void sample_face_interior(const geom::Model& model, int face, int cap,
                          const std::function<void(const Vec3&, geom::EntityRef, const Vec2&)>& add, double h) {
  const geom::ParamRange pr = model.param_range({2, face});
  const int nu = cells_for(face_extent(model, face, pr, true), 0.5 * h, 1, cap);
  const int nv = cells_for(face_extent(model, face, pr, false), 0.5 * h, 1, cap);
  for (int i = 0; i <= nu; ++i)
    for (int j = 0; j <= nv; ++j) {
      const Vec2 uv(pr.u0 + (pr.u1 - pr.u0) * i / nu, pr.v0 + (pr.v1 - pr.v0) * j / nv);
      if (model.contains_param(face, uv)) add(model.face_point(face, uv), {2, face}, uv);
    }
}

void sample_edge(const geom::Model& model, int edge, int cap,
                 const std::function<void(const Vec3&, geom::EntityRef, const Vec2&)>& add, double h) {
  const geom::ParamRange pr = model.param_range({1, edge});
  const int n = cells_for(model.length(edge), 0.5 * h, 1, cap);
  for (int i = 0; i <= n; ++i) {
    const double u = pr.u0 + (pr.u1 - pr.u0) * i / n;
    add(model.edge_point(edge, u), {1, edge}, Vec2(u, 0));
  }
}

}  // namespace

std::vector<SizeSample> sample_entity_size(const geom::Model& model, geom::EntityRef e, double h,
                                           int max_points_per_direction) {
  if (!(h > 0) || !std::isfinite(h)) throw std::invalid_argument("entity size must be finite and > 0");
  std::vector<SizeSample> out;
  const std::function<void(const Vec3&, geom::EntityRef, const Vec2&)> add = [&](const Vec3& x, geom::EntityRef on,
                                                                                   const Vec2& uv) {
    out.push_back({x, h, SizeSource::kEntitySize, on, uv, 0, 0, Vec3::Zero()});
  };
  const int cap = std::max(1, max_points_per_direction);
  // The faces to cover, and the edges that bound them, each once: a region's
  // faces share their edges, and a seam or an internal face is used twice.
  std::vector<int> faces, edges;
  switch (e.dim) {
    case 0: add(model.vertex_point(e.tag), e, Vec2::Zero()); return out;
    case 1: sample_edge(model, e.tag, cap, add, h); return out;
    case 2: faces.push_back(e.tag); break;
    case 3:
      for (const geom::OrientedUse& use : model.region_faces(e.tag)) faces.push_back(use.tag);
      break;
    default:
      throw std::invalid_argument("a size can be given on a vertex, an edge, a face or a region (dimension 0-3)");
  }
  std::sort(faces.begin(), faces.end());
  faces.erase(std::unique(faces.begin(), faces.end()), faces.end());
  for (const int f : faces)
    for (const geom::Loop& loop : model.face_loops(f))
      for (const geom::OrientedUse& use : loop.edges) edges.push_back(use.tag);
  std::sort(edges.begin(), edges.end());
  edges.erase(std::unique(edges.begin(), edges.end()), edges.end());
  for (const int edge : edges) sample_edge(model, edge, cap, add, h);
  for (const int f : faces) sample_face_interior(model, f, cap, add, h);
  return out;
}

namespace {

// The longest way around a face closed in u or v, measured along the
// periodic direction at a few stations across the other (a cone's apex
// makes its way around vanish at one end: the longest is what the face
// needs segments for); 0 when the face is closed in neither.
double longest_way_around(const geom::Model& model, int face) {
  const geom::ParamRange r = model.param_range({2, face});
  const auto closed = [](double lo, double hi, bool periodic, double period) {
    return periodic && period > 0 && hi - lo >= period * (1 - 1e-9);
  };
  const bool around_u = closed(r.u0, r.u1, r.periodic_u, r.period_u);
  const bool around_v = closed(r.v0, r.v1, r.periodic_v, r.period_v);
  if (!around_u && !around_v) return 0;
  constexpr int kSteps = 24;
  double longest = 0;
  for (const double s : {0.1, 0.5, 0.9}) {
    double length = 0;
    for (int k = 0; k < kSteps; ++k) {
      const double t = (k + 0.5) / kSteps;
      const Vec2 uv = around_u ? Vec2(r.u0 + t * (r.u1 - r.u0), r.v0 + s * (r.v1 - r.v0))
                               : Vec2(r.u0 + s * (r.u1 - r.u0), r.v0 + t * (r.v1 - r.v0));
      const geom::SurfaceDerivatives d = model.face_derivatives(face, uv);
      length += (around_u ? d.du.norm() * (r.u1 - r.u0) : d.dv.norm() * (r.v1 - r.v0)) / kSteps;
    }
    if (std::isfinite(length)) longest = std::max(longest, length);
  }
  return longest;
}

}  // namespace

std::vector<SizeSample> sample_thin_closed_face(const geom::Model& model, int face, double hmin,
                                                std::size_t max_points) {
  const double around = longest_way_around(model, face);
  if (!(around > 0) || around >= 3 * hmin) return {};
  const double h = std::max(around / 5, kCuspStripFloor * hmin);
  // Sampling at h/2 spacing puts about 4 area / h² points on the face.
  if (around < 3 * h || 4 * model.area(face) / (h * h) > static_cast<double>(max_points)) return {};
  std::vector<SizeSample> out = sample_entity_size(model, {2, face}, h);
  if (out.size() > max_points) return {};
  for (SizeSample& sm : out) sm.source = SizeSource::kThinClosedFace;
  return out;
}

}  // namespace cm::size
