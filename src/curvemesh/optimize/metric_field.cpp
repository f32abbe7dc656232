#include "curvemesh/optimize/metric_field.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <utility>

#include <Eigen/Eigenvalues>
#include <fmt/format.h>
#include <tbb/parallel_for.h>

#include "curvemesh/core/predicates.hpp"
#include "curvemesh/modify/measure.hpp"
#include "curvemesh/quality/measures.hpp"
#include "curvemesh/size/background_field.hpp"

namespace cm::optimize {

namespace {

template <class F>
size::Metric map_eigenvalues(const size::Metric& m, F f) {
  const Eigen::SelfAdjointEigenSolver<size::Metric> eig(0.5 * (m + m.transpose()));
  const Vec3 l = eig.eigenvalues().unaryExpr(f);
  return eig.eigenvectors() * l.asDiagonal() * eig.eigenvectors().transpose();
}

size::Metric log_of(const size::Metric& m) {
  return map_eigenvalues(m, [](double l) { return std::log(l); });
}

bool is_diagonal(const size::Metric& m) {
  return m(0, 1) == 0 && m(0, 2) == 0 && m(1, 2) == 0 && m(1, 0) == 0 && m(2, 0) == 0 && m(2, 1) == 0;
}

// Exponentials are of log-metrics, whose eigenvalues are of modest size
// (the logarithms of the metric's), so the closed-form 3×3 solver is exact
// enough and several times faster than the iterative one; every metric
// quality of a tet goes through here.
size::Metric exp_of(const size::Metric& m) {
  if (is_diagonal(m)) return Vec3(std::exp(m(0, 0)), std::exp(m(1, 1)), std::exp(m(2, 2))).asDiagonal();
  Eigen::SelfAdjointEigenSolver<size::Metric> eig;
  eig.computeDirect(0.5 * (m + m.transpose()));
  const Vec3 l = eig.eigenvalues().array().exp();
  return eig.eigenvectors() * l.asDiagonal() * eig.eigenvectors().transpose();
}


// Unique edges (a < b) of the live tets, sorted.
std::vector<std::pair<VertId, VertId>> unique_edges(const mesh::TetMesh& m) {
  std::vector<std::pair<VertId, VertId>> edges;
  edges.reserve(6 * m.num_tets());
  for (const auto& tv : m.tet2verts) {
    if (tv[0] == kNone) continue;
    for (const auto& e : mesh::kTetEdges) edges.push_back(std::minmax(tv[e[0]], tv[e[1]]));
  }
  std::sort(edges.begin(), edges.end());
  edges.erase(std::unique(edges.begin(), edges.end()), edges.end());
  return edges;
}

// Mean length of each vertex's edges; vertices in no tet get the global mean.
std::vector<double> mean_edge_lengths(const mesh::TetMesh& m) {
  const auto edges = unique_edges(m);
  std::vector<double> sum(m.num_verts(), 0);
  std::vector<int> count(m.num_verts(), 0);
  double total = 0;
  for (const auto& [a, b] : edges) {
    const double l = (m.coords[a] - m.coords[b]).norm();
    sum[a] += l;
    sum[b] += l;
    ++count[a];
    ++count[b];
    total += l;
  }
  const double fallback = edges.empty() ? 1.0 : total / static_cast<double>(edges.size());
  for (std::size_t v = 0; v < sum.size(); ++v) sum[v] = count[v] > 0 && sum[v] > 0 ? sum[v] / count[v] : fallback;
  return sum;
}

}  // namespace

MetricField MetricField::from_sizes(std::span<const double> sizes) {
  MetricField f;
  f.metrics_.resize(sizes.size());
  f.logs_.resize(sizes.size());
  for (std::size_t v = 0; v < sizes.size(); ++v) {
    const double h = sizes[v];
    if (!(h > 0) || !std::isfinite(h))
      throw std::invalid_argument(fmt::format("size {} at vertex {} is not finite and > 0", h, v + 1));
    f.metrics_[v] = size::Metric::Identity() / (h * h);
    f.logs_[v] = size::Metric::Identity() * (-2 * std::log(h));
  }
  return f;
}

MetricField MetricField::from_tensors(std::vector<size::Metric> metrics) {
  MetricField f;
  for (std::size_t v = 0; v < metrics.size(); ++v)
    if (!size::is_metric(metrics[v]))
      throw std::invalid_argument(fmt::format("the tensor at vertex {} is not symmetric positive definite", v + 1));
  f.logs_.resize(metrics.size());
  for (std::size_t v = 0; v < metrics.size(); ++v) f.logs_[v] = log_of(metrics[v]);
  f.metrics_ = std::move(metrics);
  f.anisotropic_ = true;
  return f;
}

double MetricField::size_at(VertId v) const {
  if (!anisotropic_) return 1 / std::sqrt(metrics_[v](0, 0));
  return size::min_size(metrics_[v]);
}

void MetricField::set(VertId v, const size::Metric& m) {
  if (v >= metrics_.size()) {
    metrics_.resize(v + 1, size::Metric::Identity());
    logs_.resize(v + 1, size::Metric::Zero());
  }
  metrics_[v] = m;
  logs_[v] = anisotropic_ ? log_of(m) : size::Metric::Identity() * std::log(m(0, 0));
}

void MetricField::set_interpolated(VertId v, VertId a, VertId b, double t) {
  const size::Metric log_m = (1 - t) * logs_[a] + t * logs_[b];
  if (v >= metrics_.size()) {
    metrics_.resize(v + 1, size::Metric::Identity());
    logs_.resize(v + 1, size::Metric::Zero());
  }
  logs_[v] = log_m;
  metrics_[v] = is_diagonal(log_m) ? size::Metric(log_m.diagonal().array().exp().matrix().asDiagonal())
                                   : exp_of(log_m);
}

size::Metric MetricField::tet_metric(const std::array<VertId, 4>& v) const {
  const size::Metric mean = 0.25 * (logs_[v[0]] + logs_[v[1]] + logs_[v[2]] + logs_[v[3]]);
  if (!anisotropic_) return size::Metric::Identity() * std::exp(mean(0, 0));
  return exp_of(mean);
}

double MetricField::edge_length(const mesh::TetMesh& m, VertId a, VertId b) const {
  return edge_metric_length(m.coords[a], m.coords[b], metrics_[a], metrics_[b]);
}

double MetricField::tet_quality(const mesh::TetMesh& m, const std::array<VertId, 4>& v) const {
  // A constant isotropic metric does not change shape.
  if (!anisotropic_) return modify::tet_quality(m, v);
  const Vec3 &a = m.coords[v[0]], &b = m.coords[v[1]], &c = m.coords[v[2]], &d = m.coords[v[3]];
  if (predicates::orient3d(a.data(), b.data(), c.data(), d.data()) <= 0) return -1;
  return std::max(quality::tet_metric_mean_ratio(a, b, c, d, tet_metric(v)), 0.0);
}

double MetricField::tet_quality_at(const std::array<Vec3, 4>& x,
                                   const std::array<const size::Metric*, 4>& logs) const {
  if (predicates::orient3d(x[0].data(), x[1].data(), x[2].data(), x[3].data()) <= 0) return -1;
  if (!anisotropic_) return std::max(quality::tet_mean_ratio(x[0], x[1], x[2], x[3]), 0.0);
  const size::Metric mean = 0.25 * (*logs[0] + *logs[1] + *logs[2] + *logs[3]);
  return std::max(quality::tet_metric_mean_ratio(x[0], x[1], x[2], x[3], exp_of(mean)), 0.0);
}

double edge_metric_length(const Vec3& p, const Vec3& q, const size::Metric& mp, const size::Metric& mq) {
  const Vec3 e = q - p;
  const double la = std::sqrt(std::max(0.0, e.dot(mp * e)));
  const double lb = std::sqrt(std::max(0.0, e.dot(mq * e)));
  if (!(la > 0) || !(lb > 0)) return 0.5 * (la + lb);
  // la·lb over their logarithmic mean; near equality the logarithmic mean
  // is the arithmetic one to O((la−lb)²), and the quotient would cancel.
  if (std::abs(la - lb) <= 1e-4 * std::max(la, lb)) return 2 * la * lb / (la + lb);
  return la * lb * std::log(la / lb) / (la - lb);
}

MetricField metric_field_from_values(std::span<const double> values, int components, std::size_t num_verts) {
  if (components != 1 && components != 6)
    throw std::invalid_argument(fmt::format("{} components per vertex (1 for sizes, 6 for tensors)", components));
  const std::size_t per = static_cast<std::size_t>(components);
  if (values.size() % per != 0 || values.size() / per != num_verts)
    throw std::invalid_argument(fmt::format("{} {} for the {} vertices of the mesh", values.size() / per,
                                            components == 1 ? "sizes" : "tensors", num_verts));
  if (components == 1) return MetricField::from_sizes(values);
  std::vector<size::Metric> ms(num_verts);
  for (std::size_t v = 0; v < num_verts; ++v) {
    const double* t = &values[6 * v];  // m11 m12 m22 m13 m23 m33
    ms[v] << t[0], t[1], t[3], t[1], t[2], t[4], t[3], t[4], t[5];
  }
  return MetricField::from_tensors(std::move(ms));
}

std::vector<double> metric_field_values(const MetricField& field) {
  std::vector<double> out;
  out.reserve(field.size() * (field.anisotropic() ? 6 : 1));
  for (VertId v = 0; v < field.size(); ++v) {
    if (!field.anisotropic()) {
      out.push_back(field.size_at(v));
      continue;
    }
    const auto& t = field.metric(v);
    out.insert(out.end(), {t(0, 0), t(0, 1), t(1, 1), t(0, 2), t(1, 2), t(2, 2)});
  }
  return out;
}

MetricField metric_field_from_mesh_sizes(const mesh::TetMesh& m) {
  return MetricField::from_sizes(mean_edge_lengths(m));
}

MetricField metric_field_from_mesh_shape(const mesh::TetMesh& m) {
  using Mat6 = Eigen::Matrix<double, 6, 6>;
  using Vec6 = Eigen::Matrix<double, 6, 1>;
  const std::size_t nv = m.num_verts();
  const std::vector<double> h = mean_edge_lengths(m);
  std::vector<Mat6> normal(nv, Mat6::Zero());
  std::vector<Vec6> rhs(nv, Vec6::Zero());
  for (const auto& [a, b] : unique_edges(m)) {
    // Scaled by the local size so the normal equations are well conditioned.
    for (const VertId v : {a, b}) {
      const Vec3 e = (m.coords[b] - m.coords[a]) / h[v];
      Vec6 row;
      row << e.x() * e.x(), 2 * e.x() * e.y(), e.y() * e.y(), 2 * e.x() * e.z(), 2 * e.y() * e.z(), e.z() * e.z();
      normal[v] += row * row.transpose();
      rhs[v] += row;
    }
  }
  std::vector<size::Metric> ms(nv);
  tbb::parallel_for(std::size_t{0}, nv, [&](std::size_t v) {
    const size::Metric iso = size::Metric::Identity() / (h[v] * h[v]);
    ms[v] = iso;
    const Eigen::SelfAdjointEigenSolver<Mat6> eig(normal[v], Eigen::EigenvaluesOnly);
    if (!(eig.eigenvalues()[0] > 1e-6 * eig.eigenvalues()[5])) return;  // edges in too few directions
    const Vec6 x = normal[v].ldlt().solve(rhs[v]);
    size::Metric fit;
    fit << x[0], x[1], x[3], x[1], x[2], x[4], x[3], x[4], x[5];
    fit /= h[v] * h[v];
    if (!size::is_metric(fit)) return;
    // An implausible stretching comes from a degenerate ball, not a design.
    const Vec3 sizes = size::metric_sizes(fit);
    if (sizes[2] > 1e3 * sizes[0] || sizes[2] > 10 * h[v] || sizes[0] < 0.1 * h[v]) return;
    ms[v] = fit;
  });
  return MetricField::from_tensors(std::move(ms));
}

MetricField metric_field_from_size_field(const mesh::TetMesh& m, const size::SizeField& field) {
  const std::size_t nv = m.num_verts();
  if (field.anisotropic()) {
    std::vector<size::Metric> ms(nv);
    tbb::parallel_for(std::size_t{0}, nv, [&](std::size_t v) { ms[v] = field.metric(m.coords[v]); });
    return MetricField::from_tensors(std::move(ms));
  }
  std::vector<double> h(nv);
  tbb::parallel_for(std::size_t{0}, nv, [&](std::size_t v) { h[v] = field.size(m.coords[v]); });
  return MetricField::from_sizes(h);
}

void clamp_sizes(MetricField& field, double hmin, double hmax) {
  if (hmin > 0 && hmax > 0 && hmin > hmax)
    throw std::invalid_argument(fmt::format("hmin {} is larger than hmax {}", hmin, hmax));
  const double lo = hmax > 0 ? 1 / (hmax * hmax) : 0;
  const double hi = hmin > 0 ? 1 / (hmin * hmin) : std::numeric_limits<double>::infinity();
  for (VertId v = 0; v < field.size(); ++v) {
    const size::Metric& m = field.metric(v);
    if (!field.anisotropic()) {
      const double c = std::clamp(m(0, 0), lo, hi);
      if (c != m(0, 0)) field.set(v, size::Metric::Identity() * c);
      continue;
    }
    const Eigen::SelfAdjointEigenSolver<size::Metric> eig(m);
    const Vec3& l = eig.eigenvalues();
    if (l.minCoeff() >= lo && l.maxCoeff() <= hi) continue;
    const Vec3 c = l.cwiseMax(lo).cwiseMin(hi);
    field.set(v, eig.eigenvectors() * c.asDiagonal() * eig.eigenvectors().transpose());
  }
}

void grade(MetricField& field, const mesh::TetMesh& m, double hgrad) {
  if (!(hgrad > 0)) return;
  if (field.size() != m.num_verts())
    throw std::invalid_argument(
        fmt::format("grade: {} metrics for the {} vertices of the mesh", field.size(), m.num_verts()));
  if (!field.anisotropic()) {
    std::vector<double> h(field.size());
    for (VertId v = 0; v < h.size(); ++v) h[v] = field.size_at(v);
    field = MetricField::from_sizes(size::grade_sizes(m, std::move(h), hgrad));
    return;
  }
  std::vector<size::Metric> ms(field.size());
  for (VertId v = 0; v < ms.size(); ++v) ms[v] = field.metric(v);
  field = MetricField::from_tensors(size::grade_metrics(m, std::move(ms), hgrad));
}

LengthStats measure_lengths(const mesh::TetMesh& m, const MetricField& field) {
  LengthStats s;
  const auto edges = unique_edges(m);
  s.edges = edges.size();
  if (edges.empty()) return s;
  s.min = std::numeric_limits<double>::infinity();
  double sum = 0;
  for (const auto& [a, b] : edges) {
    const double l = field.edge_length(m, a, b);
    s.min = std::min(s.min, l);
    s.max = std::max(s.max, l);
    sum += l;
    s.in_range += l >= kShortEdge && l <= kLongEdge;
    s.too_short += l < kShortEdge;
    s.too_long += l > kLongEdge;
    const auto bin = static_cast<std::size_t>(std::min(12.0, std::floor(l / 0.25)));
    ++s.histogram[bin];
  }
  s.mean = sum / static_cast<double>(edges.size());
  return s;
}

}  // namespace cm::optimize
