#pragma once
// Internal to geom_occ, but free of OpenCASCADE: a closed triangulated
// surface (the tessellation of a region's boundary) with a bounding-volume
// hierarchy, for the fast paths of OccModel::classify_point. Exact CAD
// classification costs milliseconds per point; ray parity on the triangles
// answers in microseconds for every point outside a band around them. Each
// triangle carries its own band (how far the face it approximates may stray
// from it: zero for a plane but for the tolerances), the face it comes from
// and the (u, v) of its corners on that face, so that a point inside the
// band can be projected on the right face from a good start.
//
// Immutable after construction, so queries are thread-safe.
#include <array>
#include <cstdint>
#include <optional>
#include <vector>

#include "curvemesh/core/types.hpp"

namespace cm::geom_occ::detail {

class TriangleClassifier {
 public:
  struct Triangle {
    std::array<Vec3, 3> corners;  ///< orientation irrelevant
    double band = 0;              ///< >= 0: half-width of the uncertain zone around it
    int face = 0;                 ///< model face it approximates
    std::array<Vec2, 3> uv = {Vec2::Zero(), Vec2::Zero(), Vec2::Zero()};  ///< corners' (u, v) on that face
  };

  struct Nearest {
    const Triangle* triangle = nullptr;
    double distance = 0;
    Vec3 barycentric = Vec3::Zero();  ///< of the closest point, on corners 0, 1, 2
  };

  /// The surface the triangles form should be closed (shared edges with the
  /// same corner points); inside() detects the cracks it happens to cross.
  /// O(T log T).
  explicit TriangleClassifier(std::vector<Triangle> triangles);

  bool empty() const { return triangles_.empty(); }
  std::size_t size() const { return triangles_.size(); }

  /// Whether x lies within some triangle's band of it. O(log T) when few
  /// triangles are near x.
  bool in_band(const Vec3& x) const;

  /// The triangle nearest to x (nullopt when there is none).
  std::optional<Nearest> nearest(const Vec3& x) const;

  /// The faces that may reach the ball of `radius` around x: those with a
  /// triangle t within radius + t.band of it, each with its triangle nearest
  /// to x, sorted by face. Stops (returning what it has, more than
  /// `max_faces`) once more than `max_faces` faces are found.
  std::vector<Nearest> faces_within(const Vec3& x, double radius, std::size_t max_faces) const;

  /// Whether x is inside the closed surface: the parity of crossings of rays
  /// from x in fixed directions, two of which must agree. nullopt when rays
  /// pass within rounding of a triangle's edge or plane (the count would be
  /// unreliable) or disagree (a crack in the surface). The answer holds for
  /// points outside the band (in_band false).
  std::optional<bool> inside(const Vec3& x) const;

 private:
  struct Node {
    Vec3 lo, hi;
    double band = 0;          // largest band of the triangles below
    std::uint32_t first = 0;  // leaf: first triangle; inner: left child (right = left + 1)
    std::uint32_t count = 0;  // triangles in a leaf; 0 for an inner node
  };
  void build(std::uint32_t self, std::uint32_t first, std::uint32_t count, std::vector<Vec3>& centroids);
  /// Crossings of the ray x + t·dir (t > 0), or nullopt when ambiguous.
  std::optional<int> crossings(const Vec3& x, const Vec3& dir) const;

  std::vector<Triangle> triangles_;
  std::vector<Node> nodes_;
};

}  // namespace cm::geom_occ::detail
