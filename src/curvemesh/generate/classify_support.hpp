#pragma once
// Internal to classify_on_model: what its passes ask of the model, computed
// once, and the assignment of boundary triangles to model faces.
#include <array>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "curvemesh/geom/model.hpp"
#include "curvemesh/mesh/tet_mesh.hpp"

namespace cm::generate::classify {

/// Model entities, tolerances and a spatial index of the faces. Arrays are
/// indexed by tag (entry 0 unused).
struct ModelIndex {
  explicit ModelIndex(const geom::Model& model);

  const geom::Model& model;
  /// check_boundary's floor under every tolerance: round-off of coordinates.
  double floor = 0;
  /// tolerance(e) raised to the floor: "on the entity" at its parameters.
  std::vector<double> vertex_tol, edge_tol, face_tol;
  /// What a mesh vertex on the closure of the entity may be off it: the
  /// tolerance, or twice that of a bounding entity (the vertex within it of
  /// a model vertex or edge that is itself within it of the surface: a
  /// face may miss its corner by the corner's tolerance).
  std::vector<double> edge_reach, face_reach;
  std::vector<geom::BoundingBox> face_box;       ///< inflated by reach and a margin
  std::vector<std::vector<int>> face_edges;      ///< non-degenerate, sorted
  std::vector<std::vector<int>> face_lone_edges; ///< edges bounding this face only (seams)
  std::vector<std::vector<int>> face_vertices;   ///< of every edge of the face, sorted
  std::vector<std::vector<int>> face_regions;    ///< upward, first region first
  std::vector<std::array<int, 2>> edge_ends;
  std::vector<geom::ParamRange> edge_range, face_range;

  /// Parameters of a point on the edge or face with periodic directions
  /// wrapped into the entity's range, [u0, u0 + period): closest_point may
  /// answer a period or two off (geom_occ on some closed faces), and
  /// neighbours' parameters are interpolated by the curving step.
  Vec2 normalized(int dim, int tag, Vec2 param) const;

  /// Faces whose inflated box may hold x (a superset; test the boxes).
  std::span<const int> faces_near(const Vec3& x) const;
  /// The model vertex nearest x within its tolerance, or 0.
  int vertex_at(const Vec3& x) const;

 private:
  geom::BoundingBox grid_box_;
  std::array<int, 3> grid_n_{1, 1, 1};
  Vec3 cell_;
  std::vector<std::size_t> cell_start_;
  std::vector<int> cell_faces_;
  std::vector<std::pair<double, int>> vertex_by_x_;
  double max_vertex_tol_ = 0;
};

/// A boundary triangle: oriented with its normal out of tet `inside`.
struct BoundaryTri {
  std::array<VertId, 3> verts;
  TetId inside = kNone;
  TetId outside = kNone;  ///< across the triangle, kNone on the hull
  int group = -1;         ///< index of its input face tag, -1 if untagged
  int face = 0;           ///< model face, 0 until assigned
};

/// The closest point of a mesh vertex on a model face or edge.
struct Projected {
  VertId vert;
  int entity;
  Vec2 param;
  double distance;
  friend bool operator<(const Projected& a, const Projected& b) {
    return a.vert < b.vert || (a.vert == b.vert && a.entity < b.entity);
  }
};

/// Sorted projections, looked up by (vertex, entity).
class ProjectionTable {
 public:
  /// Sorts; for a pair given twice keeps the nearer answer (the first of
  /// equal ones: callers list in a deterministic order).
  explicit ProjectionTable(std::vector<Projected> all);
  const Projected* find(VertId v, int entity) const;

 private:
  std::vector<Projected> items_;
};

/// Past this many triangles that fit no face the mesh is not of the model:
/// the search stops.
inline constexpr std::size_t kMisfitsEnough = 64;

/// A triangle no model face takes, for the error message.
struct Misfit {
  std::size_t tri;
  int nearest_face = 0;  ///< 0: no face's box holds it
  VertId worst_vertex = kNone;
  double distance = 0;
};

struct FaceAssignment {
  /// (vertex, face of one of its triangles), but for vertices on the border
  /// of a group of triangles (mostly on model edges) unless searched.
  std::vector<Projected> face_projections;
  std::size_t groups = 0;  ///< with boundary triangles
  std::size_t groups_whole = 0, searched = 0;
  std::vector<Misfit> misfits;  ///< triangles that fit no face
  std::size_t unsearched = 0;   ///< left unsearched after kMisfitsEnough misfits
};

/// Sets tris[i].face for every triangle: each group on the face that fits
/// all of it, the rest one by one.
FaceAssignment assign_faces(const ModelIndex& index, const mesh::TetMesh& m, std::vector<BoundaryTri>& tris,
                            std::size_t num_groups);

/// A point on the triangle's surface: the quadratic triangle's centroid when
/// the mesh stores its edge nodes, else the straight one.
Vec3 triangle_probe(const mesh::TetMesh& m, const std::array<VertId, 3>& v);

}  // namespace cm::generate::classify
