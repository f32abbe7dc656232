#pragma once
// Classification of an existing tet mesh on a geometric model (seed paper 1,
// §2: every mesh entity classified on one model entity): for meshes made
// elsewhere (Gmsh's MSH 4.1 above all, of any order) from the CAD model
// curvemesh loads, so that the optimizer can move their boundary on the model
// and the curving step can place nodes on it. The other tool's tags name its
// own entities, which need not be ours (a different numbering, a face split
// in two), and a reader of a file without a model has only the mesh to go on:
// geometry decides, the input's tags only group triangles.
#include <cstddef>
#include <string>
#include <vector>

#include "curvemesh/geom/model.hpp"
#include "curvemesh/mesh/tet_mesh.hpp"

namespace cm::generate {

/// An input tag (of a face or region) and where its elements went.
struct TagMapping {
  int input = 0;           ///< the tag in the mesh before classification
  int model = 0;           ///< the model tag most of its elements went to
  std::size_t count = 0;   ///< its elements (boundary triangles or tets)
  std::size_t others = 0;  ///< of them, on other model entities than `model`
};

struct ModelClassification {
  // Boundary triangles: hull faces and faces between model regions.
  std::size_t boundary_triangles = 0;
  std::size_t input_faces = 0;          ///< distinct input face tags among them
  std::size_t input_faces_whole = 0;    ///< of them, those whose triangles all fit one model face
  std::size_t triangles_searched = 0;   ///< placed one by one (their group fit no single face, or no tag)
  std::size_t triangles_flipped = 0;    ///< listed reversed from the input, to follow the face's normal
  /// Input triangles inside a model region (an embedded face the model does
  /// not have, or between input regions that map to one), left out of m.tris.
  std::size_t triangles_dropped = 0;
  std::vector<TagMapping> face_map;     ///< per input face tag, by increasing tag
  std::vector<TagMapping> region_map;   ///< per input region tag
  // Vertices by the dimension of their model entity.
  std::size_t vertices_on_model_vertices = 0, vertices_on_model_edges = 0, vertices_on_model_faces = 0,
              interior_vertices = 0;
  std::size_t mesh_edges_on_model_edges = 0;  ///< m.edges after
  // What differs from the input's classification.
  std::size_t vertices_changed = 0;   ///< another (dim, tag)
  std::size_t triangles_changed = 0;  ///< another face tag, or not in the input's triangles
  std::size_t edges_changed = 0;      ///< edges added to, removed from or retagged in m.edges
  std::size_t tets_changed = 0;       ///< another region tag
  // Fit: each boundary vertex against its entity evaluated at its parameters.
  double max_distance = 0;           ///< in model length units
  double max_relative_distance = 0;  ///< over the entity's tolerance (generate::check_boundary's measure)
  /// Inconsistencies that leave the classification short of a geometric
  /// triangulation of the model but the mesh usable: a model entity with no
  /// mesh entity, a face two regions share where the mesh does not conform
  /// (each region meshed on its own), a mesh edge spanning two model edges,
  /// a vertex where model edges meet away from a model vertex, vertices off
  /// their entity by more than its tolerance (within twice), input physical
  /// groups merged onto one model entity. The first few, naming entities.
  std::vector<std::string> problems;
  std::size_t num_problems = 0;
  double seconds = 0;
};

struct ClassifyOptions {
  /// Names the mesh in error messages (its file, typically).
  std::string mesh_name = "mesh";
  std::size_t max_problems = 20;
};

/// Reclassifies m on `model` by geometry, replacing its classification:
/// - tet_region: each input region tag goes to the model region that holds a
///   few of its tets (geom::Model::classify_point on their centroids);
/// - m.tris: the hull faces and the faces between tets of different model
///   regions, each on the model face all three of its vertices lie on
///   (within the face's tolerance, or twice its edges' and vertices': a
///   surface may miss its own corner by the corner's tolerance), listed to
///   follow face_normal (out of the face's first region, as
///   generate::check_boundary expects; also where two regions' meshes meet
///   on a shared face without conforming). Triangles of one input face tag are
///   tried on one model face together (candidates pruned by bounding box);
///   those that do not fit it are placed one by one, so a many-to-one or
///   one-to-many tag correspondence comes out right;
/// - m.edges: the mesh edges on model edges — where triangles of different
///   model faces meet, and on seams and other edges that bound one face
///   only — each on the model edge its end points and its midpoint (or
///   high-order nodes, when the mesh has them) lie on;
/// - vert_class / vert_param: {0, V} within V's tolerance of its point (the
///   nearest such mesh vertex, others inside a shorter model edge go on it),
///   {1, E} with u along mesh edges of model edge E, {2, F} with (u, v) inside model face
///   F (as closest_point returns them: periodic directions wrapped into the
///   face's range), {3, region} inside; model vertices carry no parameters;
/// - m.entities: the model's topology (bounding entities signed as
///   curvemesh's mesher writes them), with the physical groups and names of
///   the input entities that map to each.
/// A mesh curvemesh made of `model` gets back exactly the classification it
/// was written with (up to parameter round-off and periods).
/// Preconditions: adjacency and vert2tet built (mesh::build_adjacency, as
/// io::read_mesh does); positive tets. High-order nodes are kept as they are
/// (unmoved); the vertex arrays are resized to #V.
/// On success the boundary passes check_boundary's vertex test for any mesh
/// made from the model by a tool that puts vertices on it.
/// Throws cm::InputError (file = options.mesh_name), leaving m unchanged,
/// when the mesh is not of this model: a boundary triangle whose vertices
/// lie on no one model face (the message names it, the nearest face and the
/// distance, and a likely unit mismatch when the mesh's size differs from
/// the model's), tets in no model region, no tets.
/// Complexity: one closest-point query per boundary vertex and model entity
/// it is on (Newton from a neighbour's parameters), a few per input tag and
/// candidate face; linear in the boundary size otherwise. Parallel (TBB),
/// deterministic whatever the thread count.
ModelClassification classify_on_model(mesh::TetMesh& m, const geom::Model& model, const ClassifyOptions& options = {});

/// The model's entities with their bounding entities as curvemesh records
/// them in TetMesh::entities: an edge by its start vertex and its end vertex
/// negated (once for a closed edge), a face by its non-degenerate edge uses
/// in loop order (signed by orientation; a seam twice), a region by its
/// faces (signed).
std::vector<mesh::EntityInfo> model_entities(const geom::Model& model);

}  // namespace cm::generate
