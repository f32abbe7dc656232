#pragma once
// Closed-form solids behind geom::Model: a sphere, a finite cylinder and a
// ring torus, so that meshing, sizing and curving can be tested without a CAD
// file (SCOREC gmi_analytic plays the same role). Each model is a complete
// B-rep with the topology, tag numbering, parametrizations and face
// orientations that OpenCASCADE's BRepPrimAPI_MakeSphere / MakeCylinder /
// MakeTorus produce, so a mesher that handles one handles the other.
//
// Every query is closed form and exact to rounding: derivatives to second
// order, normals, principal curvatures and directions, closest points
// (clamped to the trimmed entity; the hint is used only to break ties such
// as a probe on an axis or a parameter on a seam), p-curves, areas, lengths,
// volume and centre of mass, and classify_point (the solid's exact signed
// distance function compared with the tolerance, so kOn is the band of
// that width around the whole boundary, rims included). Models are
// immutable, so queries are thread-safe. Units are "" (unitless); every
// entity's tolerance is 1e-9 × the model's bounding-box diagonal.
//
// Frames: for an axis a, the reference direction x = reference_x_direction(a)
// and y = a × x (right-handed). The sphere uses the world frame (axis +Z).
//
// Sphere (centre c, radius R): 1 region, 1 face, 3 edges, 2 vertices.
//   face 1  kSphere  p(u,v) = c + R(cos v cos u x + cos v sin u y + sin v z),
//           u in [0, 2π] periodic, v in [-π/2, π/2]; du × dv points out.
//   vertex 1 north pole (v = π/2), vertex 2 south pole (v = -π/2).
//   edge 1  degenerate at the north pole (type kPoint, zero derivatives,
//           length 0), t in [0, 2π], p-curve (t, π/2).
//   edge 2  seam, kCircle, p(t) = c + R(cos t x + sin t z), t in [-π/2, π/2],
//           from vertex 2 to vertex 1; p-curve (2π, t) forward, (0, t) reversed.
//   edge 3  degenerate at the south pole, t in [0, 2π], p-curve (t, -π/2).
//   loop of face 1: edge 1 reversed, 2 reversed, 3 forward, 2 forward.
//
// Cylinder (base centre b, axis a, radius R, height H): 1 region, 3 faces,
// 3 edges, 2 vertices.
//   face 1  kCylinder, lateral, p(u,v) = b + R(cos u x + sin u y) + v a,
//           u in [0, 2π] periodic, v in [0, H]; du × dv points out.
//   face 2  kPlane, top cap, p(u,v) = b + H a + u x + v y, u² + v² <= R²;
//           normal +a; used forward by the region.
//   face 3  kPlane, bottom cap, p(u,v) = b + u x + v y, u² + v² <= R²;
//           du × dv = +a points into the solid, so the region uses it
//           reversed and face_normal returns -a (as OpenCASCADE does).
//   vertex 1 b + H a + R x (top of the seam), vertex 2 b + R x.
//   edge 1  top circle, kCircle, p(t) = b + H a + R(cos t x + sin t y),
//           t in [0, 2π] periodic, closed on vertex 1.
//   edge 2  seam, kLine, p(t) = b + R x + t a, t in [0, H], vertex 2 -> 1;
//           p-curve on face 1 (2π, t) forward, (0, t) reversed.
//   edge 3  bottom circle like edge 1 at b, closed on vertex 2.
//   loops: face 1: edge 1 rev, 2 rev, 3 fwd, 2 fwd; face 2: edge 1 fwd
//          (p-curve (R cos t, R sin t)); face 3: edge 3 rev (same p-curve).
//
// Torus (centre c, axis a, major radius R, minor radius r, R > r > 0):
// 1 region, 1 face, 2 edges, 1 vertex.
//   face 1  kTorus, p(u,v) = c + (R + r cos v)(cos u x + sin u y) + r sin v a,
//           u, v in [0, 2π], both periodic; du × dv points out.
//   vertex 1 c + (R + r) x.
//   edge 1  outer equator (v = 0), kCircle, radius R + r, parameter u, closed
//           on vertex 1; p-curve (t, 0) forward, (t, 2π) reversed.
//   edge 2  meridian (u = 0), kCircle, p(t) = c + (R + r cos t) x + r sin t a,
//           closed on vertex 1; p-curve (2π, t) forward, (0, t) reversed.
//   loop of face 1: edge 1 rev, 2 rev, 1 fwd, 2 fwd.
//
// Principal curvatures follow model.hpp's sign convention (positive where
// the face bends away from its outward normal): sphere 1/R twice; cylinder
// 1/R around, 0 along the axis (dir2 = ±a); torus 1/r around the tube and
// cos v / (R + r cos v) along the parallel (1/(R + r) on the outer equator,
// -1/(R - r) on the inner). Directions satisfy dir1 × dir2 = face_normal.
//
// Parameters outside an entity's range are evaluated on the underlying
// untrimmed curve or surface; contains_param tells whether they are on the
// face. Tags that do not exist throw std::out_of_range; an edge that does not
// bound the face given to edge_param_on_face throws std::invalid_argument.
#include <memory>

#include "curvemesh/geom/model.hpp"

namespace cm::geom {

/// Sphere of `radius` > 0 around `center`, axis +Z. Throws cm::GeometryError
/// for a non-positive or non-finite radius or centre.
std::unique_ptr<Model> make_analytic_sphere(const Vec3& center, double radius);

/// Closed cylinder: lateral face and two disk caps. `axis_dir` need not be
/// unit but must be non-zero; `radius` and `height` > 0. Throws
/// cm::GeometryError otherwise.
std::unique_ptr<Model> make_analytic_cylinder(const Vec3& base_center, const Vec3& axis_dir,
                                              double radius, double height);

/// Ring torus around `axis_dir` through `center`. Requires
/// major_radius > minor_radius > 0 (no self-intersecting horn/spindle
/// torus); throws cm::GeometryError otherwise.
std::unique_ptr<Model> make_analytic_torus(const Vec3& center, const Vec3& axis_dir,
                                           double major_radius, double minor_radius);

/// The x direction of the frame the factories build around `axis_dir`
/// (non-zero): the world axis least aligned with it, made perpendicular and
/// unit. +X for a +Z axis.
Vec3 analytic_reference_direction(const Vec3& axis_dir);

}  // namespace cm::geom
