#pragma once
// From curvature to requested edge length (seed paper 1, §4, eqs. 4.1–4.5).
//
// A straight edge of length ℓ whose end points lie on a circle of radius R
// deviates from the arc by ε with R² = (R − ε)² + (ℓ/2)², so
//   ℓ = (8Rε − 4ε²)^½                                   (4.1 / 4.3)
// for a constant deviation ε (--curv-eps), and, with ε = αℓ (4.4),
//   ℓ = 8Rα / (1 + 4α²)                                  (4.5)
// for a deviation proportional to the length (--curv-alpha). R is the radius
// of the tightest principal curvature, R = 1 / max(|κ₁|, |κ₂|) (both signs:
// a concave fillet needs the same resolution as a convex one).
//
// Constraint ε < 2R (the seed's): a chord cannot be longer than the
// diameter. Formula 4.3 peaks at ε = R with ℓ = 2R and decreases beyond,
// which would make a *larger* tolerance give *smaller* elements; we take
// ℓ = 2R for every ε ≥ R (any chord of the circle is then within ε). In the
// same way α is limited to (0, 1/2]: 4.5 peaks at α = 1/2 with ℓ = 2R.
#include <array>
#include <limits>

#include "curvemesh/geom/model.hpp"
#include "curvemesh/size/metric.hpp"

namespace cm::size {

struct CurvatureRule {
  enum class Kind { kOff, kChordDeviation /* ε, eq. 4.3 */, kRelativeDeviation /* α, eq. 4.5 */ };
  Kind kind = Kind::kOff;
  double value = 0;  ///< ε (a length) or α (dimensionless, in (0, 1/2])

  static CurvatureRule off() { return {}; }
  /// Throws std::invalid_argument unless eps > 0 and finite.
  static CurvatureRule chord_deviation(double eps);
  /// Throws std::invalid_argument unless 0 < alpha <= 1/2.
  static CurvatureRule relative_deviation(double alpha);
  bool enabled() const { return kind != Kind::kOff; }
};

/// Requested length for a curvature κ (either sign); +infinity for κ = 0 or a
/// rule that is off.
double curvature_length(double kappa, const CurvatureRule& rule);

/// Requested length at a face point: from R = 1 / max(|κ₁|, |κ₂|).
double surface_curvature_length(const geom::Curvatures& c, const CurvatureRule& rule);

/// The principal curvatures at (u, v) when they mean something: at a regular
/// point of the parametrization (|du × dv| > 1e-8 (|du|² + |dv|²)), finite,
/// and with radii above the face's tolerance. At a singular point (the pole
/// of a B-spline sphere, a cone's apex) kernels return arbitrary values that
/// are artefacts of du × dv vanishing; a radius below the model tolerance
/// cannot be meshed anyway. Returns false for those.
bool usable_curvatures(const geom::Model& model, int face, const Vec2& uv, geom::Curvatures* out);
/// The same test on an evaluation already made (Model::face_geometry), with
/// the face's tolerance.
bool usable_curvatures(const geom::SurfaceGeometry& g, double tolerance, geom::Curvatures* out);

/// Octree level of eq. 4.6 for a length ℓ in a root cube of side L:
/// N = log₂(L/ℓ), rounded up so the octant side L/2ᴺ is <= ℓ; >= 0.
int octree_level(double root_side, double length);

/// Directional variant (seed §4, footnote 1): lengths ℓ₁, ℓ₂ along the
/// principal directions, each from its own κ, clamped to [hmin, hmax]; the
/// normal direction gets min(ℓ₁, ℓ₂) so that the elements touching the
/// surface are not stretched across it.
Metric surface_curvature_metric(const geom::Curvatures& c, const Vec3& normal, const CurvatureRule& rule,
                                double hmin, double hmax);

}  // namespace cm::size
