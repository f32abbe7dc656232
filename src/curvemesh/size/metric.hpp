#pragma once
// Riemannian metric tensors for size control: M symmetric positive definite,
// a vector e has length sqrt(eᵀ M e), and the isotropic size h is M = I / h².
// Eigen's self-adjoint solvers do the algebra; these helpers fix the
// conventions (which intersection, how sizes are read off) in one place.
#include <array>
#include <span>

#include "curvemesh/core/types.hpp"

namespace cm::size {

using Metric = Mat3;

/// M = I / h². Requires h > 0 and finite.
Metric isotropic_metric(double h);

/// M = Σ dᵢdᵢᵀ / hᵢ² for orthonormal directions dᵢ (normalized here) and sizes hᵢ > 0.
Metric metric_from_sizes(const std::array<Vec3, 3>& directions, const Vec3& sizes);

/// Sizes hᵢ = 1/sqrt(λᵢ) along the eigenvectors, smallest first, with the
/// eigenvectors as the columns of `directions` when it is given.
Vec3 metric_sizes(const Metric& m, Mat3* directions = nullptr);

/// The smallest size the metric asks for (its finest direction).
double min_size(const Metric& m);

/// Symmetric, finite and positive definite (all eigenvalues > 0).
bool is_metric(const Metric& m);

/// Metric intersection by simultaneous reduction: the largest metric (the
/// coarsest sizes) whose unit ball lies inside both unit balls, i.e. in the
/// common eigenbasis P of A⁻¹B the size along each P column is the smaller
/// of the two. intersect(I/a², I/b²) = I/min(a,b)². Commutative.
Metric intersect(const Metric& a, const Metric& b);

/// Length of the segment from p to q in the metric (constant along it).
double metric_length(const Metric& m, const Vec3& p, const Vec3& q);

/// Log-Euclidean interpolation Σ wᵢ log(Mᵢ), exponentiated. Weights should
/// sum to 1 and be >= 0; the result is SPD for any SPD inputs and, unlike the
/// linear mean, does not inflate the volume of the unit ball (det is the
/// geometric mean).
Metric interpolate(std::span<const Metric> metrics, std::span<const double> weights);

}  // namespace cm::size
