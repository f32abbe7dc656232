// The fast trimmed-face test: each loop's p-curves sampled into a closed
// polygon in (u, v) (TrimClassifier), checked against OCC's classifier before
// it is trusted, and face_contains, which asks the polygon first.
#include <algorithm>
#include <cmath>

#include <gp_Pnt2d.hxx>

#include "curvemesh/geom_occ/detail/occ_model.hpp"

namespace cm::geom_occ::detail {

namespace {

// Chord deviation the polygons aim for, as a fraction of the face's
// parameter extent: the band (twice the largest deviation measured) is then
// a few thousandths of the extent, and about that share of queries falls
// back to OCC.
constexpr double kDeviation = 2e-4;
constexpr int kSegmentsPerUse = 16;
constexpr int kMaxDepth = 10;
// Points the polygon is checked at against OCC, on each side of the band.
constexpr int kBoundaryChecks = 16;

Vec2 at(const Handle(Geom2d_Curve)& c, double t) {
  const gp_Pnt2d p = c->Value(t);
  return {p.X(), p.Y()};
}

// Appends the points of c over [t0, t1) (t1's point is the next piece's
// first), subdividing where the curve strays from the chord by more than
// `target` at a quarter, half or three quarters of the piece; records the
// largest deviation left.
void sample(const Handle(Geom2d_Curve)& c, double t0, double t1, const Vec2& p0, const Vec2& p1, double target,
            int depth, std::vector<Vec2>& out, double& deviation) {
  double worst = 0;
  const Vec2 chord = p1 - p0;
  const double len2 = chord.squaredNorm();
  for (const double s : {0.25, 0.5, 0.75}) {
    const Vec2 q = at(c, t0 + s * (t1 - t0));
    const double d = len2 > 0 ? std::abs(chord.x() * (q - p0).y() - chord.y() * (q - p0).x()) / std::sqrt(len2)
                              : (q - p0).norm();
    worst = std::max(worst, d);
  }
  if (worst > target && depth < kMaxDepth) {
    const double tm = 0.5 * (t0 + t1);
    const Vec2 pm = at(c, tm);
    sample(c, t0, tm, p0, pm, target, depth + 1, out, deviation);
    sample(c, tm, t1, pm, p1, target, depth + 1, out, deviation);
    return;
  }
  deviation = std::max(deviation, worst);
  out.push_back(p0);
}

// The classifier brings periodic parameters into range one period at a
// time: do it in one step.
Vec2 in_period(const FaceData& f, Vec2 uv) {
  const geom::ParamRange& r = f.range;
  if (r.periodic_u && (uv.x() < r.u0 || uv.x() > r.u0 + r.period_u))
    uv.x() -= std::floor((uv.x() - r.u0) / r.period_u) * r.period_u;
  if (r.periodic_v && (uv.y() < r.v0 || uv.y() > r.v0 + r.period_v))
    uv.y() -= std::floor((uv.y() - r.v0) / r.period_v) * r.period_v;
  return uv;
}

// The polygons' answer for uv (in period), or nullopt. OCC's classifier
// also tries the point one period over where that lands in the face's box:
// a point just below u0 of a face that does not span the period is one the
// window sent to the far end. So every shift that can reach the polygons is
// asked: inside if one is, undecided if one is near a loop.
std::optional<bool> trim_contains(const FaceData& f, const TrimClassifier& trim, const Vec2& uv) {
  const geom::ParamRange& r = f.range;
  const double pu = r.periodic_u ? r.period_u : 0, pv = r.periodic_v ? r.period_v : 0;
  bool in = false;
  for (int i = pu > 0 ? -1 : 0; i <= (pu > 0 ? 1 : 0); ++i)
    for (int j = pv > 0 ? -1 : 0; j <= (pv > 0 ? 1 : 0); ++j) {
      const auto here = trim.inside(uv + Vec2(i * pu, j * pv));
      if (!here) return std::nullopt;
      in |= *here;
    }
  return in;
}

}  // namespace

std::optional<bool> trim_face_contains(const FaceData& f, const TrimClassifier& trim, const Vec2& uv) {
  if (!std::isfinite(uv.x()) || !std::isfinite(uv.y())) return false;
  return trim_contains(f, trim, in_period(f, uv));
}

std::unique_ptr<TrimClassifier> build_trim_classifier(const FaceData& d, const std::vector<EdgeData>& edges) {
  const geom::ParamRange& r = d.range;
  const double extent = std::max(r.u1 - r.u0, r.v1 - r.v0);
  if (!(extent > 0) || !std::isfinite(extent) || d.loops.empty()) return nullptr;
  std::vector<std::vector<Vec2>> polygons;
  double deviation = 0;
  std::size_t use = 0;
  for (const geom::Loop& loop : d.loops) {
    std::vector<Vec2> polygon;
    for (std::size_t k = 0; k < loop.edges.size(); ++k, ++use) {
      if (use >= d.pcurves.size() || d.pcurves[use].curve.IsNull()) return nullptr;
      const PCurveUse& pc = d.pcurves[use];
      const EdgeData& e = edges[pc.edge - 1];
      const double t0 = pc.forward ? e.first : e.last, t1 = pc.forward ? e.last : e.first;
      for (int s = 0; s < kSegmentsPerUse; ++s) {
        const double a = t0 + (t1 - t0) * s / kSegmentsPerUse, b = t0 + (t1 - t0) * (s + 1) / kSegmentsPerUse;
        sample(pc.curve, a, b, at(pc.curve, a), at(pc.curve, b), kDeviation * extent, 0, polygon, deviation);
      }
    }
    polygons.push_back(std::move(polygon));
  }
  if (use != d.pcurves.size()) return nullptr;
  // The band covers the polygon's own error, the loops' gaps (bridged by
  // straight segments) and OCC's ON zone.
  const double band = 2 * deviation + 2 * d.uv_tolerance + d.uv_loop_gap + 1e-12 * extent;
  auto trim = std::make_unique<TrimClassifier>(polygons, band);
  // Checked where it matters most, just outside the band on both sides of
  // the loops: a face whose loops the polygons misread (a parity OCC sees
  // differently) keeps OCC's classifier alone.
  const std::size_t total = trim->segments();
  for (const auto& polygon : polygons) {
    const std::size_t n = polygon.size();
    const std::size_t step = std::max<std::size_t>(1, total / kBoundaryChecks);
    for (std::size_t k = 0; k < n; k += step) {
      const Vec2 a = polygon[k], b = polygon[(k + 1) % n];
      const Vec2 t = b - a;
      if (!(t.norm() > 0)) continue;
      const Vec2 normal = Vec2(-t.y(), t.x()).normalized();
      for (const double side : {-3.0, 3.0}) {
        const Vec2 q = 0.5 * (a + b) + side * band * normal;
        const auto fast = trim_face_contains(d, *trim, q);
        if (fast && *fast != occ_face_contains(d, in_period(d, q))) return nullptr;
      }
    }
  }
  return trim;
}

int OccModel::faces_with_trim_polygons() const {
  int n = 0;
  for (int f = 1; f <= count(2); ++f) n += face_at(f).trim != nullptr;
  return n;
}

bool occ_face_contains(const FaceData& f, const Vec2& uv) {
  // ON (within the classifier's band, FaceData::uv_tolerance) counts as in.
  const std::lock_guard<std::mutex> lock(*f.classifier_mutex);
  return f.classifier->Perform(gp_Pnt2d(uv.x(), uv.y()), true) != TopAbs_OUT;
}

bool face_contains(const FaceData& f, Vec2 uv) {
  if (!std::isfinite(uv.x()) || !std::isfinite(uv.y())) return false;
  uv = in_period(f, uv);
  if (f.trim)
    if (const auto in = trim_contains(f, *f.trim, uv)) return *in;
  return occ_face_contains(f, uv);
}

std::optional<bool> OccModel::contains_param_quick(int face, const Vec2& uv) const {
  const FaceData& f = face_at(face);
  if (!f.trim) return face_contains(f, uv);
  return trim_face_contains(f, *f.trim, uv);
}

bool OccModel::contains_param_by_occ(int face, const Vec2& uv) const {
  if (!std::isfinite(uv.x()) || !std::isfinite(uv.y())) return false;
  const FaceData& f = face_at(face);
  return occ_face_contains(f, in_period(f, uv));
}

}  // namespace cm::geom_occ::detail
