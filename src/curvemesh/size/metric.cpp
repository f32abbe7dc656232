#include "curvemesh/size/metric.hpp"

#include <cmath>
#include <stdexcept>

#include <Eigen/Eigenvalues>

namespace cm::size {

namespace {

Metric symmetrized(const Metric& m) { return 0.5 * (m + m.transpose()); }

// Applies f to the eigenvalues of a symmetric matrix.
template <class F>
Metric map_eigenvalues(const Metric& m, F f) {
  const Eigen::SelfAdjointEigenSolver<Metric> eig(symmetrized(m));
  const Vec3 l = eig.eigenvalues().unaryExpr(f);
  return eig.eigenvectors() * l.asDiagonal() * eig.eigenvectors().transpose();
}

}  // namespace

Metric isotropic_metric(double h) {
  if (!(h > 0) || !std::isfinite(h)) throw std::invalid_argument("isotropic_metric: size must be finite and > 0");
  return Metric::Identity() / (h * h);
}

Metric metric_from_sizes(const std::array<Vec3, 3>& directions, const Vec3& sizes) {
  Metric m = Metric::Zero();
  for (int i = 0; i < 3; ++i) {
    if (!(sizes[i] > 0) || !std::isfinite(sizes[i]))
      throw std::invalid_argument("metric_from_sizes: sizes must be finite and > 0");
    const Vec3 d = directions[i].normalized();
    m += d * d.transpose() / (sizes[i] * sizes[i]);
  }
  return m;
}

Vec3 metric_sizes(const Metric& m, Mat3* directions) {
  const Eigen::SelfAdjointEigenSolver<Metric> eig(symmetrized(m));
  // Eigenvalues come in increasing order: reverse so the sizes increase.
  Vec3 sizes;
  for (int i = 0; i < 3; ++i) sizes[i] = 1 / std::sqrt(eig.eigenvalues()[2 - i]);
  if (directions)
    for (int i = 0; i < 3; ++i) directions->col(i) = eig.eigenvectors().col(2 - i);
  return sizes;
}

double min_size(const Metric& m) {
  const Eigen::SelfAdjointEigenSolver<Metric> eig(symmetrized(m), Eigen::EigenvaluesOnly);
  return 1 / std::sqrt(eig.eigenvalues()[2]);
}

bool is_metric(const Metric& m) {
  if (!m.allFinite()) return false;
  if ((m - m.transpose()).cwiseAbs().maxCoeff() > 1e-12 * m.cwiseAbs().maxCoeff()) return false;
  const Eigen::SelfAdjointEigenSolver<Metric> eig(m, Eigen::EigenvaluesOnly);
  return eig.eigenvalues()[0] > 0;
}

Metric intersect(const Metric& a, const Metric& b) {
  // Simultaneous reduction: solve B p = λ A p; with P the A-orthonormal
  // eigenvectors (Pᵀ A P = I, Pᵀ B P = diag λ), both metrics are diagonal in
  // the basis P and the intersection keeps max(1, λᵢ) there.
  const Eigen::GeneralizedSelfAdjointEigenSolver<Metric> ges(symmetrized(b), symmetrized(a));
  const Mat3& p = ges.eigenvectors();
  const Vec3 mu = ges.eigenvalues().cwiseMax(1.0);
  const Mat3 p_inv = p.inverse();
  return symmetrized(p_inv.transpose() * mu.asDiagonal() * p_inv);
}

double metric_length(const Metric& m, const Vec3& p, const Vec3& q) {
  const Vec3 e = q - p;
  return std::sqrt(std::max(0.0, e.dot(m * e)));
}

Metric interpolate(std::span<const Metric> metrics, std::span<const double> weights) {
  if (metrics.size() != weights.size() || metrics.empty())
    throw std::invalid_argument("interpolate: need as many weights as metrics, at least one");
  Metric log_sum = Metric::Zero();
  for (std::size_t i = 0; i < metrics.size(); ++i)
    log_sum += weights[i] * map_eigenvalues(metrics[i], [](double l) { return std::log(l); });
  return map_eigenvalues(log_sum, [](double l) { return std::exp(l); });
}

}  // namespace cm::size
